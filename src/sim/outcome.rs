//! How a run ended: status, summary, Prop. 3 figures along a path, per-iteration recording.

pub use crate::servo::{Certainty, Status, StopRule};

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
    /// Largest commanded linear (m/s) and angular (rad/s) speeds (the law's twist, after its
    /// twist limits, before the robot's joint limits).
    pub peak_speeds: (f64, f64),
    /// Prop. 3 figures along the planned path (None without a path).
    pub tracking: Option<Tracking>,
    /// Images in the loop: median and largest distance of a tracked centroid from the true
    /// projection of its dot's centre, pixels (None without `[vision]`).
    pub detection_error: Option<(f64, f64)>,
    /// Smallest manipulability of the arm along the run (None for other robots).
    pub min_manipulability: Option<f64>,
    /// What the final images say about the pose (None when it could not be computed: too few
    /// points in view, or fewer than three images to measure the noise).
    pub certainty: Option<Certainty>,
    /// Ground truth: whether the final pose is within `[stop] max_translation_uncertainty` and
    /// `max_rotation_uncertainty_deg` of the goal.
    pub within_tolerance: bool,
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
    /// Number of joints: 6 for the free-flying camera (x, y, z, theta-u) and the Cartesian
    /// robot, the arm's degrees of freedom otherwise.
    pub n_joints: usize,
    /// Joint positions: (N, n_joints).
    pub joints: Vec<f64>,
    /// Arm joint velocities after saturation (NaN on the last row; empty for other robots):
    /// (N, n_joints).
    pub joint_velocities: Vec<f64>,
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
    /// Images in the loop: distance of each tracked centroid from the true projection of its
    /// dot's centre, pixels (NaN where not found; empty without `[vision]`): (N, n).
    pub detection_error: Vec<f64>,
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
