//! What a run needs: the scene, the cameras, the law, the depth source, noise, stop rules.

use nalgebra::Isometry3;

use crate::core::adaptive_gain::AdaptiveGain;
use crate::core::camera::Intrinsics;
use crate::core::control::InvariantControllerConfig;
use crate::core::distortion::Distortion;
use crate::core::ibvs::Interaction;
use crate::core::saturation::TwistLimits;
use crate::sim::camera_model::CameraModel;
use crate::sim::depth_source::DepthSource;
use crate::sim::robot::Robot;
use crate::sim::scene::Scene;

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
        /// A gain that depends on the pixel error norm, replacing `gain`.
        adaptive_gain: Option<AdaptiveGain>,
        /// Largest linear and angular speeds.
        twist_limits: Option<TwistLimits>,
    },
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
    /// `tau21` and `tau_11 > 0`, `tau_22 > 0` (correction 8).
    pub invariant_error: f64,
    /// Threshold on `|tau_21|` for the invariant rule.
    pub tau21: f64,
    /// The errors are averaged over this many last iterations before the comparison (1: no
    /// averaging; noisy runs want 10 or so).
    pub window: usize,
    /// A camera farther than this (metres) from the reference pose counts as diverged.
    pub divergence_distance: f64,
    /// When the image rule is met, the run is `converged` only if the pose uncertainty the
    /// images still allow (3 sigma plus the offset the mean error implies, see
    /// [`crate::core::uncertainty`]) is at most this far from the goal, metres; otherwise it is
    /// `settled`. Also the tolerance of the summary's `within_tolerance`.
    pub max_translation_uncertainty: f64,
    /// The same for the rotation, degrees.
    pub max_rotation_uncertainty_deg: f64,
    /// The reference image's pixel noise, pixels; `None`: assumed equal to the noise measured
    /// on the servo camera's images (one image cannot show its own noise).
    pub reference_pixel_sigma: Option<f64>,
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
            max_translation_uncertainty: 0.005,
            max_rotation_uncertainty_deg: 0.5,
            reference_pixel_sigma: None,
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
    /// The lens distortion believed to be the servo camera's: its image points are undistorted
    /// with it and K_hat before the control law (none: they are fed as they are).
    pub estimate_distortion: Distortion,
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
    /// Plan a path in the invariant space from the first image (sec. 3); None keeps the
    /// reference still.
    pub path: Option<PathPlan>,
    /// Images in the loop: render, detect and track the dots (None: exact projections).
    pub vision: Option<crate::vision::RenderConfig>,
    /// Keep the per-iteration record.
    pub record: bool,
}

/// A path planned in the invariant space from the first image (sec. 3, the `[path]` table).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PathPlan {
    /// Number of samples at the control period: the path lasts `samples * dt` (the paper's N).
    pub samples: usize,
}
