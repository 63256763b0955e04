//! Scalar arguments PyO3 would refuse with `OverflowError` or `ValueError` (a negative
//! count, an out-of-range threshold, a tuple of the wrong length): read here so that they
//! raise `InvalidInput` naming the argument, as every other bad value does. A wrong Python
//! type (a str where an integer is expected) still raises `TypeError` naming the argument.

use pyo3::exceptions::PyOverflowError;
use pyo3::prelude::*;
use pyo3::types::PyString;

use super::errors::invalid_argument;

/// An integer in `[min, max]`; `TypeError` for a non-integer, `InvalidInput` otherwise.
fn int_in_range(obj: &Bound<'_, PyAny>, what: &str, min: i128, max: i128) -> PyResult<i128> {
    let py = obj.py();
    let value: i128 = match obj.extract::<i128>() {
        Ok(v) => v,
        Err(e) if e.is_instance_of::<PyOverflowError>(py) => {
            return Err(invalid_argument(what, format!("{what}: expected an integer in [{min}, {max}], got {obj}")));
        }
        Err(e) => return Err(e),
    };
    if value < min || value > max {
        return Err(invalid_argument(what, format!("{what}: expected an integer in [{min}, {max}], got {value}")));
    }
    Ok(value)
}

/// One of the named `choices` (`[("png", Png), ...]`); anything else raises `InvalidInput`
/// naming `what` and listing the names (`or None` when `none_too`: the argument may be left
/// out).
pub fn choice<T: Copy>(
    obj: &Bound<'_, PyAny>,
    what: &'static str,
    choices: &[(&str, T)],
    none_too: bool,
) -> PyResult<T> {
    let text = obj.extract::<String>().ok();
    if let Some(&(_, value)) = choices.iter().find(|(name, _)| text.as_deref() == Some(*name)) {
        return Ok(value);
    }
    let mut names: Vec<String> = choices.iter().map(|(name, _)| format!("'{name}'")).collect();
    if none_too {
        names.push("None".into());
    }
    let listed = match names.split_last() {
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
        None => String::new(),
    };
    let other = obj.repr().map_or_else(|_| "?".to_string(), |r| r.to_string());
    Err(crate::Error::InvalidParameter { name: what, reason: format!("expected {listed}, got {other}") }.into())
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

pub fn min_contrast(obj: &Bound<'_, PyAny>) -> PyResult<u8> {
    Ok(int_in_range(obj, "min_contrast", 0, 255)? as u8)
}

/// An image's width in pixels: an integer in [1, 65536] (`vision::image::MAX_IMAGE_SIDE`).
pub fn width(obj: &Bound<'_, PyAny>) -> PyResult<u32> {
    Ok(int_in_range(obj, "width", 1, i128::from(crate::vision::image::MAX_IMAGE_SIDE))? as u32)
}

/// An image's height in pixels: an integer in [1, 65536] (`vision::image::MAX_IMAGE_SIDE`).
pub fn height(obj: &Bound<'_, PyAny>) -> PyResult<u32> {
    Ok(int_in_range(obj, "height", 1, i128::from(crate::vision::image::MAX_IMAGE_SIDE))? as u32)
}

/// A background grey level in [0, 254] (below the renderer's foreground, 255).
pub fn background(obj: &Bound<'_, PyAny>) -> PyResult<u8> {
    Ok(int_in_range(obj, "background", 0, 254)? as u8)
}

/// A seed of the sensor noise: an integer in [0, 2^64 - 1].
pub fn seed(obj: &Bound<'_, PyAny>) -> PyResult<u64> {
    Ok(int_in_range(obj, "seed", 0, i128::from(u64::MAX))? as u64)
}

/// A frame number (which noise draw): an integer in [0, 2^64 - 1].
pub fn frame(obj: &Bound<'_, PyAny>) -> PyResult<u64> {
    Ok(int_in_range(obj, "frame", 0, i128::from(u64::MAX))? as u64)
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

/// `None` or `(lambda_0, lambda_inf, lambda'_0)`; anything else (a bool, a string, two
/// numbers) is `InvalidInput` naming `adaptive_gain`, never a bare `TypeError`.
pub fn adaptive_gain(obj: &Bound<'_, PyAny>) -> PyResult<Option<(f64, f64, f64)>> {
    if obj.is_none() {
        return Ok(None);
    }
    let py = obj.py();
    obj.extract::<(f64, f64, f64)>().map(Some).map_err(|e| {
        invalid_argument(
            "adaptive_gain",
            format!("adaptive_gain: expected (lambda_0, lambda_inf, lambda'_0), three numbers ({})", e.value(py)),
        )
    })
}

/// A basis argument: three point indices, or "auto" for the widest triangle of the
/// reference (or given) image.
#[derive(Clone, Copy)]
pub(crate) enum BasisArg {
    Fixed([usize; 3]),
    Auto,
}

impl<'a, 'py> FromPyObject<'a, 'py> for BasisArg {
    type Error = PyErr;
    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        if let Ok(s) = obj.cast::<PyString>() {
            return match &*s.to_cow()? {
                "auto" => Ok(BasisArg::Auto),
                other => {
                    Err(invalid_argument("basis", format!("basis: expected three indices or \"auto\", got {other:?}")))
                }
            };
        }
        let v: Vec<i64> = obj
            .extract()
            .map_err(|_| invalid_argument("basis", "basis: expected three integer indices or \"auto\"".into()))?;
        match v.as_slice() {
            &[a, b, c] if a >= 0 && b >= 0 && c >= 0 => Ok(BasisArg::Fixed([a as usize, b as usize, c as usize])),
            _ => Err(invalid_argument("basis", format!("basis: expected three non-negative indices, got {v:?}"))),
        }
    }
}

impl BasisArg {
    /// The indices; for "auto", the widest triangle of `pixels`, searched only after
    /// `validate` has accepted the other arguments (bad input fails before the search) and
    /// without the GIL.
    pub(crate) fn resolve(
        self,
        py: Python<'_>,
        pixels: &[[f64; 2]],
        validate: impl FnOnce() -> crate::Result<()>,
    ) -> PyResult<[usize; 3]> {
        match self {
            BasisArg::Fixed(b) => Ok(b),
            BasisArg::Auto => {
                validate()?;
                choose_basis_detached(py, pixels)
            }
        }
    }
}

/// `choose_basis`, with the GIL released when the search is not trivially short.
pub(crate) fn choose_basis_detached(py: Python<'_>, pixels: &[[f64; 2]]) -> PyResult<[usize; 3]> {
    let search = || crate::core::invariant::choose_basis(pixels);
    let small = pixels.len() <= crate::core::widest_triangle::EXHAUSTIVE_MAX_POINTS / 4;
    Ok(if small { search() } else { py.detach(search) }?)
}
