//! Bindings of the scenario runner: scenarios from files, built-in names or dictionaries,
//! runs with the GIL released, and recordings handed to NumPy without copying.

use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

use super::errors::{PyError, invalid_argument, reraise};
use crate::sim::arm::ArmRobot;
use crate::sim::robot::Robot;
use crate::sim::scenario::{BUILTIN, FileAccess, Scenario, builtin};
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
    /// The scenario as a dictionary (every default filled in); edit it and pass it back to
    /// `run_scenario` or `Scenario.from_dict`.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let text = self.inner.to_json()?;
        py.import("json")?.call_method1("loads", (text,))
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
    let py = d.py();
    let text: String = py
        .import("json")?
        .call_method1("dumps", (d,))
        .map_err(|e| invalid_argument("scenario", format!("scenario: cannot be written as JSON ({e})")))?
        .extract()?;
    Ok(Scenario::from_json_with(&text, access)?)
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

/// Loads a scenario from a built-in name, a TOML file path or a dictionary. The files it
/// names (`calibration`, `robot.urdf`) must be inside its folder (the working directory for
/// a dictionary) unless `allow_outside_files`.
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

/// The result of a run: `.summary` (a dict) and the recorded arrays, NumPy views of the
/// simulator's buffers (one row per iteration).
#[pyclass(name = "RunResult", module = "vsinv._core", frozen)]
pub struct PyRunResult {
    /// The run's summary (status, iterations, final errors, ...), a dict.
    #[pyo3(get)]
    summary: Py<PyDict>,
    /// The scenario that was run.
    #[pyo3(get)]
    scenario: Py<PyScenario>,
    /// Time, s, (N,).
    #[pyo3(get)]
    time: Py<PyAny>,
    /// Camera pose in F*, (N, 4, 4).
    #[pyo3(get)]
    pose: Py<PyAny>,
    /// Twist sent to the robot (NaN on the last row when no step followed), (N, 6).
    #[pyo3(get)]
    twist: Py<PyAny>,
    /// Joint positions, (N, 6).
    #[pyo3(get)]
    joints: Py<PyAny>,
    /// Measured pixels (NaN where not visible), (N, n, 2).
    #[pyo3(get)]
    pixels: Py<PyAny>,
    /// Visibility, bool (N, n).
    #[pyo3(get)]
    visible: Py<PyAny>,
    /// ||s - s*|| (to the reference image), (N,).
    #[pyo3(get)]
    invariant_error: Py<PyAny>,
    /// ||s - s*(t)|| (to the moving reference of a planned path; NaN outside the invariant
    /// law), (N,).
    #[pyo3(get)]
    tracking_error: Py<PyAny>,
    /// Task function eps (NaN for IBVS), (N, 5).
    #[pyo3(get)]
    eps: Py<PyAny>,
    /// eps_z = det(Q*) tau_21, (N,).
    #[pyo3(get)]
    eps_z: Py<PyAny>,
    /// Largest pixel error of a visible point, (N,).
    #[pyo3(get)]
    image_error: Py<PyAny>,
    /// Distance from the reference pose, metres, (N,).
    #[pyo3(get)]
    translation_error: Py<PyAny>,
    /// Angle from the reference pose, radians, (N,).
    #[pyo3(get)]
    rotation_error: Py<PyAny>,
    /// Reference pixels (with their noise, if any), (n, 2).
    #[pyo3(get)]
    reference_pixels: Py<PyAny>,
    /// Per iteration and point, the tracked centroid's distance to the true projection of
    /// the dot's centre (pixels, NaN where not found), (N, n); None without `[vision]`.
    #[pyo3(get)]
    detection_error: Option<Py<PyAny>>,
    /// Per iteration, the commanded joint velocities of an arm (rad/s or m/s), (N, n_joints);
    /// None for other robots.
    #[pyo3(get)]
    joint_velocities: Option<Py<PyAny>>,
    /// An arm's joint names and position and velocity limits (a dict); None for other robots.
    #[pyo3(get)]
    joint_limits: Option<Py<PyDict>>,
}

#[pymethods]
impl PyRunResult {
    /// The recorded arrays by name.
    #[getter]
    fn arrays<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("time", self.time.bind(py))?;
        d.set_item("pose", self.pose.bind(py))?;
        d.set_item("twist", self.twist.bind(py))?;
        d.set_item("joints", self.joints.bind(py))?;
        d.set_item("pixels", self.pixels.bind(py))?;
        d.set_item("visible", self.visible.bind(py))?;
        d.set_item("invariant_error", self.invariant_error.bind(py))?;
        d.set_item("tracking_error", self.tracking_error.bind(py))?;
        d.set_item("eps", self.eps.bind(py))?;
        d.set_item("eps_z", self.eps_z.bind(py))?;
        d.set_item("image_error", self.image_error.bind(py))?;
        d.set_item("translation_error", self.translation_error.bind(py))?;
        d.set_item("rotation_error", self.rotation_error.bind(py))?;
        d.set_item("reference_pixels", self.reference_pixels.bind(py))?;
        if let Some(e) = &self.detection_error {
            d.set_item("detection_error", e.bind(py))?;
        }
        if let Some(v) = &self.joint_velocities {
            d.set_item("joint_velocities", v.bind(py))?;
        }
        Ok(d)
    }
    fn __repr__(&self, py: Python<'_>) -> String {
        let s = self.summary.bind(py);
        let get = |k: &str| s.get_item(k).ok().flatten().map_or("?".into(), |v| v.to_string());
        format!("RunResult(status={}, iterations={})", get("status"), get("iterations"))
    }
}

/// Moves a buffer into NumPy (no copy) and views it with `shape`.
fn array<T: numpy::Element>(py: Python<'_>, data: Vec<T>, shape: &[usize]) -> PyResult<Py<PyAny>> {
    Ok(PyArray1::from_vec(py, data).reshape(shape)?.into_any().unbind())
}

/// The summary as a dictionary (millimetres and degrees for the pose errors).
pub fn summary_dict<'py>(py: Python<'py>, name: &str, o: &Outcome) -> PyResult<Bound<'py, PyDict>> {
    let s = &o.summary;
    let d = PyDict::new(py);
    d.set_item("name", name)?;
    d.set_item("status", s.status.as_str())?;
    d.set_item("message", &s.message)?;
    d.set_item("iterations", s.iterations)?;
    d.set_item("final_translation_error_mm", s.final_translation_error * 1e3)?;
    d.set_item("final_rotation_error_deg", s.final_rotation_error.to_degrees())?;
    d.set_item("final_image_error_px", s.final_image_error)?;
    d.set_item("final_invariant_error", s.final_invariant_error)?;
    d.set_item("final_tau_11", s.final_tau[0])?;
    d.set_item("final_tau_21", s.final_tau[1])?;
    d.set_item("final_tau_22", s.final_tau[2])?;
    d.set_item("prop1", s.prop1)?;
    d.set_item("prop2", s.prop2)?;
    d.set_item("stop_rule", format!("{:?}", s.stop_rule).to_lowercase())?;
    d.set_item("start_translation_error_mm", s.start_error.0 * 1e3)?;
    d.set_item("start_rotation_error_deg", s.start_error.1.to_degrees())?;
    d.set_item("basis", s.basis.to_vec())?;
    d.set_item("max_line_deviation_mm", s.max_line_deviation * 1e3)?;
    d.set_item("peak_linear_speed_m_s", s.peak_speeds.0)?;
    d.set_item("peak_angular_speed_deg_s", s.peak_speeds.1.to_degrees())?;
    let t = s.tracking.as_ref();
    d.set_item("path_duration_s", t.map(|t| t.duration))?;
    d.set_item("plane_parallax_residual", t.map(|t| t.plane_parallax_residual))?;
    d.set_item("tracking_sigma", t.map(|t| t.sigma))?;
    d.set_item("tracking_psi", t.map(|t| t.psi))?;
    d.set_item("tracking_phi", t.map(|t| t.phi))?;
    d.set_item("tracking_bound", t.map(|t| t.bound))?;
    d.set_item("observed_max_eps", t.map(|t| t.max_eps))?;
    d.set_item("detection_error_median_px", s.detection_error.map(|e| e.0))?;
    d.set_item("detection_error_max_px", s.detection_error.map(|e| e.1))?;
    d.set_item("min_manipulability", s.min_manipulability)?;
    let c = s.certainty.as_ref();
    d.set_item("pixel_sigma_px", c.map(|c| c.pixel_sigma))?;
    d.set_item("reference_pixel_sigma_px", c.map(|c| c.reference_pixel_sigma))?;
    d.set_item("translation_sigma_mm", c.map(|c| c.sigma.0 * 1e3))?;
    d.set_item("rotation_sigma_deg", c.map(|c| c.sigma.1.to_degrees()))?;
    d.set_item("translation_uncertainty_mm", c.map(|c| c.bound.0 * 1e3))?;
    d.set_item("rotation_uncertainty_deg", c.map(|c| c.bound.1.to_degrees()))?;
    d.set_item("within_tolerance", s.within_tolerance)?;
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
    if let Some(cb) = &progress
        && !cb.bind(py).is_callable()
    {
        let kind = cb.bind(py).get_type().name()?.to_string();
        return Err(pyo3::exceptions::PyTypeError::new_err(format!(
            "progress: expected a callable progress(done, total) or None, got {kind}"
        )));
    }
    let scenario = scenario_arg_with(scenario, access(allow_outside_files))?;
    let mut config = scenario.to_config()?;
    config.record = record;
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
    let mut outcome = outcome?;
    let summary = summary_dict(py, &scenario.name, &outcome)?;
    let r = outcome.recording.take().unwrap_or_default();
    let (rows, n) = (r.len(), scenario.object.points.len());
    let n_joints = if let Robot::Arm(arm) = &config.robot { arm.dof() } else { 6 };
    let joint_limits = match &config.robot {
        Robot::Arm(arm) => Some(arm_limits(py, arm)?.unbind()),
        _ => None,
    };
    let joint_velocities = match joint_limits {
        Some(_) => Some(array(py, r.joint_velocities, &[rows, n_joints])?),
        None => None,
    };
    let reference = std::mem::take(&mut outcome.reference_pixels);
    Ok(PyRunResult {
        summary: summary.unbind(),
        scenario: Py::new(py, PyScenario { inner: scenario })?,
        time: array(py, r.time, &[rows])?,
        pose: array(py, r.pose, &[rows, 4, 4])?,
        twist: array(py, r.twist, &[rows, 6])?,
        joints: array(py, r.joints, &[rows, n_joints])?,
        pixels: array(py, r.pixels, &[rows, n, 2])?,
        visible: array(py, r.visible, &[rows, n])?,
        invariant_error: array(py, r.invariant_error, &[rows])?,
        tracking_error: array(py, r.tracking_error, &[rows])?,
        eps: array(py, r.eps, &[rows, 5])?,
        eps_z: array(py, r.eps_z, &[rows])?,
        image_error: array(py, r.image_error, &[rows])?,
        translation_error: array(py, r.translation_error, &[rows])?,
        rotation_error: array(py, r.rotation_error, &[rows])?,
        reference_pixels: array(py, reference.into_flattened(), &[n, 2])?,
        detection_error: match outcome.summary.detection_error {
            Some(_) => Some(array(py, r.detection_error, &[rows, n])?),
            None => None,
        },
        joint_velocities,
        joint_limits,
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
/// in parallel with the GIL released (recording off) and returns the
/// table as a dict of NumPy arrays, one row per scenario: status (str), iterations,
/// final_translation_error_mm, final_rotation_error_deg, final_image_error_px,
/// final_invariant_error, prop1, prop2, max_line_deviation_mm, observed_max_eps,
/// pixel_sigma_px, translation_uncertainty_mm, rotation_uncertainty_deg (NaN where not
/// measured), within_tolerance, message (str). A scenario
/// whose configuration is invalid raises before anything runs; a run that fails on the way
/// has status "error" and its message.
#[pyfunction]
#[pyo3(signature = (scenarios, threads = None, allow_outside_files = false))]
pub fn run_batch<'py>(
    py: Python<'py>,
    scenarios: &Bound<'py, PyAny>,
    #[pyo3(from_py_with = super::args::threads)] threads: Option<usize>,
    allow_outside_files: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let access = access(allow_outside_files);
    let texts = batch_texts(scenarios, access)?;
    let results = py.detach(|| crate::sim::batch::run_json_batch_with(&texts, threads, access))?;
    let mut table = BatchTable::with_capacity(results.len());
    results.iter().for_each(|r| table.push(r));
    table.into_dict(py)
}

/// The batch's scenarios as JSON texts. Dictionaries become JSON here (the GIL is needed);
/// parsing, validation and the runs happen in parallel with the GIL released.
fn batch_texts(scenarios: &Bound<'_, PyAny>, access: FileAccess) -> PyResult<Vec<String>> {
    let py = scenarios.py();
    let dumps = py.import("json")?.getattr("dumps")?;
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
            dumps.call1((&item,)).and_then(|t| t.extract::<String>())
        } else if let Ok(s) = item.cast::<PyString>()
            && s.to_str()?.trim_start().starts_with('{')
        {
            // A scenario already written as JSON (sweeps serialise while the previous chunk runs).
            s.extract::<String>()
        } else {
            scenario_arg_with(&item, access).and_then(|s| Ok(s.to_json()?))
        };
        let text = text.map_err(|e| reraise(&e, format!("scenario {i}: {}", e.value(py)), None))?;
        if let Some(k) = key {
            loaded.insert(k, text.clone());
        }
        texts.push(text);
    }
    Ok(texts)
}

/// The float columns of `run_batch`'s table, in the order of [`BatchTable::floats`].
const BATCH_FLOAT_COLUMNS: [&str; 9] = [
    "final_translation_error_mm",
    "final_rotation_error_deg",
    "final_image_error_px",
    "final_invariant_error",
    "max_line_deviation_mm",
    "observed_max_eps",
    "pixel_sigma_px",
    "translation_uncertainty_mm",
    "rotation_uncertainty_deg",
];

/// `run_batch`'s table, one row per run.
struct BatchTable {
    status: Vec<String>,
    message: Vec<String>,
    iterations: Vec<i64>,
    floats: [Vec<f64>; 9],
    prop1: Vec<bool>,
    prop2: Vec<bool>,
    within: Vec<bool>,
}

impl BatchTable {
    fn with_capacity(m: usize) -> Self {
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
    fn push(&mut self, result: &crate::Result<crate::sim::outcome::Summary>) {
        let s = match result {
            Ok(s) => s,
            Err(e) => return self.push_error(e),
        };
        self.status.push(s.status.as_str().to_string());
        self.message.push(s.message.clone());
        self.iterations.push(s.iterations as i64);
        let values = [
            s.final_translation_error * 1e3,
            s.final_rotation_error.to_degrees(),
            s.final_image_error,
            s.final_invariant_error,
            s.max_line_deviation * 1e3,
            s.tracking.map_or(f64::NAN, |t| t.max_eps),
            s.certainty.map_or(f64::NAN, |c| c.pixel_sigma),
            s.certainty.map_or(f64::NAN, |c| c.bound.0 * 1e3),
            s.certainty.map_or(f64::NAN, |c| c.bound.1.to_degrees()),
        ];
        self.floats.iter_mut().zip(values).for_each(|(c, v)| c.push(v));
        self.prop1.push(s.prop1);
        self.prop2.push(s.prop2);
        self.within.push(s.within_tolerance);
    }

    /// A run that failed on the way: status "error" and its message.
    fn push_error(&mut self, e: &crate::Error) {
        self.status.push("error".to_string());
        self.message.push(e.to_string());
        self.iterations.push(0);
        self.floats.iter_mut().for_each(|c| c.push(f64::NAN));
        self.prop1.push(false);
        self.prop2.push(false);
        self.within.push(false);
    }

    /// The table as a dict of NumPy arrays (strings as a `str` array).
    fn into_dict(self, py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
        let np = py.import("numpy")?;
        let d = PyDict::new(py);
        let str_array = |v: Vec<String>| -> PyResult<Bound<'_, PyAny>> {
            let kwargs = PyDict::new(py);
            kwargs.set_item("dtype", "str")?;
            np.call_method("array", (v,), Some(&kwargs))
        };
        d.set_item("status", str_array(self.status)?)?;
        d.set_item("iterations", PyArray1::from_vec(py, self.iterations))?;
        for (name, c) in BATCH_FLOAT_COLUMNS.iter().zip(self.floats) {
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
    m.add_function(wrap_pyfunction!(load_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(list_scenarios, m)?)?;
    m.add_function(wrap_pyfunction!(run_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(run_batch, m)?)?;
    Ok(())
}
