//! `RunResult.from_recording`: a run recorded outside the Rust simulator (the MuJoCo world's
//! loop, in Python) made into a `RunResult` of the same schema, its summary and columns
//! checked against the declarations (`SUMMARY_FIELDS`, `COLUMNS`).

use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyString};

use super::arrays::f64_array;
use super::errors::{invalid_argument, shape_error};
use crate::sim::outcome::{COLUMNS, Column, Recorded, SUMMARY_FIELDS, Status, StopRule};

/// The summary's keys other than the numbers of `SUMMARY_FIELDS`, in `summary_dict`'s order.
const HEAD: [&str; 10] = [
    "name",
    "status",
    "message",
    "iterations",
    "stop_rule",
    "prop1",
    "prop2",
    "within_tolerance",
    "basis",
    "basis_switches",
];

const STATUSES: [Status; 10] = [
    Status::Converged,
    Status::MaxIterations,
    Status::LostFeatures,
    Status::Diverged,
    Status::Degenerate,
    Status::RzTrap,
    Status::Observed,
    Status::JointLimit,
    Status::Singular,
    Status::Settled,
];

/// The recorded columns of `arrays`, in the order of `COLUMNS` (None where absent), each a
/// new C-contiguous array of its declared dtype and shape.
pub fn columns_of(arrays: &Bound<'_, PyDict>) -> PyResult<(Vec<Option<Py<PyAny>>>, usize)> {
    for key in arrays.keys() {
        let name: String =
            key.extract().map_err(|_| invalid_argument("arrays", "arrays: keys must be strings".into()))?;
        if !COLUMNS.iter().any(|c| c.name == name) {
            let known: Vec<&str> = COLUMNS.iter().map(|c| c.name).collect();
            let msg = format!("arrays[{name:?}]: not a recorded column (known: {})", known.join(", "));
            return Err(invalid_argument("arrays", msg));
        }
    }
    let get = |name: &str| arrays.get_item(name);
    let time = f64_array(&req(arrays, "time")?, "arrays[\"time\"]", &[None])?;
    let rows = time.shape()[0];
    check_time(time.as_slice()?)?;
    let reference = f64_array(&req(arrays, "reference_pixels")?, "arrays[\"reference_pixels\"]", &[None, Some(2)])?;
    let points = reference.shape()[0];
    let joints = f64_array(&req(arrays, "joints")?, "arrays[\"joints\"]", &[Some(rows), None])?;
    let n_joints = joints.shape()[1];
    let mut out = Vec::with_capacity(COLUMNS.len());
    for c in &COLUMNS {
        let Some(obj) = get(c.name)? else {
            if c.recorded == Recorded::Always {
                return Err(invalid_argument(
                    "arrays",
                    format!("arrays: {:?} is missing (recorded by every run)", c.name),
                ));
            }
            out.push(None);
            continue;
        };
        out.push(Some(column(&obj, c, &c.dims(rows, points, n_joints))?));
    }
    Ok((out, points))
}

/// `arrays[name]`, which every run records.
fn req<'py>(arrays: &Bound<'py, PyDict>, name: &str) -> PyResult<Bound<'py, PyAny>> {
    arrays
        .get_item(name)?
        .ok_or_else(|| invalid_argument("arrays", format!("arrays: {name:?} is missing (recorded by every run)")))
}

/// Times finite and increasing.
fn check_time(t: &[f64]) -> PyResult<()> {
    let ok = t.iter().all(|v| v.is_finite()) && t.windows(2).all(|w| w[1] > w[0]);
    if ok {
        Ok(())
    } else {
        Err(invalid_argument("arrays", "arrays[\"time\"]: expected finite, increasing times".into()))
    }
}

/// One column as a new array of its dtype and shape `dims`.
fn column(obj: &Bound<'_, PyAny>, c: &Column, dims: &[usize]) -> PyResult<Py<PyAny>> {
    let py = obj.py();
    let what = format!("arrays[{:?}]", c.name);
    let want: Vec<Option<usize>> = dims.iter().map(|&d| Some(d)).collect();
    if !c.boolean {
        let a = f64_array(obj, &what, &want)?;
        let copy = numpy::PyArray1::from_slice(py, a.as_slice()?).reshape(dims.to_vec())?;
        return Ok(copy.into_any().unbind());
    }
    let numpy = py.import("numpy")?;
    let raw = numpy.call_method1("asarray", (obj,))?;
    let kind: String = raw.getattr("dtype")?.getattr("kind")?.extract()?;
    if kind != "b" {
        let dtype = raw.getattr("dtype")?.str()?.to_string();
        return Err(invalid_argument(&what, format!("{what}: expected a bool array, got dtype {dtype}")));
    }
    let a = raw.cast::<PyArrayDyn<bool>>().map_err(|_| invalid_argument(&what, format!("{what}: not a bool array")))?;
    if a.shape() != dims {
        return Err(shape_error(&what, format!("shape {dims:?}"), format!("{:?}", a.shape())));
    }
    Ok(numpy.call_method1("array", (a,))?.unbind())
}

/// The summary in the kinematic run's key order, each value checked: exactly the keys of
/// `HEAD` and `SUMMARY_FIELDS`.
pub fn summary_of<'py>(summary: &Bound<'py, PyDict>, name: &str, points: usize) -> PyResult<Bound<'py, PyDict>> {
    let py = summary.py();
    let numbers = SUMMARY_FIELDS.iter().map(|f| f.name);
    for key in summary.keys() {
        let k: String =
            key.extract().map_err(|_| invalid_argument("summary", "summary: keys must be strings".into()))?;
        if !HEAD.contains(&k.as_str()) && !SUMMARY_FIELDS.iter().any(|f| f.name == k) {
            return Err(invalid_argument("summary", format!("summary[{k:?}]: not a key of RunResult.summary")));
        }
    }
    let out = PyDict::new(py);
    for key in HEAD.iter().copied().chain(numbers) {
        let v = summary
            .get_item(key)?
            .ok_or_else(|| invalid_argument("summary", format!("summary: {key:?} is missing")))?;
        check_value(&v, key, name, points)?;
        out.set_item(key, v)?;
    }
    Ok(out)
}

/// One summary value: of its key's type and range.
fn check_value(v: &Bound<'_, PyAny>, key: &str, name: &str, points: usize) -> PyResult<()> {
    let bad = |expected: &str| {
        let got = v.repr().map_or_else(|_| "?".to_string(), |r| crate::input_file::excerpt(&r.to_string()));
        invalid_argument("summary", format!("summary[{key:?}]: expected {expected}, got {got}"))
    };
    let text = || v.cast::<PyString>().ok().map(|s| s.to_string());
    let count = || v.is_instance_of::<PyInt>() && !v.is_instance_of::<PyBool>() && v.extract::<usize>().is_ok();
    let ok = match key {
        "name" => text().is_some_and(|t| t == name),
        "status" => text().is_some_and(|t| STATUSES.iter().any(|s| s.as_str() == t)),
        "message" => text().is_some(),
        "stop_rule" => text().is_some_and(|t| [StopRule::Pixel, StopRule::Invariant].iter().any(|r| r.as_str() == t)),
        "iterations" | "basis_switches" => count(),
        "prop1" | "prop2" | "within_tolerance" => v.is_instance_of::<PyBool>(),
        "basis" => v.extract::<[usize; 3]>().is_ok_and(|b| b.iter().all(|&i| i < points)),
        _ => v.is_none() || (v.is_instance_of::<PyFloat>() || count()),
    };
    if ok {
        return Ok(());
    }
    Err(match key {
        "name" => bad(&format!("the scenario's name {name:?}")),
        "status" => bad(&format!("one of {}", STATUSES.map(|s| s.as_str()).join(", "))),
        "message" => bad("a string"),
        "stop_rule" => bad("\"pixel\" or \"invariant\""),
        "iterations" | "basis_switches" => bad("a count (an int >= 0)"),
        "prop1" | "prop2" | "within_tolerance" => bad("a bool"),
        "basis" => bad(&format!("three point indices below {points}")),
        _ => bad("a float or None"),
    })
}

/// An arm's joint limits: exactly `names`, `lower`, `upper`, `velocity`.
pub fn check_joint_limits(limits: &Bound<'_, PyDict>) -> PyResult<()> {
    const KEYS: [&str; 4] = ["names", "lower", "upper", "velocity"];
    let keys: Vec<String> = limits.keys().extract().unwrap_or_default();
    if keys.len() == KEYS.len() && KEYS.iter().all(|k| keys.iter().any(|g| g == k)) {
        return Ok(());
    }
    Err(invalid_argument("joint_limits", format!("joint_limits: expected the keys {}, got {keys:?}", KEYS.join(", "))))
}
