//! The package's exception hierarchy, built when the module loads:
//! `VsinvError(Exception)`, `InvalidInput(VsinvError, ValueError)` and
//! `DegenerateGeometry(VsinvError, ValueError)` and `NotReady(VsinvError, RuntimeError)`.

use pyo3::exceptions::{PyException, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};

static VSINV_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static INVALID_INPUT: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static DEGENERATE: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static NOT_READY: PyOnceLock<Py<PyType>> = PyOnceLock::new();

fn new_class<'py>(py: Python<'py>, name: &str, bases: Bound<'py, PyTuple>, doc: &str) -> PyResult<Bound<'py, PyType>> {
    let dict = PyDict::new(py);
    dict.set_item("__module__", "vsinv")?;
    dict.set_item("__doc__", doc)?;
    let class = py.import("builtins")?.getattr("type")?.call1((name, bases, dict))?;
    Ok(class.cast_into::<PyType>()?)
}

/// Creates the classes and adds them to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    let base = VSINV_ERROR.get_or_try_init(py, || {
        let bases = PyTuple::new(py, [py.get_type::<PyException>()])?;
        Ok::<_, PyErr>(new_class(py, "VsinvError", bases, "Base class of every vsinv error.")?.unbind())
    })?;
    let base = base.bind(py).clone();
    let invalid = INVALID_INPUT.get_or_try_init(py, || {
        let bases = PyTuple::new(py, [base.clone(), py.get_type::<PyValueError>()])?;
        let doc = "Malformed input: NaN or infinity, wrong shape or dtype, invalid intrinsics or parameters.";
        Ok::<_, PyErr>(new_class(py, "InvalidInput", bases, doc)?.unbind())
    })?;
    let degenerate = DEGENERATE.get_or_try_init(py, || {
        let bases = PyTuple::new(py, [base.clone(), py.get_type::<PyValueError>()])?;
        let doc = "Geometry the method cannot work with: collinear basis points, fewer than 6 points, \
                   a planar object or equal depth estimates, points at or behind the camera.";
        Ok::<_, PyErr>(new_class(py, "DegenerateGeometry", bases, doc)?.unbind())
    })?;
    let not_ready = NOT_READY.get_or_try_init(py, || {
        let bases = PyTuple::new(py, [base.clone(), py.get_type::<PyRuntimeError>()])?;
        let doc = "A state read before it exists, e.g. a controller's eps before its first step.";
        Ok::<_, PyErr>(new_class(py, "NotReady", bases, doc)?.unbind())
    })?;
    m.add("VsinvError", base)?;
    m.add("NotReady", not_ready.bind(py))?;
    m.add("InvalidInput", invalid.bind(py))?;
    m.add("DegenerateGeometry", degenerate.bind(py))?;
    Ok(())
}

fn raise(cell: &PyOnceLock<Py<PyType>>, msg: String) -> PyErr {
    Python::attach(|py| match cell.get(py) {
        Some(ty) => PyErr::from_type(ty.bind(py).clone(), msg),
        None => PyRuntimeError::new_err(msg),
    })
}

/// `NotReady(msg)`.
pub fn not_ready(msg: &str) -> PyErr {
    raise(&NOT_READY, msg.to_string())
}

/// `InvalidInput(msg)`.
pub fn invalid_input(msg: String) -> PyErr {
    raise(&INVALID_INPUT, msg)
}

/// Maps a core error to the matching Python exception.
pub fn to_py(err: crate::Error) -> PyErr {
    if err.is_degenerate() { raise(&DEGENERATE, err.to_string()) } else { raise(&INVALID_INPUT, err.to_string()) }
}
