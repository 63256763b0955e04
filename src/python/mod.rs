//! Python bindings (feature `python`): the only module that knows about Python. Thin
//! wrappers that read NumPy arrays in place, call the core and map errors to the package's
//! exception hierarchy; no panic crosses into Python.

mod args;
mod arrays;
mod control;
mod errors;
mod lens;
mod planning;
mod se3;
mod servo;
mod sim;
mod uncertainty;
mod vision;

use nalgebra::Matrix3;
use numpy::{Complex64, PyArray1, PyArray2, PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyString, PyType};

use arrays::{F64Array, f64_array, finite_out, from_matrix, mat, points2, points3, vec1};
use errors::{invalid_input, to_py};

use crate::core::adaptive_gain::AdaptiveGain;
use crate::core::camera::Intrinsics;
use crate::core::ibvs::Interaction;
use crate::core::jacobian::check_pixels_and_depths;
use crate::core::rz_task::RzTask;
use crate::core::saturation::TwistLimits;
use crate::core::stability::{StabilityReport, check_upper_triangular};
use crate::error::fixed_or_short;

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
            return match s.to_str()? {
                "auto" => Ok(BasisArg::Auto),
                other => Err(invalid_input(format!("basis: expected three indices or \"auto\", got {other:?}"))),
            };
        }
        let v: Vec<i64> =
            obj.extract().map_err(|_| invalid_input("basis: expected three integer indices or \"auto\"".into()))?;
        match v.as_slice() {
            &[a, b, c] if a >= 0 && b >= 0 && c >= 0 => Ok(BasisArg::Fixed([a as usize, b as usize, c as usize])),
            _ => Err(invalid_input(format!("basis: expected three non-negative indices, got {v:?}"))),
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
                validate().map_err(to_py)?;
                choose_basis_detached(py, pixels)
            }
        }
    }
}

/// `choose_basis`, with the GIL released when the search is not trivially short.
fn choose_basis_detached(py: Python<'_>, pixels: &[[f64; 2]]) -> PyResult<[usize; 3]> {
    let search = || crate::core::invariant::choose_basis(pixels);
    let small = pixels.len() <= crate::core::widest_triangle::EXHAUSTIVE_MAX_POINTS / 4;
    if small { search() } else { py.detach(search) }.map_err(to_py)
}

/// Intrinsic parameters of eq. (4): `Intrinsics(fku, fkv, u0, v0, skew=pi/2)`, pixels and
/// radians. `skew` is the angle theta between the image axes.
#[pyclass(name = "Intrinsics", module = "vsinv._core", frozen, from_py_object)]
#[derive(Clone)]
struct PyIntrinsics {
    inner: Intrinsics,
}

#[pymethods]
impl PyIntrinsics {
    #[new]
    #[pyo3(signature = (fku, fkv, u0, v0, skew = std::f64::consts::FRAC_PI_2))]
    fn new(fku: f64, fkv: f64, u0: f64, v0: f64, skew: f64) -> PyResult<Self> {
        Ok(Self { inner: Intrinsics::new(fku, fkv, u0, v0, skew).map_err(to_py)? })
    }
    /// From a 3x3 upper-triangular matrix K with K[2] = (0, 0, 1).
    #[staticmethod]
    fn from_matrix(k: &Bound<'_, PyAny>) -> PyResult<Self> {
        Ok(Self { inner: Intrinsics::from_matrix(&matrix3(k, "K")?).map_err(to_py)? })
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
fn intrinsics_repr(i: &Intrinsics) -> String {
    format!("Intrinsics(fku={:?}, fkv={:?}, u0={:?}, v0={:?}, skew={:?})", i.fku(), i.fkv(), i.u0(), i.v0(), i.theta())
}

/// A float or None in Python notation.
fn opt_repr(x: Option<f64>) -> String {
    x.map_or_else(|| "None".to_string(), |x| format!("{x:?}"))
}

/// A Python bool.
fn bool_repr(b: bool) -> &'static str {
    if b { "True" } else { "False" }
}

/// The adaptive gain as the constructor's `(lambda_0, lambda_inf, lambda'_0)`.
fn adaptive_gain_args(g: Option<AdaptiveGain>) -> Option<(f64, f64, f64)> {
    g.map(|g| (g.at_zero, g.at_infinity, g.slope_at_zero))
}

/// The speed limits as the constructor's `(max_linear_speed, max_angular_speed)` (None: free).
fn twist_limit_args(l: Option<TwistLimits>) -> (Option<f64>, Option<f64>) {
    let finite = |x: f64| x.is_finite().then_some(x);
    l.map_or((None, None), |l| (finite(l.linear), finite(l.angular)))
}

fn adaptive_gain_repr(g: Option<AdaptiveGain>) -> String {
    adaptive_gain_args(g).map_or_else(|| "None".to_string(), |(a, b, c)| format!("({a:?}, {b:?}, {c:?})"))
}

fn rz_task_name(t: RzTask) -> &'static str {
    match t {
        RzTask::Angle => "angle",
        RzTask::Tau21 => "tau21",
    }
}

fn interaction_name(i: Interaction) -> &'static str {
    match i {
        Interaction::Current => "current",
        Interaction::Desired => "desired",
        Interaction::Mean => "mean",
    }
}

fn matrix3(obj: &Bound<'_, PyAny>, what: &'static str) -> PyResult<Matrix3<f64>> {
    let a = f64_array(obj, what, &[Some(3), Some(3)])?;
    let m = Matrix3::from_row_slice(a.as_slice()?);
    crate::error::check_finite_matrix(what, &m).map_err(to_py)?;
    Ok(m)
}

/// An `Intrinsics` or a 3x3 array, validated.
pub(crate) fn intrinsics(obj: &Bound<'_, PyAny>, what: &'static str) -> PyResult<Intrinsics> {
    if let Ok(k) = obj.cast::<PyIntrinsics>() {
        return Ok(k.get().inner);
    }
    Intrinsics::from_matrix(&matrix3(obj, what)?).map_err(to_py)
}

pub(crate) fn pixels_arg<'py>(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<F64Array<'py>> {
    f64_array(obj, what, &[None, Some(2)])
}

pub(crate) fn depths_arg<'py>(obj: &Bound<'py, PyAny>) -> PyResult<F64Array<'py>> {
    f64_array(obj, "depths", &[None])
}

/// The fewest points `invariant_jacobian` and `jacobian_factors` take (the basis and one more).
const MIN_JACOBIAN_POINTS: usize = 4;

type PixelsAndDepths<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray1<f64>>);
type PixelsPair<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>);

/// Projects points given in the camera frame (n, 3), metres, with intrinsics K:
/// returns (pixels (n, 2), depths (n,)).
#[pyfunction]
#[allow(non_snake_case)]
fn project<'py>(py: Python<'py>, points: &Bound<'py, PyAny>, K: &Bound<'py, PyAny>) -> PyResult<PixelsAndDepths<'py>> {
    let pts = f64_array(points, "points", &[None, Some(3)])?;
    let k = intrinsics(K, "K")?;
    let (px, z) = crate::core::camera::project_points(points3(&pts)?, &k).map_err(to_py)?;
    finite_out("points, K", px.as_flattened())?;
    Ok((mat(py, px.len(), 2, px.into_flattened())?, PyArray1::from_vec(py, z)))
}

/// The invariant points q_k = Q^-1 p_k of all n points (sec. 2.3), an (n, 3) array.
#[pyfunction]
#[pyo3(signature = (pixels, basis = BasisArg::Fixed([0, 1, 2])), text_signature = "(pixels, basis=(0, 1, 2))")]
fn invariant_points<'py>(
    py: Python<'py>,
    pixels: &Bound<'py, PyAny>,
    basis: BasisArg,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let a = pixels_arg(pixels, "pixels")?;
    let px = points2(&a)?;
    let q = crate::core::invariant::invariant_points(px, basis.resolve(py, px, || Ok(()))?).map_err(to_py)?;
    finite_out("pixels", q.as_flattened())?;
    mat(py, q.len(), 3, q.into_flattened())
}

/// The invariant Jacobian J (3(n-3), 5) of sec. 4.1 at the given pixels and depths.
#[pyfunction]
#[pyo3(signature = (pixels, depths, K, basis = BasisArg::Fixed([0, 1, 2])), text_signature = "(pixels, depths, K, basis=(0, 1, 2))")]
#[allow(non_snake_case)]
fn invariant_jacobian<'py>(
    py: Python<'py>,
    pixels: &Bound<'py, PyAny>,
    depths: &Bound<'py, PyAny>,
    K: &Bound<'py, PyAny>,
    basis: BasisArg,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (a, z) = (pixels_arg(pixels, "pixels")?, depths_arg(depths)?);
    let px = points2(&a)?;
    let k = intrinsics(K, "K")?;
    let z = z.as_slice()?;
    let basis = basis.resolve(py, px, || check_pixels_and_depths(px, z, MIN_JACOBIAN_POINTS))?;
    let j = crate::core::jacobian::invariant_jacobian(px, z, &k, basis).map_err(to_py)?;
    finite_out("pixels, depths, K", j.as_slice())?;
    from_matrix(py, &j)
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
    let ls = crate::core::camera::pixel_interactions(px, z, &k).map_err(to_py)?;
    finite_out("pixels, depths, K", &ls.iter().flat_map(|l| l.iter().copied()).collect::<Vec<f64>>())?;
    let flat: Vec<f64> = ls.iter().flat_map(|l| (0..2).flat_map(move |r| (0..6).map(move |c| l[(r, c)]))).collect();
    PyArray1::from_vec(py, flat).reshape([ls.len(), 2, 6])
}

/// The factors (Phi (3(n-3), 3), Psi (3(n-3), 2)) of sec. 4.1: J = [Phi K, Psi F(K)].
#[pyfunction]
#[pyo3(signature = (pixels, depths, basis = BasisArg::Fixed([0, 1, 2])), text_signature = "(pixels, depths, basis=(0, 1, 2))")]
fn jacobian_factors<'py>(
    py: Python<'py>,
    pixels: &Bound<'py, PyAny>,
    depths: &Bound<'py, PyAny>,
    basis: BasisArg,
) -> PyResult<PixelsPair<'py>> {
    let (a, z) = (pixels_arg(pixels, "pixels")?, depths_arg(depths)?);
    let px = points2(&a)?;
    let z = z.as_slice()?;
    let basis = basis.resolve(py, px, || check_pixels_and_depths(px, z, MIN_JACOBIAN_POINTS))?;
    let (phi, psi) = crate::core::jacobian::jacobian_factors(px, z, basis).map_err(to_py)?;
    finite_out("pixels, depths", phi.as_slice())?;
    finite_out("pixels, depths", psi.as_slice())?;
    Ok((from_matrix(py, &phi)?, from_matrix(py, &psi)?))
}

/// The coefficients (a, c (5,)) of eq. (23): d eps_z/dt = a w_z + c . (vx, vy, vz, wx, wy).
#[pyfunction]
#[allow(non_snake_case)]
#[pyo3(signature = (pixels, depths, reference_pixels, K, basis = BasisArg::Fixed([0, 1, 2])), text_signature = "(pixels, depths, reference_pixels, K, basis=(0, 1, 2))")]
fn rz_coefficients<'py>(
    py: Python<'py>,
    pixels: &Bound<'py, PyAny>,
    depths: &Bound<'py, PyAny>,
    reference_pixels: &Bound<'py, PyAny>,
    K: &Bound<'py, PyAny>,
    basis: BasisArg,
) -> PyResult<(f64, Bound<'py, PyArray1<f64>>)> {
    let (a, z) = (pixels_arg(pixels, "pixels")?, depths_arg(depths)?);
    let r = pixels_arg(reference_pixels, "reference_pixels")?;
    let (px, rpx) = (points2(&a)?, points2(&r)?);
    let k = intrinsics(K, "K")?;
    let z = z.as_slice()?;
    let basis = basis.resolve(py, rpx, || {
        check_pixels_and_depths(px, z, 3)?;
        crate::error::check_finite_points("reference_pixels", rpx)?;
        match rpx.len() == px.len() {
            true => Ok(()),
            false => Err(crate::Error::Shape {
                what: "reference_pixels",
                expected: format!("{} points", px.len()),
                got: format!("{} points", rpx.len()),
            }),
        }
    })?;
    let (coef_a, c) = crate::core::jacobian::rz_coefficients(px, z, rpx, &k, basis).map_err(to_py)?;
    finite_out("pixels, depths, reference_pixels, K", &[coef_a])?;
    finite_out("pixels, depths, reference_pixels, K", c.as_slice())?;
    Ok((coef_a, vec1(py, c.as_slice())))
}

/// sigma_5/sigma_1 of the depth-balanced invariant Jacobian (degenerate-structure measure).
#[pyfunction]
#[pyo3(signature = (pixels, depths, K, basis = BasisArg::Fixed([0, 1, 2])), text_signature = "(pixels, depths, K, basis=(0, 1, 2))")]
#[allow(non_snake_case)]
fn structure_ratio(
    py: Python<'_>,
    pixels: &Bound<'_, PyAny>,
    depths: &Bound<'_, PyAny>,
    K: &Bound<'_, PyAny>,
    basis: BasisArg,
) -> PyResult<f64> {
    let (a, z) = (pixels_arg(pixels, "pixels")?, depths_arg(depths)?);
    let px = points2(&a)?;
    let k = intrinsics(K, "K")?;
    let z = z.as_slice()?;
    let basis = basis.resolve(py, px, || check_pixels_and_depths(px, z, crate::core::jacobian::MIN_POINTS))?;
    let r = crate::core::jacobian::structure_ratio(px, z, &k, basis).map_err(to_py)?;
    finite_out("pixels, depths, K", &[r])?;
    Ok(r)
}

/// Three points well spread in the image (the widest triangle; among equal areas the first
/// (i, j, k) in index order), sorted. O(n log n); refuses (InvalidInput, `pixels`) point sets
/// with more than 10,000 convex-hull vertices. Runs without the GIL.
#[pyfunction]
fn choose_basis(py: Python<'_>, pixels: &Bound<'_, PyAny>) -> PyResult<(usize, usize, usize)> {
    let a = pixels_arg(pixels, "pixels")?;
    let [i, j, k] = choose_basis_detached(py, points2(&a)?)?;
    Ok((i, j, k))
}

/// Stability verdicts of Props. 1-2 and the sigma of Prop. 3.
#[pyclass(name = "StabilityReport", module = "vsinv._core", frozen)]
struct PyStabilityReport {
    inner: StabilityReport,
    single: bool,
}

#[pymethods]
impl PyStabilityReport {
    /// Prop. 1 (constant K): necessary and sufficient.
    #[getter]
    fn prop1(&self) -> bool {
        self.inner.prop1
    }
    /// Prop. 2 (K varying over the schedule): sufficient.
    #[getter]
    fn prop2(&self) -> bool {
        self.inner.prop2
    }
    /// Smallest eigenvalue of A + A^T over the schedule (Prop. 3's sigma when positive).
    #[getter]
    fn sigma(&self) -> f64 {
        self.inner.sigma
    }
    /// Eigenvalues of A: complex (5,) for one K, (m, 5) for a schedule of m matrices.
    #[getter]
    fn eigenvalues<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let flat: Vec<Complex64> =
            self.inner.eigenvalues.iter().flatten().map(|c| Complex64::new(c.re, c.im)).collect();
        let arr = PyArray1::from_vec(py, flat);
        if self.single { Ok(arr.into_any()) } else { Ok(arr.reshape([self.inner.eigenvalues.len(), 5])?.into_any()) }
    }
    /// Prop. 3: the bound psi/phi on ||eps|| when ||b(t)|| <= max_b; InvalidInput when
    /// Prop. 2 fails (sigma <= 0: no bound).
    fn tracking_bound(&self, max_b: f64) -> PyResult<f64> {
        self.inner.tracking_bound(max_b).map_err(to_py)
    }
    fn __repr__(&self) -> String {
        format!(
            "StabilityReport(prop1={}, prop2={}, sigma={})",
            self.inner.prop1,
            self.inner.prop2,
            fixed_or_short(self.inner.sigma, 6)
        )
    }
}

/// Reads K as one camera (Intrinsics or (3, 3)) or a schedule ((m, 3, 3) or a list).
fn k_schedule(obj: &Bound<'_, PyAny>) -> PyResult<(Vec<Matrix3<f64>>, bool)> {
    if let Ok(k) = obj.cast::<PyIntrinsics>() {
        return Ok((vec![k.get().inner.matrix()], true));
    }
    if let Ok(list) = obj.cast::<pyo3::types::PyList>()
        && list.iter().any(|x| x.cast::<PyIntrinsics>().is_ok())
    {
        let ks = list
            .iter()
            .enumerate()
            .map(|(m, x)| {
                intrinsics(&x, "K")
                    .map(|k| k.matrix())
                    .map_err(|e| invalid_input(format!("K: matrix {m}: {}", e.value(x.py()))))
            })
            .collect::<PyResult<_>>()?;
        return Ok((ks, false));
    }
    let a = f64_array(obj, "K", &[None, Some(3), Some(3)]).or_else(|_| f64_array(obj, "K", &[Some(3), Some(3)]));
    let a =
        a.map_err(|_| invalid_input("K: expected an Intrinsics, a (3, 3) array or an (m, 3, 3) schedule".into()))?;
    let single = a.shape().len() == 2;
    for (m, k) in a.as_slice()?.chunks_exact(9).enumerate() {
        if let Some(i) = k.iter().position(|x| !x.is_finite()) {
            let at = if single { "at ".to_string() } else { format!("in matrix {m}, ") };
            return Err(invalid_input(format!("K: non-finite value {at}row {}, column {}", i / 3, i % 3)));
        }
    }
    let ks = a.as_slice()?.chunks_exact(9).map(Matrix3::from_row_slice).collect();
    Ok((ks, single))
}

/// Props. 1-2 for true intrinsics K (one camera or a schedule), an estimate K_hat (any
/// signs: a 3x3 upper-triangular matrix or Intrinsics), depth scale kappa and gain lambda.
#[pyfunction]
#[pyo3(signature = (K, K_hat, kappa = 1.0, gain = 1.0), text_signature = "(K, K_hat, kappa=1.0, gain=1.0)")]
#[allow(non_snake_case)]
fn check_stability(
    K: &Bound<'_, PyAny>,
    K_hat: &Bound<'_, PyAny>,
    kappa: f64,
    gain: f64,
) -> PyResult<PyStabilityReport> {
    let (ks, single) = k_schedule(K)?;
    let k_hat = match K_hat.cast::<PyIntrinsics>() {
        Ok(i) => i.get().inner.matrix(),
        Err(_) => matrix3(K_hat, "K_hat")?,
    };
    check_upper_triangular("K_hat", &k_hat).map_err(to_py)?;
    let inner = crate::core::stability::check_stability(&ks, &k_hat, kappa, gain).map_err(to_py)?;
    Ok(PyStabilityReport { inner, single })
}

/// Prop. 3 bound psi/phi = 2 max_b / (gain sigma) (eq. 20); InvalidInput for gain <= 0,
/// sigma <= 0 (Prop. 2 fails: no bound), max_b < 0 or a bound that overflows.
#[pyfunction]
fn tracking_bound(gain: f64, sigma: f64, max_b: f64) -> PyResult<f64> {
    crate::core::stability::tracking_bound(gain, sigma, max_b).map_err(to_py)
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    errors::register(m)?;
    m.add_class::<PyIntrinsics>()?;
    m.add_class::<control::PyInvariantController>()?;
    m.add_class::<control::PyIbvsController>()?;
    m.add_class::<servo::PyServo>()?;
    m.add_class::<servo::PyServoStep>()?;
    m.add_class::<PyStabilityReport>()?;
    m.add_class::<uncertainty::PyPoseUncertainty>()?;
    m.add_class::<uncertainty::PyPixelNoiseMeter>()?;
    m.add_function(wrap_pyfunction!(project, m)?)?;
    m.add_function(wrap_pyfunction!(invariant_points, m)?)?;
    m.add_function(wrap_pyfunction!(invariant_jacobian, m)?)?;
    m.add_function(wrap_pyfunction!(structure_ratio, m)?)?;
    m.add_function(wrap_pyfunction!(interaction_matrix, m)?)?;
    m.add_function(wrap_pyfunction!(jacobian_factors, m)?)?;
    m.add_function(wrap_pyfunction!(rz_coefficients, m)?)?;
    m.add_function(wrap_pyfunction!(choose_basis, m)?)?;
    m.add_function(wrap_pyfunction!(check_stability, m)?)?;
    m.add_function(wrap_pyfunction!(tracking_bound, m)?)?;
    m.add_class::<planning::PyPlaneParallax>()?;
    m.add_class::<planning::PyInvariantPath>()?;
    m.add_class::<planning::PyResectionDepths>()?;
    m.add_function(wrap_pyfunction!(planning::estimate_plane_parallax, m)?)?;
    m.add_function(wrap_pyfunction!(planning::depths_from_translation, m)?)?;
    m.add_class::<sim::PyScenario>()?;
    m.add_class::<sim::PyRunResult>()?;
    m.add_function(wrap_pyfunction!(sim::load_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(sim::list_scenarios, m)?)?;
    m.add_function(wrap_pyfunction!(sim::run_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(sim::run_batch, m)?)?;
    m.add_class::<vision::PyDots>()?;
    m.add_class::<vision::PyDotTracker>()?;
    m.add_function(wrap_pyfunction!(vision::render, m)?)?;
    m.add_function(wrap_pyfunction!(vision::render_view, m)?)?;
    m.add_function(wrap_pyfunction!(vision::detect_dots, m)?)?;
    m.add_function(wrap_pyfunction!(vision::load_image, m)?)?;
    m.add_function(wrap_pyfunction!(vision::save_image, m)?)?;
    m.add_function(wrap_pyfunction!(se3::exp_twist, m)?)?;
    m.add_function(wrap_pyfunction!(se3::pose_from_position_thetau, m)?)?;
    m.add_function(wrap_pyfunction!(se3::thetau_from_pose, m)?)?;
    m.add_class::<lens::PyDistortion>()?;
    m.add_class::<lens::PyCalibration>()?;
    m.add_function(wrap_pyfunction!(lens::distort_points, m)?)?;
    m.add_function(wrap_pyfunction!(lens::undistort_points, m)?)?;
    m.add_function(wrap_pyfunction!(lens::load_calibration, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
