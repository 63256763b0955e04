//! What a run needs: the scene, the cameras, the law, the depth source, noise, stop rules.

use nalgebra::Isometry3;

use crate::core::camera::Intrinsics;
use crate::core::distortion::Distortion;
use crate::sim::camera_model::CameraModel;
use crate::sim::depth_source::DepthSource;
use crate::sim::robot::Robot;
use crate::sim::scene::Scene;

pub use crate::servo::{Law, PathPlan, StopRules};

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
    /// The most memory the record holds, bytes ([`MAX_RECORD_BYTES`](crate::sim::MAX_RECORD_BYTES)
    /// from a scenario): a longer run keeps one iteration in 2, 4, ... and its last one.
    pub record_bytes: usize,
}
