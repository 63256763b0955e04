//! Kinematic simulation of a camera on a robot servoing on an object: cameras that may
//! differ between the reference image (K*) and the servo (K(t), with a zoom schedule), pixel
//! noise, depth sources, visibility, stop rules and a per-iteration recording.

use nalgebra::{Isometry3, Matrix3, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use crate::camera::Intrinsics;
use crate::control::{InvariantController, InvariantControllerConfig};
use crate::depth::{ResectionDepths, depths_from_translation};
use crate::error::{Error, Result, check_finite, check_positive};
use crate::ibvs::{IbvsController, Interaction};
use crate::invariant::{BasisFrame, RzReference, choose_basis, non_basis_indices, validate_basis};
use crate::jacobian::MIN_POINTS;
use crate::planning::{InvariantPath, estimate_plane_parallax};
use crate::robot::Robot;
use crate::scene::{ImageSize, Observation, Scene};
use crate::se3::pose_error;
use crate::stability::a_matrix;
use crate::stability::stability_verdicts;

/// A piecewise-linear schedule of the intrinsics in time (a zoom).
#[derive(Debug, Clone, PartialEq)]
pub struct Zoom {
    /// Knot times in seconds, increasing.
    pub times: Vec<f64>,
    /// `f ku` at each knot.
    pub fku: Vec<f64>,
    /// `f kv` at each knot.
    pub fkv: Vec<f64>,
    /// `u0` at each knot (None: the camera's own).
    pub u0: Option<Vec<f64>>,
    /// `v0` at each knot (None: the camera's own).
    pub v0: Option<Vec<f64>>,
}

/// A camera: intrinsics, an optional zoom schedule and an optional image size.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraModel {
    /// The intrinsics (before the first zoom knot and when there is no zoom).
    pub intrinsics: Intrinsics,
    /// Optional zoom schedule.
    pub zoom: Option<Zoom>,
    /// Optional image bounds; points outside are not visible.
    pub image: Option<ImageSize>,
}

fn interpolate(times: &[f64], values: &[f64], t: f64) -> f64 {
    match times.iter().position(|&k| k > t) {
        Some(0) => values[0],
        None => values[values.len() - 1],
        Some(i) => {
            let w = (t - times[i - 1]) / (times[i] - times[i - 1]);
            values[i - 1] + w * (values[i] - values[i - 1])
        }
    }
}

impl CameraModel {
    /// A fixed camera.
    pub fn fixed(intrinsics: Intrinsics, image: Option<ImageSize>) -> Self {
        Self { intrinsics, zoom: None, image }
    }

    /// Checks the zoom schedule and the image size.
    pub fn validate(&self) -> Result<()> {
        if let Some(s) = self.image
            && !(s.width.is_finite() && s.height.is_finite() && s.width > 0.0 && s.height > 0.0)
        {
            return Err(Error::InvalidParameter { name: "camera", reason: "width and height must be > 0".into() });
        }
        let Some(z) = &self.zoom else { return Ok(()) };
        let bad = |reason: String| Err(Error::InvalidParameter { name: "camera.zoom", reason });
        let m = z.times.len();
        if m == 0 {
            return bad("times must not be empty".into());
        }
        let lens = [Some(z.fku.len()), Some(z.fkv.len()), z.u0.as_ref().map(Vec::len), z.v0.as_ref().map(Vec::len)];
        if lens.iter().flatten().any(|&l| l != m) {
            return bad(format!("times, fku, fkv (and u0, v0 if given) must have the same length {m}"));
        }
        check_finite("camera.zoom", &z.times)?;
        if z.times.windows(2).any(|w| w[1] <= w[0]) {
            return bad("times must be strictly increasing".into());
        }
        for i in 0..m {
            self.at_knot(i)?;
        }
        Ok(())
    }

    fn at_knot(&self, i: usize) -> Result<Intrinsics> {
        let k = &self.intrinsics;
        let Some(z) = &self.zoom else { return Ok(*k) };
        Intrinsics::new(
            z.fku[i],
            z.fkv[i],
            z.u0.as_ref().map_or(k.u0(), |u| u[i]),
            z.v0.as_ref().map_or(k.v0(), |v| v[i]),
            k.theta(),
        )
    }

    /// The intrinsics at time `t`.
    pub fn at(&self, t: f64) -> Result<Intrinsics> {
        let k = &self.intrinsics;
        let Some(z) = &self.zoom else { return Ok(*k) };
        let f = |v: &[f64]| interpolate(&z.times, v, t);
        Intrinsics::new(
            f(&z.fku),
            f(&z.fkv),
            z.u0.as_deref().map_or(k.u0(), f),
            z.v0.as_deref().map_or(k.v0(), f),
            k.theta(),
        )
    }

    /// The intrinsics at every knot of the schedule (one matrix without zoom).
    pub fn schedule(&self) -> Result<Vec<Matrix3<f64>>> {
        let m = self.zoom.as_ref().map_or(1, |z| z.times.len());
        (0..m).map(|i| self.at_knot(i).map(|k| k.matrix())).collect()
    }
}

/// The control law run by the simulator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Law {
    /// The invariant law of sec. 4.
    Invariant(InvariantControllerConfig),
    /// No control: the camera stays still (sec. 5.1, a stationary zooming camera).
    Observe,
    /// Classic pixel-space IBVS.
    Ibvs {
        /// lambda.
        gain: f64,
        /// Where the interaction matrix is evaluated.
        interaction: Interaction,
    },
}

/// A depth estimator running inside the loop: from the current (noisy) pixels, the depths
/// of all points up to one positive scale (`zeta_hat = kappa(t) zeta`, sec. 4.1). The
/// appendix-A method plugs in here.
pub trait DepthEstimator: Send {
    /// Fills `depths` (one per point; entries of hidden points are ignored by the law).
    fn estimate(&mut self, pixels: &[[f64; 2]], visible: &[bool], depths: &mut [f64]) -> Result<()>;
}

/// Builds a fresh [`DepthEstimator`] for each run, from the scene and the reference image.
pub trait DepthEstimatorFactory: Send + Sync {
    /// The estimator for one run.
    fn start(&self, scene: &Scene, reference_pixels: &[[f64; 2]]) -> Result<Box<dyn DepthEstimator>>;
}

impl DepthEstimator for ResectionDepths {
    fn estimate(&mut self, pixels: &[[f64; 2]], visible: &[bool], depths: &mut [f64]) -> Result<()> {
        ResectionDepths::estimate(self, pixels, visible, depths)
    }
}

/// Appendix A in the simulator: two images of the object taken by `camera` (unknown to the
/// controller) at `first_pose` and after a pure translation `translation` (F*, metres) give
/// the depths up to scale; every iteration then resects the current camera.
#[derive(Debug, Clone, PartialEq)]
pub struct TranslationPairDepths {
    /// The camera of the pair.
    pub camera: Intrinsics,
    /// Its pose for the first image (camera frame in F*).
    pub first_pose: Isometry3<f64>,
    /// The translation of its centre to the second image, in F*.
    pub translation: Vector3<f64>,
    /// The mean depth the estimates give the reference image (see [`ResectionDepths::new`]).
    pub reference_mean_depth: f64,
}

impl DepthEstimatorFactory for TranslationPairDepths {
    fn start(&self, scene: &Scene, reference_pixels: &[[f64; 2]]) -> Result<Box<dyn DepthEstimator>> {
        let second_pose = nalgebra::Translation3::from(self.translation) * self.first_pose;
        let mut images = [Observation::default(), Observation::default()];
        for (obs, pose) in images.iter_mut().zip([self.first_pose, second_pose]) {
            scene.observe(&pose, &self.camera, None, obs);
            if let Some(i) = obs.visible.iter().position(|v| !v) {
                return Err(Error::InvalidParameter {
                    name: "depth_estimation",
                    reason: format!("point {i} is not seen by the translation pair (behind the camera or occluded)"),
                });
            }
        }
        let first = depths_from_translation(&images[0].pixels, &images[1].pixels)?;
        Ok(Box::new(ResectionDepths::new(
            &images[0].pixels,
            &first.depths,
            reference_pixels,
            self.reference_mean_depth,
        )?))
    }
}

/// Per-point depths given to the control law.
#[derive(Clone)]
pub enum DepthSource {
    /// The true current depths.
    True,
    /// The depths measured at the reference pose, zeta* (sec. 5.2).
    Reference,
    /// Depths from an estimator (appendix A).
    Estimated(std::sync::Arc<dyn DepthEstimatorFactory>),
}

impl std::fmt::Debug for DepthSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            DepthSource::True => "True",
            DepthSource::Reference => "Reference",
            DepthSource::Estimated(_) => "Estimated",
        })
    }
}

/// Gaussian pixel noise (the `[noise]` table of a scenario).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Noise {
    /// Standard deviation in pixels, on each coordinate.
    pub pixel_sigma: f64,
    /// Seed of the generator (runs are reproducible).
    pub seed: u64,
    /// Also perturb the reference image.
    pub on_reference: bool,
}

impl Default for Noise {
    fn default() -> Self {
        Self { pixel_sigma: 0.0, seed: 0, on_reference: false }
    }
}

/// When a run stops (the `[stop]` table of a scenario).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StopRules {
    /// Iteration limit.
    pub max_iterations: usize,
    /// Same camera (K = K* throughout) or IBVS: stop when every point is closer than this to
    /// its reference pixel (the paper's 0.5 px).
    pub pixel_error: f64,
    /// Different cameras: stop when `||s - s*||` is below this, with `|tau_21|` below
    /// `tau21` and `tau_11 > 0`, `tau_22 > 0` (NOTES.md item 8).
    pub invariant_error: f64,
    /// Threshold on `|tau_21|` for the invariant rule.
    pub tau21: f64,
    /// The errors are averaged over this many last iterations before the comparison (1: no
    /// averaging; noisy runs want 10 or so).
    pub window: usize,
    /// A camera farther than this (metres) from the reference pose counts as diverged.
    pub divergence_distance: f64,
}

impl Default for StopRules {
    fn default() -> Self {
        Self {
            max_iterations: 2000,
            pixel_error: 0.5,
            invariant_error: 1e-4,
            tau21: 1e-4,
            window: 1,
            divergence_distance: 10.0,
        }
    }
}

/// Everything a run needs.
#[derive(Debug, Clone)]
pub struct SimulationConfig {
    /// Points and occluders, in F*.
    pub scene: Scene,
    /// Basis indices; None chooses the widest triangle of the reference image.
    pub basis: Option<[usize; 3]>,
    /// The camera that took the reference image at F* (K*).
    pub reference_camera: CameraModel,
    /// The camera on the robot while servoing (K(t)).
    pub camera: CameraModel,
    /// The intrinsics the control law uses (K_hat).
    pub estimate: Intrinsics,
    /// Start pose of the camera in F*.
    pub start: Isometry3<f64>,
    /// The robot carrying the camera.
    pub robot: Robot,
    /// The control law.
    pub law: Law,
    /// Depths given to the law.
    pub depths: DepthSource,
    /// Control period in seconds.
    pub dt: f64,
    /// Pixel noise.
    pub noise: Noise,
    /// Stop rules.
    pub stop: StopRules,
    /// Plan a path in the invariant space from the first image (sec. 3), sampled this many
    /// times at the control period (`T = samples dt`); None keeps the reference still.
    pub path_samples: Option<usize>,
    /// Keep the per-iteration record.
    pub record: bool,
}

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// The stop rule was met.
    Converged,
    /// The iteration limit was reached.
    MaxIterations,
    /// Fewer than 6 points (or a basis point) visible.
    LostFeatures,
    /// The camera ran away, the twist became non-finite, or the rz law became singular.
    Diverged,
    /// The structure cannot be servoed (planar object, equal depth estimates, collinear basis).
    Degenerate,
}

impl Status {
    /// The name used in summaries and JSON.
    pub fn as_str(&self) -> &'static str {
        match self {
            Status::Converged => "converged",
            Status::MaxIterations => "max_iterations",
            Status::LostFeatures => "lost_features",
            Status::Diverged => "diverged",
            Status::Degenerate => "degenerate",
        }
    }
}

/// Which stop rule applies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopRule {
    /// Image error (same camera, or IBVS).
    Pixel,
    /// Invariant error with tau_21 and the signs of tau_11, tau_22 (different cameras).
    Invariant,
}

/// The outcome of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// How it ended.
    pub status: Status,
    /// Why, in words.
    pub message: String,
    /// Control steps applied.
    pub iterations: usize,
    /// Final distance of the camera centre from the reference pose, metres.
    pub final_translation_error: f64,
    /// Final rotation angle from the reference pose, radians.
    pub final_rotation_error: f64,
    /// Final largest pixel distance of a visible point from its reference pixel.
    pub final_image_error: f64,
    /// Final `||s - s*||`.
    pub final_invariant_error: f64,
    /// Final tau_11, tau_21, tau_22.
    pub final_tau: [f64; 3],
    /// Prop. 1 verdict for K_hat against K(t) (kappa = 1, lambda = gain).
    pub prop1: bool,
    /// Prop. 2 verdict over the zoom schedule.
    pub prop2: bool,
    /// The stop rule that applied.
    pub stop_rule: StopRule,
    /// Start distance and angle from the reference pose (metres, radians).
    pub start_error: (f64, f64),
    /// Basis used.
    pub basis: [usize; 3],
    /// Largest distance of the camera centre from the segment between start and goal, metres.
    pub max_line_deviation: f64,
    /// Prop. 3 figures along the planned path (None without a path).
    pub tracking: Option<Tracking>,
}

/// Prop. 3 along the path: the bound `psi / phi` on `||eps(t)||` and what was observed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tracking {
    /// Smallest eigenvalue of `A(t) + A(t)^T` along the path (sigma of Prop. 3).
    pub sigma: f64,
    /// `psi = 2 max ||b(t)||`.
    pub psi: f64,
    /// `phi = lambda sigma`.
    pub phi: f64,
    /// `psi / phi` (infinite when sigma <= 0).
    pub bound: f64,
    /// The largest `||eps(t)||` observed while the reference moved.
    pub max_eps: f64,
    /// Path duration T, seconds.
    pub duration: f64,
    /// RMS residual of the plane + parallax estimate.
    pub plane_parallax_residual: f64,
}

/// The per-iteration record, in flat row-major buffers (one row per recorded iteration).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Recording {
    /// Number of points.
    pub n_points: usize,
    /// Time, s: (N,).
    pub time: Vec<f64>,
    /// Camera pose in F*: (N, 4, 4).
    pub pose: Vec<f64>,
    /// Twist sent to the robot (NaN on the last row when no step followed): (N, 6).
    pub twist: Vec<f64>,
    /// Joint positions: (N, 6).
    pub joints: Vec<f64>,
    /// Measured pixels (NaN where not visible): (N, n, 2).
    pub pixels: Vec<f64>,
    /// Visibility: (N, n).
    pub visible: Vec<bool>,
    /// `||s - s*||` (to the reference image): (N,).
    pub invariant_error: Vec<f64>,
    /// `||s - s*(t)||` (to the moving reference of a planned path; NaN outside the invariant
    /// law): (N,).
    pub tracking_error: Vec<f64>,
    /// Task function eps (NaN for IBVS): (N, 5).
    pub eps: Vec<f64>,
    /// eps_z = det(Q*) tau_21: (N,).
    pub eps_z: Vec<f64>,
    /// Largest pixel error of a visible point: (N,).
    pub image_error: Vec<f64>,
    /// Distance from the reference pose, metres: (N,).
    pub translation_error: Vec<f64>,
    /// Angle from the reference pose, radians: (N,).
    pub rotation_error: Vec<f64>,
}

impl Recording {
    /// Number of recorded iterations.
    pub fn len(&self) -> usize {
        self.time.len()
    }
    /// Whether nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }
}

/// A finished run.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// The summary.
    pub summary: Summary,
    /// The per-iteration record (if asked for).
    pub recording: Option<Recording>,
    /// Reference pixels (with their noise, if any).
    pub reference_pixels: Vec<[f64; 2]>,
}

/// Distance from `p` to the segment `[a, b]`.
fn distance_to_segment(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    let t = if len2 > 0.0 { ((p - a).dot(&ab) / len2).clamp(0.0, 1.0) } else { 0.0 };
    (p - (a + ab * t)).norm()
}

/// What the reference image provides to the measurements.
struct ReferenceImage {
    pixels: Vec<[f64; 2]>,
    basis: [usize; 3],
    others: Vec<usize>,
    s_star: Vec<Vector3<f64>>,
    rz: RzReference,
}

/// Measurements that do not depend on the law, from the noisy pixels.
struct Metrics {
    invariant_error: f64,
    tau: [f64; 3],
    eps_z: f64,
    image_error: f64,
}

/// The stop rules' low-pass filter: the error *vectors* (`tau_21`, `s - s*`, `p - p*`, NaN
/// for hidden points) averaged over the last `window` images, so that zero-mean pixel noise
/// averages out instead of adding up in a norm.
struct StopWindow {
    window: usize,
    rows: std::collections::VecDeque<Vec<f64>>,
    mean: Vec<f64>,
}

impl StopWindow {
    fn new(window: usize) -> Self {
        Self { window, rows: std::collections::VecDeque::with_capacity(window + 1), mean: Vec::new() }
    }

    /// A row to fill with [`measure`] (the oldest row, recycled, once the window is full).
    fn next_row(&mut self) -> Vec<f64> {
        let mut row =
            if self.rows.len() == self.window { self.rows.pop_front().unwrap_or_default() } else { Vec::new() };
        row.clear();
        row
    }

    /// Adds the errors of one image; returns the means once the window is full.
    fn push(&mut self, row: Vec<f64>) -> Option<&[f64]> {
        self.rows.push_back(row);
        if self.rows.len() < self.window {
            return None;
        }
        if self.window == 1 {
            return self.rows.front().map(Vec::as_slice);
        }
        let len = self.rows[0].len();
        self.mean.clear();
        self.mean.resize(len, 0.0);
        for r in &self.rows {
            self.mean.iter_mut().zip(r).for_each(|(m, v)| *m += v);
        }
        let w = self.window as f64;
        self.mean.iter_mut().for_each(|m| *m /= w);
        Some(&self.mean)
    }
}

/// Measures one image against the reference: the summary metrics, and the error vectors of
/// the stop rule written into `row` (`tau_21`, then `s - s*`, then `p - p*`; NaN for
/// hidden points).
fn measure(pixels: &[[f64; 2]], visible: &[bool], r: &ReferenceImage, row: &mut Vec<f64>) -> Metrics {
    let (reference, basis, others, rz, s_star) = (&r.pixels, r.basis, &r.others, &r.rz, &r.s_star);
    let frame = if basis.iter().all(|&b| visible[b]) { BasisFrame::new(pixels, basis, "current").ok() } else { None };
    let (tau, eps_z) = match &frame {
        Some(f) => {
            let t = rz.t_matrix(f);
            let v = Vector3::new(pixels[basis[0]][1], pixels[basis[1]][1], pixels[basis[2]][1]);
            ([t[(0, 0)], t[(1, 0)], t[(1, 1)]], rz.eps_z(&v))
        }
        None => ([f64::NAN; 3], f64::NAN),
    };
    row.push(tau[1]);
    let mut err2 = 0.0;
    for (k, &i) in others.iter().enumerate() {
        let e = match &frame {
            Some(f) if visible[i] => f.transform(pixels[i]) - s_star[k],
            _ => Vector3::repeat(f64::NAN),
        };
        if visible[i] {
            err2 += e.norm_squared();
        }
        row.extend_from_slice(e.as_slice());
    }
    let mut image_error = f64::NAN; // NaN when no point is visible
    for (i, p) in pixels.iter().enumerate() {
        if visible[i] {
            let (du, dv) = (p[0] - reference[i][0], p[1] - reference[i][1]);
            image_error = image_error.max((du * du + dv * dv).sqrt());
            row.extend_from_slice(&[du, dv]);
        } else {
            row.extend_from_slice(&[f64::NAN; 2]);
        }
    }
    let invariant_error = if frame.is_some() { err2.sqrt() } else { f64::NAN };
    Metrics { invariant_error, tau, eps_z, image_error }
}

/// Plans the path of sec. 3 from the current (first) image; returns it with the plane +
/// parallax residual.
fn plan_path(pixels: &[[f64; 2]], visible: &[bool], r: &ReferenceImage, duration: f64) -> Result<(InvariantPath, f64)> {
    if let Some(i) = (0..pixels.len()).find(|&i| !visible[i]) {
        return Err(Error::InvalidParameter {
            name: "path",
            reason: format!("point {i} is not visible in the first image; the path needs every point"),
        });
    }
    let frame = BasisFrame::new(pixels, r.basis, "current")?;
    let q: Vec<Vector3<f64>> = r.others.iter().map(|&i| frame.transform(pixels[i])).collect();
    let estimate = estimate_plane_parallax(&q, &r.s_star)?;
    Ok((InvariantPath::new(&r.s_star, &estimate, duration)?, estimate.residual))
}

enum AnyController {
    Invariant(Box<InvariantController>),
    Ibvs(Box<IbvsController>),
    Observe,
}

impl AnyController {
    fn step(&mut self, pixels: &[[f64; 2]], depths: &[f64], visible: &[bool]) -> Result<nalgebra::Vector6<f64>> {
        match self {
            AnyController::Invariant(c) => c.step_visible(pixels, depths, visible),
            AnyController::Ibvs(c) => c.step_visible(pixels, depths, visible),
            AnyController::Observe => Ok(nalgebra::Vector6::zeros()),
        }
    }
}

/// Why a control-step error ends the run.
fn status_of(err: &Error) -> Status {
    match err {
        Error::TooFewPoints { .. } | Error::PointBehindCamera { .. } => Status::LostFeatures,
        Error::RzSingular { .. } | Error::NonFinite { .. } => Status::Diverged,
        _ => Status::Degenerate,
    }
}

/// Runs a simulation. `progress(done, max)` is called every few iterations; returning false
/// stops the run (its status is then `max_iterations`).
pub fn simulate(config: &SimulationConfig, progress: &mut dyn FnMut(usize, usize) -> bool) -> Result<Outcome> {
    check_positive("dt", config.dt)?;
    config.reference_camera.validate()?;
    config.camera.validate()?;
    if !(config.noise.pixel_sigma.is_finite() && config.noise.pixel_sigma >= 0.0) {
        return Err(Error::InvalidParameter { name: "noise.pixel_sigma", reason: "must be finite and >= 0".into() });
    }
    let stop = &config.stop;
    if stop.window == 0 || stop.max_iterations == 0 {
        return Err(Error::InvalidParameter { name: "stop", reason: "window and max_iterations must be >= 1".into() });
    }
    config.robot.check_reachable(&config.start)?;
    let n = config.scene.points().len();
    if n < MIN_POINTS && matches!(config.law, Law::Invariant(_)) {
        return Err(Error::TooFewPoints { needed: MIN_POINTS, got: n, why: "the invariant law needs six points" });
    }

    // The reference image, taken at F* with K*: every point must be in view.
    let k_star = config.reference_camera.at(0.0)?;
    let mut obs = Observation::default();
    config.scene.observe(&Isometry3::identity(), &k_star, config.reference_camera.image, &mut obs);
    if let Some(i) = (0..n).find(|&i| obs.depths[i] <= 0.0) {
        return Err(Error::PointBehindCamera { index: i, depth: obs.depths[i] });
    }
    if let Some(i) = (0..n).find(|&i| !obs.visible[i]) {
        return Err(Error::InvalidParameter {
            name: "object",
            reason: format!("point {i} is not visible in the reference image (outside the image or occluded)"),
        });
    }
    let mut rng = ChaCha8Rng::seed_from_u64(config.noise.seed);
    let normal = Normal::new(0.0, config.noise.pixel_sigma.max(f64::MIN_POSITIVE))
        .map_err(|e| Error::InvalidParameter { name: "noise.pixel_sigma", reason: e.to_string() })?;
    let add_noise = |pixels: &mut [[f64; 2]], visible: &[bool], rng: &mut ChaCha8Rng| {
        if config.noise.pixel_sigma > 0.0 {
            for (p, _) in pixels.iter_mut().zip(visible).filter(|(_, v)| **v) {
                p[0] += normal.sample(rng);
                p[1] += normal.sample(rng);
            }
        }
    };
    let mut reference = obs.pixels.clone();
    let reference_depths = obs.depths.clone();
    if config.noise.on_reference {
        add_noise(&mut reference, &obs.visible, &mut rng);
    }
    let basis = match config.basis {
        Some(b) => validate_basis(b, n)?,
        None => choose_basis(&reference)?,
    };
    let others = non_basis_indices(n, basis);
    let reference_frame = BasisFrame::new(&reference, basis, "reference")?;
    let s_star = others.iter().map(|&i| reference_frame.transform(reference[i])).collect();
    let refimg = ReferenceImage { pixels: reference, basis, others, s_star, rz: RzReference::new(&reference_frame) };
    let reference = &refimg.pixels;

    let (mut controller, gain) = match config.law {
        Law::Invariant(c) => (
            AnyController::Invariant(Box::new(InvariantController::new(reference, config.estimate, basis, c)?)),
            c.gain,
        ),
        Law::Ibvs { gain, interaction } => (
            AnyController::Ibvs(Box::new(IbvsController::new(
                reference,
                config.estimate,
                gain,
                interaction,
                Some(&reference_depths),
            )?)),
            gain,
        ),
        Law::Observe => (AnyController::Observe, 1.0),
    };
    let same_camera = config.camera.zoom.is_none() && config.camera.intrinsics == config.reference_camera.intrinsics;
    let stop_rule =
        if same_camera || matches!(config.law, Law::Ibvs { .. }) { StopRule::Pixel } else { StopRule::Invariant };
    let (prop1, prop2, _) = stability_verdicts(&config.camera.schedule()?, &config.estimate.matrix(), 1.0, gain)?;

    let goal = Isometry3::identity();
    let start_error = pose_error(&goal, &config.start);
    let (line_a, line_b) = (config.start.translation.vector, Vector3::zeros());
    let mut rec = config.record.then(|| Recording { n_points: n, ..Default::default() });
    let mut pose = config.start;
    let mut joints = config.robot.joints(&pose);
    let mut history = StopWindow::new(stop.window);
    let mut max_line_deviation = 0.0_f64;
    let mut pixels = vec![[0.0; 2]; n];
    let mut estimator = match &config.depths {
        DepthSource::Estimated(factory) => Some(factory.start(&config.scene, &refimg.pixels)?),
        _ => None,
    };
    let mut estimated = vec![0.0; n];
    let mut path: Option<(InvariantPath, f64)> = None;
    let m_others = refimg.others.len();
    let (mut path_points, mut path_rates) = (vec![[0.0; 3]; m_others], vec![[0.0; 3]; m_others]);
    let feedforward = matches!(config.law, Law::Invariant(c) if c.feedforward);
    let (mut sigma_min, mut max_b, mut max_eps) = (f64::INFINITY, 0.0_f64, 0.0_f64);
    let mut iteration = 0;
    let (status, message, last) = loop {
        let t = iteration as f64 * config.dt;
        let k = config.camera.at(t)?;
        config.scene.observe(&pose, &k, config.camera.image, &mut obs);
        pixels.copy_from_slice(&obs.pixels);
        add_noise(&mut pixels, &obs.visible, &mut rng);
        let mut row = history.next_row();
        let m = measure(&pixels, &obs.visible, &refimg, &mut row);
        // The goal is the identity: the distance is |t|, the angle that of the rotation.
        let dt_err = pose.translation.vector.norm();
        max_line_deviation = max_line_deviation.max(distance_to_segment(&pose.translation.vector, &line_a, &line_b));
        if let Some(r) = rec.as_mut() {
            r.time.push(t);
            let h = pose.to_homogeneous();
            r.pose.extend((0..16).map(|i| h[(i / 4, i % 4)]));
            r.joints.extend_from_slice(&joints);
            for (p, &v) in pixels.iter().zip(&obs.visible) {
                r.pixels.extend_from_slice(&if v { *p } else { [f64::NAN; 2] });
            }
            r.visible.extend_from_slice(&obs.visible);
            r.invariant_error.push(m.invariant_error);
            r.eps_z.push(m.eps_z);
            r.image_error.push(m.image_error);
            r.translation_error.push(dt_err);
            r.rotation_error.push(pose.rotation.angle());
        }
        let finish = |status: Status, message: String, m: Metrics| (status, message, m);

        if dt_err.is_nan() || dt_err > stop.divergence_distance {
            break finish(Status::Diverged, format!("camera {dt_err:.2} m from the goal"), m);
        }
        let seen = obs.visible.iter().filter(|&&v| v).count();
        let basis_seen = basis.iter().all(|&b| obs.visible[b]);
        let needed = match config.law {
            Law::Invariant(_) | Law::Observe => MIN_POINTS,
            Law::Ibvs { .. } => crate::ibvs::IBVS_MIN_POINTS,
        };
        if seen < needed || (matches!(config.law, Law::Invariant(_)) && !basis_seen) {
            let lost: Vec<usize> = (0..n).filter(|&i| !obs.visible[i]).collect();
            break finish(
                Status::LostFeatures,
                format!("{seen} of {n} points visible (basis {basis:?}); lost points {lost:?}"),
                m,
            );
        }
        let means = history.push(row);
        let converged = match means {
            None => false,
            Some(_) if matches!(config.law, Law::Observe) => false,
            Some(mean) => {
                let m_inv = 3 * refimg.others.len();
                let invariant = mean[1..1 + m_inv].iter().map(|v| v * v).sum::<f64>().sqrt();
                let image = mean[1 + m_inv..]
                    .chunks_exact(2)
                    .map(|c| (c[0] * c[0] + c[1] * c[1]).sqrt())
                    .fold(0.0, |a: f64, b| if b.is_nan() { f64::INFINITY } else { a.max(b) });
                match stop_rule {
                    // NaN (a point hidden in the window) never passes a comparison.
                    StopRule::Pixel => image < stop.pixel_error,
                    StopRule::Invariant => {
                        invariant < stop.invariant_error
                            && mean[0].abs() < stop.tau21
                            && m.tau[0] > 0.0
                            && m.tau[2] > 0.0
                    }
                }
            }
        };
        if converged {
            break finish(Status::Converged, "stop rule met".into(), m);
        }
        if iteration >= stop.max_iterations {
            break finish(Status::MaxIterations, format!("iteration limit {} reached", stop.max_iterations), m);
        }
        if iteration % 64 == 0 && !progress(iteration, stop.max_iterations) {
            break finish(Status::MaxIterations, "stopped by the caller".into(), m);
        }
        let depths = match (&config.depths, estimator.as_mut()) {
            (DepthSource::Reference, _) => &reference_depths,
            (DepthSource::Estimated(_), Some(e)) => {
                if let Err(err) = e.estimate(&pixels, &obs.visible, &mut estimated) {
                    break finish(Status::Degenerate, format!("depth estimation failed: {err}"), m);
                }
                &estimated
            }
            _ => &obs.depths,
        };
        // Sec. 3: plan the path from the first image, then move the reference along it.
        if let (Some(samples), AnyController::Invariant(c)) = (config.path_samples, &mut controller) {
            if path.is_none() {
                match plan_path(&pixels, &obs.visible, &refimg, samples as f64 * config.dt) {
                    Ok(p) => path = Some(p),
                    Err(e) => break finish(Status::Degenerate, format!("path planning failed: {e}"), m),
                }
            }
            if let Some((p, _)) = &path {
                p.sample(t, &mut path_points, &mut path_rates);
                if let Err(e) = c.set_reference(&path_points, Some(&path_rates)) {
                    break finish(Status::Diverged, format!("path sample: {e}"), m);
                }
            }
        }
        let twist = match controller.step(&pixels, depths, &obs.visible) {
            Ok(tw) => tw,
            Err(e) => break finish(status_of(&e), e.to_string(), m),
        };
        // Prop. 3 along the path: A(t) from K(t), K_hat and kappa(t) (known here, since the
        // simulator knows the true depths), b(t) and ||eps(t)||.
        if let (Some((p, _)), AnyController::Invariant(c)) = (&path, &controller)
            && t < p.duration()
            && let Some(state) = c.state()
        {
            let (sum, count) = (0..n)
                .filter(|&i| obs.visible[i])
                .fold((0.0, 0.0), |(s, c), i| (s + depths[i] / obs.depths[i], c + 1.0));
            if let Ok(a) = a_matrix(&k.matrix(), &config.estimate.matrix(), sum / count) {
                sigma_min = sigma_min.min((a + a.transpose()).symmetric_eigenvalues().min());
                let r = state.reference_rate_term;
                let b = if feedforward { (a - nalgebra::Matrix5::identity()) * r } else { -r };
                max_b = max_b.max(b.norm());
            }
            max_eps = max_eps.max(state.eps.norm());
        }
        if let Some(r) = rec.as_mut() {
            let (eps, tracking) = match &controller {
                AnyController::Invariant(c) => {
                    c.state().map_or(([f64::NAN; 5], f64::NAN), |s| (s.eps.into(), s.invariant_error))
                }
                AnyController::Ibvs(_) | AnyController::Observe => ([f64::NAN; 5], f64::NAN),
            };
            r.eps.extend_from_slice(&eps);
            r.tracking_error.push(tracking);
        }
        if !twist.iter().all(|v| v.is_finite()) {
            break finish(Status::Diverged, "non-finite twist".into(), m);
        }
        let moved = match config.robot.step_pose(&pose, &twist, config.dt) {
            Ok(s) => s,
            Err(e) => break finish(Status::Diverged, e.to_string(), m),
        };
        if let Some(r) = rec.as_mut() {
            r.twist.extend_from_slice(moved.twist.as_slice());
        }
        pose = moved.pose;
        if rec.is_some() {
            joints = if moved.joints[0].is_nan() { config.robot.joints(&pose) } else { moved.joints };
        }
        iteration += 1;
    };
    // Pad the per-step columns of the last recorded row (no step followed it).
    if let Some(r) = rec.as_mut() {
        let rows = r.time.len();
        r.twist.resize(rows * 6, f64::NAN);
        r.eps.resize(rows * 5, f64::NAN);
        r.tracking_error.resize(rows, f64::NAN);
    }
    let (final_t, final_r) = pose_error(&goal, &pose);
    let summary = Summary {
        status,
        message,
        iterations: iteration,
        final_translation_error: final_t,
        final_rotation_error: final_r,
        final_image_error: last.image_error,
        final_invariant_error: last.invariant_error,
        final_tau: last.tau,
        prop1,
        prop2,
        stop_rule,
        start_error,
        basis,
        max_line_deviation,
        tracking: path.map(|(p, residual)| {
            let phi = gain * sigma_min;
            let psi = 2.0 * max_b;
            Tracking {
                sigma: sigma_min,
                psi,
                phi,
                bound: if phi > 0.0 { psi / phi } else { f64::INFINITY },
                max_eps,
                duration: p.duration(),
                plane_parallax_residual: residual,
            }
        }),
    };
    Ok(Outcome { summary, recording: rec, reference_pixels: refimg.pixels })
}
