//! How a run ended: status, summary, Prop. 3 figures along a path, per-iteration recording;
//! and the one declaration of the recorded columns ([`COLUMNS`]) and of the summary's numbers
//! ([`SUMMARY_FIELDS`]) with their units, which the Python bindings build from.

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
    /// Basis used at the end (the session switches when a basis point leaves the view).
    pub basis: [usize; 3],
    /// How many times the basis changed because one of its points was not visible.
    pub basis_switches: usize,
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

/// One axis of a recorded column's shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    /// One row per recorded iteration (`N`).
    Rows,
    /// One per object point (`n`).
    Points,
    /// One per robot joint (`n_joints`).
    Joints,
    /// A fixed length.
    Fixed(usize),
}

impl Axis {
    /// The length of this axis for a recording of `rows` rows, `points` points, `joints` joints.
    pub fn len(self, rows: usize, points: usize, joints: usize) -> usize {
        match self {
            Axis::Rows => rows,
            Axis::Points => points,
            Axis::Joints => joints,
            Axis::Fixed(k) => k,
        }
    }
    /// The symbol of a variable axis (`N`, `n`, `n_joints`), None for a fixed one.
    pub fn symbol(self) -> Option<&'static str> {
        match self {
            Axis::Rows => Some("N"),
            Axis::Points => Some("n"),
            Axis::Joints => Some("n_joints"),
            Axis::Fixed(_) => None,
        }
    }
}

/// The runs that record a column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Recorded {
    /// Every run.
    Always,
    /// Runs with images in the loop (`[vision]`).
    Vision,
    /// Runs on an arm (`[robot] kind = "urdf"`).
    Arm,
}

/// A recorded column: name, unit, shape, element type, which runs record it, and what it is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Column {
    /// The name (a `RunResult` attribute, an `.npz` entry).
    pub name: &'static str,
    /// SI unit, or `px`, `1` (dimensionless), `bool`.
    pub unit: &'static str,
    /// The shape.
    pub shape: &'static [Axis],
    /// Whether the elements are booleans (else f64).
    pub boolean: bool,
    /// Which runs record it.
    pub recorded: Recorded,
    /// What it is.
    pub description: &'static str,
}

impl Column {
    /// The shape for `rows` rows, `points` points and `joints` joints.
    pub fn dims(&self, rows: usize, points: usize, joints: usize) -> Vec<usize> {
        self.shape.iter().map(|a| a.len(rows, points, joints)).collect()
    }
}

const fn column(name: &'static str, unit: &'static str, shape: &'static [Axis], description: &'static str) -> Column {
    Column { name, unit, shape, boolean: false, recorded: Recorded::Always, description }
}

use Axis::{Fixed, Joints, Points, Rows};

/// The recorded columns, in the order of [`Recording::into_buffers`]: the one declaration of
/// their names, units and shapes.
pub const COLUMNS: [Column; 16] = [
    column("time", "s", &[Rows], "time"),
    column("pose", "m", &[Rows, Fixed(4), Fixed(4)], "camera pose in F* (4x4, translation in metres)"),
    column(
        "twist",
        "m/s, rad/s",
        &[Rows, Fixed(6)],
        "twist sent to the robot (vx, vy, vz, wx, wy, wz; NaN on the last row when no step followed)",
    ),
    column("joints", "m, rad", &[Rows, Joints], "joint positions (x, y, z, theta-u for the free-flying camera)"),
    column("pixels", "px", &[Rows, Points, Fixed(2)], "measured pixels (NaN where not visible)"),
    Column { boolean: true, ..column("visible", "bool", &[Rows, Points], "visibility of each point") },
    column("invariant_error", "1", &[Rows], "||s - s*||, to the reference image"),
    column(
        "tracking_error",
        "1",
        &[Rows],
        "||s - s*(t)||, to the moving reference of a planned path (NaN outside the invariant law)",
    ),
    column("eps", "m, rad", &[Rows, Fixed(5)], "task function eps (NaN for IBVS)"),
    column("eps_z", "px^2", &[Rows], "eps_z = det(Q*) tau_21"),
    column("image_error", "px", &[Rows], "largest distance of a visible point from its reference pixel"),
    column("translation_error", "m", &[Rows], "distance of the camera centre from the reference pose"),
    column("rotation_error", "rad", &[Rows], "rotation angle from the reference pose"),
    column(
        "reference_pixels",
        "px",
        &[Points, Fixed(2)],
        "reference pixels (with their noise, if any); one row per point, not per iteration",
    ),
    Column {
        recorded: Recorded::Vision,
        ..column(
            "detection_error",
            "px",
            &[Rows, Points],
            "distance of each tracked centroid from the true projection of its dot's centre (NaN where not found)",
        )
    },
    Column {
        recorded: Recorded::Arm,
        ..column(
            "joint_velocities",
            "m/s, rad/s",
            &[Rows, Joints],
            "an arm's joint velocities after saturation (NaN on the last row)",
        )
    },
];

/// A recorded buffer, flat and row-major.
#[derive(Debug, Clone, PartialEq)]
pub enum Buffer {
    /// f64 elements.
    F64(Vec<f64>),
    /// Boolean elements.
    Bool(Vec<bool>),
}

impl Recording {
    /// The buffers in the order of [`COLUMNS`], with the run's `reference_pixels`.
    pub fn into_buffers(self, reference_pixels: Vec<[f64; 2]>) -> [Buffer; COLUMNS.len()] {
        use Buffer::{Bool, F64};
        [
            F64(self.time),
            F64(self.pose),
            F64(self.twist),
            F64(self.joints),
            F64(self.pixels),
            Bool(self.visible),
            F64(self.invariant_error),
            F64(self.tracking_error),
            F64(self.eps),
            F64(self.eps_z),
            F64(self.image_error),
            F64(self.translation_error),
            F64(self.rotation_error),
            F64(reference_pixels.into_flattened()),
            F64(self.detection_error),
            F64(self.joint_velocities),
        ]
    }
}

/// A number of the summary: name, unit and its value (None where it does not apply).
#[derive(Debug, Clone, Copy)]
pub struct SummaryField {
    /// The name (a key of the summary dict).
    pub name: &'static str,
    /// SI unit, or `px`, `1` (dimensionless).
    pub unit: &'static str,
    /// The value in a summary.
    pub value: fn(&Summary) -> Option<f64>,
    /// What it is.
    pub description: &'static str,
}

const fn field(
    name: &'static str,
    unit: &'static str,
    value: fn(&Summary) -> Option<f64>,
    description: &'static str,
) -> SummaryField {
    SummaryField { name, unit, value, description }
}

/// The numbers of the summary: the one declaration of their names and units.
pub const SUMMARY_FIELDS: [SummaryField; 29] = [
    field(
        "final_translation_error",
        "m",
        |s| Some(s.final_translation_error),
        "final distance of the camera centre from the reference pose",
    ),
    field(
        "final_rotation_error",
        "rad",
        |s| Some(s.final_rotation_error),
        "final rotation angle from the reference pose",
    ),
    field(
        "final_image_error",
        "px",
        |s| Some(s.final_image_error),
        "final largest distance of a visible point from its reference pixel",
    ),
    field("final_invariant_error", "1", |s| Some(s.final_invariant_error), "final ||s - s*||"),
    field("final_tau_11", "1", |s| Some(s.final_tau[0]), "final tau_11"),
    field("final_tau_21", "1", |s| Some(s.final_tau[1]), "final tau_21"),
    field("final_tau_22", "1", |s| Some(s.final_tau[2]), "final tau_22"),
    field("start_translation_error", "m", |s| Some(s.start_error.0), "start distance from the reference pose"),
    field("start_rotation_error", "rad", |s| Some(s.start_error.1), "start rotation angle from the reference pose"),
    field(
        "max_line_deviation",
        "m",
        |s| Some(s.max_line_deviation),
        "largest distance of the camera centre from the segment between start and goal",
    ),
    field(
        "peak_linear_speed",
        "m/s",
        |s| Some(s.peak_speeds.0),
        "largest commanded linear speed (after the law's twist limits)",
    ),
    field(
        "peak_angular_speed",
        "rad/s",
        |s| Some(s.peak_speeds.1),
        "largest commanded angular speed (after the law's twist limits)",
    ),
    field(
        "path_duration",
        "s",
        |s| s.tracking.map(|t| t.duration),
        "duration of the planned path (None without a path)",
    ),
    field(
        "plane_parallax_residual",
        "1",
        |s| s.tracking.map(|t| t.plane_parallax_residual),
        "RMS residual of the plane + parallax estimate",
    ),
    field(
        "tracking_sigma",
        "1",
        |s| s.tracking.map(|t| t.sigma),
        "Prop. 3: smallest eigenvalue of A(t) + A(t)^T along the path",
    ),
    field("tracking_psi", "m/s, rad/s", |s| s.tracking.map(|t| t.psi), "Prop. 3: psi = 2 max ||b(t)||"),
    field("tracking_phi", "1/s", |s| s.tracking.map(|t| t.phi), "Prop. 3: phi = lambda sigma"),
    field("tracking_bound", "m, rad", |s| s.tracking.map(|t| t.bound), "Prop. 3: the bound psi / phi on ||eps(t)||"),
    field(
        "observed_max_eps",
        "m, rad",
        |s| s.tracking.map(|t| t.max_eps),
        "largest ||eps(t)|| observed while the reference moved",
    ),
    field(
        "detection_error_median",
        "px",
        |s| s.detection_error.map(|e| e.0),
        "median distance of a tracked centroid from its dot's true projection (None without [vision])",
    ),
    field(
        "detection_error_max",
        "px",
        |s| s.detection_error.map(|e| e.1),
        "largest distance of a tracked centroid from its dot's true projection (None without [vision])",
    ),
    field(
        "min_manipulability",
        "1",
        |s| s.min_manipulability,
        "smallest manipulability of the arm (None for other robots)",
    ),
    field("pixel_sigma", "px", |s| s.certainty.map(|c| c.pixel_sigma), "pixel noise measured on the final images"),
    field(
        "reference_pixel_sigma",
        "px",
        |s| s.certainty.map(|c| c.reference_pixel_sigma),
        "the reference image's pixel noise",
    ),
    field(
        "translation_sigma",
        "m",
        |s| s.certainty.map(|c| c.sigma.0),
        "one sigma of the final position the images allow",
    ),
    field(
        "rotation_sigma",
        "rad",
        |s| s.certainty.map(|c| c.sigma.1),
        "one sigma of the final orientation the images allow",
    ),
    field(
        "translation_uncertainty",
        "m",
        |s| s.certainty.map(|c| c.bound.0),
        "3 sigma plus the offset the mean error implies, position",
    ),
    field(
        "rotation_uncertainty",
        "rad",
        |s| s.certainty.map(|c| c.bound.1),
        "3 sigma plus the offset the mean error implies, orientation",
    ),
    field(
        "floor_pixel_sigma",
        "px",
        |s| s.certainty.and_then(|c| c.floor_pixel_sigma),
        "the disagreement floor between the reference and the current detections the stall rule measured \
         (included in the uncertainty bounds; none with the stall rule off)",
    ),
];

/// A summary field by name.
pub fn summary_field(name: &str) -> Option<&'static SummaryField> {
    SUMMARY_FIELDS.iter().find(|f| f.name == name)
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

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique() {
        let mut names: Vec<&str> = COLUMNS.iter().map(|c| c.name).collect();
        names.extend(SUMMARY_FIELDS.iter().map(|f| f.name));
        let n = names.len();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), n);
    }

    #[test]
    fn buffers_follow_the_declaration() {
        // Each buffer gets a length of its own: the declared order must match.
        let (rows, points, joints) = (3, 7, 5);
        let f = |c: &str| {
            vec![0.0; COLUMNS.iter().find(|k| k.name == c).unwrap().dims(rows, points, joints).iter().product()]
        };
        let r = Recording {
            n_points: points,
            time: f("time"),
            pose: f("pose"),
            twist: f("twist"),
            n_joints: joints,
            joints: f("joints"),
            joint_velocities: f("joint_velocities"),
            pixels: f("pixels"),
            visible: vec![false; rows * points],
            invariant_error: f("invariant_error"),
            tracking_error: f("tracking_error"),
            eps: f("eps"),
            eps_z: f("eps_z"),
            image_error: f("image_error"),
            translation_error: f("translation_error"),
            rotation_error: f("rotation_error"),
            detection_error: f("detection_error"),
        };
        let buffers = r.into_buffers(vec![[0.0; 2]; points]);
        for (c, b) in COLUMNS.iter().zip(&buffers) {
            let len = match b {
                Buffer::F64(v) => v.len(),
                Buffer::Bool(v) => v.len(),
            };
            assert_eq!(len, c.dims(rows, points, joints).iter().product::<usize>(), "{}", c.name);
            assert_eq!(matches!(b, Buffer::Bool(_)), c.boolean, "{}", c.name);
        }
    }

    #[test]
    fn serde_names_are_the_summary_names() {
        for rule in [StopRule::Pixel, StopRule::Invariant] {
            assert_eq!(serde_json::to_string(&rule).unwrap(), format!("\"{}\"", rule.as_str()));
        }
        for status in
            [Status::Converged, Status::MaxIterations, Status::LostFeatures, Status::RzTrap, Status::JointLimit]
        {
            assert_eq!(serde_json::to_string(&status).unwrap(), format!("\"{}\"", status.as_str()));
        }
    }
}
