//! `vsinv._core.TARGETS`: the vision layer's table of the targets
//! ([`TARGETS`](crate::vision::targets::TARGETS)), for the layers written in Python (the
//! `--target` choices, the ROS parameter `target`, the docs).

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::vision::targets::{ArgKind, TARGETS, TargetArg, TargetSpec};

/// One argument as a dict: name, kind, choices, min, max, default, required, doc.
fn arg_dict<'py>(py: Python<'py>, a: &TargetArg) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("name", a.name)?;
    d.set_item("kind", a.kind.name())?;
    let choices: &[&str] = if let ArgKind::Choice(names) = a.kind { names } else { &[] };
    d.set_item("choices", PyTuple::new(py, choices)?)?;
    let (min, max) = if let ArgKind::Count { min, max } = a.kind { (Some(min), Some(max)) } else { (None, None) };
    d.set_item("min", min)?;
    d.set_item("max", max)?;
    d.set_item("default", a.default)?;
    d.set_item("required", a.required)?;
    d.set_item("doc", a.doc)?;
    Ok(d)
}

/// One target as a dict: name, doc, detector (name, module, doc), args, scenario_keys.
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
    Ok(d)
}

/// Adds `TARGETS`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    let table: Vec<Bound<'_, PyDict>> = TARGETS.iter().map(|t| target_dict(py, t)).collect::<PyResult<_>>()?;
    m.add("TARGETS", PyTuple::new(py, table)?)?;
    Ok(())
}
