//! The camera model of eq. (4): `Intrinsics`, projection and pixel interaction matrices.

use nalgebra::Matrix3;
use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyType;

use super::arrays::{depths_arg, f64_array, finite_out, from_matrix, mat, pixels_arg, points2, points3};
use crate::core::camera::Intrinsics;

type PixelsAndDepths<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray1<f64>>);

/// Intrinsic parameters of eq. (4): `Intrinsics(fku, fkv, u0, v0, skew=pi/2)`, pixels and
/// radians. `skew` is the angle theta between the image axes.
#[pyclass(name = "Intrinsics", module = "vsinv._core", frozen, from_py_object)]
#[derive(Clone)]
pub(crate) struct PyIntrinsics {
    pub(crate) inner: Intrinsics,
}

#[pymethods]
impl PyIntrinsics {
    #[new]
    #[pyo3(signature = (fku, fkv, u0, v0, skew = std::f64::consts::FRAC_PI_2))]
    fn new(fku: f64, fkv: f64, u0: f64, v0: f64, skew: f64) -> PyResult<Self> {
        Ok(Self { inner: Intrinsics::new(fku, fkv, u0, v0, skew)? })
    }
    /// From a 3x3 upper-triangular matrix K with K[2] = (0, 0, 1).
    #[staticmethod]
    fn from_matrix(k: &Bound<'_, PyAny>) -> PyResult<Self> {
        Ok(Self { inner: Intrinsics::from_matrix(&matrix3(k, "K")?)? })
    }
    /// f ku, the horizontal focal length in pixels.
    #[getter]
    fn fku(&self) -> f64 {
        self.inner.fku()
    }
    /// f kv, the vertical focal length in pixels.
    #[getter]
    fn fkv(&self) -> f64 {
        self.inner.fkv()
    }
    /// u0, the principal point's column in pixels.
    #[getter]
    fn u0(&self) -> f64 {
        self.inner.u0()
    }
    /// v0, the principal point's row in pixels.
    #[getter]
    fn v0(&self) -> f64 {
        self.inner.v0()
    }
    /// theta, the angle between the image axes in radians (pi/2: no skew).
    #[getter]
    fn skew(&self) -> f64 {
        self.inner.theta()
    }
    /// K, a new (3, 3) array.
    #[getter]
    fn matrix<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        from_matrix(py, &self.inner.matrix())
    }
    fn __repr__(&self) -> String {
        intrinsics_repr(&self.inner)
    }
    /// Equal parameters (exactly).
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other.cast::<PyIntrinsics>().is_ok_and(|o| o.get().inner == self.inner)
    }
    /// Pickling: the five parameters, restored exactly.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> (Bound<'py, PyType>, (f64, f64, f64, f64, f64)) {
        let i = &slf.get().inner;
        (slf.get_type(), (i.fku(), i.fkv(), i.u0(), i.v0(), i.theta()))
    }
}

/// `Intrinsics(fku=..., ...)` with Python's float notation (round-trips exactly).
pub(crate) fn intrinsics_repr(i: &Intrinsics) -> String {
    format!("Intrinsics(fku={:?}, fkv={:?}, u0={:?}, v0={:?}, skew={:?})", i.fku(), i.fkv(), i.u0(), i.v0(), i.theta())
}

pub(crate) fn matrix3(obj: &Bound<'_, PyAny>, what: &'static str) -> PyResult<Matrix3<f64>> {
    let a = f64_array(obj, what, &[Some(3), Some(3)])?;
    let m = Matrix3::from_row_slice(a.as_slice()?);
    crate::error::check_finite_matrix(what, &m)?;
    Ok(m)
}

/// An `Intrinsics` or a 3x3 array, validated.
pub(crate) fn intrinsics(obj: &Bound<'_, PyAny>, what: &'static str) -> PyResult<Intrinsics> {
    if let Ok(k) = obj.cast::<PyIntrinsics>() {
        return Ok(k.get().inner);
    }
    Ok(Intrinsics::from_matrix(&matrix3(obj, what)?)?)
}

/// Projects points (n, 3) given in the camera frame (metres) with intrinsics `K` (eqs. 1-3): returns (pixels (n,
/// 2), depths (n,)).
#[pyfunction]
#[allow(non_snake_case)]
fn project<'py>(py: Python<'py>, points: &Bound<'py, PyAny>, K: &Bound<'py, PyAny>) -> PyResult<PixelsAndDepths<'py>> {
    let pts = f64_array(points, "points", &[None, Some(3)])?;
    let k = intrinsics(K, "K")?;
    let (px, z) = crate::core::camera::project_points(points3(&pts)?, &k)?;
    finite_out("points, K", px.as_flattened())?;
    Ok((mat(py, px.len(), 2, px.into_flattened())?, PyArray1::from_vec(py, z)))
}

/// Pixel interaction matrices (n, 2, 6) of the points: dp_k/dt = L_k (v, w) (Espiau et al.).
#[pyfunction]
#[allow(non_snake_case)]
fn interaction_matrix<'py>(
    py: Python<'py>,
    pixels: &Bound<'py, PyAny>,
    depths: &Bound<'py, PyAny>,
    K: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray3<f64>>> {
    let (a, z) = (pixels_arg(pixels, "pixels")?, depths_arg(depths)?);
    let (px, z) = (points2(&a)?, z.as_slice()?);
    let k = intrinsics(K, "K")?;
    let ls = crate::core::camera::pixel_interactions(px, z, &k)?;
    finite_out("pixels, depths, K", &ls.iter().flat_map(|l| l.iter().copied()).collect::<Vec<f64>>())?;
    let flat: Vec<f64> = ls.iter().flat_map(|l| (0..2).flat_map(move |r| (0..6).map(move |c| l[(r, c)]))).collect();
    PyArray1::from_vec(py, flat).reshape([ls.len(), 2, 6])
}

/// Adds `Intrinsics`, `project` and `interaction_matrix`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyIntrinsics>()?;
    m.add_function(wrap_pyfunction!(project, m)?)?;
    m.add_function(wrap_pyfunction!(interaction_matrix, m)?)?;
    Ok(())
}
