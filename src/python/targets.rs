//! `vsinv._core.TARGETS`: the vision layer's table of the targets
//! ([`TARGETS`](crate::vision::targets::TARGETS)), for the layers written in Python (the
//! `--target` choices, the ROS parameter `target`, the docs); and `TRACKER_SETTINGS`, the dot
//! tracker's settings ([`TRACKER_SETTINGS`](crate::vision::tracker::TRACKER_SETTINGS): the
//! dots' argument `tracker`, the ROS parameters `tracker.*`, the command options).

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::vision::targets::{ArgDefault, ArgKind, TARGETS, TargetArg, TargetSpec};
use crate::vision::tracker::{SettingKind, TRACKER_SETTINGS, TrackerSetting};

/// One argument as a dict: name, kind, choices, min, max, default (a str, an int or None),
/// required, doc.
fn arg_dict<'py>(py: Python<'py>, a: &TargetArg) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("name", a.name)?;
    d.set_item("kind", a.kind.name())?;
    let choices: &[&str] = if let ArgKind::Choice(names) = a.kind { names } else { &[] };
    d.set_item("choices", PyTuple::new(py, choices)?)?;
    let (min, max) = if let ArgKind::Count { min, max } = a.kind { (Some(min), Some(max)) } else { (None, None) };
    d.set_item("min", min)?;
    d.set_item("max", max)?;
    match a.default {
        None => d.set_item("default", py.None())?,
        Some(ArgDefault::Name(name)) => d.set_item("default", name)?,
        Some(ArgDefault::Count(n)) => d.set_item("default", n)?,
    }
    d.set_item("required", a.required)?;
    d.set_item("doc", a.doc)?;
    Ok(d)
}

/// One target as a dict: name, doc, detector (name, module, doc), args, scenario_keys,
/// simulated.
fn target_dict<'py>(py: Python<'py>, t: &TargetSpec) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("name", t.name)?;
    d.set_item("doc", t.doc)?;
    let detector = PyDict::new(py);
    detector.set_item("name", t.detector.name)?;
    detector.set_item("module", t.detector.module)?;
    detector.set_item("doc", t.detector.doc)?;
    d.set_item("detector", detector)?;
    let args: Vec<Bound<'_, PyDict>> = t.args.iter().map(|a| arg_dict(py, a)).collect::<PyResult<_>>()?;
    d.set_item("args", PyTuple::new(py, args)?)?;
    d.set_item("scenario_keys", PyTuple::new(py, t.scenario_keys)?)?;
    d.set_item("simulated", t.simulated)?;
    Ok(d)
}

/// One tracker setting as a dict: name, kind ("number", "count", "choice"), default (a float,
/// an int or a str), min, min_open, choices, unit, doc.
fn setting_dict<'py>(py: Python<'py>, s: &TrackerSetting) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("name", s.name)?;
    d.set_item("kind", s.kind.name())?;
    let bad_default = || pyo3::exceptions::PyRuntimeError::new_err(format!("tracker setting {}: default", s.name));
    let (default, min, min_open, choices): (Bound<'py, PyAny>, Option<f64>, bool, &[&str]) = match s.kind {
        SettingKind::Number { min, strict } => {
            let x: f64 = s.default.parse().map_err(|_| bad_default())?;
            (x.into_pyobject(py)?.into_any(), Some(min), strict, &[])
        }
        SettingKind::Count => {
            let n: usize = s.default.parse().map_err(|_| bad_default())?;
            (n.into_pyobject(py)?.into_any(), Some(0.0), false, &[])
        }
        SettingKind::Choice(names) => (s.default.into_pyobject(py)?.into_any(), None, false, names),
    };
    d.set_item("default", default)?;
    d.set_item("min", min)?;
    d.set_item("min_open", min_open)?;
    d.set_item("choices", PyTuple::new(py, choices)?)?;
    d.set_item("unit", s.unit)?;
    d.set_item("doc", s.doc)?;
    Ok(d)
}

/// Adds `TARGETS` and `TRACKER_SETTINGS`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    let table: Vec<Bound<'_, PyDict>> = TARGETS.iter().map(|t| target_dict(py, t)).collect::<PyResult<_>>()?;
    m.add("TARGETS", PyTuple::new(py, table)?)?;
    let settings: Vec<Bound<'_, PyDict>> =
        TRACKER_SETTINGS.iter().map(|s| setting_dict(py, s)).collect::<PyResult<_>>()?;
    m.add("TRACKER_SETTINGS", PyTuple::new(py, settings)?)?;
    Ok(())
}
