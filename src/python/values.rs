//! Structured data across the boundary: Python objects (dicts, lists, numbers, strings, NumPy
//! scalars and arrays) to `serde_json::Value` and back, walked directly (no JSON text).
//!
//! The rules are those the package had when dictionaries crossed as JSON text: what
//! `json.dumps` accepts (dict keys str, int, float, bool or None; lists and tuples; NumPy
//! values through `tolist()`), numbers exactly (an `f64` is carried as itself; integers beyond
//! 64 bits as the nearest `f64`), and NaN or infinity refused, now with the key at fault.

use pyo3::IntoPyObjectExt;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::{Map, Number, Value};

/// How deep a value may nest (serde_json's own limit when it parsed the text).
const MAX_DEPTH: usize = 128;

/// A value that cannot cross: where (`a.b[2]`, empty for the whole value) and why.
#[derive(Debug, Clone, PartialEq)]
pub struct ConvertError {
    /// The dotted path of the entry at fault, list indices in brackets.
    pub path: String,
    /// What is wrong.
    pub reason: String,
}

/// One step of the path to a value.
enum Step {
    Key(String),
    Index(usize),
}

/// The walk's state: the path to the current value, the NumPy types (if NumPy is installed)
/// and how many values may still be read.
struct Walk<'py> {
    path: Vec<Step>,
    numpy: Option<(Bound<'py, PyAny>, Bound<'py, PyAny>)>,
    budget: usize,
}

impl Walk<'_> {
    fn error(&self, reason: String) -> ConvertError {
        let mut path = String::new();
        for step in &self.path {
            match step {
                Step::Key(k) if path.is_empty() => path.push_str(k),
                Step::Key(k) => {
                    path.push('.');
                    path.push_str(k);
                }
                Step::Index(i) => path.push_str(&format!("[{i}]")),
            }
        }
        ConvertError { path, reason }
    }

    fn is_numpy(&self, obj: &Bound<'_, PyAny>) -> PyResult<bool> {
        match &self.numpy {
            Some((generic, ndarray)) => Ok(obj.is_instance(generic)? || obj.is_instance(ndarray)?),
            None => Ok(false),
        }
    }
}

/// A Python value as a `serde_json::Value`; at most `max_values` values (scalars and
/// containers) are read. Python errors (a `tolist()` that raises) are returned as they are.
pub fn to_value(obj: &Bound<'_, PyAny>, max_values: usize) -> PyResult<Result<Value, ConvertError>> {
    let py = obj.py();
    let numpy = match py.import("numpy") {
        Ok(np) => Some((np.getattr("generic")?, np.getattr("ndarray")?)),
        Err(_) => None,
    };
    let mut walk = Walk { path: Vec::new(), numpy, budget: max_values };
    walk_value(&mut walk, obj)
}

fn walk_value(w: &mut Walk<'_>, obj: &Bound<'_, PyAny>) -> PyResult<Result<Value, ConvertError>> {
    if w.path.len() > MAX_DEPTH {
        return Ok(Err(w.error(format!("nested more than {MAX_DEPTH} levels deep"))));
    }
    if w.budget == 0 {
        return Ok(Err(w.error("more values than a scenario may hold".into())));
    }
    w.budget -= 1;
    if obj.is_none() {
        return Ok(Ok(Value::Null));
    }
    if let Ok(b) = obj.cast::<PyBool>() {
        return Ok(Ok(Value::Bool(b.is_true())));
    }
    if let Ok(i) = obj.cast::<PyInt>() {
        return Ok(int_value(w, i));
    }
    if let Ok(f) = obj.cast::<PyFloat>() {
        return Ok(float_value(w, f.value()));
    }
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(Ok(Value::String(s.to_cow()?.into_owned())));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        return walk_dict(w, d);
    }
    if obj.cast::<PyList>().is_ok() || obj.cast::<PyTuple>().is_ok() {
        return walk_items(w, obj);
    }
    if w.is_numpy(obj)? {
        w.budget += 1; // the list it becomes is counted
        return walk_value(w, &obj.call_method0("tolist")?);
    }
    let kind = obj.get_type().name()?;
    Ok(Err(w.error(format!("Object of type {kind} is not JSON serializable"))))
}

/// An int exactly when it fits 64 bits, else the nearest `f64` (as the JSON text was read).
fn int_value(w: &Walk<'_>, i: &Bound<'_, PyInt>) -> Result<Value, ConvertError> {
    if let Ok(v) = i.extract::<i64>() {
        return Ok(Value::from(v));
    }
    if let Ok(v) = i.extract::<u64>() {
        return Ok(Value::from(v));
    }
    match i.extract::<f64>() {
        Ok(v) => float_value(w, v),
        Err(_) => Err(w.error("number out of range".into())),
    }
}

/// A finite float as itself; NaN and infinity refused.
fn float_value(w: &Walk<'_>, v: f64) -> Result<Value, ConvertError> {
    match Number::from_f64(v) {
        Some(n) => Ok(Value::Number(n)),
        None => Err(w.error(format!("expected a finite number, got {v}"))),
    }
}

fn walk_dict(w: &mut Walk<'_>, d: &Bound<'_, PyDict>) -> PyResult<Result<Value, ConvertError>> {
    let mut map = Map::with_capacity(d.len());
    for (k, v) in d.iter() {
        let key = match dict_key(&k)? {
            Some(key) => key,
            None => {
                let kind = k.get_type().name()?;
                return Ok(Err(w.error(format!("keys must be str, int, float, bool or None, not {kind}"))));
            }
        };
        w.path.push(Step::Key(key.clone()));
        let value = walk_value(w, &v)?;
        w.path.pop();
        match value {
            Ok(value) => map.insert(key, value),
            Err(e) => return Ok(Err(e)),
        };
    }
    Ok(Ok(Value::Object(map)))
}

/// A dict key as `json.dumps` writes it (None for a key it refuses).
fn dict_key(k: &Bound<'_, PyAny>) -> PyResult<Option<String>> {
    if let Ok(s) = k.cast::<PyString>() {
        return Ok(Some(s.to_cow()?.into_owned()));
    }
    if k.is_none() {
        return Ok(Some("null".into()));
    }
    if let Ok(b) = k.cast::<PyBool>() {
        return Ok(Some(if b.is_true() { "true" } else { "false" }.into()));
    }
    if k.cast::<PyInt>().is_ok() || k.cast::<PyFloat>().is_ok() {
        return Ok(Some(k.repr()?.to_cow()?.into_owned()));
    }
    Ok(None)
}

fn walk_items(w: &mut Walk<'_>, seq: &Bound<'_, PyAny>) -> PyResult<Result<Value, ConvertError>> {
    let mut items = Vec::with_capacity(seq.len()?);
    for (i, item) in seq.try_iter()?.enumerate() {
        w.path.push(Step::Index(i));
        let value = walk_value(w, &item?)?;
        w.path.pop();
        match value {
            Ok(value) => items.push(value),
            Err(e) => return Ok(Err(e)),
        }
    }
    Ok(Ok(Value::Array(items)))
}

/// A `serde_json::Value` as Python objects: dicts (in the value's key order), lists, ints,
/// floats (the same `f64`), strings, bools and None.
pub fn to_python<'py>(py: Python<'py>, value: &Value) -> PyResult<Bound<'py, PyAny>> {
    match value {
        Value::Null => Ok(py.None().into_bound(py)),
        Value::Bool(b) => b.into_bound_py_any(py),
        Value::Number(n) => number(py, n),
        Value::String(s) => s.into_bound_py_any(py),
        Value::Array(items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(to_python(py, item)?)?;
            }
            Ok(list.into_any())
        }
        Value::Object(map) => {
            let dict = PyDict::new(py);
            for (k, v) in map {
                dict.set_item(k, to_python(py, v)?)?;
            }
            Ok(dict.into_any())
        }
    }
}

fn number<'py>(py: Python<'py>, n: &Number) -> PyResult<Bound<'py, PyAny>> {
    if let Some(i) = n.as_i64() {
        return i.into_bound_py_any(py);
    }
    if let Some(u) = n.as_u64() {
        return u.into_bound_py_any(py);
    }
    n.as_f64().unwrap_or(f64::NAN).into_bound_py_any(py)
}
