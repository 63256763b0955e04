//! [`Servo`]: one servo session, the loop logic every caller shares (a robot driver, a ROS
//! node, a user's own loop, the simulator). Each step: take the image points, measure them
//! against the reference, decide whether to stop (lost features, the image rule certified
//! by the pose uncertainty, the rz = pi trap, the iteration limit), then estimate depths,
//! follow the planned path (sec. 3) and run the law.

use nalgebra::Vector6;

use crate::core::camera::Intrinsics;
use crate::core::control::ControlState;
use crate::core::distortion::{Distortion, undistort_point};
use crate::core::invariant::validate_basis;
use crate::core::noise_meter::PixelNoiseMeter;
use crate::core::uncertainty::Measurement;
use crate::error::{Error, Result, check_finite_points, check_positive};
use crate::servo::basis_hold::BasisHold;
use crate::servo::certainty::Certainty;
use crate::servo::depths::ServoDepths;
use crate::servo::law::{Law, ServoLaw};
use crate::servo::measure::{Metrics, measure};
use crate::servo::path::{PathPlan, PlannedPath};
use crate::servo::reference::{ReferenceImage, choose_visible_basis};
use crate::servo::stall::StallWatch;
use crate::servo::stop::{StopRule, StopRules, stop_rule_met};
use crate::servo::stop_window::StopWindow;
use crate::servo::telemetry::{ServoStep, Telemetry};
use crate::servo::verdict::{Status, Verdict};

/// Images the noise meter looks back over.
const NOISE_IMAGES: usize = 32;

/// Consecutive images a basis point of a running session may be missing for before the
/// basis changes (see [`ServoConfig::basis_hold`]): 0.12 s at 25 Hz, which covers a
/// keypoint lost by its tracker for a frame or two and found again.
pub const BASIS_HOLD_IMAGES: usize = 3;

/// How a session is set up (everything but the reference image and the depth source).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoConfig {
    /// The control law and its tuning.
    pub law: Law,
    /// The intrinsics the law believes the servo camera has, K_hat.
    pub k_hat: Intrinsics,
    /// The lens distortion believed to be the servo camera's: image points are undistorted
    /// with it and K_hat before the law (identity: fed as they are).
    pub distortion: Distortion,
    /// Basis indices; None chooses the widest triangle of the reference image.
    pub basis: Option<[usize; 3]>,
    /// Consecutive images a basis point may be missing for while the basis is kept (0: the
    /// basis changes in the first image without it). The invariant points q_k = Q^-1 m_k
    /// (sec. 2.2, eq. 5) are defined by the basis's three points, so each change of basis
    /// moves the error e = s - s* (eq. 10) to another space and restarts the controller; a
    /// basis point lost for an image or two (a keypoint's track failing its checks) is
    /// therefore ridden out: the session repeats its last twist, judges no stop on those
    /// images, and keeps the basis when the point is back. A basis point missing longer, or
    /// missing before the basis was ever seen, changes the basis.
    pub basis_hold: usize,
    /// Layers of convex hull set aside before the widest triangle is chosen as the basis, at
    /// the start (when `basis` is None) and at each change (0: the widest triangle of all the
    /// points, sec. 5.1). The keypoint target sets 1: see `choose_visible_basis`.
    pub basis_inset: usize,
    /// Thresholds, averaging window, iteration limit, pose tolerance.
    pub stop: StopRules,
    /// The image rule; None: the law's own (invariant rule for the invariant law, pixel rule
    /// for IBVS). With the same camera for both images the pixel rule is the stricter one.
    pub stop_rule: Option<StopRule>,
    /// A path planned in the invariant space from the first image (invariant law only).
    pub path: Option<PathPlan>,
    /// The control period, seconds (the path's clock).
    pub dt: f64,
}

impl ServoConfig {
    /// A session of `law` with K_hat and default stop rules, at 25 Hz.
    pub fn new(law: Law, k_hat: Intrinsics) -> Self {
        Self {
            law,
            k_hat,
            distortion: Distortion::none(),
            basis: None,
            basis_hold: BASIS_HOLD_IMAGES,
            basis_inset: 0,
            stop: StopRules::default(),
            stop_rule: None,
            path: None,
            dt: 0.04,
        }
    }
}

/// The reference image: pinhole pixels in K* (undistorted with the reference camera's own
/// calibration), and its depths zeta* where known (IBVS's desired interaction and the
/// reference depth source read them).
#[derive(Debug, Clone, PartialEq)]
pub struct ServoReference {
    /// Pixels of the reference image, one per point.
    pub pixels: Vec<[f64; 2]>,
    /// Depths of the points at the reference pose, metres (any common scale for the
    /// invariant law).
    pub depths: Option<Vec<f64>>,
}

/// A servo session. See the module documentation for what a step does.
pub struct Servo {
    law: Box<dyn ServoLaw>,
    law_config: Law,
    reference_depths: Option<Vec<f64>>,
    basis_switches: usize,
    basis_lost: Option<String>,
    /// How the session rides out a basis point's short loss (see [`ServoConfig::basis_hold`]).
    hold: BasisHold,
    basis_inset: usize,
    reference: ReferenceImage,
    rule: StopRule,
    stop: StopRules,
    k_hat: Intrinsics,
    distortion: Distortion,
    dt: f64,
    plan: Option<PathPlan>,
    path: Option<PlannedPath>,
    depth_source: ServoDepths,
    depths: Vec<f64>,
    pixels: Vec<[f64; 2]>,
    visible: Vec<bool>,
    window: StopWindow,
    stall: StallWatch,
    rule_met: bool,
    metrics: Metrics,
    noise_meter: PixelNoiseMeter,
    certainty: Option<Certainty>,
    telemetry: Telemetry,
    iteration: usize,
    /// The stop [`step`](Servo::step) returned: final (every later step returns it).
    ended: Option<Verdict>,
}

impl Servo {
    /// A session servoing to `reference` with `depths` as the law's depth source.
    pub fn new(config: ServoConfig, reference: ServoReference, depths: ServoDepths) -> Result<Self> {
        check_positive("dt", config.dt)?;
        config.stop.validate()?;
        let ServoReference { pixels, depths: reference_depths } = reference;
        let n = pixels.len();
        check_finite_points("reference_pixels", &pixels)?;
        let basis = match config.basis {
            Some(b) => validate_basis(b, n)?,
            None => choose_visible_basis(&pixels, &vec![true; n], config.basis_inset)?,
        };
        let reference_image = ReferenceImage::new(pixels, basis)?;
        if let Some(z) = &reference_depths {
            check_depths("reference_depths", z, None, n)?;
        }
        let law = config.law.build(&reference_image.pixels, basis, reference_depths.as_deref(), config.k_hat)?;
        let initial_depths = depths.initial(n, reference_depths.as_deref())?;
        if config.path.is_some() && law.invariant().is_none() {
            return Err(Error::InvalidParameter {
                name: "path",
                reason: format!("the {} law follows no path", law.name()),
            });
        }
        Ok(Self {
            rule: config.stop_rule.unwrap_or(law.default_stop_rule()),
            law,
            law_config: config.law,
            reference_depths,
            basis_switches: 0,
            basis_lost: None,
            hold: BasisHold::new(config.basis_hold),
            basis_inset: config.basis_inset,
            reference: reference_image,
            stop: config.stop,
            k_hat: config.k_hat,
            distortion: config.distortion,
            dt: config.dt,
            plan: config.path,
            path: None,
            depth_source: depths,
            depths: initial_depths,
            pixels: vec![[0.0; 2]; n],
            visible: vec![false; n],
            window: StopWindow::new(config.stop.window),
            stall: StallWatch::new(config.stop.stall_window),
            rule_met: false,
            metrics: Metrics { invariant_error: f64::NAN, tau: [f64::NAN; 3], eps_z: f64::NAN, image_error: f64::NAN },
            noise_meter: PixelNoiseMeter::new(NOISE_IMAGES)?,
            certainty: None,
            telemetry: Telemetry::empty(),
            iteration: 0,
            ended: None,
        })
    }

    /// One step: [`observe`](Self::observe), then [`verdict`](Self::verdict), then, while
    /// running, [`control`](Self::control). `visible` flags the points found (None: all);
    /// `depths` are required with [`ServoDepths::PerStep`] and refused otherwise.
    ///
    /// A stop is final: once a step has returned one (converged, settled, lost features, the
    /// iteration limit, ...), every later step returns the same verdict with a zero twist and
    /// the same telemetry, without looking at its image; a new session servos again.
    pub fn step(&mut self, pixels: &[[f64; 2]], visible: Option<&[bool]>, depths: Option<&[f64]>) -> Result<ServoStep> {
        if let Some(verdict) = &self.ended {
            return Ok(ServoStep { twist: Vector6::zeros(), verdict: verdict.clone(), telemetry: self.telemetry });
        }
        self.observe(pixels, visible, depths)?;
        let step = match self.verdict() {
            Verdict::Running => self.control(),
            verdict => ServoStep { twist: Vector6::zeros(), verdict, telemetry: self.telemetry },
        };
        if !step.verdict.is_running() {
            self.ended = Some(step.verdict.clone());
        }
        Ok(step)
    }

    /// The final verdict, once a [`step`](Servo::step) has returned a stop.
    pub fn ended(&self) -> Option<&Verdict> {
        self.ended.as_ref()
    }

    /// Takes an image's points: undistorts them with K_hat and the believed distortion (a
    /// point that cannot be undistorted is dropped), measures the pixel noise, measures the
    /// image against the reference and feeds the stop window.
    pub fn observe(&mut self, pixels: &[[f64; 2]], visible: Option<&[bool]>, depths: Option<&[f64]>) -> Result<()> {
        self.take_inputs(pixels, visible, depths)?;
        self.undistort();
        self.noise_meter.push(&self.pixels, Some(&self.visible))?;
        self.keep_basis_in_view()?;
        let mut row = self.window.next_row();
        self.metrics = measure(&self.pixels, &self.visible, &self.reference, &mut row);
        let m = &self.metrics;
        self.telemetry = Telemetry {
            iteration: self.iteration,
            invariant_error: m.invariant_error,
            image_error: m.image_error,
            tau: m.tau,
            eps_z: m.eps_z,
            basis: self.reference.basis,
            basis_switches: self.basis_switches,
            ..Telemetry::empty()
        };
        let (rule, n_others, tau, moves) = (self.rule, self.reference.others.len(), m.tau, self.law.moves());
        let min_points = self.law.min_points();
        if self.hold.holding() {
            // No invariant point without the basis (eq. 5): nothing to judge a stop on.
            self.rule_met = false;
            return Ok(());
        }
        if self.stop.stall {
            let error = if rule == StopRule::Pixel { m.image_error } else { m.invariant_error };
            self.stall.push_error(error);
            let mut copy = self.stall.rows.next_row();
            copy.extend_from_slice(&row);
            self.stall.rows.push(copy);
        }
        self.rule_met = match self.window.push(row) {
            Some(mean) if moves => stop_rule_met(rule, &self.stop, mean, n_others, tau, min_points),
            _ => false,
        };
        Ok(())
    }

    /// Keeps the basis of a law that needs one in view. A basis point missing for at most
    /// [`ServoConfig::basis_hold`] consecutive images of a basis seen before is ridden out
    /// ([`BasisHold`]: the basis stays, the last twist is repeated, no stop is judged). Beyond
    /// that (or a basis point missing from the start), the basis becomes the widest triangle of the *reference* pixels of the visible points
    /// (s* of the new basis comes from the reference image, so nothing is lost) and what
    /// depends on it is rebuilt: the reference measurements, the law's controller (its
    /// state starts afresh), the stop window (its rows are laid out by the basis). A planned
    /// path (sec. 3) is dropped: it was planned in the old basis's invariant space, and
    /// re-planning needs every point in view; the law then servos straight to s*. With
    /// fewer visible points than the law needs, or no well-spread triangle among them, the
    /// basis stays and [`verdict`](Self::verdict) says `lost_features`.
    fn keep_basis_in_view(&mut self) -> Result<()> {
        self.basis_lost = None;
        let visible = &self.visible;
        if !self.law.needs_basis() || self.reference.basis.iter().all(|&b| visible[b]) {
            self.hold.observe(true);
            return Ok(());
        }
        let seen = visible.iter().filter(|&&v| v).count();
        if seen < self.law.min_points() {
            self.hold.release();
            return Ok(()); // lost_features reports the count
        }
        if self.hold.observe(false) {
            return Ok(());
        }
        let basis = match choose_visible_basis(&self.reference.pixels, visible, self.basis_inset) {
            Ok(b) => b,
            Err(e) => {
                let why = format!(
                    "basis {:?} not visible and no new basis among the visible points: {e}",
                    self.reference.basis
                );
                self.basis_lost = Some(why);
                return Ok(());
            }
        };
        let pixels = std::mem::take(&mut self.reference.pixels);
        self.reference = ReferenceImage::new(pixels, basis)?;
        self.law =
            self.law_config.build(&self.reference.pixels, basis, self.reference_depths.as_deref(), self.k_hat)?;
        self.window = StopWindow::new(self.stop.window);
        self.stall.reset();
        (self.plan, self.path) = (None, None);
        self.basis_switches += 1;
        self.hold.rebased();
        Ok(())
    }

    /// Checks and copies a step's inputs.
    fn take_inputs(&mut self, pixels: &[[f64; 2]], visible: Option<&[bool]>, depths: Option<&[f64]>) -> Result<()> {
        let n = self.pixels.len();
        let shape = |what, got: usize| Error::Shape { what, expected: format!("{n} points"), got: got.to_string() };
        if pixels.len() != n {
            return Err(shape("pixels", pixels.len()));
        }
        match visible {
            Some(v) if v.len() != n => return Err(shape("visible", v.len())),
            Some(v) => self.visible.copy_from_slice(v),
            None => self.visible.fill(true),
        }
        match (&self.depth_source, depths) {
            (ServoDepths::PerStep, Some(z)) => {
                check_depths("depths", z, visible, n)?;
                self.depths.copy_from_slice(z);
            }
            (ServoDepths::PerStep, None) => {
                return Err(Error::InvalidParameter {
                    name: "depths",
                    reason: "this session takes depths each step".into(),
                });
            }
            (source, Some(_)) => {
                let reason = format!("this session's depths come from {source:?}; pass none");
                return Err(Error::InvalidParameter { name: "depths", reason });
            }
            (_, None) => {}
        }
        self.pixels.copy_from_slice(pixels);
        Ok(())
    }

    /// The image points through the law's calibration (K_hat and its distortion).
    fn undistort(&mut self) {
        if self.distortion.is_identity() {
            return;
        }
        for (p, v) in self.pixels.iter_mut().zip(self.visible.iter_mut()).filter(|(_, v)| **v) {
            match undistort_point(*p, &self.k_hat, &self.distortion) {
                Ok(q) => *p = q,
                Err(_) => *v = false,
            }
        }
    }

    /// The stop checks on the last observed image, in order: lost features, the image rule
    /// (certified by the pose uncertainty), the rz = pi trap, the iteration limit.
    pub fn verdict(&mut self) -> Verdict {
        if let Some(lost) = self.lost_features() {
            return lost;
        }
        let holding = self.hold.holding();
        if self.rule_met
            && let Some(end) = self.certify(false)
        {
            return end;
        }
        if self.stop.stall
            && !holding
            && self.law.moves()
            && self.stall.stalled(&self.stop, self.dt)
            && let Some(end) = self.certify(true)
        {
            return end;
        }
        let at_limit = self.iteration >= self.stop.max_iterations;
        if let Some(trap) = self.rz_trap(at_limit) {
            return trap;
        }
        match (at_limit, self.law.moves()) {
            (false, _) => Verdict::Running,
            (true, true) => {
                Verdict::stop(Status::MaxIterations, format!("iteration limit {} reached", self.stop.max_iterations))
            }
            (true, false) => {
                Verdict::stop(Status::Observed, format!("{} images taken (no control)", self.iteration + 1))
            }
        }
    }

    fn lost_features(&self) -> Option<Verdict> {
        if let Some(why) = &self.basis_lost {
            return Some(Verdict::stop(Status::LostFeatures, why.clone()));
        }
        let (visible, basis) = (&self.visible, self.reference.basis);
        let seen = visible.iter().filter(|&&v| v).count();
        let basis_seen = !self.law.needs_basis() || self.hold.holding() || basis.iter().all(|&b| visible[b]);
        if seen >= self.law.min_points() && basis_seen {
            return None;
        }
        let n = visible.len();
        let lost: Vec<usize> = (0..n).filter(|&i| !visible[i]).collect();
        let why = format!("{seen} of {n} points visible (basis {basis:?}); lost points {lost:?}");
        Some(Verdict::stop(Status::LostFeatures, why))
    }

    /// The image rule is met (or, `stalled`, the stall rule): `converged` if the pose
    /// uncertainty the images averaged over the rule's window allow is within the tolerance,
    /// `settled` if not; `None` (carry on) until the noise can be measured (three images) and
    /// while too few points were in view throughout the window.
    fn certify(&mut self, stalled: bool) -> Option<Verdict> {
        let (window, size) = match stalled {
            true => (&self.stall.rows, self.stop.stall_window),
            false => (&self.window, self.stop.window),
        };
        let (pixels, seen) = self.window_mean_pixels(window)?;
        let certainty = self.certainty_of(&pixels, &seen, size)?;
        self.certainty = Some(certainty);
        let rule = match stalled {
            true => format!("stalled (the error stopped decreasing over {size} images, the camera still)"),
            false => "stop rule met".to_string(),
        };
        Some(match certainty.within(&self.stop) {
            true if stalled => {
                let (t, r) = certainty.bound;
                let why = format!("{rule}; the images certify {:.3} mm and {:.3} deg", t * 1e3, r.to_degrees());
                Verdict::stop(Status::Converged, why)
            }
            true => Verdict::stop(Status::Converged, rule),
            false => Verdict::stop(Status::Settled, certainty.settled_reason(&self.stop, &rule)),
        })
    }

    /// The pixels averaged over the stop window, `p* + mean(p - p*)`, and which points were
    /// in view throughout it (the others' mean is NaN): the points the rule was judged on.
    fn window_mean_pixels(&self, window: &StopWindow) -> Option<(Vec<[f64; 2]>, Vec<bool>)> {
        let mean = window.mean()?;
        let offset = 1 + 3 * self.reference.others.len();
        let errors = mean[offset..].chunks_exact(2);
        let pixels: Vec<[f64; 2]> =
            self.reference.pixels.iter().zip(errors).map(|(p, e)| [p[0] + e[0], p[1] + e[1]]).collect();
        let seen = pixels.iter().map(|p| p[0].is_finite() && p[1].is_finite()).collect();
        Some((pixels, seen))
    }

    fn certainty_of(&self, pixels: &[[f64; 2]], visible: &[bool], averaged: usize) -> Option<Certainty> {
        let m = Measurement {
            pixels,
            depths: &self.depths,
            reference_pixels: &self.reference.pixels,
            visible: Some(visible),
            k_hat: &self.k_hat,
        };
        Certainty::of(self.law.as_ref(), &self.noise_meter, &self.stop, &m, self.reference.basis, averaged)
    }

    /// The rz = pi equilibrium of the invariant law: `s = s*` and `tau_21 = 0` reached with
    /// `tau_11 < 0` or `tau_22 < 0`, or either sign wrong when the iteration limit is reached.
    fn rz_trap(&self, at_limit: bool) -> Option<Verdict> {
        if !self.law.watches_rz_trap() {
            return None;
        }
        let [tau11, tau21, tau22] = self.metrics.tau;
        let flipped = tau11 < 0.0 || tau22 < 0.0;
        let settled = self.metrics.invariant_error < self.stop.invariant_error && tau21.abs() < self.stop.tau21;
        (flipped && (settled || at_limit)).then(|| {
            let why = format!(
                "settled rotated by about 180 degrees about the optical axis (tau_11 = {tau11:.3}, tau_22 = {tau22:.3}): \
                 the rz = pi equilibrium of eq. (24); use control.rz_task = \"angle\""
            );
            Verdict::stop(Status::RzTrap, why)
        })
    }

    /// The control step on the last observed image: depths, the path's reference, the law.
    /// A failure of any of them is a stop verdict, not an error.
    /// An image ridden out with a basis point missing (see [`ServoConfig::basis_hold`]) repeats the last twist.
    pub fn control(&mut self) -> ServoStep {
        if self.hold.holding() {
            self.iteration += 1;
            return ServoStep { twist: self.hold.twist(), verdict: Verdict::Running, telemetry: self.telemetry };
        }
        match self.try_control() {
            Ok(twist) => {
                self.iteration += 1;
                self.hold.record(twist);
                if self.stop.stall {
                    self.stall.push_twist(twist);
                }
                ServoStep { twist, verdict: Verdict::Running, telemetry: self.telemetry }
            }
            Err(verdict) => ServoStep { twist: Vector6::zeros(), verdict, telemetry: self.telemetry },
        }
    }

    fn try_control(&mut self) -> std::result::Result<Vector6<f64>, Verdict> {
        if let ServoDepths::Estimated(e) = &mut self.depth_source {
            e.estimate(&self.pixels, &self.visible, &mut self.depths)
                .map_err(|err| Verdict::stop(Status::Degenerate, format!("depth estimation failed: {err}")))?;
        }
        self.follow_path()?;
        let twist = self.law.twist(&self.pixels, &self.depths, &self.visible).map_err(Verdict::stop_on)?;
        let (eps, tracking) = self.law.eps_and_tracking();
        (self.telemetry.eps, self.telemetry.tracking_error, self.telemetry.law_ran) = (eps, tracking, true);
        if !twist.iter().all(|v| v.is_finite()) {
            return Err(Verdict::stop(Status::Diverged, "non-finite twist"));
        }
        Ok(twist)
    }

    /// Sec. 3: plan the path from the first image, then move the reference along it.
    fn follow_path(&mut self) -> std::result::Result<(), Verdict> {
        let (Some(plan), Some(controller)) = (self.plan, self.law.invariant_mut()) else { return Ok(()) };
        if self.path.is_none() {
            let duration = plan.samples as f64 * self.dt;
            let planned = PlannedPath::plan(&self.pixels, &self.visible, &self.reference, duration)
                .map_err(|e| Verdict::stop(Status::Degenerate, format!("path planning failed: {e}")))?;
            self.path = Some(planned);
        }
        let t = self.iteration as f64 * self.dt;
        match self.path.as_mut() {
            Some(p) => {
                p.follow(t, controller).map_err(|e| Verdict::stop(Status::Diverged, format!("path sample: {e}")))
            }
            None => Ok(()),
        }
    }
}

impl std::fmt::Debug for Servo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Servo")
            .field("law", &self.law.name())
            .field("points", &self.pixels.len())
            .field("basis", &self.reference.basis)
            .field("stop_rule", &self.rule)
            .field("depths", &self.depth_source)
            .field("iterations", &self.iteration)
            .finish_non_exhaustive()
    }
}

/// What a session shows of itself between steps.
impl Servo {
    /// The image points in use after the last observation (undistorted), one per point.
    pub fn pixels(&self) -> &[[f64; 2]] {
        &self.pixels
    }
    /// Which points the last observation used.
    pub fn visible(&self) -> &[bool] {
        &self.visible
    }
    /// The depths the law was last given.
    pub fn depths(&self) -> &[f64] {
        &self.depths
    }
    /// The reference image's pixels.
    pub fn reference_pixels(&self) -> &[[f64; 2]] {
        &self.reference.pixels
    }
    /// The basis in use (it changes when a basis point leaves the view, see
    /// [`Servo::observe`]).
    pub fn basis(&self) -> [usize; 3] {
        self.reference.basis
    }
    /// How many times the basis changed because one of its points was not visible.
    pub fn basis_switches(&self) -> usize {
        self.basis_switches
    }
    /// How many images were ridden out with a basis point missing, the basis kept and the
    /// last twist repeated (see [`ServoConfig::basis_hold`]).
    pub fn basis_held_images(&self) -> usize {
        self.hold.images()
    }
    /// The image rule that decides convergence.
    pub fn stop_rule(&self) -> StopRule {
        self.rule
    }
    /// The stop rules.
    pub fn stop_rules(&self) -> &StopRules {
        &self.stop
    }
    /// The law.
    pub fn law(&self) -> &dyn ServoLaw {
        self.law.as_ref()
    }
    /// Control steps applied.
    pub fn iterations(&self) -> usize {
        self.iteration
    }
    /// The figures of the last step.
    pub fn telemetry(&self) -> &Telemetry {
        &self.telemetry
    }
    /// The invariant law's state after its last step (None for the other laws).
    pub fn invariant_state(&self) -> Option<&ControlState> {
        self.law.invariant().and_then(|c| c.state())
    }
    /// The planned path's duration (s) and plane + parallax residual, once planned.
    pub fn path(&self) -> Option<(f64, f64)> {
        self.path.as_ref().map(|p| (p.path.duration(), p.residual))
    }
    /// The pixel noise measured on the last images (at least three), pixels.
    pub fn pixel_sigma(&self) -> Option<f64> {
        self.noise_meter.sigma()
    }
    /// What the images said about the pose when the image rule was met; otherwise what the
    /// last image alone allows (None for a law that does not move, or when it cannot be
    /// computed).
    pub fn certainty(&self) -> Option<Certainty> {
        match self.certainty {
            Some(c) => Some(c),
            None if !self.law.moves() => None,
            None => self.certainty_of(&self.pixels, &self.visible, 1),
        }
    }
}

/// Depths for `n` points: finite and positive where the point is in use.
fn check_depths(what: &'static str, depths: &[f64], visible: Option<&[bool]>, n: usize) -> Result<()> {
    if depths.len() != n {
        return Err(Error::Shape { what, expected: format!("{n} depths"), got: depths.len().to_string() });
    }
    let in_use = |i: usize| visible.is_none_or(|v| v[i]);
    if let Some(index) = (0..n).find(|&i| in_use(i) && !depths[i].is_finite()) {
        return Err(Error::NonFinite { what, index });
    }
    match (0..n).find(|&i| in_use(i) && depths[i] <= 0.0) {
        Some(index) => Err(Error::PointBehindCamera { index, depth: depths[index] }),
        None => Ok(()),
    }
}
