//! Lenses in Python: `Distortion`, `distort_points`, `undistort_points`, `distort_rays`,
//! `undistort_rays`, `Calibration` and `load_calibration`. The loops run in Rust, with the GIL released for large arrays.

use numpy::PyArray2;
use pyo3::prelude::*;

use super::arrays::{f64_array, mat, points2, points3, vec1};
use super::errors::invalid_argument;
use super::{PyIntrinsics, intrinsics, pixels_arg};
use crate::calibration::Calibration;
use crate::core::distortion::{
    DEFAULT_UNDISTORT_MAX_ITER, DEFAULT_UNDISTORT_TOL, Distortion, DistortionModel, distort_points as distort,
    distort_rays as distort_r, undistort_points as undistort, undistort_rays as undistort_r,
};

/// Arrays with at least this many points are processed with the GIL released.
const DETACH_MIN_POINTS: usize = 512;

/// Lens distortion: OpenCV's coefficients and the model, "plumb_bob" (k1, k2, p1, p2[, k3]),
/// "rational_polynomial" (k1, k2, p1, p2, k3, k4, k5, k6) or "equidistant", OpenCV's fisheye
/// (cv2.fisheye, Kannala-Brandt: k1, k2, k3, k4). Without a model, 4 or 5 coefficients are
/// plumb_bob and 8 rational_polynomial: a fisheye needs model="equidistant".
#[pyclass(name = "Distortion", module = "vsinv._core", frozen, from_py_object)]
#[derive(Clone)]
pub struct PyDistortion {
    inner: Distortion,
}

#[pymethods]
impl PyDistortion {
    #[new]
    #[pyo3(signature = (coefficients, model = None))]
    fn new(coefficients: &Bound<'_, PyAny>, model: Option<&str>) -> PyResult<Self> {
        let c = f64_array(coefficients, "coefficients", &[None])?;
        let inner = match model {
            None => Distortion::from_coefficients(c.as_slice()?),
            Some(name) => {
                let m = DistortionModel::from_name(name).ok_or_else(|| {
                    invalid_argument(
                        "model",
                        format!("model: unknown distortion model {name:?}; expected {}", DistortionModel::NAMES),
                    )
                })?;
                Distortion::with_model(m, c.as_slice()?)
            }
        }?;
        Ok(Self { inner })
    }
    /// "plumb_bob", "rational_polynomial" or "equidistant".
    #[getter]
    fn model(&self) -> &'static str {
        self.inner.model().name()
    }
    /// The coefficients in OpenCV's order, a new (5,), (8,) or (4,) (equidistant) array.
    #[getter]
    fn coefficients<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<f64>> {
        vec1(py, self.inner.coefficients())
    }
    fn __repr__(&self) -> String {
        format!("Distortion({:?}, model={:?})", self.inner.coefficients(), self.inner.model().name())
    }
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other.cast::<PyDistortion>().is_ok_and(|o| o.get().inner == self.inner)
    }
    /// The largest angle from the optical axis (radians) the model images one-to-one, not
    /// included: for equidistant its fold (where d theta_d / d theta reaches 0) or pi,
    /// whichever comes first; pi / 2 for the others (the half-space in front of the camera).
    #[getter]
    fn max_angle(&self) -> f64 {
        self.inner.max_angle()
    }
}

/// A `Distortion` or an array of 4, 5 or 8 coefficients.
pub(super) fn distortion_arg(obj: &Bound<'_, PyAny>) -> PyResult<Distortion> {
    if let Ok(d) = obj.cast::<PyDistortion>() {
        return Ok(d.get().inner);
    }
    let c = f64_array(obj, "coefficients", &[None])
        .or_else(|_| f64_array(obj, "coefficients", &[Some(1), None]))
        .or_else(|_| f64_array(obj, "coefficients", &[None, Some(1)]))
        .map_err(|_| {
            invalid_argument("coefficients", "coefficients: expected a Distortion or 4, 5 or 8 coefficients".into())
        })?;
    Ok(Distortion::from_coefficients(c.as_slice()?)?)
}

/// Runs `f` on the pixels, with the GIL released when there are many.
fn run_points<'py>(
    py: Python<'py>,
    px: &[[f64; 2]],
    f: impl FnOnce(&[[f64; 2]]) -> crate::Result<Vec<[f64; 2]>> + Send,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let out = if px.len() >= DETACH_MIN_POINTS { py.detach(|| f(px)) } else { f(px) }?;
    super::arrays::finite_out("pixels, K, distortion", out.as_flattened())?;
    mat(py, out.len(), 2, out.into_flattened())
}

/// Distorts pixels (n, 2) of the ideal pinhole image: `K d(K^-1 p)`; K may have skew. Raises for a point at or
/// beyond an equidistant lens's fold.
#[pyfunction]
#[allow(non_snake_case)]
pub fn distort_points<'py>(
    py: Python<'py>,
    pixels: &Bound<'py, PyAny>,
    K: &Bound<'py, PyAny>,
    distortion: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let a = pixels_arg(pixels, "pixels")?;
    let k = intrinsics(K, "K")?;
    let d = distortion_arg(distortion)?;
    run_points(py, points2(&a)?, |px| distort(px, &k, &d))
}

/// Undistorts pixels (n, 2) by Newton's method, the inverse of `distort_points`, to `tol` pixels within `max_iter`
/// iterations (for equidistant, Newton's method on the angle theta). Raises for a pixel beyond the image of the fold,
/// and for an equidistant pixel whose ray is 90 degrees or more from the axis (no pinhole pixel: see `undistort_rays`).
#[pyfunction]
#[pyo3(signature = (pixels, K, distortion, tol = DEFAULT_UNDISTORT_TOL, max_iter = DEFAULT_UNDISTORT_MAX_ITER), text_signature = "(pixels, K, distortion, tol=1e-10, max_iter=50)")]
#[allow(non_snake_case)]
pub fn undistort_points<'py>(
    py: Python<'py>,
    pixels: &Bound<'py, PyAny>,
    K: &Bound<'py, PyAny>,
    distortion: &Bound<'py, PyAny>,
    tol: f64,
    #[pyo3(from_py_with = super::args::max_iter)] max_iter: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let a = pixels_arg(pixels, "pixels")?;
    let k = intrinsics(K, "K")?;
    let d = distortion_arg(distortion)?;
    run_points(py, points2(&a)?, |px| undistort(px, &k, &d, tol, max_iter))
}

/// Distorts rays (n, 3) of the camera frame into pixels (n, 2): for equidistant `K m_d` with
/// `m_d = theta_d (X, Y) / sqrt(X^2 + Y^2)`, `theta` the ray's angle from the axis, which images rays beyond 90
/// degrees while `theta < max_angle`; for the others `K d(X/Z, Y/Z)`, which needs `Z > 0`.
#[pyfunction]
#[allow(non_snake_case)]
pub fn distort_rays<'py>(
    py: Python<'py>,
    rays: &Bound<'py, PyAny>,
    K: &Bound<'py, PyAny>,
    distortion: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let a = f64_array(rays, "rays", &[None, Some(3)])?;
    let k = intrinsics(K, "K")?;
    let d = distortion_arg(distortion)?;
    let r = points3(&a)?;
    let out = if r.len() >= DETACH_MIN_POINTS { py.detach(|| distort_r(r, &k, &d)) } else { distort_r(r, &k, &d) }?;
    super::arrays::finite_out("rays, K, distortion", out.as_flattened())?;
    mat(py, out.len(), 2, out.into_flattened())
}

/// The unit rays (n, 3) of distorted pixels (n, 2), the inverse of `distort_rays`: for equidistant Newton's method
/// on theta (rays beyond 90 degrees have Z < 0); for the others `undistort_points`' normalised point, normalised.
#[pyfunction]
#[pyo3(signature = (pixels, K, distortion, tol = DEFAULT_UNDISTORT_TOL, max_iter = DEFAULT_UNDISTORT_MAX_ITER), text_signature = "(pixels, K, distortion, tol=1e-10, max_iter=50)")]
#[allow(non_snake_case)]
pub fn undistort_rays<'py>(
    py: Python<'py>,
    pixels: &Bound<'py, PyAny>,
    K: &Bound<'py, PyAny>,
    distortion: &Bound<'py, PyAny>,
    tol: f64,
    #[pyo3(from_py_with = super::args::max_iter)] max_iter: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let a = pixels_arg(pixels, "pixels")?;
    let k = intrinsics(K, "K")?;
    let d = distortion_arg(distortion)?;
    let px = points2(&a)?;
    let f = || undistort_r(px, &k, &d, tol, max_iter);
    let out = if px.len() >= DETACH_MIN_POINTS { py.detach(f) } else { f() }?;
    mat(py, out.len(), 3, out.into_flattened())
}

/// A camera calibration read from a file: intrinsics, distortion and image size.
#[pyclass(name = "Calibration", module = "vsinv._core", frozen)]
pub struct PyCalibration {
    inner: Calibration,
}

#[pymethods]
impl PyCalibration {
    /// The camera matrix as `Intrinsics` (no skew).
    #[getter]
    fn intrinsics(&self) -> PyIntrinsics {
        PyIntrinsics { inner: self.inner.intrinsics }
    }
    /// The lens distortion.
    #[getter]
    fn distortion(&self) -> PyDistortion {
        PyDistortion { inner: self.inner.distortion }
    }
    /// (width, height) in pixels, or None when the file does not give it.
    #[getter]
    fn image_size(&self) -> Option<(u32, u32)> {
        self.inner.image_size
    }
    fn __repr__(&self) -> String {
        let c = &self.inner;
        let k = &c.intrinsics;
        format!(
            "Calibration(intrinsics=Intrinsics(fku={}, fkv={}, u0={}, v0={}), distortion={:?} {:?}, image_size={})",
            k.fku(),
            k.fkv(),
            k.u0(),
            k.v0(),
            c.distortion.model().name(),
            c.distortion.coefficients(),
            c.image_size.map_or("None".to_string(), |(w, h)| format!("({w}, {h})"))
        )
    }
}

/// Reads a calibration file: ROS camera_info YAML, OpenCV FileStorage YAML or XML (a regular
/// file of at most 1 MiB; no YAML aliases).
#[pyfunction]
pub fn load_calibration(py: Python<'_>, path: std::path::PathBuf) -> PyResult<PyCalibration> {
    let inner = py.detach(|| crate::calibration::load_calibration(&path))?;
    Ok(PyCalibration { inner })
}

/// Adds lens distortion and calibration files.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyDistortion>()?;
    m.add_class::<PyCalibration>()?;
    m.add_function(wrap_pyfunction!(distort_points, m)?)?;
    m.add_function(wrap_pyfunction!(undistort_points, m)?)?;
    m.add_function(wrap_pyfunction!(distort_rays, m)?)?;
    m.add_function(wrap_pyfunction!(undistort_rays, m)?)?;
    m.add_function(wrap_pyfunction!(load_calibration, m)?)?;
    Ok(())
}
