//! NumPy array arguments: read float64 C-contiguous arrays in place, convert anything else
//! once, and refuse what cannot be a real array with `InvalidInput`.

use numpy::{
    PyArray1, PyArray2, PyArrayDyn, PyArrayMethods, PyReadonlyArray1, PyReadonlyArrayDyn, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;

use super::errors::{invalid_argument, invalid_input, shape_error};

/// A read-only float64 array borrowed from Python, C-contiguous.
pub struct F64Array<'py> {
    array: PyReadonlyArrayDyn<'py, f64>,
}

impl F64Array<'_> {
    pub fn shape(&self) -> &[usize] {
        self.array.shape()
    }
    pub fn as_slice(&self) -> PyResult<&[f64]> {
        self.array.as_slice().map_err(|e| invalid_input(format!("array is not contiguous: {e}")))
    }
}

fn numpy_fn<'py>(py: Python<'py>, cell: &'static PyOnceLock<Py<PyAny>>, name: &str) -> PyResult<&'static Py<PyAny>> {
    cell.get_or_try_init(py, || Ok(py.import("numpy")?.getattr(name)?.unbind()))
}

/// `numpy.ascontiguousarray(numpy.asarray(obj), dtype)`, refusing a dtype whose kind is not
/// one of `kinds` (`InvalidInput` saying it expected `expected`).
fn contiguous_copy(
    obj: &Bound<'_, PyAny>,
    what: &str,
    kinds: &str,
    expected: &str,
    dtype: Option<&str>,
) -> PyResult<Py<PyAny>> {
    static ASARRAY: PyOnceLock<Py<PyAny>> = PyOnceLock::new();
    static CONTIGUOUS: PyOnceLock<Py<PyAny>> = PyOnceLock::new();
    let py = obj.py();
    let raw = numpy_fn(py, &ASARRAY, "asarray")?
        .call1(py, (obj,))
        .map_err(|e| invalid_argument(what, format!("{what}: cannot be read as an array ({e})")))?;
    let raw = raw.bind(py);
    let kind: String = raw.getattr("dtype")?.getattr("kind")?.extract()?;
    if kind.is_empty() || !kinds.contains(kind.as_str()) {
        let dtype = raw.getattr("dtype")?.str()?.to_string();
        return Err(invalid_argument(what, format!("{what}: expected {expected}, got dtype {dtype}")));
    }
    numpy_fn(py, &CONTIGUOUS, "ascontiguousarray")?.call1(py, (raw, dtype))
}

/// Reads `obj` as a float64 array of `ndim` dimensions (`None` in `dims` accepts any size).
/// A float64 C-contiguous ndarray is borrowed without copying; integers, booleans, other
/// float types, lists and non-contiguous arrays are converted once; anything else (complex,
/// strings, objects, ragged lists) raises `InvalidInput`.
pub fn f64_array<'py>(obj: &Bound<'py, PyAny>, what: &str, dims: &[Option<usize>]) -> PyResult<F64Array<'py>> {
    let py = obj.py();
    let fast = obj.cast::<PyArrayDyn<f64>>().ok().filter(|a| a.is_c_contiguous()).cloned();
    let array = match fast {
        Some(a) => a,
        None => {
            let converted = contiguous_copy(obj, what, "biuf", "a real numeric array", Some("float64"))?;
            converted
                .bind(py)
                .cast::<PyArrayDyn<f64>>()
                .map_err(|_| invalid_argument(what, format!("{what}: conversion to float64 failed")))?
                .clone()
        }
    };
    let shape = array.shape();
    let shape_ok = shape.len() == dims.len() && shape.iter().zip(dims).all(|(s, d)| d.is_none_or(|d| d == *s));
    if !shape_ok {
        let want: Vec<String> = dims.iter().map(|d| d.map_or("n".to_string(), |d| d.to_string())).collect();
        return Err(shape_error(what, format!("shape ({})", want.join(", ")), format!("{shape:?}")));
    }
    let array =
        array.try_readonly().map_err(|e| invalid_argument(what, format!("{what}: array is being written to ({e})")))?;
    Ok(F64Array { array })
}

/// A read-only 1-d bool array borrowed from Python, C-contiguous.
pub struct BoolArray<'py> {
    array: PyReadonlyArray1<'py, bool>,
}

impl BoolArray<'_> {
    pub fn as_slice(&self) -> PyResult<&[bool]> {
        self.array.as_slice().map_err(|e| invalid_input(format!("array is not contiguous: {e}")))
    }
}

/// Reads `obj` as a bool array of shape `(n,)`: a C-contiguous bool ndarray is borrowed
/// without copying, a list of bools or a strided array is converted once; any other dtype
/// (integers included) or shape raises `InvalidInput`.
pub fn bool_array<'py>(obj: &Bound<'py, PyAny>, what: &str, n: usize) -> PyResult<BoolArray<'py>> {
    let py = obj.py();
    let fast = obj.cast::<PyArray1<bool>>().ok().filter(|a| a.is_c_contiguous()).cloned();
    let array = match fast {
        Some(a) => a,
        None => {
            let converted = contiguous_copy(obj, what, "b", "a bool array", None)?;
            let converted = converted.bind(py);
            let shape: Vec<usize> = converted.getattr("shape")?.extract()?;
            if shape.len() != 1 {
                return Err(shape_error(what, format!("shape ({n},)"), format!("{shape:?}")));
            }
            converted
                .cast::<PyArray1<bool>>()
                .map_err(|_| invalid_argument(what, format!("{what}: not a bool array")))?
                .clone()
        }
    };
    if array.len() != n {
        return Err(shape_error(what, format!("shape ({n},)"), format!("({},)", array.len())));
    }
    let array =
        array.try_readonly().map_err(|e| invalid_argument(what, format!("{what}: array is being written to ({e})")))?;
    Ok(BoolArray { array })
}

/// Refuses an output with NaN or infinity: finite inputs whose result overflows float64
/// (pixels or depths near 1e300) raise `InvalidInput` naming the inputs, never return NaN.
pub fn finite_out(inputs: &str, values: &[f64]) -> PyResult<()> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(invalid_argument(
            inputs,
            format!("{inputs}: the result is not finite (values too large or too small for float64)"),
        ))
    }
}

/// `(n, 2)` pixel array as `[[f64; 2]]` without copying.
pub fn points2<'a>(a: &'a F64Array<'_>) -> PyResult<&'a [[f64; 2]]> {
    let (chunks, _) = a.as_slice()?.as_chunks::<2>();
    Ok(chunks)
}

/// `(n, 3)` array as `[[f64; 3]]` without copying.
pub fn points3<'a>(a: &'a F64Array<'_>) -> PyResult<&'a [[f64; 3]]> {
    let (chunks, _) = a.as_slice()?.as_chunks::<3>();
    Ok(chunks)
}

/// A new 1-d array.
pub fn vec1<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, v)
}

/// A new `(rows, cols)` array from row-major data.
pub fn mat<'py>(py: Python<'py>, rows: usize, cols: usize, row_major: Vec<f64>) -> PyResult<Bound<'py, PyArray2<f64>>> {
    PyArray1::from_vec(py, row_major).reshape([rows, cols])
}

/// A new `(rows, cols)` array from a nalgebra matrix (column-major storage).
pub fn from_matrix<'py, R: nalgebra::Dim, C: nalgebra::Dim, S: nalgebra::RawStorage<f64, R, C>>(
    py: Python<'py>,
    m: &nalgebra::Matrix<f64, R, C, S>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (rows, cols) = m.shape();
    let data: Vec<f64> = (0..rows).flat_map(|r| (0..cols).map(move |c| (r, c))).map(|(r, c)| m[(r, c)]).collect();
    mat(py, rows, cols, data)
}

/// An `(n, 2)` pixel array argument.
pub(crate) fn pixels_arg<'py>(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<F64Array<'py>> {
    f64_array(obj, what, &[None, Some(2)])
}

/// A 4x4 homogeneous pose argument (`pose`), finite and rigid: its isometry.
pub(crate) fn pose_arg(obj: &Bound<'_, PyAny>) -> PyResult<nalgebra::Isometry3<f64>> {
    let a = f64_array(obj, "pose", &[Some(4), Some(4)])?;
    Ok(crate::core::se3::pose_from_matrix(&nalgebra::Matrix4::from_row_slice(a.as_slice()?))?)
}

/// An `(n,)` depth array argument.
pub(crate) fn depths_arg<'py>(obj: &Bound<'py, PyAny>) -> PyResult<F64Array<'py>> {
    f64_array(obj, "depths", &[None])
}
