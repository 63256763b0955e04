//! The closed loop of a run, one named step at a time: observe the scene with K(t), add
//! noise, measure against the reference image, apply the stop rules, estimate depths,
//! follow the planned path (sec. 3), run the control law, move the robot, record.

use nalgebra::{Isometry3, Matrix5, Vector3, Vector6};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use crate::core::camera::Intrinsics;
use crate::core::control::InvariantController;
use crate::core::distortion::undistort_point;
use crate::core::ibvs::{IBVS_MIN_POINTS, IbvsController};
use crate::core::invariant::{BasisFrame, choose_basis, validate_basis};
use crate::core::jacobian::MIN_POINTS;
use crate::core::noise_meter::PixelNoiseMeter;
use crate::core::planning::{InvariantPath, estimate_plane_parallax};
use crate::core::se3::pose_error;
use crate::core::stability::{a_matrix, stability_verdicts};
use crate::core::uncertainty::{
    DEFAULT_SIGMAS, ImageNoise, Measurement, PoseUncertainty, invariant_pose_uncertainty, pixel_pose_uncertainty,
};
use crate::error::{Error, Result, check_positive, fixed_or_short};
use crate::sim::arm::{ArmEvent, ArmRobot, ArmStep};
use crate::sim::camera_model::CameraModel;
use crate::sim::config::{Law, SimulationConfig};
use crate::sim::depth_source::{DepthEstimator, DepthSource};
use crate::sim::image_loop::{ImageLoop, Tracked, pixel_size};
use crate::sim::measure::{Metrics, ReferenceImage, StopWindow, measure, stop_rule_met};
use crate::sim::outcome::{Certainty, Outcome, Recording, Status, StopRule, Summary, Tracking};
use crate::sim::robot::Robot;
use crate::sim::scene::Observation;

/// Runs a simulation. `progress(done, max)` is called every few iterations; returning false
/// stops the run (its status is then `max_iterations`).
pub fn simulate(config: &SimulationConfig, progress: &mut dyn FnMut(usize, usize) -> bool) -> Result<Outcome> {
    validate(config)?;
    let (reference, reference_depths) = take_reference_image(config)?;
    let mut run = Run::new(config, reference, reference_depths)?;
    let end = loop {
        if let Some(end) = run.iterate(progress)? {
            break end;
        }
    };
    Ok(run.finish(end))
}

/// Checks what the scenario schema cannot (a config may also be built in code).
fn validate(config: &SimulationConfig) -> Result<()> {
    check_positive("dt", config.dt)?;
    config.reference_camera.validate()?;
    config.camera.validate()?;
    if !(config.noise.pixel_sigma.is_finite() && config.noise.pixel_sigma >= 0.0) {
        return Err(Error::InvalidParameter { name: "noise.pixel_sigma", reason: "must be finite and >= 0".into() });
    }
    if config.stop.window == 0 || config.stop.max_iterations == 0 {
        return Err(Error::InvalidParameter { name: "stop", reason: "window and max_iterations must be >= 1".into() });
    }
    config.robot.check_reachable(&config.start)?;
    let n = config.scene.points().len();
    if n < MIN_POINTS && matches!(config.law, Law::Invariant(_)) {
        return Err(Error::TooFewPoints { needed: MIN_POINTS, got: n, why: "the invariant law needs six points" });
    }
    Ok(())
}

/// The reference image, taken at F* with K*: every point must be in view. Returns the
/// observation (pixels still noise-free) and the reference depths zeta*.
fn take_reference_image(config: &SimulationConfig) -> Result<(Observation, Vec<f64>)> {
    let camera = &config.reference_camera;
    let k_star = camera.at(0.0)?;
    let mut obs = Observation::default();
    config.scene.observe_through(&Isometry3::identity(), &k_star, &camera.distortion, camera.image, &mut obs);
    let n = obs.depths.len();
    if let Some(i) = (0..n).find(|&i| obs.depths[i] <= 0.0) {
        return Err(Error::PointBehindCamera { index: i, depth: obs.depths[i] });
    }
    if let Some(i) = (0..n).find(|&i| !obs.visible[i]) {
        return Err(Error::InvalidParameter {
            name: "object",
            reason: format!(
                "point {i} is not visible in the reference image: outside the reference_camera's image \
                 or occluded (check object.points[{i}] and the reference_camera table)"
            ),
        });
    }
    if let Some(vision) = config.vision {
        let size = pixel_size(config.reference_camera.image, "reference_camera")?;
        ImageLoop::reference(vision, &config.scene, &k_star, &camera.distortion, size, &mut obs)?;
    }
    let depths = obs.depths.clone();
    Ok((obs, depths))
}

/// The reference image's points through its own calibration: pinhole pixels of K*.
fn undistort_reference(pixels: &mut [[f64; 2]], camera: &CameraModel) -> Result<()> {
    for (i, p) in pixels.iter_mut().enumerate() {
        *p = undistort_point(*p, &camera.intrinsics, &camera.distortion).map_err(|e| Error::InvalidParameter {
            name: "reference_camera.distortion",
            reason: format!("point {i} of the reference image cannot be undistorted: {e}"),
        })?;
    }
    Ok(())
}

/// Gaussian pixel noise on the visible points.
struct PixelNoise {
    rng: ChaCha8Rng,
    normal: Option<Normal<f64>>,
}

impl PixelNoise {
    fn new(sigma: f64, seed: u64) -> Result<Self> {
        let normal = if sigma > 0.0 {
            Some(
                Normal::new(0.0, sigma)
                    .map_err(|e| Error::InvalidParameter { name: "noise.pixel_sigma", reason: e.to_string() })?,
            )
        } else {
            None
        };
        Ok(Self { rng: ChaCha8Rng::seed_from_u64(seed), normal })
    }

    fn add(&mut self, pixels: &mut [[f64; 2]], visible: &[bool]) {
        let Some(normal) = &self.normal else { return };
        for (p, _) in pixels.iter_mut().zip(visible).filter(|(_, v)| **v) {
            p[0] += normal.sample(&mut self.rng);
            p[1] += normal.sample(&mut self.rng);
        }
    }
}

enum AnyController {
    Invariant(Box<InvariantController>),
    Ibvs(Box<IbvsController>),
    Observe,
}

impl AnyController {
    /// The law's controller and its gain lambda.
    fn new(config: &SimulationConfig, reference: &ReferenceImage, reference_depths: &[f64]) -> Result<(Self, f64)> {
        let pixels = &reference.pixels;
        Ok(match config.law {
            Law::Invariant(c) => (
                Self::Invariant(Box::new(InvariantController::new(pixels, config.estimate, reference.basis, c)?)),
                c.gain,
            ),
            Law::Ibvs { gain, interaction, adaptive_gain, twist_limits } => {
                let mut ibvs = IbvsController::new(pixels, config.estimate, gain, interaction, Some(reference_depths))?;
                ibvs.set_adaptive_gain(adaptive_gain)?;
                ibvs.set_twist_limits(twist_limits)?;
                (Self::Ibvs(Box::new(ibvs)), gain)
            }
            Law::Observe => (Self::Observe, 1.0),
        })
    }

    fn step(&mut self, pixels: &[[f64; 2]], depths: &[f64], visible: &[bool]) -> Result<Vector6<f64>> {
        match self {
            Self::Invariant(c) => c.step_visible(pixels, depths, visible),
            Self::Ibvs(c) => c.step_visible(pixels, depths, visible),
            Self::Observe => Ok(Vector6::zeros()),
        }
    }

    /// The task function eps and the tracking error `||s - s*(t)||` (NaN outside the
    /// invariant law).
    fn eps_and_tracking(&self) -> ([f64; 5], f64) {
        match self {
            Self::Invariant(c) => c.state().map_or(([f64::NAN; 5], f64::NAN), |s| (s.eps.into(), s.invariant_error)),
            Self::Ibvs(_) | Self::Observe => ([f64::NAN; 5], f64::NAN),
        }
    }
}

/// Why a control-step error ends the run.
fn status_of(err: &Error) -> Status {
    match err {
        Error::TooFewPoints { .. } | Error::PointBehindCamera { .. } => Status::LostFeatures,
        Error::RzSingular { .. } | Error::NonFinite { .. } | Error::NonFinitePoint { .. } => Status::Diverged,
        _ => Status::Degenerate,
    }
}

/// How a run ends: its status and the reason, in words.
type End = (Status, String);

/// The planned path of sec. 3 and Prop. 3's figures observed along it.
struct PathTracking {
    path: InvariantPath,
    residual: f64,
    points: Vec<[f64; 3]>,
    rates: Vec<[f64; 3]>,
    sigma_min: f64,
    max_b: f64,
    max_eps: f64,
}

impl PathTracking {
    /// Plans the path from the current (first) image; every point must be visible.
    fn plan(pixels: &[[f64; 2]], visible: &[bool], r: &ReferenceImage, duration: f64) -> Result<Self> {
        if let Some(i) = (0..pixels.len()).find(|&i| !visible[i]) {
            return Err(Error::InvalidParameter {
                name: "path",
                reason: format!("point {i} is not visible in the first image; the path needs every point"),
            });
        }
        let frame = BasisFrame::new(pixels, r.basis, "current")?;
        let q: Vec<Vector3<f64>> = r.others.iter().map(|&i| frame.transform(pixels[i])).collect();
        let estimate = estimate_plane_parallax(&q, &r.s_star)?;
        let m = r.others.len();
        Ok(Self {
            path: InvariantPath::new(&r.s_star, &estimate, duration)?,
            residual: estimate.residual,
            points: vec![[0.0; 3]; m],
            rates: vec![[0.0; 3]; m],
            sigma_min: f64::INFINITY,
            max_b: 0.0,
            max_eps: 0.0,
        })
    }

    /// Prop. 3 along the path: A(t) from K(t), K_hat and kappa(t) (known here, since the
    /// simulator knows the true depths), b(t) and `||eps(t)||`.
    fn observe(&mut self, c: &InvariantController, k: &Intrinsics, estimate: &Intrinsics, kappa: f64, ff: bool) {
        let Some(state) = c.state() else { return };
        if let Ok(a) = a_matrix(&k.matrix(), &estimate.matrix(), kappa) {
            self.sigma_min = self.sigma_min.min((a + a.transpose()).symmetric_eigenvalues().min());
            let r = state.reference_rate_term;
            let b = if ff { (a - Matrix5::identity()) * r } else { -r };
            self.max_b = self.max_b.max(b.norm());
        }
        self.max_eps = self.max_eps.max(state.eps.norm());
    }

    fn summary(&self, gain: f64) -> Tracking {
        let phi = gain * self.sigma_min;
        let psi = 2.0 * self.max_b;
        Tracking {
            sigma: self.sigma_min,
            psi,
            phi,
            bound: if phi > 0.0 { psi / phi } else { f64::INFINITY },
            max_eps: self.max_eps,
            duration: self.path.duration(),
            plane_parallax_residual: self.residual,
        }
    }
}

/// The state of a run between iterations.
struct Run<'a> {
    config: &'a SimulationConfig,
    reference: ReferenceImage,
    reference_depths: Vec<f64>,
    controller: AnyController,
    gain: f64,
    stop_rule: StopRule,
    prop1: bool,
    prop2: bool,
    noise: PixelNoise,
    obs: Observation,
    pixels: Vec<[f64; 2]>,
    /// Points in use: visible in the scene (and found by the tracker with images).
    visible: Vec<bool>,
    images: Option<ImageLoop>,
    detection: Vec<f64>,
    pose: Isometry3<f64>,
    /// Joint positions: the state of an arm, derived from the pose for the other robots.
    joints: Vec<f64>,
    /// Smallest manipulability of an arm so far.
    min_manipulability: Option<f64>,
    /// Set when an arm step ends the run (joint limit, singularity).
    arm_end: Option<End>,
    window: StopWindow,
    max_line_deviation: f64,
    /// Largest commanded linear (m/s) and angular (rad/s) speeds so far.
    peak_speeds: (f64, f64),
    estimator: Option<Box<dyn DepthEstimator>>,
    estimated: Vec<f64>,
    path: Option<PathTracking>,
    recording: Option<Recording>,
    metrics: Metrics,
    iteration: usize,
    /// The pixel noise of the last images (what the law is fed).
    noise_meter: PixelNoiseMeter,
    /// What the images said about the pose when the stop rule was met.
    certainty: Option<Certainty>,
}

/// Images the noise meter looks back over.
const NOISE_IMAGES: usize = 32;

impl<'a> Run<'a> {
    fn new(config: &'a SimulationConfig, mut obs: Observation, reference_depths: Vec<f64>) -> Result<Self> {
        let mut noise = PixelNoise::new(config.noise.pixel_sigma, config.noise.seed)?;
        let mut pixels = std::mem::take(&mut obs.pixels);
        if config.noise.on_reference {
            noise.add(&mut pixels, &obs.visible);
        }
        undistort_reference(&mut pixels, &config.reference_camera)?;
        let n = pixels.len();
        let basis = match config.basis {
            Some(b) => validate_basis(b, n)?,
            None => choose_basis(&pixels)?,
        };
        let reference = ReferenceImage::new(pixels, basis)?;
        let (controller, gain) = AnyController::new(config, &reference, &reference_depths)?;
        let same_camera =
            config.camera.zoom.is_none() && config.camera.intrinsics == config.reference_camera.intrinsics;
        let pixel_rule = same_camera || matches!(config.law, Law::Ibvs { .. });
        let (prop1, prop2, _) = stability_verdicts(&config.camera.schedule()?, &config.estimate.matrix(), 1.0, gain)?;
        let images = match config.vision {
            Some(v) => Some(ImageLoop::new(v, &config.scene, pixel_size(config.camera.image, "camera")?)?),
            None => None,
        };
        let (joints, min_manipulability) = start_joints(&config.robot, &config.start)?;
        let estimator = match &config.depths {
            DepthSource::Estimated(factory) => Some(factory.start(&config.scene, &reference.pixels)?),
            _ => None,
        };
        Ok(Self {
            config,
            reference,
            reference_depths,
            controller,
            gain,
            stop_rule: if pixel_rule { StopRule::Pixel } else { StopRule::Invariant },
            prop1,
            prop2,
            noise,
            obs,
            pixels: vec![[0.0; 2]; n],
            visible: vec![false; n],
            images,
            detection: vec![f64::NAN; n],
            pose: config.start,
            recording: config.record.then(|| Recording { n_points: n, n_joints: joints.len(), ..Default::default() }),
            joints,
            min_manipulability,
            arm_end: None,
            window: StopWindow::new(config.stop.window),
            max_line_deviation: 0.0,
            peak_speeds: (0.0, 0.0),
            estimator,
            estimated: vec![0.0; n],
            path: None,
            metrics: Metrics { invariant_error: f64::NAN, tau: [f64::NAN; 3], eps_z: f64::NAN, image_error: f64::NAN },
            iteration: 0,
            noise_meter: PixelNoiseMeter::new(NOISE_IMAGES)?,
            certainty: None,
        })
    }

    /// One iteration; `Some` when the run ends.
    fn iterate(&mut self, progress: &mut dyn FnMut(usize, usize) -> bool) -> Result<Option<End>> {
        let t = self.iteration as f64 * self.config.dt;
        let k = self.config.camera.at(t)?;
        if let Err(e) = self.observe(&k) {
            return Ok(Some((Status::LostFeatures, format!("dot tracking failed: {e}"))));
        }
        let converged = self.measure_and_record(t);
        if let Some(end) = self.arm_end.take() {
            return Ok(Some(end));
        }
        if let Some(end) = self.stop_check(converged, progress) {
            return Ok(Some(end));
        }
        let twist = match self.control(t, &k) {
            Ok(twist) => twist,
            Err(end) => return Ok(Some(end)),
        };
        if let Err(end) = self.move_robot(&twist) {
            return Ok(Some(end));
        }
        self.iteration += 1;
        Ok(None)
    }

    /// Observes the scene with K(t): the exact projections with pixel noise, or the dots
    /// tracked in the rendered image.
    fn observe(&mut self, k: &Intrinsics) -> Result<()> {
        let (scene, pose, camera) = (&self.config.scene, &self.pose, &self.config.camera);
        scene.observe_through(pose, k, &camera.distortion, camera.image, &mut self.obs);
        self.visible.copy_from_slice(&self.obs.visible);
        match self.images.as_mut() {
            Some(images) => {
                let run =
                    Tracked { pixels: &mut self.pixels, visible: &mut self.visible, detection: &mut self.detection };
                images.observe(pose, k, &camera.distortion, &self.obs, run)?;
            }
            None => {
                self.pixels.copy_from_slice(&self.obs.pixels);
                self.noise.add(&mut self.pixels, &self.visible);
            }
        }
        self.undistort();
        self.noise_meter.push(&self.pixels, Some(&self.visible))
    }

    /// The image points through the controller's calibration (K_hat and its distortion); a
    /// point that cannot be undistorted is not used.
    fn undistort(&mut self) {
        let (k_hat, d_hat) = (&self.config.estimate, &self.config.estimate_distortion);
        if d_hat.is_identity() {
            return;
        }
        for (p, v) in self.pixels.iter_mut().zip(self.visible.iter_mut()).filter(|(_, v)| **v) {
            match undistort_point(*p, k_hat, d_hat) {
                Ok(q) => *p = q,
                Err(_) => *v = false,
            }
        }
    }

    /// Measures against the reference and records; returns whether the stop rule is met.
    fn measure_and_record(&mut self, t: f64) -> bool {
        let mut row = self.window.next_row();
        self.metrics = measure(&self.pixels, &self.visible, &self.reference, &mut row);
        // The goal is the identity, so the line from start to goal ends at the origin.
        let position = self.pose.translation.vector;
        let deviation = distance_to_segment(&position, &self.config.start.translation.vector, &Vector3::zeros());
        self.max_line_deviation = self.max_line_deviation.max(deviation);
        self.record_observation(t);
        let (rule, stop, n_others, tau) =
            (self.stop_rule, &self.config.stop, self.reference.others.len(), self.metrics.tau);
        match self.window.push(row) {
            Some(_) if matches!(self.config.law, Law::Observe) => false,
            Some(mean) => stop_rule_met(rule, stop, mean, n_others, tau),
            None => false,
        }
    }

    fn record_observation(&mut self, t: f64) {
        let Some(r) = self.recording.as_mut() else { return };
        let (pose, m) = (&self.pose, &self.metrics);
        r.time.push(t);
        let h = pose.to_homogeneous();
        r.pose.extend((0..16).map(|i| h[(i / 4, i % 4)]));
        r.joints.extend_from_slice(&self.joints);
        for (p, &v) in self.pixels.iter().zip(&self.visible) {
            r.pixels.extend_from_slice(&if v { *p } else { [f64::NAN; 2] });
        }
        r.visible.extend_from_slice(&self.visible);
        r.invariant_error.push(m.invariant_error);
        r.eps_z.push(m.eps_z);
        r.image_error.push(m.image_error);
        r.translation_error.push(pose.translation.vector.norm());
        r.rotation_error.push(pose.rotation.angle());
        if self.images.is_some() {
            r.detection_error.extend_from_slice(&self.detection);
        }
    }

    /// The stop rules, in order: divergence, lost features, convergence, limits.
    fn stop_check(&mut self, converged: bool, progress: &mut dyn FnMut(usize, usize) -> bool) -> Option<End> {
        let stop = &self.config.stop;
        let distance = self.pose.translation.vector.norm();
        if distance.is_nan() || distance > stop.divergence_distance {
            return Some((Status::Diverged, format!("camera {} m from the goal", fixed_or_short(distance, 2))));
        }
        if let Some(end) = self.lost_features() {
            return Some(end);
        }
        if converged && let Some(end) = self.certify() {
            return Some(end);
        }
        let at_limit = self.iteration >= stop.max_iterations;
        if let Some(end) = self.rz_trap(at_limit) {
            return Some(end);
        }
        if at_limit && matches!(self.config.law, Law::Observe) {
            return Some((Status::Observed, format!("{} images taken (no control)", self.iteration + 1)));
        }
        if at_limit {
            return Some((Status::MaxIterations, format!("iteration limit {} reached", stop.max_iterations)));
        }
        if self.iteration.is_multiple_of(64) && !progress(self.iteration, stop.max_iterations) {
            return Some((Status::MaxIterations, "stopped by the caller".into()));
        }
        None
    }

    /// The rz = pi equilibrium of the invariant law: `s = s*` and `tau_21 = 0` reached with
    /// `tau_11 < 0` or `tau_22 < 0`, or either sign wrong when the iteration limit is reached.
    fn rz_trap(&self, at_limit: bool) -> Option<End> {
        if !matches!(self.config.law, Law::Invariant(_)) {
            return None;
        }
        let (m, stop) = (&self.metrics, &self.config.stop);
        let [tau11, tau21, tau22] = m.tau;
        let flipped = tau11 < 0.0 || tau22 < 0.0;
        let settled = m.invariant_error < stop.invariant_error && tau21.abs() < stop.tau21;
        (flipped && (settled || at_limit)).then(|| {
            let why = format!(
                "settled rotated by about 180 degrees about the optical axis (tau_11 = {tau11:.3}, tau_22 = {tau22:.3}): \
                 the rz = pi equilibrium of eq. (24); use control.rz_task = \"angle\""
            );
            (Status::RzTrap, why)
        })
    }

    /// The image rule is met: `converged` if the pose uncertainty the averaged images allow is
    /// within the tolerance, `settled` if not; `None` (carry on) until the noise can be
    /// measured (three images).
    fn certify(&mut self) -> Option<End> {
        let stop = &self.config.stop;
        let certainty = match self.window.mean().map(|mean| self.mean_pixels(mean)) {
            Some(pixels) => self.certainty_of(&pixels, stop.window)?,
            None => return None,
        };
        self.certainty = Some(certainty);
        let (t, r) = certainty.bound;
        let (t_tol, r_tol) = (stop.max_translation_uncertainty, stop.max_rotation_uncertainty_deg.to_radians());
        if t <= t_tol && r <= r_tol {
            return Some((Status::Converged, "stop rule met".into()));
        }
        let why = format!(
            "stop rule met, but the images allow {:.3} mm and {:.3} deg from the goal (tolerance {:.3} mm, {:.3} deg; \
             pixel noise {:.3} px measured, reference {:.3} px)",
            t * 1e3,
            r.to_degrees(),
            t_tol * 1e3,
            stop.max_rotation_uncertainty_deg,
            certainty.pixel_sigma,
            certainty.reference_pixel_sigma
        );
        Some((Status::Settled, why))
    }

    /// The pixels averaged over the stop window: `p* + mean(p - p*)` (every point is in view
    /// when a rule is met).
    fn mean_pixels(&self, mean: &[f64]) -> Vec<[f64; 2]> {
        let offset = 1 + 3 * self.reference.others.len();
        let errors = mean[offset..].chunks_exact(2);
        self.reference.pixels.iter().zip(errors).map(|(p, e)| [p[0] + e[0], p[1] + e[1]]).collect()
    }

    /// The pose uncertainty of `pixels` (the average of `averaged` images) under the law's
    /// measurements, with its depths and K_hat; `None` when it cannot be computed.
    fn certainty_of(&self, pixels: &[[f64; 2]], averaged: usize) -> Option<Certainty> {
        let pixel_sigma = self.noise_meter.sigma()?;
        let reference_pixel_sigma = self.config.stop.reference_pixel_sigma.unwrap_or(pixel_sigma);
        let noise = ImageNoise { current: pixel_sigma, reference: reference_pixel_sigma, averaged_images: averaged };
        let m = Measurement {
            pixels,
            depths: self.law_depths(),
            reference_pixels: &self.reference.pixels,
            visible: Some(&self.visible),
            k_hat: &self.config.estimate,
        };
        // Where the loop settles is the law's business: the invariant law matches s and tau_21
        // (fewer constraints than the pixels, whatever the stop rule reads), IBVS the pixels.
        let u: PoseUncertainty = match self.config.law {
            Law::Invariant(_) => invariant_pose_uncertainty(&m, self.reference.basis, noise),
            _ => pixel_pose_uncertainty(&m, noise),
        }
        .ok()?;
        let sigma = (u.translation_sigma(), u.rotation_sigma());
        let bound = (u.translation_bound(DEFAULT_SIGMAS), u.rotation_bound(DEFAULT_SIGMAS));
        Some(Certainty { pixel_sigma, reference_pixel_sigma, sigma, bound })
    }

    /// The depths the law is given.
    fn law_depths(&self) -> &[f64] {
        law_depths(&self.config.depths, &self.obs, &self.reference_depths, &self.estimated)
    }

    fn lost_features(&self) -> Option<End> {
        let visible = &self.visible;
        let (n, basis) = (visible.len(), self.reference.basis);
        let seen = visible.iter().filter(|&&v| v).count();
        let invariant = matches!(self.config.law, Law::Invariant(_));
        let needed = if matches!(self.config.law, Law::Ibvs { .. }) { IBVS_MIN_POINTS } else { MIN_POINTS };
        if seen >= needed && (!invariant || basis.iter().all(|&b| visible[b])) {
            return None;
        }
        let lost: Vec<usize> = (0..n).filter(|&i| !visible[i]).collect();
        Some((Status::LostFeatures, format!("{seen} of {n} points visible (basis {basis:?}); lost points {lost:?}")))
    }

    /// Depths for the law, the path's reference, the control step and Prop. 3's figures.
    fn control(&mut self, t: f64, k: &Intrinsics) -> std::result::Result<Vector6<f64>, End> {
        self.estimate_depths()?;
        self.follow_path(t)?;
        let depths = law_depths(&self.config.depths, &self.obs, &self.reference_depths, &self.estimated);
        let twist =
            self.controller.step(&self.pixels, depths, &self.visible).map_err(|e| (status_of(&e), e.to_string()))?;
        if let (Some(path), AnyController::Invariant(c)) = (self.path.as_mut(), &self.controller)
            && t < path.path.duration()
        {
            let (sum, count) = (0..depths.len())
                .filter(|&i| self.visible[i])
                .fold((0.0, 0.0), |(s, c), i| (s + depths[i] / self.obs.depths[i], c + 1.0));
            path.observe(c, k, &self.config.estimate, sum / count, c.config().feedforward);
        }
        if let Some(r) = self.recording.as_mut() {
            let (eps, tracking) = self.controller.eps_and_tracking();
            r.eps.extend_from_slice(&eps);
            r.tracking_error.push(tracking);
        }
        if !twist.iter().all(|v| v.is_finite()) {
            return Err((Status::Diverged, "non-finite twist".into()));
        }
        Ok(twist)
    }

    fn estimate_depths(&mut self) -> std::result::Result<(), End> {
        let Some(e) = self.estimator.as_mut() else { return Ok(()) };
        e.estimate(&self.pixels, &self.visible, &mut self.estimated)
            .map_err(|err| (Status::Degenerate, format!("depth estimation failed: {err}")))
    }

    /// Sec. 3: plan the path from the first image, then move the reference along it.
    fn follow_path(&mut self, t: f64) -> std::result::Result<(), End> {
        let (Some(plan), AnyController::Invariant(c)) = (self.config.path, &mut self.controller) else {
            return Ok(());
        };
        if self.path.is_none() {
            let duration = plan.samples as f64 * self.config.dt;
            let planned = PathTracking::plan(&self.pixels, &self.visible, &self.reference, duration)
                .map_err(|e| (Status::Degenerate, format!("path planning failed: {e}")))?;
            self.path = Some(planned);
        }
        if let Some(p) = self.path.as_mut() {
            p.path
                .sample(t, &mut p.points, &mut p.rates)
                .map_err(|e| (Status::Diverged, format!("path sample: {e}")))?;
            c.set_reference(&p.points, Some(&p.rates)).map_err(|e| (Status::Diverged, format!("path sample: {e}")))?;
        }
        Ok(())
    }

    /// Sends the twist to the robot and integrates it over one period.
    fn move_robot(&mut self, twist: &Vector6<f64>) -> std::result::Result<(), End> {
        let (v, w) = (twist.fixed_rows::<3>(0).norm(), twist.fixed_rows::<3>(3).norm());
        self.peak_speeds = (self.peak_speeds.0.max(v), self.peak_speeds.1.max(w));
        let config = self.config;
        if let Robot::Arm(arm) = &config.robot {
            return self.move_arm(arm, twist);
        }
        let robot = &config.robot;
        let moved =
            robot.step_pose(&self.pose, twist, self.config.dt).map_err(|e| (Status::Diverged, e.to_string()))?;
        // Quarantine: a non-finite pose is never taken; the run ends at the last finite one.
        let finite =
            moved.pose.translation.vector.iter().chain(moved.pose.rotation.coords.iter()).all(|v| v.is_finite());
        if !finite {
            return Err((Status::Diverged, "the integrated pose is not finite".into()));
        }
        self.pose = moved.pose;
        if let Some(r) = self.recording.as_mut() {
            r.twist.extend_from_slice(moved.twist.as_slice());
            let joints = if moved.joints[0].is_nan() { robot.joints(&self.pose) } else { moved.joints };
            self.joints.copy_from_slice(&joints);
        }
        Ok(())
    }

    /// Moves an arm from its joint positions; a joint limit or a singularity ends the run
    /// once the image where the arm stopped is recorded.
    fn move_arm(&mut self, arm: &ArmRobot, twist: &Vector6<f64>) -> std::result::Result<(), End> {
        let step: ArmStep =
            arm.step(&self.joints, twist, self.config.dt).map_err(|e| (Status::Diverged, e.to_string()))?;
        self.pose = step.pose;
        self.joints.copy_from_slice(&step.joints);
        self.min_manipulability = self.min_manipulability.map(|w| w.min(step.manipulability));
        if let Some(r) = self.recording.as_mut() {
            r.twist.extend_from_slice(step.twist.as_slice());
            r.joint_velocities.extend_from_slice(&step.velocities);
        }
        self.arm_end = step.event.map(|event| {
            let status = match event {
                ArmEvent::JointLimit { .. } => Status::JointLimit,
                ArmEvent::Singular { .. } => Status::Singular,
            };
            (status, event.message())
        });
        Ok(())
    }

    fn finish(mut self, (status, message): End) -> Outcome {
        // Pad the per-step columns of the last recorded row (no step followed it).
        if let Some(r) = self.recording.as_mut() {
            let rows = r.time.len();
            r.twist.resize(rows * 6, f64::NAN);
            r.eps.resize(rows * 5, f64::NAN);
            r.tracking_error.resize(rows, f64::NAN);
            if self.min_manipulability.is_some() {
                r.joint_velocities.resize(rows * r.n_joints, f64::NAN);
            }
        }
        let goal = Isometry3::identity();
        let (final_t, final_r) = pose_error(&goal, &self.pose);
        // Ended otherwise than by the stop rule: what the last image alone allows.
        let certainty = match (self.certainty, &self.config.law) {
            (Some(c), _) => Some(c),
            (None, Law::Observe) => None,
            (None, _) => self.certainty_of(&self.pixels, 1),
        };
        let stop = &self.config.stop;
        let within_tolerance =
            final_t <= stop.max_translation_uncertainty && final_r <= stop.max_rotation_uncertainty_deg.to_radians();
        let m = &self.metrics;
        let summary = Summary {
            status,
            message,
            iterations: self.iteration,
            final_translation_error: final_t,
            final_rotation_error: final_r,
            final_image_error: m.image_error,
            final_invariant_error: m.invariant_error,
            final_tau: m.tau,
            prop1: self.prop1,
            prop2: self.prop2,
            stop_rule: self.stop_rule,
            start_error: pose_error(&goal, &self.config.start),
            basis: self.reference.basis,
            max_line_deviation: self.max_line_deviation,
            peak_speeds: self.peak_speeds,
            tracking: self.path.as_ref().map(|p| p.summary(self.gain)),
            detection_error: self.images.as_ref().map(ImageLoop::error_summary),
            min_manipulability: self.min_manipulability,
            certainty,
            within_tolerance,
        };
        Outcome { summary, recording: self.recording, reference_pixels: self.reference.pixels }
    }
}

/// The joint positions at the start and, for an arm, its manipulability there.
fn start_joints(robot: &Robot, start: &Isometry3<f64>) -> Result<(Vec<f64>, Option<f64>)> {
    Ok(match robot {
        Robot::Arm(arm) => (arm.start.clone(), Some(arm.model.manipulability(&arm.start)?)),
        other => (other.joints(start).to_vec(), None),
    })
}

/// The depths the law is given: true, the reference image's, or estimated.
fn law_depths<'b>(source: &DepthSource, obs: &'b Observation, reference: &'b [f64], estimated: &'b [f64]) -> &'b [f64] {
    match source {
        DepthSource::True => &obs.depths,
        DepthSource::Reference => reference,
        DepthSource::Estimated(_) => estimated,
    }
}

/// Distance from `p` to the segment `[a, b]`.
fn distance_to_segment(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    let t = if len2 > 0.0 { ((p - a).dot(&ab) / len2).clamp(0.0, 1.0) } else { 0.0 };
    (p - (a + ab * t)).norm()
}
