//! `vsinv.Servo`: the servo session (the `servo` layer) stepped from NumPy arrays.

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

use super::arrays::{bool_array, mat, points2, vec1};
use super::errors::invalid_argument;
use super::{BasisArg, depths_arg, intrinsics, pixels_arg};
use crate::core::adaptive_gain::AdaptiveGain;
use crate::core::camera::Intrinsics;
use crate::servo::law::options::{LAW_OPTIONS, LAWS, LawOptions, OptionKind, OptionSpec, OptionValue, option};
use crate::servo::{
    Law, PathPlan, Servo, ServoConfig, ServoDepths, ServoReference, ServoStep, StopRule, StopRules, Telemetry,
};
use crate::sim::scenario::DEPTHS_REMEDY;

/// The law named `law` with the options given; an option of another law is refused by name.
fn law_of(law: &str, options: &LawOptions) -> PyResult<Law> {
    if !LAWS.contains(&law) {
        return Err(invalid_argument("law", format!("law: expected \"invariant\", \"ibvs\" or \"none\", got {law:?}")));
    }
    if let Some(name) = options.given().find(|n| option(n).is_some_and(|o| !o.reads(law))) {
        return Err(invalid_argument(name, format!("{name}: not an argument of the {law:?} law")));
    }
    Ok(Law::from_options(law, options)?)
}

/// A law option's value from Python, as the table's kind says; None when unset.
pub(super) fn option_value(spec: &OptionSpec, value: &Bound<'_, PyAny>) -> PyResult<Option<OptionValue>> {
    if value.is_none() {
        return Ok(None);
    }
    let py = value.py();
    let name = spec.name;
    let bad = |e: PyErr| invalid_argument(name, format!("{name}: {}", e.value(py)));
    Ok(Some(match spec.kind {
        OptionKind::Number => OptionValue::Number(value.extract().map_err(bad)?),
        OptionKind::Flag => OptionValue::Flag(value.extract().map_err(bad)?),
        OptionKind::Choice(_) => OptionValue::Choice(value.extract().map_err(bad)?),
        OptionKind::AdaptiveGain => match super::args::adaptive_gain(value)? {
            Some((at_zero, at_infinity, slope_at_zero)) => {
                OptionValue::AdaptiveGain(AdaptiveGain { at_zero, at_infinity, slope_at_zero })
            }
            None => return Ok(None),
        },
    }))
}

/// The `stop` dictionary over the default stop rules; an unknown key is refused by name.
fn stop_rules(stop: Option<&Bound<'_, PyDict>>) -> PyResult<StopRules> {
    let mut rules = StopRules::default();
    let Some(stop) = stop else { return Ok(rules) };
    for (key, value) in stop.iter() {
        let key: String = key.extract().map_err(|_| invalid_argument("stop", "stop: keys must be strings".into()))?;
        let bad = |_| invalid_argument(&format!("stop.{key}"), format!("stop.{key}: expected a number"));
        match key.as_str() {
            "max_iterations" => rules.max_iterations = value.extract().map_err(bad)?,
            "window" => rules.window = value.extract().map_err(bad)?,
            "pixel_error" => rules.pixel_error = value.extract().map_err(bad)?,
            "invariant_error" => rules.invariant_error = value.extract().map_err(bad)?,
            "tau21" => rules.tau21 = value.extract().map_err(bad)?,
            "max_translation_uncertainty" => rules.max_translation_uncertainty = value.extract().map_err(bad)?,
            "max_rotation_uncertainty_deg" => rules.max_rotation_uncertainty_deg = value.extract().map_err(bad)?,
            "reference_pixel_sigma" => rules.reference_pixel_sigma = value.extract().map_err(bad)?,
            "stall" => rules.stall = value.extract().map_err(bad)?,
            "stall_window" => rules.stall_window = value.extract().map_err(bad)?,
            "stall_motion" => rules.stall_motion = value.extract().map_err(bad)?,
            _ => {
                let known = "max_iterations, window, pixel_error, invariant_error, tau21, \
                             max_translation_uncertainty, max_rotation_uncertainty_deg, reference_pixel_sigma, \
                             stall, stall_window, stall_motion";
                return Err(invalid_argument(
                    &format!("stop.{key}"),
                    format!("stop.{key}: unknown key; known: {known}"),
                ));
            }
        }
    }
    Ok(rules)
}

/// `depths`: "reference", "per_step", one depth in metres for every point, or a
/// `ResectionDepths` estimator (appendix A; the session runs a copy of it).
fn depth_source(depths: &Bound<'_, PyAny>) -> PyResult<ServoDepths> {
    if let Ok(e) = depths.cast::<super::planning::PyResectionDepths>() {
        return Ok(ServoDepths::Estimated(Box::new(e.borrow().inner.clone())));
    }
    if let Ok(s) = depths.cast::<PyString>() {
        return match &*s.to_cow()? {
            "reference" => Ok(ServoDepths::Reference),
            "per_step" => Ok(ServoDepths::PerStep),
            other => Err(invalid_argument(
                "depths",
                format!("depths: expected \"reference\", \"per_step\" or a depth, got {other:?}"),
            )),
        };
    }
    let z: f64 = depths.extract().map_err(|_| {
        invalid_argument("depths", "depths: expected \"reference\", \"per_step\", a number or a ResectionDepths".into())
    })?;
    Ok(ServoDepths::Constant(z))
}

fn parse_stop_rule(name: Option<&str>) -> PyResult<Option<StopRule>> {
    match name {
        None => Ok(None),
        Some("pixel") => Ok(Some(StopRule::Pixel)),
        Some("invariant") => Ok(Some(StopRule::Invariant)),
        Some(other) => {
            Err(invalid_argument("stop_rule", format!("stop_rule: expected \"pixel\" or \"invariant\", got {other:?}")))
        }
    }
}

/// Every keyword argument of `Servo` but the reference pixels and K_hat: what `ImageServo`
/// passes on to its session.
pub(super) struct ServoOptions<'py> {
    law: String,
    reference_depths: Option<Bound<'py, PyAny>>,
    depths: Option<Bound<'py, PyAny>>,
    basis: BasisArg,
    /// The laws' options given ([`LAW_OPTIONS`]), checked.
    law_options: LawOptions,
    stop: Option<Bound<'py, PyDict>>,
    stop_rule: Option<String>,
    path_samples: Option<usize>,
    basis_hold: Option<usize>,
    dt: f64,
}

/// The session's keyword arguments `ServoOptions::from_kwargs` knows besides the laws'
/// options ([`LAW_OPTIONS`]), in `Servo`'s order.
pub(super) const SESSION_OPTIONS: [&str; 9] =
    ["law", "reference_depths", "depths", "basis", "stop", "stop_rule", "path_samples", "basis_hold", "dt"];

/// Every keyword argument of the session: its own, then the laws' options.
pub(super) fn servo_option_names() -> Vec<&'static str> {
    SESSION_OPTIONS.iter().copied().chain(LAW_OPTIONS.iter().map(|o| o.name)).collect()
}

impl<'py> ServoOptions<'py> {
    /// The options in a `**kwargs` dictionary (None: the defaults); a key `Servo` does not
    /// take is refused by name.
    pub(super) fn from_kwargs(kwargs: Option<&Bound<'py, PyDict>>) -> PyResult<Self> {
        let mut o = Self {
            law: "invariant".into(),
            reference_depths: None,
            depths: None,
            basis: BasisArg::Auto,
            law_options: LawOptions::new(),
            stop: None,
            stop_rule: None,
            path_samples: None,
            basis_hold: None,
            dt: 0.04,
        };
        let Some(kwargs) = kwargs else { return Ok(o) };
        for (key, value) in kwargs.iter() {
            let key: String = key.extract()?;
            o.set(&key, value)?;
        }
        Ok(o)
    }

    fn set(&mut self, key: &str, value: Bound<'py, PyAny>) -> PyResult<()> {
        let py = value.py();
        let bad = |e: PyErr| invalid_argument(key, format!("{key}: {}", e.value(py)));
        let given = !value.is_none();
        match key {
            "law" => self.law = value.extract().map_err(bad)?,
            "reference_depths" => self.reference_depths = given.then_some(value),
            "depths" => self.depths = given.then_some(value),
            "basis" => self.basis = value.extract()?,
            "stop" => {
                self.stop = if given { Some(value.cast_into::<PyDict>().map_err(|e| bad(e.into()))?) } else { None }
            }
            "stop_rule" => self.stop_rule = value.extract().map_err(bad)?,
            "path_samples" => self.path_samples = value.extract().map_err(bad)?,
            "basis_hold" => self.basis_hold = value.extract().map_err(bad)?,
            "dt" => self.dt = value.extract().map_err(bad)?,
            _ if option(key).is_some() => self.set_law_option(key, &value)?,
            _ => {
                let known = servo_option_names().join(", ");
                return Err(invalid_argument(
                    key,
                    format!("{key}: not an argument of the servo session; known: {known}"),
                ));
            }
        }
        Ok(())
    }

    /// A law option, checked against the table (the error names it).
    fn set_law_option(&mut self, key: &str, value: &Bound<'py, PyAny>) -> PyResult<()> {
        let Some(spec) = option(key) else { return Ok(()) };
        if let Some(v) = option_value(spec, value)? {
            self.law_options.set(spec.name, v)?;
        }
        Ok(())
    }

    /// Whether the `stop` dictionary sets `key`.
    pub(super) fn stop_sets(&self, key: &str) -> bool {
        self.stop.as_ref().is_some_and(|d| d.contains(key).unwrap_or(false))
    }

    /// The session's configuration, the reference depths and the depth source.
    pub(super) fn session(self, k_hat: Intrinsics) -> PyResult<(ServoConfig, Option<Vec<f64>>, ServoDepths)> {
        let law = law_of(&self.law, &self.law_options)?;
        let reference_depths = match &self.reference_depths {
            Some(z) => Some(depths_arg(z)?.as_slice()?.to_vec()),
            None => None,
        };
        let source = match &self.depths {
            Some(d) => depth_source(d)?,
            None => ServoDepths::Reference,
        };
        let mut config = ServoConfig::new(law, k_hat);
        config.stop = stop_rules(self.stop.as_ref())?;
        (config.stop_rule, config.dt) = (parse_stop_rule(self.stop_rule.as_deref())?, self.dt);
        config.path = self.path_samples.map(|samples| PathPlan { samples });
        if let Some(images) = self.basis_hold {
            config.basis_hold = images;
        }
        config.basis = match self.basis {
            BasisArg::Fixed(b) => Some(b),
            BasisArg::Auto => None,
        };
        Ok((config, reference_depths, source))
    }
}

/// A servo session: the reference image, the law, the depth source and the stop rules; each
/// `step(pixels, depths, visible)` returns the twist to send and the verdict.
///
/// The keyword arguments are the session's (`reference_depths`, `depths`, `basis`, `stop`,
/// `stop_rule`, `path_samples`, `basis_hold`, `dt`) and the laws' options
/// (`vsinv.laws.LAW_OPTIONS`: `gain` to `max_angular_speed`; None or absent: the law's default);
/// arguments of another law are refused by name. `basis_hold` (default 3) is how many
/// consecutive images a missing basis point is ridden out, the basis kept and the last twist
/// repeated with no stop judged; 0 changes the basis at once. A step runs the loop logic the
/// simulator runs too: stop rules certified by the pose uncertainty, lost features, the rz = pi
/// trap, the iteration limit, depth estimation, path following. A stop is final: once a step has
/// returned one, every later step returns the same verdict with a zero twist.
///
/// Works from several threads: each call holds the GIL, so calls take turns.
#[pyclass(name = "Servo", module = "vsinv._core")]
pub(super) struct PyServo {
    inner: Servo,
}

#[pymethods]
impl PyServo {
    #[new]
    #[allow(non_snake_case)]
    #[pyo3(
        signature = (reference_pixels, K_hat, law = "invariant", **options),
        text_signature = "(reference_pixels, K_hat, law='invariant', **options)"
    )]
    fn new(
        py: Python<'_>,
        reference_pixels: &Bound<'_, PyAny>,
        K_hat: &Bound<'_, PyAny>,
        law: &str,
        options: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let a = pixels_arg(reference_pixels, "reference_pixels")?;
        let pixels = points2(&a)?.to_vec();
        let k_hat = intrinsics(K_hat, "K_hat")?;
        let mut options = ServoOptions::from_kwargs(options)?;
        options.law = law.to_string();
        let (config, reference_depths, source) = options.session(k_hat)?;
        let reference = ServoReference { pixels, depths: reference_depths };
        let inner = py.detach(|| Servo::new(config, reference, source))?;
        Ok(Self { inner })
    }

    /// One step from the current pixels (n, 2): `depths` (n,) with `depths="per_step"` (None
    /// otherwise), `visible` a bool array (n,) of the points found (None: all). Returns a
    /// ServoStep: the twist to send (zero when stopping), the verdict and the telemetry. After a
    /// stop, every later step returns that stop again (zero twist).
    #[pyo3(signature = (pixels, depths = None, visible = None))]
    fn step(
        &mut self,
        pixels: &Bound<'_, PyAny>,
        depths: Option<&Bound<'_, PyAny>>,
        visible: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyServoStep> {
        let a = pixels_arg(pixels, "pixels")?;
        let px = points2(&a)?;
        let z = depths.map(depths_arg).transpose()?;
        let v = visible.map(|v| bool_array(v, "visible", px.len())).transpose()?;
        let step = self.inner.step(
            px,
            v.as_ref().map(|v| v.as_slice()).transpose()?,
            z.as_ref().map(|z| z.as_slice()).transpose()?,
        )?;
        Ok(PyServoStep::from(step))
    }

    /// Control steps applied.
    #[getter]
    fn iterations(&self) -> usize {
        self.inner.iterations()
    }
    /// The basis in use (three point indices; it changes when a basis point is not visible).
    #[getter]
    fn basis(&self) -> (usize, usize, usize) {
        let [a, b, c] = self.inner.basis();
        (a, b, c)
    }
    /// How many times the basis changed because one of its points was not visible.
    #[getter]
    fn basis_switches(&self) -> usize {
        self.inner.basis_switches()
    }
    /// How many images were ridden out with a basis point missing: the basis kept and the last
    /// twist repeated (`basis_hold`).
    #[getter]
    fn basis_held_images(&self) -> usize {
        self.inner.basis_held_images()
    }
    /// The law: "invariant", "ibvs" or "none".
    #[getter]
    fn law(&self) -> &'static str {
        self.inner.law().name()
    }
    /// The image rule that decides convergence: "pixel" or "invariant".
    #[getter]
    fn stop_rule(&self) -> &'static str {
        match self.inner.stop_rule() {
            StopRule::Pixel => "pixel",
            StopRule::Invariant => "invariant",
        }
    }
    /// The reference pixels (n, 2).
    #[getter]
    fn reference_pixels<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let px = self.inner.reference_pixels();
        mat(py, px.len(), 2, px.as_flattened().to_vec())
    }
    /// The pixel noise measured on the last images (None before three), pixels.
    #[getter]
    fn pixel_sigma(&self) -> Option<f64> {
        self.inner.pixel_sigma()
    }
    /// What the images say about the pose, a dict of pixel_sigma, reference_pixel_sigma,
    /// translation_sigma, translation_bound in metres, rotation_sigma, rotation_bound in radians,
    /// floor_pixel_sigma in pixels: the disagreement floor, None with the stall rule off; None
    /// when it cannot be computed.
    fn certainty<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        certainty_dict(py, &self.inner)
    }
    fn __repr__(&self) -> String {
        let s = &self.inner;
        format!(
            "Servo(law={:?}, points={}, basis={:?}, iterations={})",
            s.law().name(),
            s.pixels().len(),
            s.basis(),
            s.iterations()
        )
    }
}

/// A session's `certainty()` as the dict Python sees: pixel_sigma, reference_pixel_sigma
/// (pixels), translation_sigma, translation_bound (metres), rotation_sigma, rotation_bound
/// (radians; the accuracy ceiling, with the disagreement floor when the stall rule is on),
/// floor_pixel_sigma (pixels, None with the stall rule off); None when it cannot be computed.
pub(super) fn certainty_dict<'py>(py: Python<'py>, servo: &Servo) -> PyResult<Option<Bound<'py, PyDict>>> {
    let Some(c) = servo.certainty() else { return Ok(None) };
    let d = PyDict::new(py);
    d.set_item("pixel_sigma", c.pixel_sigma)?;
    d.set_item("reference_pixel_sigma", c.reference_pixel_sigma)?;
    d.set_item("translation_sigma", c.sigma.0)?;
    d.set_item("rotation_sigma", c.sigma.1)?;
    d.set_item("translation_bound", c.bound.0)?;
    d.set_item("rotation_bound", c.bound.1)?;
    d.set_item("floor_pixel_sigma", c.floor_pixel_sigma)?;
    Ok(Some(d))
}

/// What one `Servo.step` returns.
#[pyclass(name = "ServoStep", module = "vsinv._core", frozen, subclass)]
pub(super) struct PyServoStep {
    twist: [f64; 6],
    verdict: &'static str,
    reason: Option<String>,
    telemetry: Telemetry,
}

impl From<ServoStep> for PyServoStep {
    fn from(step: ServoStep) -> Self {
        let verdict = step.verdict.status().map_or("running", |s| s.as_str());
        let reason = step.verdict.reason_with_remedy(DEPTHS_REMEDY);
        let twist = [0, 1, 2, 3, 4, 5].map(|i| step.twist[i]);
        Self { twist, verdict, reason, telemetry: step.telemetry }
    }
}

#[pymethods]
impl PyServoStep {
    /// The twist to send (vx, vy, vz, wx, wy, wz) in the camera frame, m/s and rad/s; zero
    /// when the verdict is to stop.
    #[getter]
    fn twist<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, &self.twist)
    }
    /// "running", or why to stop: "converged", "settled", "lost_features", "rz_trap",
    /// "degenerate", "diverged", "max_iterations", "observed".
    #[getter]
    fn verdict(&self) -> &'static str {
        self.verdict
    }
    /// Why the session stops, in words (None while running).
    #[getter]
    fn reason(&self) -> Option<&str> {
        self.reason.as_deref()
    }
    /// Whether the loop goes on.
    #[getter]
    fn running(&self) -> bool {
        self.reason.is_none()
    }
    /// The figures of this step: a dict of iteration, invariant_error, image_error (pixels),
    /// tau (tau_11, tau_21, tau_22), eps_z, eps (5,), tracking_error, law_ran, basis (the
    /// three point indices in use) and basis_switches (how often a hidden basis point made
    /// the session change its basis); NaN where a figure does not apply.
    #[getter]
    fn telemetry<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let t = &self.telemetry;
        let d = PyDict::new(py);
        d.set_item("iteration", t.iteration)?;
        d.set_item("invariant_error", t.invariant_error)?;
        d.set_item("image_error", t.image_error)?;
        d.set_item("tau", (t.tau[0], t.tau[1], t.tau[2]))?;
        d.set_item("eps_z", t.eps_z)?;
        d.set_item("eps", vec1(py, &t.eps))?;
        d.set_item("tracking_error", t.tracking_error)?;
        d.set_item("law_ran", t.law_ran)?;
        d.set_item("basis", (t.basis[0], t.basis[1], t.basis[2]))?;
        d.set_item("basis_switches", t.basis_switches)?;
        Ok(d)
    }
    fn __repr__(&self) -> String {
        match &self.reason {
            None => format!("ServoStep(verdict='running', twist={:?})", self.twist),
            Some(r) => format!("ServoStep(verdict={:?}, reason={r:?})", self.verdict),
        }
    }
}

/// Adds the servo session's classes to the module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyServo>()?;
    m.add_class::<PyServoStep>()?;
    Ok(())
}
