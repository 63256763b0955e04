//! Python bindings (feature `python`): the only module that knows about Python. Thin
//! wrappers that read NumPy arrays in place, call the core and map errors to the package's
//! exception hierarchy; no panic crosses into Python.

mod args;
mod arrays;
mod errors;
mod lens;
mod planning;
mod se3;
mod sim;
mod vision;

use nalgebra::Matrix3;
use numpy::{Complex64, PyArray1, PyArray2, PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyString, PyType};

use arrays::{F64Array, bool_array, f64_array, finite_out, from_matrix, mat, points2, points3, vec1};
use errors::{invalid_input, to_py};

use crate::core::adaptive_gain::AdaptiveGain;
use crate::core::camera::Intrinsics;
use crate::core::control::{Controller, InvariantController, InvariantControllerConfig};
use crate::core::ibvs::{IbvsController, Interaction};
use crate::core::rz_task::RzTask;
use crate::core::saturation::TwistLimits;
use crate::core::stability::{StabilityReport, check_upper_triangular};

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
    pub(crate) fn resolve(self, pixels: &[[f64; 2]]) -> PyResult<[usize; 3]> {
        match self {
            BasisArg::Fixed(b) => Ok(b),
            BasisArg::Auto => crate::core::invariant::choose_basis(pixels).map_err(to_py),
        }
    }
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
fn intrinsics(obj: &Bound<'_, PyAny>, what: &'static str) -> PyResult<Intrinsics> {
    if let Ok(k) = obj.cast::<PyIntrinsics>() {
        return Ok(k.get().inner);
    }
    Intrinsics::from_matrix(&matrix3(obj, what)?).map_err(to_py)
}

pub(crate) fn pixels_arg<'py>(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<F64Array<'py>> {
    f64_array(obj, what, &[None, Some(2)])
}

fn depths_arg<'py>(obj: &Bound<'py, PyAny>) -> PyResult<F64Array<'py>> {
    f64_array(obj, "depths", &[None])
}

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
    let q = crate::core::invariant::invariant_points(px, basis.resolve(px)?).map_err(to_py)?;
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
    let j = crate::core::jacobian::invariant_jacobian(px, z.as_slice()?, &k, basis.resolve(px)?).map_err(to_py)?;
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
    let (phi, psi) = crate::core::jacobian::jacobian_factors(px, z.as_slice()?, basis.resolve(px)?).map_err(to_py)?;
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
    let (coef_a, c) =
        crate::core::jacobian::rz_coefficients(px, z.as_slice()?, rpx, &k, basis.resolve(rpx)?).map_err(to_py)?;
    finite_out("pixels, depths, reference_pixels, K", &[coef_a])?;
    finite_out("pixels, depths, reference_pixels, K", c.as_slice())?;
    Ok((coef_a, vec1(py, c.as_slice())))
}

/// sigma_5/sigma_1 of the depth-balanced invariant Jacobian (degenerate-structure measure).
#[pyfunction]
#[pyo3(signature = (pixels, depths, K, basis = BasisArg::Fixed([0, 1, 2])), text_signature = "(pixels, depths, K, basis=(0, 1, 2))")]
#[allow(non_snake_case)]
fn structure_ratio(
    pixels: &Bound<'_, PyAny>,
    depths: &Bound<'_, PyAny>,
    K: &Bound<'_, PyAny>,
    basis: BasisArg,
) -> PyResult<f64> {
    let (a, z) = (pixels_arg(pixels, "pixels")?, depths_arg(depths)?);
    let px = points2(&a)?;
    let k = intrinsics(K, "K")?;
    let r = crate::core::jacobian::structure_ratio(px, z.as_slice()?, &k, basis.resolve(px)?).map_err(to_py)?;
    finite_out("pixels, depths, K", &[r])?;
    Ok(r)
}

/// Three points well spread in the image (the widest triangle), sorted.
#[pyfunction]
fn choose_basis(pixels: &Bound<'_, PyAny>) -> PyResult<(usize, usize, usize)> {
    let a = pixels_arg(pixels, "pixels")?;
    let [i, j, k] = crate::core::invariant::choose_basis(points2(&a)?).map_err(to_py)?;
    Ok((i, j, k))
}

/// Reads the step's arrays in place and returns the twist as a new (6,) array.
fn step_controller<'py, C: Controller>(
    ctl: &mut C,
    py: Python<'py>,
    pixels: &Bound<'py, PyAny>,
    depths: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let (a, z) = (pixels_arg(pixels, "pixels")?, depths_arg(depths)?);
    let tw = ctl.step(points2(&a)?, z.as_slice()?).map_err(to_py)?;
    finite_out("pixels, depths", tw.as_slice())?;
    Ok(vec1(py, tw.as_slice()))
}

/// `step_controller` with a visibility mask: a bool array of one flag per pixel row.
fn step_controller_visible<'py, C: Controller>(
    ctl: &mut C,
    py: Python<'py>,
    pixels: &Bound<'py, PyAny>,
    depths: &Bound<'py, PyAny>,
    visible: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let (a, z) = (pixels_arg(pixels, "pixels")?, depths_arg(depths)?);
    let px = points2(&a)?;
    let v = bool_array(visible, "visible", px.len())?;
    let tw = ctl.step_visible(px, z.as_slice()?, v.as_slice()?).map_err(to_py)?;
    finite_out("pixels, depths", tw.as_slice())?;
    Ok(vec1(py, tw.as_slice()))
}

/// The reference pixels as a new (n, 2) array.
fn pixels_out<'py>(py: Python<'py>, px: &[[f64; 2]]) -> PyResult<Bound<'py, PyArray2<f64>>> {
    mat(py, px.len(), 2, px.as_flattened().to_vec())
}

/// (n, 3) invariant points as a new array.
fn invariants_out<'py>(py: Python<'py>, s: &[nalgebra::Vector3<f64>]) -> PyResult<Bound<'py, PyArray2<f64>>> {
    mat(py, s.len(), 3, s.iter().flat_map(|q| [q.x, q.y, q.z]).collect())
}

/// The invariant visual-servoing law (sec. 4): eqs. (14), (17) and (24). Pickles with its
/// configuration, K_hat and s*(t); a copy's next twist is the original's, but the state of
/// the last step (eps, tau_11, ...) is not kept.
#[pyclass(name = "InvariantController", module = "vsinv._core")]
struct PyInvariantController {
    inner: InvariantController,
}

fn state_of(c: &InvariantController) -> PyResult<&crate::core::control::ControlState> {
    c.state().ok_or_else(|| errors::not_ready("no control step has run yet: call step() first"))
}

#[pymethods]
impl PyInvariantController {
    #[new]
    #[allow(non_snake_case)]
    #[pyo3(
        signature = (reference_pixels, K_hat, gain = 1.0, gain_rz = 1.0, basis = BasisArg::Fixed([0, 1, 2]), feedforward = true, min_structure_ratio = crate::core::jacobian::DEFAULT_MIN_STRUCTURE_RATIO, rz_task = "angle", adaptive_gain = None, max_linear_speed = None, max_angular_speed = None),
        text_signature = "(reference_pixels, K_hat, gain=1.0, gain_rz=1.0, basis=(0, 1, 2), feedforward=True, min_structure_ratio=0.001, rz_task='angle', adaptive_gain=None, max_linear_speed=None, max_angular_speed=None)"
    )]
    #[allow(clippy::too_many_arguments)]
    fn new(
        reference_pixels: &Bound<'_, PyAny>,
        K_hat: &Bound<'_, PyAny>,
        gain: f64,
        gain_rz: f64,
        basis: BasisArg,
        feedforward: bool,
        min_structure_ratio: f64,
        rz_task: &str,
        #[pyo3(from_py_with = args::adaptive_gain)] adaptive_gain: Option<(f64, f64, f64)>,
        max_linear_speed: Option<f64>,
        max_angular_speed: Option<f64>,
    ) -> PyResult<Self> {
        let a = pixels_arg(reference_pixels, "reference_pixels")?;
        let px = points2(&a)?;
        let k_hat = intrinsics(K_hat, "K_hat")?;
        let rz_task = rz_task.parse().map_err(to_py)?;
        let (adaptive_gain, twist_limits) = command_options(adaptive_gain, max_linear_speed, max_angular_speed)?;
        let config = InvariantControllerConfig {
            gain,
            gain_rz,
            feedforward,
            min_structure_ratio,
            rz_task,
            adaptive_gain,
            twist_limits,
        };
        let inner = InvariantController::new(px, k_hat, basis.resolve(px)?, config).map_err(to_py)?;
        Ok(Self { inner })
    }

    /// One control step from the current pixels (n, 2) and depth estimates (n,): the twist
    /// (vx, vy, vz, wx, wy, wz) in the camera frame, m/s and rad/s.
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        pixels: &Bound<'py, PyAny>,
        depths: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        step_controller(&mut self.inner, py, pixels, depths)
    }

    /// A step with some points hidden: `visible` is a bool array (n,); hidden points'
    /// pixels and depths are ignored (may be NaN) and drop out of s and J_hat. The three basis
    /// points and three more must be visible (else DegenerateGeometry).
    fn step_visible<'py>(
        &mut self,
        py: Python<'py>,
        pixels: &Bound<'py, PyAny>,
        depths: &Bound<'py, PyAny>,
        visible: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        step_controller_visible(&mut self.inner, py, pixels, depths, visible)
    }

    /// Replaces the estimated intrinsics K_hat (an Intrinsics or a 3x3 matrix), e.g. a zoom
    /// read-out during the servo; the next step uses them.
    #[allow(non_snake_case)]
    fn set_k_hat(&mut self, K_hat: &Bound<'_, PyAny>) -> PyResult<()> {
        let k_hat = intrinsics(K_hat, "K_hat")?;
        self.inner.set_k_hat(k_hat).map_err(to_py)
    }

    /// The estimated intrinsics K_hat used in the Jacobian.
    #[getter]
    fn k_hat(&self) -> PyIntrinsics {
        PyIntrinsics { inner: *self.inner.k_hat() }
    }

    fn __repr__(&self) -> String {
        let (c, [a, b, d]) = (self.inner.config(), self.inner.basis());
        let (v, w) = twist_limit_args(c.twist_limits);
        format!(
            "InvariantController(n_points={}, K_hat={}, gain={:?}, gain_rz={:?}, basis=({a}, {b}, {d}), \
             feedforward={}, min_structure_ratio={:?}, rz_task='{}', adaptive_gain={}, max_linear_speed={}, \
             max_angular_speed={})",
            self.inner.num_points(),
            intrinsics_repr(self.inner.k_hat()),
            c.gain,
            c.gain_rz,
            bool_repr(c.feedforward),
            c.min_structure_ratio,
            rz_task_name(c.rz_task),
            adaptive_gain_repr(c.adaptive_gain),
            opt_repr(v),
            opt_repr(w),
        )
    }

    /// Pickling: the constructor's arguments (reference pixels, K_hat, gains, basis,
    /// feed-forward, min_structure_ratio, rz_task, adaptive gain, speed limits) and the
    /// reference s*(t) with its rate as set by `set_reference`. The next twist of the copy is
    /// that of the original; the state of the last step (eps, tau_11, ...) is not kept.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let py = slf.py();
        let this = slf.borrow();
        let (ctl, c) = (&this.inner, this.inner.config());
        let (v, w) = twist_limit_args(c.twist_limits);
        let [a, b, d] = ctl.basis();
        let args = (
            pixels_out(py, ctl.reference_pixels())?,
            PyIntrinsics { inner: *ctl.k_hat() },
            c.gain,
            c.gain_rz,
            (a, b, d),
            c.feedforward,
            c.min_structure_ratio,
            rz_task_name(c.rz_task),
            adaptive_gain_args(c.adaptive_gain),
            v,
            w,
        );
        let rate = ctl.reference_rate().map(|r| invariants_out(py, r)).transpose()?;
        let state = (invariants_out(py, ctl.reference_invariants())?, rate);
        (slf.get_type(), args, state).into_pyobject(py).map(Bound::into_any)
    }

    /// Unpickling: restores the reference s*(t) and its rate, `(s_star, rate or None)`.
    fn __setstate__(&mut self, state: (Bound<'_, PyAny>, Option<Bound<'_, PyAny>>)) -> PyResult<()> {
        self.set_reference(&state.0, state.1.as_ref())
    }

    /// Sets a time-varying reference s*(t) ((n-3, 3) invariant points) and optionally its
    /// derivative ds*/dt (same shape) for the feed-forward term of eq. (17).
    #[pyo3(signature = (s_star, rate = None))]
    fn set_reference(&mut self, s_star: &Bound<'_, PyAny>, rate: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
        let s = f64_array(s_star, "s_star", &[None, Some(3)])?;
        let r = rate.map(|r| f64_array(r, "rate", &[None, Some(3)])).transpose()?;
        let r_pts = match &r {
            Some(r) => Some(points3(r)?),
            None => None,
        };
        self.inner.set_reference(points3(&s)?, r_pts).map_err(to_py)
    }

    /// Stop rule for different cameras: ||s - s*|| < invariant_tol, |tau_21| < tau21_tol,
    /// tau_11 > 0 and tau_22 > 0 (the last two exclude the rz = pi equilibrium).
    #[pyo3(signature = (invariant_tol = 1e-4, tau21_tol = 1e-4))]
    fn converged(&self, invariant_tol: f64, tau21_tol: f64) -> bool {
        self.inner.converged(invariant_tol, tau21_tol)
    }

    /// The basis indices.
    #[getter]
    fn basis(&self) -> (usize, usize, usize) {
        let [a, b, c] = self.inner.basis();
        (a, b, c)
    }
    /// The reference s*(t): (n-3, 3) invariant points of the non-basis points.
    #[getter]
    fn reference_invariants<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        invariants_out(py, self.inner.reference_invariants())
    }
    /// Task function eps of eq. (14) at the last step, (5,).
    #[getter]
    fn eps<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        Ok(vec1(py, state_of(&self.inner)?.eps.as_slice()))
    }
    /// eps_z = det(Q*) tau_21 at the last step.
    #[getter]
    fn eps_z(&self) -> PyResult<f64> {
        Ok(state_of(&self.inner)?.eps_z)
    }
    /// ||s - s*|| at the last step.
    #[getter]
    fn invariant_error(&self) -> PyResult<f64> {
        Ok(state_of(&self.inner)?.invariant_error)
    }
    /// tau_11 of T = Q Q*^-1 at the last step.
    #[getter]
    fn tau_11(&self) -> PyResult<f64> {
        Ok(state_of(&self.inner)?.tau11())
    }
    /// tau_21 of T at the last step.
    #[getter]
    fn tau_21(&self) -> PyResult<f64> {
        Ok(state_of(&self.inner)?.tau21())
    }
    /// tau_22 of T at the last step.
    #[getter]
    fn tau_22(&self) -> PyResult<f64> {
        Ok(state_of(&self.inner)?.tau22())
    }
    /// T = Q Q*^-1 (eq. 21) at the last step, (3, 3).
    #[getter]
    fn t_matrix<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        from_matrix(py, &state_of(&self.inner)?.t)
    }
    /// The lambda used at the last step (`gain`, or the adaptive gain at the invariant error).
    #[getter]
    fn last_gain(&self) -> PyResult<f64> {
        Ok(state_of(&self.inner)?.gain)
    }
    /// The factor the speed limits scaled the last twist by (1.0: within the limits).
    #[getter]
    fn saturation(&self) -> PyResult<f64> {
        Ok(state_of(&self.inner)?.saturation)
    }
}

/// The adaptive gain `(lambda_0, lambda_inf, lambda'_0)` and the speed limits (m/s, rad/s;
/// None leaves one free) of a controller.
fn command_options(
    adaptive_gain: Option<(f64, f64, f64)>,
    max_linear_speed: Option<f64>,
    max_angular_speed: Option<f64>,
) -> PyResult<(Option<AdaptiveGain>, Option<TwistLimits>)> {
    let gain = adaptive_gain.map(|(a, b, c)| AdaptiveGain::new(a, b, c)).transpose().map_err(to_py)?;
    let limits = if max_linear_speed.is_none() && max_angular_speed.is_none() {
        None
    } else {
        let (v, w) = (max_linear_speed.unwrap_or(f64::INFINITY), max_angular_speed.unwrap_or(f64::INFINITY));
        Some(TwistLimits::new(v, w).map_err(to_py)?)
    };
    Ok((gain, limits))
}

/// Classic pixel-space IBVS: v = -lambda L_hat^+ (p - p*). Pickles with its configuration;
/// a copy's next twist is the original's, but the last step's pixel_error, last_gain and
/// saturation are not kept.
#[pyclass(name = "IbvsController", module = "vsinv._core")]
struct PyIbvsController {
    inner: IbvsController,
}

#[pymethods]
impl PyIbvsController {
    #[new]
    #[allow(non_snake_case)]
    #[pyo3(
        signature = (reference_pixels, K_hat, gain = 1.0, interaction = "current", reference_depths = None, adaptive_gain = None, max_linear_speed = None, max_angular_speed = None),
        text_signature = "(reference_pixels, K_hat, gain=1.0, interaction='current', reference_depths=None, adaptive_gain=None, max_linear_speed=None, max_angular_speed=None)"
    )]
    #[allow(clippy::too_many_arguments)]
    fn new(
        reference_pixels: &Bound<'_, PyAny>,
        K_hat: &Bound<'_, PyAny>,
        gain: f64,
        interaction: &str,
        reference_depths: Option<&Bound<'_, PyAny>>,
        #[pyo3(from_py_with = args::adaptive_gain)] adaptive_gain: Option<(f64, f64, f64)>,
        max_linear_speed: Option<f64>,
        max_angular_speed: Option<f64>,
    ) -> PyResult<Self> {
        let a = pixels_arg(reference_pixels, "reference_pixels")?;
        let k_hat = intrinsics(K_hat, "K_hat")?;
        let kind: Interaction = interaction.parse().map_err(to_py)?;
        let z = reference_depths.map(|z| f64_array(z, "reference_depths", &[None])).transpose()?;
        if let Some(z) = &z {
            crate::error::check_finite("reference_depths", z.as_slice()?).map_err(to_py)?;
        }
        if let Some(z) = &z
            && z.shape()[0] != a.shape()[0]
        {
            return Err(invalid_input(format!(
                "reference_depths: expected {} values (one per reference pixel), got {}",
                a.shape()[0],
                z.shape()[0]
            )));
        }
        let z_slice = match &z {
            Some(z) => Some(z.as_slice()?),
            None => None,
        };
        let mut inner = IbvsController::new(points2(&a)?, k_hat, gain, kind, z_slice).map_err(to_py)?;
        let (adaptive_gain, twist_limits) = command_options(adaptive_gain, max_linear_speed, max_angular_speed)?;
        inner.set_adaptive_gain(adaptive_gain).map_err(to_py)?;
        inner.set_twist_limits(twist_limits).map_err(to_py)?;
        Ok(Self { inner })
    }

    /// One control step: the twist (6,) in the camera frame.
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        pixels: &Bound<'py, PyAny>,
        depths: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        step_controller(&mut self.inner, py, pixels, depths)
    }

    /// A step with only the points flagged in `visible`, a bool array (n,) (hidden points'
    /// pixels and depths are ignored and may be NaN); at least 4 must be visible (else
    /// DegenerateGeometry).
    fn step_visible<'py>(
        &mut self,
        py: Python<'py>,
        pixels: &Bound<'py, PyAny>,
        depths: &Bound<'py, PyAny>,
        visible: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        step_controller_visible(&mut self.inner, py, pixels, depths, visible)
    }

    fn __repr__(&self) -> String {
        let c = &self.inner;
        let (v, w) = twist_limit_args(c.twist_limits());
        format!(
            "IbvsController(n_points={}, K_hat={}, gain={:?}, interaction='{}', reference_depths={}, \
             adaptive_gain={}, max_linear_speed={}, max_angular_speed={})",
            c.reference_pixels().len(),
            intrinsics_repr(c.k_hat()),
            c.gain(),
            interaction_name(c.interaction()),
            if c.reference_depths().is_some() { "given" } else { "None" },
            adaptive_gain_repr(c.adaptive_gain()),
            opt_repr(v),
            opt_repr(w),
        )
    }

    /// Pickling: the constructor's arguments (reference pixels, K_hat, gain, interaction,
    /// reference depths, adaptive gain, speed limits). The next twist of the copy is that of
    /// the original; the last step's pixel_error, last_gain and saturation are not kept.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let py = slf.py();
        let this = slf.borrow();
        let c = &this.inner;
        let (v, w) = twist_limit_args(c.twist_limits());
        let args = (
            pixels_out(py, c.reference_pixels())?,
            PyIntrinsics { inner: *c.k_hat() },
            c.gain(),
            interaction_name(c.interaction()),
            c.reference_depths().map(|z| vec1(py, z)),
            adaptive_gain_args(c.adaptive_gain()),
            v,
            w,
        );
        (slf.get_type(), args).into_pyobject(py).map(Bound::into_any)
    }

    /// RMS pixel error at the last step (None before the first step).
    #[getter]
    fn pixel_error(&self) -> Option<f64> {
        self.inner.last_pixel_error()
    }
    /// The lambda used at the last step (None before the first step).
    #[getter]
    fn last_gain(&self) -> Option<f64> {
        self.inner.last_command().map(|c| c.0)
    }
    /// The factor the speed limits scaled the last twist by (None before the first step).
    #[getter]
    fn saturation(&self) -> Option<f64> {
        self.inner.last_command().map(|c| c.1)
    }
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
    /// Prop. 3: the bound psi/phi on ||eps|| when ||b(t)|| <= max_b.
    fn tracking_bound(&self, max_b: f64) -> PyResult<f64> {
        self.inner.tracking_bound(max_b).map_err(to_py)
    }
    fn __repr__(&self) -> String {
        format!(
            "StabilityReport(prop1={}, prop2={}, sigma={:.6})",
            self.inner.prop1, self.inner.prop2, self.inner.sigma
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

/// Prop. 3 bound psi/phi = 2 max_b / (gain sigma) (eq. 20).
#[pyfunction]
fn tracking_bound(gain: f64, sigma: f64, max_b: f64) -> PyResult<f64> {
    crate::core::stability::tracking_bound(gain, sigma, max_b).map_err(to_py)
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    errors::register(m)?;
    m.add_class::<PyIntrinsics>()?;
    m.add_class::<PyInvariantController>()?;
    m.add_class::<PyIbvsController>()?;
    m.add_class::<PyStabilityReport>()?;
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
