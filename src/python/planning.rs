//! Bindings of path planning (sec. 3) and depth estimation (appendix A).
// Tuples of NumPy arrays are the natural Python return values here.
#![allow(clippy::type_complexity)]

use nalgebra::Vector3;
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;

use super::arrays::{bool_array, f64_array, mat, points2, points3, vec1};
use super::errors::{PyError, invalid_argument, shape_error, shape_error_saying};
use super::{BasisArg, pixels_arg};
use crate::core::depth::{ResectionDepths, depths_from_translation as core_depths_from_translation};
use crate::core::invariant::{BasisFrame, non_basis_indices, validate_basis};
use crate::core::planning::{InvariantPath, PlaneParallax, estimate_plane_parallax as core_estimate};
use crate::core::reference_depths::reference_depths as core_reference_depths;
use crate::core::robust_depth::robust_depths_from_translation;

/// Invariant points of the non-basis points of a current and a reference image.
fn invariant_pairs(
    py: Python<'_>,
    current: &[[f64; 2]],
    reference: &[[f64; 2]],
    basis: BasisArg,
) -> PyResult<(Vec<Vector3<f64>>, Vec<Vector3<f64>>)> {
    if current.len() != reference.len() {
        let (expected, got) = (format!("{} points", reference.len()), format!("{} points", current.len()));
        let msg = format!("current_pixels has {} points, reference_pixels {}", current.len(), reference.len());
        return Err(shape_error_saying("current_pixels", expected, got, msg));
    }
    crate::error::check_finite_points("current_pixels", current)?;
    crate::error::check_finite_points("reference_pixels", reference)?;
    // Both images were checked above: "auto" searches only valid input.
    let basis = validate_basis(basis.resolve(py, reference, || Ok(()))?, reference.len())?;
    let cur = BasisFrame::new(current, basis, "current")?;
    let star = BasisFrame::new(reference, basis, "reference")?;
    let others = non_basis_indices(current.len(), basis);
    Ok((
        others.iter().map(|&i| cur.transform(current[i])).collect(),
        others.iter().map(|&i| star.transform(reference[i])).collect(),
    ))
}

fn rows<'py>(py: Python<'py>, v: &[Vector3<f64>]) -> PyResult<Bound<'py, PyArray2<f64>>> {
    mat(py, v.len(), 3, v.iter().flat_map(|x| [x.x, x.y, x.z]).collect())
}

/// The plane + parallax parameters of eq. (9) (gamma_3 = 1).
#[pyclass(name = "PlaneParallax", module = "vsinv._core", frozen)]
pub struct PyPlaneParallax {
    inner: PlaneParallax,
}

#[pymethods]
impl PyPlaneParallax {
    /// Gamma / gamma_3, (3,).
    #[getter]
    fn gamma<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, self.inner.gamma.as_slice())
    }
    /// The epipole e* (unit norm), (3,).
    #[getter]
    fn epipole<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, self.inner.epipole.as_slice())
    }
    /// mu_k* e* for each non-basis point, (n-3, 3).
    #[getter]
    fn mu_e<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        rows(py, &self.inner.mu_e)
    }
    /// gamma_k / gamma_3 for each non-basis point, (n-3,).
    #[getter]
    fn gamma_k<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, &self.inner.gamma_k)
    }
    /// RMS distance between the current invariant points and those eq. (9) predicts.
    #[getter]
    fn residual(&self) -> f64 {
        self.inner.residual
    }
    /// Number of det F = 0 candidates of the minimal method (1 for the linear method).
    #[getter]
    fn candidates(&self) -> usize {
        self.inner.candidates
    }
}

/// Eq. (9) from a current and a reference image (n >= 7 points; linear method for n >= 8,
/// minimal 7-point method otherwise).
#[pyfunction]
#[pyo3(signature = (current_pixels, reference_pixels, basis = BasisArg::Fixed([0, 1, 2])), text_signature = "(current_pixels, reference_pixels, basis=(0, 1, 2))")]
pub fn estimate_plane_parallax(
    py: Python<'_>,
    current_pixels: &Bound<'_, PyAny>,
    reference_pixels: &Bound<'_, PyAny>,
    basis: BasisArg,
) -> PyResult<PyPlaneParallax> {
    let (c, r) = (pixels_arg(current_pixels, "current_pixels")?, pixels_arg(reference_pixels, "reference_pixels")?);
    let (q, q_star) = invariant_pairs(py, points2(&c)?, points2(&r)?, basis)?;
    Ok(PyPlaneParallax { inner: core_estimate(&q, &q_star)? })
}

/// The path of eq. (10) from the current image (t = 0) to the reference image (t = T).
#[pyclass(name = "InvariantPath", module = "vsinv._core", frozen)]
pub struct PyInvariantPath {
    inner: InvariantPath,
    estimate: Py<PyPlaneParallax>,
}

#[pymethods]
impl PyInvariantPath {
    #[new]
    #[pyo3(signature = (current_pixels, reference_pixels, duration, basis = BasisArg::Fixed([0, 1, 2])), text_signature = "(current_pixels, reference_pixels, duration, basis=(0, 1, 2))")]
    fn new(
        py: Python<'_>,
        current_pixels: &Bound<'_, PyAny>,
        reference_pixels: &Bound<'_, PyAny>,
        duration: f64,
        basis: BasisArg,
    ) -> PyResult<Self> {
        let (c, r) = (pixels_arg(current_pixels, "current_pixels")?, pixels_arg(reference_pixels, "reference_pixels")?);
        InvariantPath::check_duration(duration)?;
        let (q, q_star) = invariant_pairs(py, points2(&c)?, points2(&r)?, basis)?;
        let estimate = core_estimate(&q, &q_star)?;
        let inner = InvariantPath::new(&q_star, &estimate, duration)?;
        Ok(Self { inner, estimate: Py::new(py, PyPlaneParallax { inner: estimate })? })
    }
    /// T, seconds.
    #[getter]
    fn duration(&self) -> f64 {
        self.inner.duration()
    }
    /// The plane + parallax estimate the path was built from.
    #[getter]
    fn plane_parallax(&self, py: Python<'_>) -> Py<PyPlaneParallax> {
        self.estimate.clone_ref(py)
    }
    /// (q_k*(t), dq_k*/dt) for the non-basis points, two (n-3, 3) arrays; pass them to
    /// `InvariantController.set_reference`.
    fn sample<'py>(&self, py: Python<'py>, t: f64) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>)> {
        if !t.is_finite() {
            return Err(invalid_argument("t", format!("t must be finite, got {t}")));
        }
        let m = self.inner.len();
        let (mut p, mut r) = (vec![[0.0; 3]; m], vec![[0.0; 3]; m]);
        self.inner.sample(t, &mut p, &mut r)?;
        Ok((mat(py, m, 3, p.into_flattened())?, mat(py, m, 3, r.into_flattened())?))
    }
}

/// Eq. (26): depths of the first image of a pure-translation pair (any camera), up to one
/// positive scale (mean 1). Returns (depths (n,), epipole (3,), residual). Without
/// `pixel_noise` the pixels must be exact (the epipole is a least-squares fit of every
/// point's motion). With `pixel_noise` (pixels, standard deviation per coordinate of the
/// tracking error; about 0.1-0.15 for keypoints tracked by the features target) the
/// estimate is robust: a consensus on the epipole, then a depth only for the points whose
/// residual is below 4 sqrt(2) pixel_noise and whose parallax fixes the depth to 10 % (three
/// standard deviations); the other depths are NaN (`np.isfinite(depths)` is the mask of the
/// usable points, which ResectionDepths accepts as is), the mean over the usable ones is 1
/// and the residual is their RMS distance from the epipolar lines (pixels).
#[pyfunction]
#[pyo3(signature = (first_pixels, second_pixels, pixel_noise = None))]
pub fn depths_from_translation<'py>(
    py: Python<'py>,
    first_pixels: &Bound<'py, PyAny>,
    second_pixels: &Bound<'py, PyAny>,
    pixel_noise: Option<f64>,
) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>, f64)> {
    let (a, b) = (pixels_arg(first_pixels, "first_pixels")?, pixels_arg(second_pixels, "second_pixels")?);
    crate::error::check_finite_points("first_pixels", points2(&a)?)?;
    crate::error::check_finite_points("second_pixels", points2(&b)?)?;
    if a.shape()[0] != b.shape()[0] {
        let (expected, got) = (format!("{} points", a.shape()[0]), format!("{} points", b.shape()[0]));
        let msg = format!(
            "second_pixels has {} points, first_pixels {}: one per point of the first image",
            b.shape()[0],
            a.shape()[0]
        );
        return Err(shape_error_saying("second_pixels", expected, got, msg));
    }
    let (first, second) = (points2(&a)?, points2(&b)?);
    let d = match pixel_noise {
        None => core_depths_from_translation(first, second),
        Some(sigma) => robust_depths_from_translation(first, second, sigma),
    }
    .map_err(|e| match e {
        crate::Error::InvalidParameter { name: "depth_estimation", reason } => {
            let msg = format!("first_pixels, second_pixels: {reason}");
            let err =
                PyError::invalid(msg).kind("invalid_parameter").argument("first_pixels, second_pixels").reason(reason);
            PyErr::from(err)
        }
        e => e.into(),
    })?;
    let usable: Vec<f64> = d.depths.iter().zip(&d.usable).filter(|(_, u)| **u).map(|(z, _)| *z).collect();
    super::arrays::finite_out("first_pixels, second_pixels", &usable)?;
    Ok((PyArray1::from_vec(py, d.depths), vec1(py, d.epipole.as_slice()), d.residual))
}

/// Appendix A on line: the current depths up to kappa(t) > 0 by resecting the current camera
/// against the reconstruction from the translation pair. A NaN in `first_depths` marks a
/// point without a usable depth (depths_from_translation with pixel_noise): the reference
/// camera is resected from the others and that point placed on its ray of the first image
/// where the reference image sees it.
#[pyclass(name = "ResectionDepths", module = "vsinv._core")]
pub struct PyResectionDepths {
    pub(super) inner: ResectionDepths,
    n: usize,
}

#[pymethods]
impl PyResectionDepths {
    #[new]
    #[pyo3(signature = (first_pixels, first_depths, reference_pixels, reference_mean_depth = 1.0))]
    fn new(
        first_pixels: &Bound<'_, PyAny>,
        first_depths: &Bound<'_, PyAny>,
        reference_pixels: &Bound<'_, PyAny>,
        reference_mean_depth: f64,
    ) -> PyResult<Self> {
        let a = pixels_arg(first_pixels, "first_pixels")?;
        let z = f64_array(first_depths, "first_depths", &[None])?;
        let r = pixels_arg(reference_pixels, "reference_pixels")?;
        let (first, reference) = (points2(&a)?, points2(&r)?);
        crate::error::check_finite_points("first_pixels", first)?;
        crate::error::check_finite_points("reference_pixels", reference)?;
        if z.shape()[0] != first.len() {
            let expected = format!("{} values (one per row of first_pixels)", first.len());
            return Err(shape_error("first_depths", expected, z.shape()[0].to_string()));
        }
        // NaN marks a point without a usable depth (depths_from_translation with pixel_noise);
        // the others must be finite and > 0.
        let known: Vec<f64> = z.as_slice()?.iter().map(|v| if v.is_nan() { 1.0 } else { *v }).collect();
        crate::error::check_depths(&known, first.len())?;
        let inner = ResectionDepths::new(first, z.as_slice()?, reference, reference_mean_depth)?;
        Ok(Self { inner, n: first.len() })
    }

    /// Depths (n,) of the current image up to kappa(t) > 0, from the pixels of the visible
    /// points (all by default; at least 6, not coplanar).
    #[pyo3(signature = (pixels, visible = None))]
    fn estimate<'py>(
        &mut self,
        py: Python<'py>,
        pixels: &Bound<'py, PyAny>,
        visible: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let a = pixels_arg(pixels, "pixels")?;
        let px = points2(&a)?;
        if px.len() != self.n {
            return Err(shape_error("pixels", format!("{} points", self.n), px.len().to_string()));
        }
        let flags = visible.map(|v| bool_array(v, "visible", self.n)).transpose()?;
        let all = vec![true; self.n];
        let visible = match &flags {
            Some(f) => f.as_slice()?,
            None => all.as_slice(),
        };
        for (i, p) in px.iter().enumerate() {
            if visible[i] && !(p[0].is_finite() && p[1].is_finite()) {
                return Err(PyErr::from(crate::Error::NonFinitePoint {
                    what: "pixels",
                    row: i,
                    column: usize::from(p[0].is_finite()),
                }));
            }
        }
        let mut out = vec![0.0; self.n];
        self.inner.estimate(px, visible, &mut out)?;
        super::arrays::finite_out("pixels", &out)?;
        Ok(PyArray1::from_vec(py, out))
    }
}

/// The reference depths zeta* (n,) of a photo taken with any camera: `object_points` (n, 3),
/// the object's model in any frame (metres), seen at `reference_pixels` (n, 2) in the photo
/// (undistorted pixels). At least 6 points not on one plane need no intrinsics (a DLT
/// resection); points on one plane (at least 4) need `K`, the photo's camera matrix (3x3 or
/// Intrinsics).
#[pyfunction]
#[pyo3(signature = (object_points, reference_pixels, K = None))]
#[allow(non_snake_case)]
pub fn reference_depths<'py>(
    py: Python<'py>,
    object_points: &Bound<'py, PyAny>,
    reference_pixels: &Bound<'py, PyAny>,
    K: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let points = f64_array(object_points, "object_points", &[None, Some(3)])?;
    let pixels = pixels_arg(reference_pixels, "reference_pixels")?;
    let k = K.map(|k| super::intrinsics(k, "K")).transpose()?.map(|k| k.matrix());
    let z = core_reference_depths(points3(&points)?, points2(&pixels)?, k.as_ref())?;
    Ok(PyArray1::from_vec(py, z))
}

/// Adds path planning and depth estimation.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyPlaneParallax>()?;
    m.add_class::<PyInvariantPath>()?;
    m.add_class::<PyResectionDepths>()?;
    m.add_function(wrap_pyfunction!(estimate_plane_parallax, m)?)?;
    m.add_function(wrap_pyfunction!(depths_from_translation, m)?)?;
    m.add_function(wrap_pyfunction!(reference_depths, m)?)?;
    Ok(())
}
