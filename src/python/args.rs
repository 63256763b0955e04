//! Scalar arguments PyO3 would refuse with `OverflowError` or `ValueError` (a negative
//! count, an out-of-range threshold, a tuple of the wrong length): read here so that they
//! raise `InvalidInput` naming the argument, as every other bad value does. A wrong Python
//! type (a str where an integer is expected) still raises `TypeError` naming the argument.

use pyo3::exceptions::{PyOverflowError, PyValueError};
use pyo3::prelude::*;

use super::errors::invalid_input;

/// An integer in `[min, max]`; `TypeError` for a non-integer, `InvalidInput` otherwise.
fn int_in_range(obj: &Bound<'_, PyAny>, what: &str, min: i128, max: i128) -> PyResult<i128> {
    let py = obj.py();
    let value: i128 = match obj.extract::<i128>() {
        Ok(v) => v,
        Err(e) if e.is_instance_of::<PyOverflowError>(py) => {
            return Err(invalid_input(format!("{what}: expected an integer in [{min}, {max}], got {obj}")));
        }
        Err(e) => return Err(e),
    };
    if value < min || value > max {
        return Err(invalid_input(format!("{what}: expected an integer in [{min}, {max}], got {value}")));
    }
    Ok(value)
}

/// A non-negative integer that fits in `usize`.
pub fn count(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<usize> {
    Ok(int_in_range(obj, what, 0, usize::MAX as i128)? as usize)
}

/// `None` or a non-negative integer.
pub fn opt_count(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Option<usize>> {
    if obj.is_none() { Ok(None) } else { count(obj, what).map(Some) }
}

pub fn min_area(obj: &Bound<'_, PyAny>) -> PyResult<usize> {
    count(obj, "min_area")
}

pub fn max_area(obj: &Bound<'_, PyAny>) -> PyResult<Option<usize>> {
    opt_count(obj, "max_area")
}

pub fn max_iter(obj: &Bound<'_, PyAny>) -> PyResult<usize> {
    count(obj, "max_iter")
}

pub fn averaged_images(obj: &Bound<'_, PyAny>) -> PyResult<usize> {
    count(obj, "averaged_images")
}

pub fn capacity(obj: &Bound<'_, PyAny>) -> PyResult<usize> {
    count(obj, "capacity")
}

pub fn threads(obj: &Bound<'_, PyAny>) -> PyResult<Option<usize>> {
    opt_count(obj, "threads")
}

/// `None` or a grey level 0-255.
pub fn threshold(obj: &Bound<'_, PyAny>) -> PyResult<Option<u8>> {
    if obj.is_none() {
        return Ok(None);
    }
    Ok(Some(int_in_range(obj, "threshold", 0, 255)? as u8))
}

/// `None` or `(lambda_0, lambda_inf, lambda'_0)`.
pub fn adaptive_gain(obj: &Bound<'_, PyAny>) -> PyResult<Option<(f64, f64, f64)>> {
    if obj.is_none() {
        return Ok(None);
    }
    let py = obj.py();
    match obj.extract::<(f64, f64, f64)>() {
        Ok(t) => Ok(Some(t)),
        Err(e) if e.is_instance_of::<PyValueError>(py) => Err(invalid_input(format!(
            "adaptive_gain: expected (lambda_0, lambda_inf, lambda'_0), three numbers ({})",
            e.value(py)
        ))),
        Err(e) => Err(e),
    }
}
