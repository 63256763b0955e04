//! The controllers: the invariant law (sec. 4) and classic IBVS, stepped from NumPy arrays.

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;

use super::arrays::{bool_array, f64_array, finite_out, from_matrix, mat, points2, points3, vec1};
use super::errors::shape_error;
use super::uncertainty::{PyPoseUncertainty, UncertaintyArgs};
use super::{BasisArg, PyIntrinsics, depths_arg, intrinsics, intrinsics_repr, pixels_arg};
use crate::core::adaptive_gain::AdaptiveGain;
use crate::core::control::{Controller, InvariantController, InvariantControllerConfig};
use crate::core::ibvs::{IbvsController, Interaction};
use crate::core::rz_task::RzTask;
use crate::core::saturation::TwistLimits;

/// Reads the step's arrays in place and returns the twist as a new (6,) array; `visible`, a
/// bool array of one flag per pixel row (None: all), hides points from the step.
fn step_controller<'py, C: Controller>(
    ctl: &mut C,
    py: Python<'py>,
    pixels: &Bound<'py, PyAny>,
    depths: &Bound<'py, PyAny>,
    visible: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let (a, z) = (pixels_arg(pixels, "pixels")?, depths_arg(depths)?);
    let px = points2(&a)?;
    let tw = match visible {
        None => ctl.step(px, z.as_slice()?)?,
        Some(visible) => {
            let v = bool_array(visible, "visible", px.len())?;
            ctl.step_visible(px, z.as_slice()?, v.as_slice()?)?
        }
    };
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
pub(super) struct PyInvariantController {
    inner: InvariantController,
}

fn state_of(c: &InvariantController) -> PyResult<&crate::core::control::ControlState> {
    c.state().ok_or_else(|| super::errors::not_ready("no control step has run yet: call step() first"))
}

#[pymethods]
impl PyInvariantController {
    #[new]
    #[allow(non_snake_case)]
    #[pyo3(
        signature = (reference_pixels, K_hat, gain = 1.0, gain_rz = 1.0, basis = BasisArg::Auto, feedforward = true, min_structure_ratio = crate::core::jacobian::DEFAULT_MIN_STRUCTURE_RATIO, rz_task = "angle", adaptive_gain = None, max_linear_speed = None, max_angular_speed = None),
        text_signature = "(reference_pixels, K_hat, gain=1.0, gain_rz=1.0, basis='auto', feedforward=True, min_structure_ratio=0.001, rz_task='angle', adaptive_gain=None, max_linear_speed=None, max_angular_speed=None)"
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
        #[pyo3(from_py_with = super::args::adaptive_gain)] adaptive_gain: Option<(f64, f64, f64)>,
        max_linear_speed: Option<f64>,
        max_angular_speed: Option<f64>,
    ) -> PyResult<Self> {
        let a = pixels_arg(reference_pixels, "reference_pixels")?;
        let px = points2(&a)?;
        let k_hat = intrinsics(K_hat, "K_hat")?;
        let rz_task = rz_task.parse()?;
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
        let basis = basis.resolve(reference_pixels.py(), px, || {
            crate::error::check_finite_points("reference_pixels", px)?;
            crate::core::jacobian::check_point_count(px.len(), crate::core::jacobian::MIN_POINTS)?;
            config.validate()
        })?;
        let inner = InvariantController::new(px, k_hat, basis, config)?;
        Ok(Self { inner })
    }

    /// One control step from the current pixels (n, 2) and depth estimates (n,): the twist
    /// (vx, vy, vz, wx, wy, wz) in the camera frame, m/s and rad/s. `visible`, a bool array
    /// (n,) (None: all), hides points: their pixels and depths are ignored (may be NaN) and
    /// drop out of s and J_hat; the three basis points and three more must be visible (else
    /// DegenerateGeometry).
    #[pyo3(signature = (pixels, depths, visible = None))]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        pixels: &Bound<'py, PyAny>,
        depths: &Bound<'py, PyAny>,
        visible: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        step_controller(&mut self.inner, py, pixels, depths, visible)
    }

    /// Replaces the estimated intrinsics K_hat (an Intrinsics or a 3x3 matrix), e.g. a zoom
    /// read-out during the servo; the next step uses them.
    #[allow(non_snake_case)]
    fn set_k_hat(&mut self, K_hat: &Bound<'_, PyAny>) -> PyResult<()> {
        let k_hat = intrinsics(K_hat, "K_hat")?;
        Ok(self.inner.set_k_hat(k_hat)?)
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
        Ok(self.inner.set_reference(points3(&s)?, r_pts)?)
    }

    /// The pose uncertainty that pixel noise of `pixel_sigma` pixels (per coordinate; the
    /// reference image's `reference_sigma`, default the same) leaves at `pixels` (n, 2) with
    /// `depths` (n,), under the invariant stop rule (s and tau_21) with this controller's
    /// reference image, basis and K_hat; `averaged_images` current images were averaged.
    /// First order; the translation is in the depths' scale and K_hat is taken as right.
    #[pyo3(signature = (pixels, depths, pixel_sigma, reference_sigma = None, averaged_images = 1, visible = None))]
    fn pose_uncertainty(
        &self,
        pixels: &Bound<'_, PyAny>,
        depths: &Bound<'_, PyAny>,
        pixel_sigma: f64,
        reference_sigma: Option<f64>,
        #[pyo3(from_py_with = super::args::averaged_images)] averaged_images: usize,
        visible: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyPoseUncertainty> {
        let args = UncertaintyArgs::read(pixels, depths, visible, pixel_sigma, reference_sigma, averaged_images)?;
        args.apply(|p, z, v, noise| self.inner.pose_uncertainty(p, z, v, noise))
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
pub(super) fn command_options(
    adaptive_gain: Option<(f64, f64, f64)>,
    max_linear_speed: Option<f64>,
    max_angular_speed: Option<f64>,
) -> PyResult<(Option<AdaptiveGain>, Option<TwistLimits>)> {
    let gain = adaptive_gain.map(|(a, b, c)| AdaptiveGain::new(a, b, c)).transpose()?;
    let limits = if max_linear_speed.is_none() && max_angular_speed.is_none() {
        None
    } else {
        let (v, w) = (max_linear_speed.unwrap_or(f64::INFINITY), max_angular_speed.unwrap_or(f64::INFINITY));
        Some(TwistLimits::new(v, w)?)
    };
    Ok((gain, limits))
}

/// Classic pixel-space IBVS: v = -lambda L_hat^+ (p - p*). Pickles with its configuration;
/// a copy's next twist is the original's, but the last step's pixel_error, last_gain and
/// saturation are not kept.
#[pyclass(name = "IbvsController", module = "vsinv._core")]
pub(super) struct PyIbvsController {
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
        #[pyo3(from_py_with = super::args::adaptive_gain)] adaptive_gain: Option<(f64, f64, f64)>,
        max_linear_speed: Option<f64>,
        max_angular_speed: Option<f64>,
    ) -> PyResult<Self> {
        let a = pixels_arg(reference_pixels, "reference_pixels")?;
        let k_hat = intrinsics(K_hat, "K_hat")?;
        let kind: Interaction = interaction.parse()?;
        let z = reference_depths.map(|z| f64_array(z, "reference_depths", &[None])).transpose()?;
        if let Some(z) = &z {
            crate::error::check_finite("reference_depths", z.as_slice()?)?;
        }
        if let Some(z) = &z
            && z.shape()[0] != a.shape()[0]
        {
            let expected = format!("{} values (one per reference pixel)", a.shape()[0]);
            return Err(shape_error("reference_depths", expected, z.shape()[0].to_string()));
        }
        let z_slice = match &z {
            Some(z) => Some(z.as_slice()?),
            None => None,
        };
        let mut inner = IbvsController::new(points2(&a)?, k_hat, gain, kind, z_slice)?;
        let (adaptive_gain, twist_limits) = command_options(adaptive_gain, max_linear_speed, max_angular_speed)?;
        inner.set_adaptive_gain(adaptive_gain)?;
        inner.set_twist_limits(twist_limits)?;
        Ok(Self { inner })
    }

    /// One control step from the current pixels (n, 2) and depths (n,): the twist (6,) in the
    /// camera frame. `visible`, a bool array (n,) (None: all), keeps only the flagged points
    /// (hidden points' pixels and depths are ignored and may be NaN); at least 4 must be
    /// visible (else DegenerateGeometry).
    #[pyo3(signature = (pixels, depths, visible = None))]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        pixels: &Bound<'py, PyAny>,
        depths: &Bound<'py, PyAny>,
        visible: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        step_controller(&mut self.inner, py, pixels, depths, visible)
    }

    /// The pose uncertainty that pixel noise of `pixel_sigma` pixels (per coordinate; the
    /// reference image's `reference_sigma`, default the same) leaves at `pixels` (n, 2) with
    /// `depths` (n,), under the pixel stop rule with this controller's reference image and
    /// K_hat (taken with the servo camera); `averaged_images` current images were averaged.
    /// First order; the translation is in the depths' scale and K_hat is taken as right.
    #[pyo3(signature = (pixels, depths, pixel_sigma, reference_sigma = None, averaged_images = 1, visible = None))]
    fn pose_uncertainty(
        &self,
        pixels: &Bound<'_, PyAny>,
        depths: &Bound<'_, PyAny>,
        pixel_sigma: f64,
        reference_sigma: Option<f64>,
        #[pyo3(from_py_with = super::args::averaged_images)] averaged_images: usize,
        visible: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyPoseUncertainty> {
        let args = UncertaintyArgs::read(pixels, depths, visible, pixel_sigma, reference_sigma, averaged_images)?;
        args.apply(|p, z, v, noise| self.inner.pose_uncertainty(p, z, v, noise))
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

/// A float or None in Python notation.
fn opt_repr(x: Option<f64>) -> String {
    x.map_or_else(|| "None".to_string(), |x| format!("{x:?}"))
}

/// A Python bool as Python writes it (`True`, `False`).
pub(super) fn bool_repr(b: bool) -> &'static str {
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

/// Adds the controllers.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyInvariantController>()?;
    m.add_class::<PyIbvsController>()?;
    Ok(())
}
