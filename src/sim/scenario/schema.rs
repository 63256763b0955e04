//! The scenario schema: one struct per table of a scenario file. The README's "Scenario
//! files" block describes every key with its unit and default, and a test checks that it
//! parses and covers the whole schema. Tables that the simulator can take as they are
//! (`[noise]`, `[stop]`, `[path]`, `zoom`) deserialize straight into its types.

use serde::{Deserialize, Serialize};

use crate::sim::camera_model::Zoom;
use crate::sim::config::{Noise, PathPlan, StopRules};
use crate::vision::RenderConfig;

mod control;
pub use control::{CONTROL_KEYS, ControlSpec};

fn default_skew() -> f64 {
    90.0
}
fn one() -> f64 {
    1.0
}

/// `[object]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    /// Feature points in F*, metres (none when the object is a rig of `tags`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub points: Vec<[f64; 3]>,
    /// Basis indices (default: the widest triangle of the reference image).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub basis: Option<[usize; 3]>,
    /// Occluding bodies.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bodies: Vec<BodySpec>,
    /// Per point, the normal of its dot in F* for `[vision]` (default: facing the reference
    /// camera).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normals: Option<Vec<[f64; 3]>>,
    /// A rig of AprilTags instead of `points`: the points are the tags' corners, four per tag
    /// in order (top-left, top-right, bottom-right, bottom-left as printed).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tags: Vec<TagSpec>,
    /// The family of the `tags` (a name of `vision::TagFamily::NAMES`; default tag36h11).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tag_family: Option<String>,
    /// The rig's frame in F*, in which the `tags` are placed (default: F*).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rig: Option<PoseSpec>,
}

/// One `[[object.tags]]` entry: a tag of the rig's family (`object.tag_family`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TagSpec {
    /// The tag's id in the family (0-586 for tag36h11).
    pub id: u32,
    /// Side of the square whose corners are reported, metres (AprilTag's and OpenCV's tag
    /// size: tag36h11's black border, tagStandard41h12's white square inside its black ring).
    pub size: f64,
    /// The tag's centre in the rig frame, metres.
    pub position: [f64; 3],
    /// Theta-u rotation of the tag frame in the rig frame, degrees (`rotation` is read too):
    /// the tag frame has x to the right and y up as printed and z out of the printed face.
    #[serde(default, alias = "rotation")]
    pub rotation_deg: [f64; 3],
}

/// One `[[object.bodies]]` entry.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "lowercase", deny_unknown_fields)]
pub enum BodySpec {
    /// A box.
    Cuboid {
        /// Half extents, metres.
        half_extents: [f64; 3],
        /// Centre in F*, metres.
        position: [f64; 3],
        /// Theta-u rotation, degrees (`rotation` is read too).
        #[serde(default, alias = "rotation")]
        rotation_deg: [f64; 3],
    },
    /// A ball.
    Ball {
        /// Radius, metres.
        radius: f64,
        /// Centre in F*, metres.
        position: [f64; 3],
    },
    /// A cylinder along its y axis.
    Cylinder {
        /// Half height, metres.
        half_height: f64,
        /// Radius, metres.
        radius: f64,
        /// Centre in F*, metres.
        position: [f64; 3],
        /// Theta-u rotation, degrees (`rotation` is read too).
        #[serde(default, alias = "rotation")]
        rotation_deg: [f64; 3],
    },
}

/// `[reference_camera]`, `[camera]`, `[estimate]`: the intrinsics as numbers, or a
/// calibration file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    /// A calibration file (ROS camera_info YAML, OpenCV YAML or XML), relative to the scenario
    /// file: its camera matrix, image size and distortion replace fku, fkv, u0, v0, width,
    /// height and distortion.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub calibration: Option<String>,
    /// f ku, pixels.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fku: Option<f64>,
    /// f kv, pixels.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fkv: Option<f64>,
    /// Principal point u0, pixels.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub u0: Option<f64>,
    /// Principal point v0, pixels.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub v0: Option<f64>,
    /// Angle between the image axes, degrees.
    #[serde(default = "default_skew")]
    pub skew_deg: f64,
    /// Image width, pixels.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<f64>,
    /// Image height, pixels.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height: Option<f64>,
    /// Lens distortion coefficients in OpenCV's order: 4 or 5 (plumb_bob) or 8
    /// (rational_polynomial); with `distortion_model = "equidistant"`, OpenCV's fisheye
    /// (Kannala-Brandt, `cv2.fisheye`) `k1, k2, k3, k4`: 4 values.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distortion: Option<Vec<f64>>,
    /// The model of `distortion`, as ROS names it: `"plumb_bob"`, `"rational_polynomial"` or
    /// `"equidistant"` (the fisheye). Default: from the number of coefficients (4 or 5
    /// plumb_bob, 8 rational_polynomial).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distortion_model: Option<String>,
    /// Zoom schedule (servo camera only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub zoom: Option<Zoom>,
}

/// `[start]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StartSpec {
    /// Camera centre in F*, metres.
    pub position: [f64; 3],
    /// Theta-u of the camera frame in F*, degrees (`rotation` is read too).
    #[serde(default, alias = "rotation")]
    pub rotation_deg: [f64; 3],
}

/// A pose: a position in metres and a theta-u rotation in degrees.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoseSpec {
    /// Position, metres.
    pub position: [f64; 3],
    /// Theta-u rotation, degrees (`rotation` is read too).
    #[serde(default, alias = "rotation")]
    pub rotation_deg: [f64; 3],
}

/// Control law name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LawName {
    /// Sec. 4.
    Invariant,
    /// Classic IBVS.
    Ibvs,
    /// No control: a stationary camera (sec. 5.1).
    None,
}

impl LawName {
    /// The name a scenario file gives the law.
    pub fn name(self) -> &'static str {
        match self {
            Self::Invariant => "invariant",
            Self::Ibvs => "ibvs",
            Self::None => "none",
        }
    }
}

/// Depth source name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DepthsName {
    /// True depths.
    True,
    /// Reference depths zeta*.
    Reference,
    /// Estimated up to scale (appendix A).
    Estimated,
}

/// Robot kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RobotKind {
    /// Free-flying camera.
    Free,
    /// Cartesian robot with limits.
    Cartesian,
    /// A serial arm from URDF carrying the camera on its end-effector.
    Urdf,
}

/// `[robot]`: Cartesian joint values are `(x, y, z)` in metres then the wrist `(a, b, c)` in
/// degrees; arm joint values are degrees (revolute) or metres (prismatic).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSpec {
    /// Which robot.
    #[serde(default = "default_robot")]
    pub kind: RobotKind,
    /// Lower joint limits (Cartesian: m, m, m, deg, deg, deg; arm: overrides the URDF's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_min: Option<Vec<f64>>,
    /// Upper joint limits.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_max: Option<Vec<f64>>,
    /// Joint speed limits (m/s or deg/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_velocity: Option<Vec<f64>>,
    /// Arm: a built-in model (`ur5`, `panda`) or a URDF file (relative to the scenario file).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub urdf: Option<String>,
    /// Arm: the link carrying the camera (default: the built-in model's end-effector).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub end_effector: Option<String>,
    /// Arm: pose of the camera in the end-effector frame (default: identity).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera_mount: Option<PoseSpec>,
    /// Arm: the error of the mount the controller believes, in the true camera frame
    /// (`believed = camera_mount * mount_error`; a hand-eye calibration's error); the camera
    /// moves with the true mount (default: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mount_error: Option<PoseSpec>,
    /// Arm: pose of the arm's base link in F* (default: identity).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base: Option<PoseSpec>,
    /// Arm: joint positions at the start (degrees, metres); the start pose follows from them.
    /// Give either these or the camera's start pose `[start]` (joints by inverse kinematics).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joints: Option<Vec<f64>>,
    /// Arm placed by `[start]`: the joints (degrees, metres) the inverse kinematics starts
    /// from, which picks the branch (elbow up or down, ...); default: the middle of the limits.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ik_seed: Option<Vec<f64>>,
    /// Arm: a run ends `singular` below this manipulability (default 1e-4).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_manipulability: Option<f64>,
    /// Arm: the largest damping factor of the least squares (default 0.02).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
}

fn default_robot() -> RobotKind {
    RobotKind::Free
}

impl Default for RobotSpec {
    fn default() -> Self {
        Self {
            kind: RobotKind::Free,
            joint_min: None,
            joint_max: None,
            joint_velocity: None,
            urdf: None,
            end_effector: None,
            camera_mount: None,
            mount_error: None,
            base: None,
            joints: None,
            ik_seed: None,
            min_manipulability: None,
            damping: None,
        }
    }
}

/// `[depth_estimation]`: the pure-translation image pair of appendix A.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DepthEstimationSpec {
    /// Any camera, unknown to the controller (fku, fkv, u0, v0, skew_deg).
    pub camera: CameraSpec,
    /// Camera centre of the first image in F*, metres.
    pub position: [f64; 3],
    /// Theta-u of that camera in F*, degrees (`rotation` is read too).
    #[serde(default, alias = "rotation")]
    pub rotation_deg: [f64; 3],
    /// Pure translation of the camera centre to the second image, metres, in F*.
    pub translation: [f64; 3],
    /// The mean depth the estimates give the reference image: a rough guess of the distance
    /// to the object in metres (default 1, "unknown"); it scales the translation speed only.
    #[serde(default = "one")]
    pub reference_mean_depth: f64,
}

/// The world a scenario runs in (`[world] engine`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Engine {
    /// vsinv's own simulator: a kinematic camera or robot, images drawn by vsinv (this crate).
    #[default]
    Kinematic,
    /// MuJoCo's physics and renders: run from Python, `vsinv.mujoco.run` (the `mujoco` extra).
    Mujoco,
}

impl Engine {
    /// The name a scenario file gives the engine.
    pub fn name(self) -> &'static str {
        match self {
            Self::Kinematic => "kinematic",
            Self::Mujoco => "mujoco",
        }
    }
}

/// `[world] eye_to_hand`: the camera is fixed and an arm carries the target (the
/// `mujoco` engine only). The scenario's `[start]` stays the camera's pose in F*, the frame of
/// the reference view rigid with the target; the world frame is the fixed camera's.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EyeToHandSpec {
    /// The arm carrying the target: a built-in arm (`ur5`, `ur5e`, `panda`) or a URDF file with
    /// inertias (resolved as `robot.urdf` is; `end_effector` then names the link).
    pub urdf: String,
    /// The link carrying the target (default: the built-in model's end effector).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub end_effector: Option<String>,
    /// The arm's base link in the fixed camera's frame.
    pub base: PoseSpec,
    /// F* (the target's frame: the reference view's camera frame) in the end-effector frame.
    pub target_mount: PoseSpec,
    /// The joints (degrees, metres) the inverse kinematics of the start starts from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ik_seed: Option<Vec<f64>>,
    /// The camera-to-base transform the controller believes (the fixed camera's frame in the
    /// base frame: the `matrix` of `calibrate_hand_eye(..., setup="eye_to_hand")`, as a
    /// position and a theta-u rotation), by which it carries the law's twist to the target;
    /// default: the true one, the inverse of `base`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera_to_base: Option<PoseSpec>,
}

/// `[world]`: which world runs the scenario, and what it adds to the loop.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorldSpec {
    /// `"kinematic"` (default: this crate's simulator) or `"mujoco"` (Python's `vsinv.mujoco`).
    #[serde(default)]
    pub engine: Engine,
    /// Frames between an image and the twist computed from it being applied: the twist of
    /// frame k moves the camera after frame k + N (default 0; the `mujoco` engine only).
    #[serde(default)]
    pub latency_frames: u32,
    /// Eye-to-hand: a fixed camera watching a target carried by an arm (the `mujoco` engine only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eye_to_hand: Option<EyeToHandSpec>,
    /// Each pixel of a MuJoCo image is the mean of a k x k block rendered k times larger, as a
    /// sensor's pixel integrates the light over its area (default 1: one sample a pixel, whose
    /// edge aliasing the detections carry; the `mujoco` engine only).
    #[serde(default = "one_sample", skip_serializing_if = "is_one_sample")]
    pub supersample: u32,
}

fn one_sample() -> u32 {
    1
}

fn is_one_sample(k: &u32) -> bool {
    *k == 1
}

impl Default for WorldSpec {
    fn default() -> Self {
        Self { engine: Engine::default(), latency_frames: 0, eye_to_hand: None, supersample: 1 }
    }
}

impl WorldSpec {
    /// Whether every key has its default (the table is then not written).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }
}

/// A scenario: one simulated servoing run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Short name.
    pub name: String,
    /// What it shows.
    #[serde(default)]
    pub description: String,
    /// The object.
    pub object: ObjectSpec,
    /// K* and the reference image size.
    pub reference_camera: CameraSpec,
    /// K(t) while servoing (default: the reference camera).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera: Option<CameraSpec>,
    /// K_hat (default: the servo camera at t = 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimate: Option<CameraSpec>,
    /// Start pose of the camera. With an arm, either this (the start joints then follow by
    /// inverse kinematics) or `robot.joints` (the start pose then follows from them).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start: Option<StartSpec>,
    /// The control law.
    #[serde(default)]
    pub control: ControlSpec,
    /// The robot.
    #[serde(default)]
    pub robot: RobotSpec,
    /// Pixel noise.
    #[serde(default)]
    pub noise: Noise,
    /// Stop rules.
    #[serde(default)]
    pub stop: StopRules,
    /// Path planning in the invariant space.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path: Option<PathPlan>,
    /// Images in the loop.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vision: Option<RenderConfig>,
    /// The translation pair for `control.depths = "estimated"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth_estimation: Option<DepthEstimationSpec>,
    /// The world that runs the scenario (default: the kinematic simulator).
    #[serde(default, skip_serializing_if = "WorldSpec::is_default")]
    pub world: WorldSpec,
    /// The directory of the scenario file, if any: relative `calibration` and `robot.urdf`
    /// paths start there.
    #[serde(skip)]
    pub directory: Option<std::path::PathBuf>,
    /// Where the files the scenario names may be (default: inside its folder).
    #[serde(skip)]
    pub file_access: super::FileAccess,
}
