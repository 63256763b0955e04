//! `vsinv.laws.LAW_OPTIONS`: the servo layer's table of the laws' options, for the layers written
//! in Python (the ROS parameters, the CLI flags, the docs), with its check and its Markdown.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use super::errors::invalid_argument;
use crate::servo::law::options::{LAW_OPTIONS, OptionDefault, OptionKind, OptionSpec, markdown_table, option};

/// The option's default as a Python value (None when unset).
fn default_of<'py>(py: Python<'py>, o: &OptionSpec) -> PyResult<Bound<'py, PyAny>> {
    Ok(match o.default {
        OptionDefault::Number(v) => v.into_pyobject(py)?.into_any(),
        OptionDefault::Flag(v) => v.into_pyobject(py)?.to_owned().into_any(),
        OptionDefault::Choice(c) => c.into_pyobject(py)?.into_any(),
        OptionDefault::Unset => py.None().into_bound(py),
    })
}

/// One option as a dict: name, laws, kind, choices, default, min, max, min_open, max_open,
/// range (in words), unit, scenario_key, scenario_unit, doc.
fn option_dict<'py>(py: Python<'py>, o: &OptionSpec) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("name", o.name)?;
    d.set_item("laws", PyTuple::new(py, o.laws)?)?;
    d.set_item("kind", o.kind.name())?;
    let choices: &[&str] = if let OptionKind::Choice(names) = o.kind { names } else { &[] };
    d.set_item("choices", PyTuple::new(py, choices)?)?;
    d.set_item("default", default_of(py, o)?)?;
    d.set_item("min", o.range.map(|r| r.min))?;
    d.set_item("max", o.range.map(|r| r.max))?;
    d.set_item("min_open", o.range.map(|r| r.min_open))?;
    d.set_item("max_open", o.range.map(|r| r.max_open))?;
    d.set_item("range", o.range.map(|r| r.interval()))?;
    d.set_item("unit", o.unit)?;
    d.set_item("scenario_key", o.scenario_key())?;
    d.set_item("scenario_unit", o.scenario_unit())?;
    d.set_item("doc", o.doc)?;
    Ok(d)
}

/// Checks a value of the law option `name` as `Servo` would: `InvalidInput` naming the option (or its part,
/// `adaptive_gain.at_infinity`) for a value of another kind or out of its range.
#[pyfunction]
fn check_law_option(name: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
    let spec =
        option(name).ok_or_else(|| invalid_argument("name", format!("name: {name:?} is not an option of any law")))?;
    if let Some(v) = super::servo::option_value(spec, value)? {
        spec.check(&v)?;
    }
    Ok(())
}

/// The table of the laws' options as Markdown (name, laws, values, default, unit, scenario
/// key, meaning), for the reference pages of the docs.
#[pyfunction]
fn law_options_markdown() -> String {
    markdown_table()
}

/// Adds `LAW_OPTIONS` and its functions.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    let table: Vec<Bound<'_, PyDict>> = LAW_OPTIONS.iter().map(|o| option_dict(py, o)).collect::<PyResult<_>>()?;
    m.add("LAW_OPTIONS", PyTuple::new(py, table)?)?;
    m.add_function(wrap_pyfunction!(check_law_option, m)?)?;
    m.add_function(wrap_pyfunction!(law_options_markdown, m)?)?;
    Ok(())
}
