//! Bindings of the scenario runner: scenarios from files, built-in names or dictionaries,
//! runs with the GIL released, and recordings handed to NumPy without copying.

use numpy::{PyArray1, PyArrayMethods};
use pyo3::IntoPyObjectExt;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString, PyTuple};

use super::batch_watch::run_reporting;
use super::control::bool_repr;
use super::errors::{PyError, invalid_argument, reraise};
use super::logs::{DEBUG, INFO, log};
use super::values;
use crate::sim::arm::ArmRobot;
use crate::sim::outcome::{Buffer, COLUMNS, Recorded, SUMMARY_FIELDS, summary_field};
use crate::sim::robot::Robot;
use crate::sim::scenario::{BUILTIN, FileAccess, MAX_SCENARIO_BYTES, Scenario, builtin, check_point_count};
use crate::sim::{Outcome, simulate};

/// A validated scenario (see the README for the schema).
#[pyclass(name = "Scenario", module = "vsinv._core", frozen, skip_from_py_object)]
#[derive(Clone)]
pub struct PyScenario {
    pub inner: Scenario,
}

#[pymethods]
impl PyScenario {
    /// From TOML text; the files it names must be in the working directory unless
    /// `allow_outside_files`.
    #[staticmethod]
    #[pyo3(signature = (text, allow_outside_files = false))]
    fn from_toml(text: &str, allow_outside_files: bool) -> PyResult<Self> {
        Ok(Self { inner: Scenario::from_toml_with(text, access(allow_outside_files))? })
    }
    /// From a dictionary with the structure of a scenario file; the files it names must be in
    /// the working directory unless `allow_outside_files`.
    #[staticmethod]
    #[pyo3(signature = (d, allow_outside_files = false))]
    fn from_dict(d: &Bound<'_, PyAny>, allow_outside_files: bool) -> PyResult<Self> {
        scenario_from_dict(d, access(allow_outside_files)).map(|inner| Self { inner })
    }
    /// The name.
    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }
    /// The description.
    #[getter]
    fn description(&self) -> &str {
        &self.inner.description
    }
    /// The world that runs it (`[world] engine`): "kinematic" (vsinv's simulator) or "mujoco"
    /// (`vsinv.mujoco`, the mujoco extra).
    #[getter]
    fn engine(&self) -> &'static str {
        self.inner.world.engine.name()
    }
    /// The scenario as a dictionary (every default filled in); edit it and pass it back to
    /// `run_scenario` or `Scenario.from_dict`.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        values::to_python(py, &self.inner.to_value()?)
    }
    /// The arm of `[robot] kind = "urdf"` as the kinematic simulator reads it (its start joints
    /// solved from `[start]` if need be), or None for a free camera or a Cartesian robot: what
    /// a world that moves the arm itself (`vsinv.mujoco`) needs.
    fn arm(&self, py: Python<'_>) -> PyResult<Option<super::scenario_arm::PyScenarioArm>> {
        let inner = py.detach(|| self.inner.arm())?;
        Ok(inner.map(|inner| super::scenario_arm::PyScenarioArm { inner }))
    }
    /// The scenario as TOML text.
    fn to_toml(&self) -> PyResult<String> {
        Ok(self.inner.to_toml()?)
    }
    fn __repr__(&self) -> String {
        format!("Scenario(name={:?})", self.inner.name)
    }
}

/// The file rule of an `allow_outside_files` argument.
pub fn access(allow_outside_files: bool) -> FileAccess {
    if allow_outside_files { FileAccess::Anywhere } else { FileAccess::ScenarioFolder }
}

fn scenario_from_dict(d: &Bound<'_, PyAny>, access: FileAccess) -> PyResult<Scenario> {
    Ok(Scenario::from_value_with(scenario_value(d)?, access)?)
}

/// A scenario dictionary as a structured value (NumPy scalars and arrays as the numbers and
/// lists they hold); a value that cannot be read names its key (`scenario: object.points[2][1]:
/// ...`, kind `scenario`).
pub(super) fn scenario_value(d: &Bound<'_, PyAny>) -> PyResult<serde_json::Value> {
    scenario_value_at(d, None)
}

/// [`scenario_value`] of the item `index` of a batch: keys as the batch's validation names
/// them (`[3].control.gain`).
fn scenario_value_at(d: &Bound<'_, PyAny>, index: Option<usize>) -> PyResult<serde_json::Value> {
    let at = |key: crate::Location, reason: String| crate::sim::SimError::Scenario {
        key: match index {
            Some(i) => key.under_index(i),
            None => key,
        },
        reason,
    };
    // Too many object points are refused before the dictionary is read (a million took 5 s
    // and 300 MB to be refused as too much text).
    if let Ok(n) = d.get_item("object").and_then(|o| o.get_item("points")).and_then(|p| p.len()) {
        check_point_count(n).map_err(|e| match e {
            crate::sim::SimError::Scenario { key, reason } => at(key, reason),
            other => other,
        })?;
    }
    // As many values as the text limit could hold (two bytes each at least, "0,").
    let max_values = usize::try_from(MAX_SCENARIO_BYTES / 2).unwrap_or(usize::MAX);
    values::to_value(d, max_values)?.map_err(|e| at(crate::Location::parse(&e.path), e.reason).into())
}

/// A scenario from a `Scenario`, a dictionary, a built-in name or a TOML file path; the files
/// it names must be inside its folder.
pub fn scenario_arg(obj: &Bound<'_, PyAny>) -> PyResult<Scenario> {
    scenario_arg_with(obj, FileAccess::ScenarioFolder)
}

/// [`scenario_arg`] with the file rule `access` (a `Scenario` keeps its own rule unless
/// `access` is `Anywhere`).
pub fn scenario_arg_with(obj: &Bound<'_, PyAny>, access: FileAccess) -> PyResult<Scenario> {
    if let Ok(s) = obj.cast::<PyScenario>() {
        let mut inner = s.get().inner.clone();
        if access == FileAccess::Anywhere {
            inner.file_access = access;
        }
        return Ok(inner);
    }
    if obj.cast::<PyDict>().is_ok() {
        return scenario_from_dict(obj, access);
    }
    let py = obj.py();
    let text: String = if obj.cast::<PyString>().is_ok() {
        obj.extract()?
    } else {
        py.import("os")?.call_method1("fsdecode", (obj,)).and_then(|p| p.extract()).map_err(|_| {
            invalid_argument("scenario", "scenario: expected a Scenario, a dict, a built-in name or a file path".into())
        })?
    };
    if BUILTIN.iter().any(|(n, _)| *n == text) {
        return Ok(builtin(&text)?);
    }
    let path = std::path::Path::new(&text);
    if path.is_file() {
        return Scenario::from_toml_file_with(path, access).map_err(|e| PyError::from(&e).in_file(&text).into());
    }
    let names: Vec<&str> = BUILTIN.iter().map(|(n, _)| *n).collect();
    let msg = format!("{text:?} is neither a scenario file nor a built-in scenario ({})", names.join(", "));
    Err(invalid_argument("scenario", msg))
}

/// Loads a scenario from a built-in name, a TOML file path or a dictionary. Scenario angles
/// are degrees and their keys say so (`rotation_deg`, `skew_deg`, `max_angular_speed_deg`; the
/// older `rotation` is read as degrees); the Python API itself is SI (radians). The files a
/// scenario names (`calibration`, `robot.urdf`) must be inside its folder (the working
/// directory for a dictionary) unless `allow_outside_files`.
#[pyfunction]
#[pyo3(signature = (source, allow_outside_files = false))]
pub fn load_scenario(source: &Bound<'_, PyAny>, allow_outside_files: bool) -> PyResult<PyScenario> {
    Ok(PyScenario { inner: scenario_arg_with(source, access(allow_outside_files))? })
}

/// The built-in scenarios as (name, description) pairs.
#[pyfunction]
pub fn list_scenarios() -> PyResult<Vec<(String, String)>> {
    BUILTIN.iter().map(|(n, _)| builtin(n).map(|s| (s.name, s.description)).map_err(PyErr::from)).collect()
}

/// The result of a run: `.summary` (a dict), the scenario, and the recorded columns (NumPy
/// views of the simulator's buffers, one row per iteration), one attribute each as declared in
/// `vsinv::sim::outcome::COLUMNS` (see `recorded_columns()`).
#[pyclass(name = "RunResult", module = "vsinv._core", frozen)]
pub struct PyRunResult {
    /// The run's summary (status, iterations, final errors, ...), a dict.
    #[pyo3(get)]
    summary: Py<PyDict>,
    /// The scenario that was run.
    #[pyo3(get)]
    scenario: Py<PyScenario>,
    /// The recorded arrays in the order of `COLUMNS` (None where the run does not record one).
    columns: Vec<Option<Py<PyAny>>>,
    /// An arm's joint `names` and limits `lower`, `upper` (rad or m) and `velocity` (per second); None for the
    /// other robots.
    #[pyo3(get)]
    joint_limits: Option<Py<PyDict>>,
}

#[pymethods]
impl PyRunResult {
    /// The recorded arrays by name (those this run recorded).
    #[getter]
    fn arrays<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (c, a) in COLUMNS.iter().zip(&self.columns) {
            if let Some(a) = a {
                d.set_item(c.name, a.bind(py))?;
            }
        }
        Ok(d)
    }
    /// A run recorded outside the Rust simulator (`vsinv.mujoco.run`) as a `RunResult` of the
    /// same schema: `summary` with exactly the keys of a kinematic run's (each checked: a
    /// status of the simulator's, the scenario's name, numbers or None), `arrays` the recorded
    /// columns by name (every column that all runs record, shapes as declared with N rows from
    /// `time`, n points from `reference_pixels`, `n_joints` from `joints`; copied), and an
    /// arm's `joint_limits` (names, lower, upper, velocity) or None. Raises InvalidInput naming
    /// the key or column at fault.
    #[staticmethod]
    #[pyo3(signature = (scenario, summary, arrays, joint_limits = None))]
    fn from_recording(
        py: Python<'_>,
        scenario: &Bound<'_, PyAny>,
        summary: &Bound<'_, PyDict>,
        arrays: &Bound<'_, PyDict>,
        joint_limits: Option<Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let scenario = scenario_arg(scenario)?;
        let (columns, points) = super::run_record::columns_of(arrays)?;
        let summary = super::run_record::summary_of(summary, &scenario.name, points)?;
        if let Some(limits) = &joint_limits {
            super::run_record::check_joint_limits(limits)?;
        }
        Ok(Self {
            summary: summary.unbind(),
            scenario: Py::new(py, PyScenario { inner: scenario })?,
            columns,
            joint_limits: joint_limits.map(Bound::unbind),
        })
    }
    /// The declaration of the recorded columns (as `recorded_columns()`).
    #[classattr]
    fn columns(py: Python<'_>) -> PyResult<Py<PyTuple>> {
        Ok(PyTuple::new(py, recorded_columns(py)?)?.unbind())
    }
    fn __repr__(&self, py: Python<'_>) -> String {
        let s = self.summary.bind(py);
        let get = |k: &str| s.get_item(k).ok().flatten().map_or("?".into(), |v| v.to_string());
        format!("RunResult(status={}, iterations={})", get("status"), get("iterations"))
    }
}

/// The recorded columns (each a `RunResult` attribute and an `.npz` entry): name, unit (SI, `px`, `1`
/// dimensionless, `bool`), shape (axis lengths, or `"N"` rows, `"n"` points, `"n_joints"` joints), dtype, which
/// runs record it, description.
#[pyfunction]
pub fn recorded_columns(py: Python<'_>) -> PyResult<Vec<Bound<'_, PyDict>>> {
    COLUMNS
        .iter()
        .map(|c| {
            let d = PyDict::new(py);
            d.set_item("name", c.name)?;
            d.set_item("unit", c.unit)?;
            let shape: Vec<Bound<'_, PyAny>> = c
                .shape
                .iter()
                .map(|a| match a.symbol() {
                    Some(s) => s.into_bound_py_any(py),
                    None => a.len(0, 0, 0).into_bound_py_any(py),
                })
                .collect::<PyResult<_>>()?;
            d.set_item("shape", PyTuple::new(py, shape)?)?;
            d.set_item("dtype", if c.boolean { "bool" } else { "float64" })?;
            let recorded = match c.recorded {
                Recorded::Always => "always",
                Recorded::Vision => "vision",
                Recorded::Arm => "arm",
            };
            d.set_item("recorded", recorded)?;
            d.set_item("description", c.description)?;
            Ok(d)
        })
        .collect()
}

/// The numbers of `RunResult.summary` (SI, `px`, `1`): name, unit, description.
#[pyfunction]
pub fn summary_fields(py: Python<'_>) -> PyResult<Vec<Bound<'_, PyDict>>> {
    SUMMARY_FIELDS
        .iter()
        .map(|f| {
            let d = PyDict::new(py);
            d.set_item("name", f.name)?;
            d.set_item("unit", f.unit)?;
            d.set_item("description", f.description)?;
            Ok(d)
        })
        .collect()
}

/// Adds one property per recorded column to `RunResult`, documented from the declaration.
fn add_column_properties(py: Python<'_>) -> PyResult<()> {
    let ty = py.get_type::<PyRunResult>();
    let property = py.import("builtins")?.getattr("property")?;
    for (i, c) in COLUMNS.iter().enumerate() {
        let get = pyo3::types::PyCFunction::new_closure(py, Some(c"column"), None, move |args, _kwargs| {
            let py = args.py();
            let result = args.get_item(0)?;
            let result = result.cast::<PyRunResult>()?;
            Ok::<_, PyErr>(result.get().columns[i].as_ref().map(|a| a.clone_ref(py)))
        })?;
        let shape: Vec<String> =
            c.shape.iter().map(|a| a.symbol().map_or_else(|| a.len(0, 0, 0).to_string(), str::to_string)).collect();
        let only = match c.recorded {
            Recorded::Always => "",
            Recorded::Vision => "; None without [vision]",
            Recorded::Arm => "; None for robots other than an arm",
        };
        let comma = if shape.len() == 1 { "," } else { "" };
        let doc = format!("{} ({}, shape ({}{comma}){only}).", c.description, c.unit, shape.join(", "));
        ty.setattr(c.name, property.call1((get, py.None(), py.None(), doc))?)?;
    }
    Ok(())
}

/// Moves a buffer into NumPy (no copy) and views it with `shape`.
fn array<T: numpy::Element>(py: Python<'_>, data: Vec<T>, shape: &[usize]) -> PyResult<Py<PyAny>> {
    Ok(PyArray1::from_vec(py, data).reshape(shape)?.into_any().unbind())
}

/// The summary as a dictionary: SI numbers (units in `SUMMARY_FIELDS`).
pub fn summary_dict<'py>(py: Python<'py>, name: &str, o: &Outcome) -> PyResult<Bound<'py, PyDict>> {
    let s = &o.summary;
    let d = PyDict::new(py);
    d.set_item("name", name)?;
    d.set_item("status", s.status.as_str())?;
    d.set_item("message", &s.message)?;
    d.set_item("iterations", s.iterations)?;
    d.set_item("stop_rule", s.stop_rule.as_str())?;
    d.set_item("prop1", s.prop1)?;
    d.set_item("prop2", s.prop2)?;
    d.set_item("within_tolerance", s.within_tolerance)?;
    d.set_item("basis", s.basis.to_vec())?;
    d.set_item("basis_switches", s.basis_switches)?;
    for f in &SUMMARY_FIELDS {
        d.set_item(f.name, (f.value)(s))?;
    }
    Ok(d)
}

/// Runs a scenario (a `Scenario`, dict, built-in name or TOML path) with the GIL released.
/// `progress(done, total)` is called every 64 iterations if given; Ctrl-C stops the run.
#[pyfunction]
#[pyo3(signature = (scenario, record = true, progress = None, allow_outside_files = false))]
pub fn run_scenario(
    py: Python<'_>,
    scenario: &Bound<'_, PyAny>,
    record: bool,
    progress: Option<Py<PyAny>>,
    allow_outside_files: bool,
) -> PyResult<PyRunResult> {
    check_progress(progress.as_ref().map(|p| p.bind(py)))?;
    let scenario = scenario_arg_with(scenario, access(allow_outside_files))?;
    let mut config = scenario.to_config()?;
    config.record = record;
    log(py, INFO, || format!("run_scenario {}: start (record={})", scenario.name, bool_repr(record)))?;
    log(py, DEBUG, || {
        let images = if config.vision.is_some() { "images in the loop" } else { "no images" };
        format!("run_scenario {}: {} points, dt {} s, {images}", scenario.name, config.scene.points().len(), config.dt)
    })?;
    let started = std::time::Instant::now();
    let mut raised: Option<PyErr> = None;
    let outcome = py.detach(|| {
        let mut tick = |done: usize, total: usize| {
            Python::attach(|py| {
                let result = py.check_signals().and_then(|_| match &progress {
                    Some(cb) => cb.call1(py, (done, total)).map(|_| ()),
                    None => Ok(()),
                });
                match result {
                    Ok(()) => true,
                    Err(e) => {
                        raised = Some(e);
                        false
                    }
                }
            })
        };
        simulate(&config, &mut tick)
    });
    if let Some(e) = raised {
        return Err(e);
    }
    let outcome = outcome?;
    log(py, INFO, || {
        let s = &outcome.summary;
        let secs = started.elapsed().as_secs_f64();
        format!(
            "run_scenario {}: {} after {} iterations in {secs:.4} s",
            scenario.name,
            s.status.as_str(),
            s.iterations
        )
    })?;
    run_result(py, scenario, &config, outcome)
}

/// A `progress` argument: None or a callable `progress(done, total)` (a TypeError otherwise).
pub(super) fn check_progress(progress: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
    match progress {
        Some(cb) if !cb.is_callable() => {
            let kind = cb.get_type().name()?.to_string();
            Err(pyo3::exceptions::PyTypeError::new_err(format!(
                "progress: expected a callable progress(done, total) or None, got {kind}"
            )))
        }
        _ => Ok(()),
    }
}

/// `run_scenario`'s result: the summary and the recorded columns moved into NumPy.
fn run_result(
    py: Python<'_>,
    scenario: Scenario,
    config: &crate::sim::SimulationConfig,
    mut outcome: Outcome,
) -> PyResult<PyRunResult> {
    let summary = summary_dict(py, &scenario.name, &outcome)?;
    let r = outcome.recording.take().unwrap_or_default();
    let (rows, n) = (r.len(), config.scene.points().len());
    let arm = match &config.robot {
        Robot::Arm(arm) => Some(arm),
        _ => None,
    };
    let n_joints = arm.map_or(6, |a| a.dof());
    let vision = outcome.summary.detection_error.is_some();
    let buffers = r.into_buffers(std::mem::take(&mut outcome.reference_pixels));
    let columns = COLUMNS
        .iter()
        .zip(buffers)
        .map(|(c, b)| {
            let present = match c.recorded {
                Recorded::Always => true,
                Recorded::Vision => vision,
                Recorded::Arm => arm.is_some(),
            };
            let dims = c.dims(rows, n, n_joints);
            match (present, b) {
                (false, _) => Ok(None),
                (true, Buffer::F64(v)) => array(py, v, &dims).map(Some),
                (true, Buffer::Bool(v)) => array(py, v, &dims).map(Some),
            }
        })
        .collect::<PyResult<_>>()?;
    Ok(PyRunResult {
        summary: summary.unbind(),
        scenario: Py::new(py, PyScenario { inner: scenario })?,
        columns,
        joint_limits: arm.map(|a| arm_limits(py, a).map(Bound::unbind)).transpose()?,
    })
}

/// An arm's joint names and limits (radians or metres, per second for `velocity`).
fn arm_limits<'py>(py: Python<'py>, arm: &ArmRobot) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("names", arm.model.joint_names())?;
    d.set_item("lower", arm.limits.lower.clone())?;
    d.set_item("upper", arm.limits.upper.clone())?;
    d.set_item("velocity", arm.limits.velocity.clone())?;
    Ok(d)
}

/// Runs many scenarios (Scenario objects, dicts, JSON texts, built-in names or TOML paths)
/// in parallel with the GIL released (recording off) and returns the table as a dict of NumPy
/// arrays, one row per scenario: status (str), iterations, the summary fields final_translation_error,
/// final_rotation_error, final_image_error, final_invariant_error, max_line_deviation,
/// observed_max_eps, pixel_sigma, translation_uncertainty, rotation_uncertainty (SI, NaN where
/// not measured), prop1, prop2, within_tolerance, message (str). A scenario whose configuration
/// is invalid raises before anything runs; a run that fails on the way has status "error" and
/// its message.
///
/// `progress`: None, or a callable `progress(done, total)` called from the calling thread as
/// runs finish (`done` increasing to `total`); `vsinv.sim.run_batch` draws a tqdm bar instead
/// for None, True or False. Ctrl-C or an exception of `progress` stops the batch and is raised.
/// Works in a process forked after earlier batches (the pools are rebuilt).
#[pyfunction]
#[pyo3(signature = (scenarios, threads = None, allow_outside_files = false, progress = None))]
pub fn run_batch<'py>(
    py: Python<'py>,
    scenarios: &Bound<'py, PyAny>,
    #[pyo3(from_py_with = super::args::threads)] threads: Option<usize>,
    allow_outside_files: bool,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    check_progress(progress.as_ref())?;
    let access = access(allow_outside_files);
    let texts = batch_texts(scenarios, access)?;
    let started = std::time::Instant::now();
    log(py, INFO, || format!("run_batch: {} scenarios on {}", texts.len(), threads_text(threads)))?;
    let results = run_reporting(py, &texts, threads, access, progress.as_ref())?;
    let mut table = BatchTable::with_capacity(results.len());
    results.iter().for_each(|r| table.push(r));
    log(py, INFO, || {
        let converged = table.status.iter().filter(|s| *s == "converged").count();
        let errors = table.status.iter().filter(|s| *s == "error").count();
        let (n, secs) = (table.status.len(), started.elapsed().as_secs_f64());
        format!("run_batch: {n} runs in {secs:.4} s: {converged} converged, {errors} errors")
    })?;
    table.into_dict(py)
}

/// A thread count for messages.
fn threads_text(threads: Option<usize>) -> String {
    threads.map_or_else(|| "all cores".into(), |n| format!("{n} threads"))
}

/// The batch's scenarios as JSON texts (compact; a large batch keeps no configuration: see
/// `run_json_batch`). Dictionaries are read here (the GIL is needed) and written as
/// text in Rust; parsing, validation and the runs happen in parallel with the GIL released.
fn batch_texts(scenarios: &Bound<'_, PyAny>, access: FileAccess) -> PyResult<Vec<String>> {
    let py = scenarios.py();
    let mut texts = Vec::new();
    // Names and paths repeat in a batch: load each once.
    let mut loaded: std::collections::HashMap<String, String> = std::collections::HashMap::new();
    for (i, item) in scenarios.try_iter()?.enumerate() {
        let item = item?;
        let key = item.cast::<PyString>().ok().map(|s| s.to_string());
        if let Some(text) = key.as_ref().and_then(|k| loaded.get(k)) {
            texts.push(text.clone());
            continue;
        }
        let text = if item.cast::<PyDict>().is_ok() {
            // Read here and written as compact text in Rust; errors name `[i].key`.
            let value = scenario_value_at(&item, Some(i))?;
            serde_json::to_string(&value).map_err(|e| invalid_argument("scenario", format!("scenario {i}: {e}")))?
        } else {
            batch_text(&item, access).map_err(|e| reraise(&e, format!("scenario {i}: {}", e.value(py)), None))?
        };
        if let Some(k) = key {
            loaded.insert(k, text.clone());
        }
        texts.push(text);
    }
    Ok(texts)
}

/// Opens a JSON object (written as an escape so that the braces of this file stay balanced).
const JSON_OBJECT_START: char = '\u{7b}';

/// One batch item (not a dictionary) as JSON: a JSON text as it is (sweeps serialise while
/// the previous chunk runs), anything else loaded as a scenario (name, file, Scenario).
fn batch_text(item: &Bound<'_, PyAny>, access: FileAccess) -> PyResult<String> {
    if let Ok(s) = item.cast::<PyString>()
        && s.to_cow()?.trim_start().starts_with(JSON_OBJECT_START)
    {
        return s.extract::<String>();
    }
    Ok(scenario_arg_with(item, access)?.to_json()?)
}

/// The numbers of `run_batch`'s table (summary fields, SI).
const BATCH_FIELDS: [&str; 9] = [
    "final_translation_error",
    "final_rotation_error",
    "final_image_error",
    "final_invariant_error",
    "max_line_deviation",
    "observed_max_eps",
    "pixel_sigma",
    "translation_uncertainty",
    "rotation_uncertainty",
];

/// `run_batch`'s table, one row per run.
pub(super) struct BatchTable {
    status: Vec<String>,
    message: Vec<String>,
    iterations: Vec<i64>,
    floats: [Vec<f64>; 9],
    prop1: Vec<bool>,
    prop2: Vec<bool>,
    within: Vec<bool>,
}

impl BatchTable {
    pub(super) fn with_capacity(m: usize) -> Self {
        Self {
            status: Vec::with_capacity(m),
            message: Vec::with_capacity(m),
            iterations: Vec::with_capacity(m),
            floats: [(); 9].map(|_| Vec::with_capacity(m)),
            prop1: Vec::with_capacity(m),
            prop2: Vec::with_capacity(m),
            within: Vec::with_capacity(m),
        }
    }

    /// A run's row: its summary, or status "error" and the message.
    pub(super) fn push(&mut self, result: &crate::sim::error::Result<crate::sim::outcome::Summary>) {
        let s = match result {
            Ok(s) => s,
            Err(e) => return self.push_error(e),
        };
        self.status.push(s.status.as_str().to_string());
        self.message.push(s.message.clone());
        self.iterations.push(s.iterations as i64);
        for (column, name) in self.floats.iter_mut().zip(BATCH_FIELDS) {
            column.push(summary_field(name).and_then(|f| (f.value)(s)).unwrap_or(f64::NAN));
        }
        self.prop1.push(s.prop1);
        self.prop2.push(s.prop2);
        self.within.push(s.within_tolerance);
    }

    /// A run that failed on the way: status "error" and its message.
    fn push_error(&mut self, e: &crate::sim::SimError) {
        self.status.push("error".to_string());
        self.message.push(e.to_string());
        self.iterations.push(0);
        self.floats.iter_mut().for_each(|c| c.push(f64::NAN));
        self.prop1.push(false);
        self.prop2.push(false);
        self.within.push(false);
    }

    /// The table as a dict of NumPy arrays (strings as a `str` array).
    pub(super) fn into_dict(self, py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
        let np = py.import("numpy")?;
        let d = PyDict::new(py);
        let str_array = |v: Vec<String>| -> PyResult<Bound<'_, PyAny>> {
            let kwargs = PyDict::new(py);
            kwargs.set_item("dtype", "str")?;
            np.call_method("array", (v,), Some(&kwargs))
        };
        d.set_item("status", str_array(self.status)?)?;
        d.set_item("iterations", PyArray1::from_vec(py, self.iterations))?;
        for (name, c) in BATCH_FIELDS.iter().zip(self.floats) {
            d.set_item(*name, PyArray1::from_vec(py, c))?;
        }
        d.set_item("prop1", PyArray1::from_vec(py, self.prop1))?;
        d.set_item("prop2", PyArray1::from_vec(py, self.prop2))?;
        d.set_item("within_tolerance", PyArray1::from_vec(py, self.within))?;
        d.set_item("message", str_array(self.message)?)?;
        Ok(d)
    }
}

/// Adds scenarios and the simulator.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyScenario>()?;
    m.add_class::<PyRunResult>()?;
    add_column_properties(m.py())?;
    m.add_function(wrap_pyfunction!(recorded_columns, m)?)?;
    m.add_function(wrap_pyfunction!(summary_fields, m)?)?;
    m.add_function(wrap_pyfunction!(load_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(list_scenarios, m)?)?;
    m.add_function(wrap_pyfunction!(run_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(run_batch, m)?)?;
    Ok(())
}
