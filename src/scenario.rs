//! Scenario files (TOML, or the same structure as JSON or a Python dict): the schema, its
//! validation with errors that name the key at fault, the conversion to a
//! [`SimulationConfig`], and the built-in scenarios reproducing the paper's experiments.
//!
//! ```toml
//! name = "..."                    # required
//! description = "..."
//! [object]            points = [[x, y, z], ...]     # metres, in F*; optional basis = [i, j, k]
//!                     bodies = [{ shape = "cuboid", half_extents = [..], position = [..], rotation = [..] }]
//! [reference_camera]  fku, fkv, u0, v0, skew_deg = 90, width, height      # K*
//! [camera]            same keys; zoom = { times = [...], fku = [...], fkv = [...] }  # K(t)
//! [estimate]          fku, fkv, u0, v0, skew_deg                          # K_hat
//! [start]             position = [x, y, z] (m, camera centre in F*), rotation = [rx, ry, rz] (theta-u, degrees)
//! [control]           law = "invariant" | "ibvs" | "none", gain, gain_rz, dt, depths, feedforward, interaction
//! [robot]             kind = "free" | "cartesian", joint_min, joint_max, joint_velocity
//! [noise]             pixel_sigma, seed, on_reference
//! [stop]              max_iterations, pixel_error, invariant_error, tau21, window, divergence_distance
//! [path]              samples = N                                         # sec. 3, T = N dt
//! [depth_estimation]  camera = {..}, position, rotation, translation      # appendix A
//! ```

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use crate::camera::Intrinsics;
use crate::control::InvariantControllerConfig;
use crate::error::{Error, Result};
use crate::robot::{JointLimits, Robot};
use crate::scene::{Body, ImageSize, Scene};
use crate::simulator::{
    CameraModel, DepthSource, Law, Noise, SimulationConfig, StopRules, TranslationPairDepths, Zoom,
};

fn default_skew() -> f64 {
    90.0
}
fn one() -> f64 {
    1.0
}
fn default_dt() -> f64 {
    0.04
}
fn yes() -> bool {
    true
}

/// `[object]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    /// Feature points in F*, metres.
    pub points: Vec<[f64; 3]>,
    /// Basis indices (default: the widest triangle of the reference image).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub basis: Option<[usize; 3]>,
    /// Occluding bodies.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bodies: Vec<BodySpec>,
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
        /// Theta-u rotation, degrees.
        #[serde(default)]
        rotation: [f64; 3],
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
        /// Theta-u rotation, degrees.
        #[serde(default)]
        rotation: [f64; 3],
    },
}

/// `zoom = { times, fku, fkv, u0, v0 }`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ZoomSpec {
    /// Knot times, seconds.
    pub times: Vec<f64>,
    /// f ku at the knots.
    pub fku: Vec<f64>,
    /// f kv at the knots.
    pub fkv: Vec<f64>,
    /// u0 at the knots.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub u0: Option<Vec<f64>>,
    /// v0 at the knots.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub v0: Option<Vec<f64>>,
}

/// `[reference_camera]`, `[camera]`, `[estimate]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    /// f ku, pixels.
    pub fku: f64,
    /// f kv, pixels.
    pub fkv: f64,
    /// Principal point u0, pixels.
    pub u0: f64,
    /// Principal point v0, pixels.
    pub v0: f64,
    /// Angle between the image axes, degrees.
    #[serde(default = "default_skew")]
    pub skew_deg: f64,
    /// Image width, pixels.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<f64>,
    /// Image height, pixels.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height: Option<f64>,
    /// Zoom schedule (servo camera only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub zoom: Option<ZoomSpec>,
}

/// `[start]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StartSpec {
    /// Camera centre in F*, metres.
    pub position: [f64; 3],
    /// Theta-u of the camera frame in F*, degrees.
    #[serde(default)]
    pub rotation: [f64; 3],
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

/// `[control]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControlSpec {
    /// Which law.
    #[serde(default = "default_law")]
    pub law: LawName,
    /// lambda, 1/s.
    #[serde(default = "one")]
    pub gain: f64,
    /// eta, 1/s.
    #[serde(default = "one")]
    pub gain_rz: f64,
    /// Control period, s.
    #[serde(default = "default_dt")]
    pub dt: f64,
    /// Depths given to the law.
    #[serde(default = "default_depths")]
    pub depths: DepthsName,
    /// Feed-forward term of eq. (17).
    #[serde(default = "yes")]
    pub feedforward: bool,
    /// IBVS interaction matrix: "current", "desired" or "mean".
    #[serde(default = "default_interaction")]
    pub interaction: String,
}

fn default_law() -> LawName {
    LawName::Invariant
}
fn default_depths() -> DepthsName {
    DepthsName::Reference
}
fn default_interaction() -> String {
    "current".into()
}

impl Default for ControlSpec {
    fn default() -> Self {
        Self {
            law: default_law(),
            gain: 1.0,
            gain_rz: 1.0,
            dt: default_dt(),
            depths: default_depths(),
            feedforward: true,
            interaction: default_interaction(),
        }
    }
}

/// Robot kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RobotKind {
    /// Free-flying camera.
    Free,
    /// Cartesian robot with limits.
    Cartesian,
}

/// `[robot]`: joint values are `(x, y, z)` in metres then the wrist `(a, b, c)` in degrees.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSpec {
    /// Which robot.
    #[serde(default = "default_robot")]
    pub kind: RobotKind,
    /// Lower joint limits (m, m, m, deg, deg, deg).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_min: Option<[f64; 6]>,
    /// Upper joint limits.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_max: Option<[f64; 6]>,
    /// Joint speed limits (m/s, m/s, m/s, deg/s, deg/s, deg/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_velocity: Option<[f64; 6]>,
}

fn default_robot() -> RobotKind {
    RobotKind::Free
}

impl Default for RobotSpec {
    fn default() -> Self {
        Self { kind: RobotKind::Free, joint_min: None, joint_max: None, joint_velocity: None }
    }
}

/// `[path]`: plan a path in the invariant space from the first image (sec. 3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PathSpec {
    /// Number of samples; the path lasts `samples * control.dt` seconds (the paper's N).
    pub samples: usize,
}

/// `[depth_estimation]`: the pure-translation image pair of appendix A.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DepthEstimationSpec {
    /// Any camera, unknown to the controller (fku, fkv, u0, v0, skew_deg).
    pub camera: CameraSpec,
    /// Camera centre of the first image in F*, metres.
    pub position: [f64; 3],
    /// Theta-u of that camera in F*, degrees.
    #[serde(default)]
    pub rotation: [f64; 3],
    /// Pure translation of the camera centre to the second image, metres, in F*.
    pub translation: [f64; 3],
    /// The mean depth the estimates give the reference image: a rough guess of the distance
    /// to the object in metres (default 1, "unknown"); it scales the translation speed only.
    #[serde(default = "one")]
    pub reference_mean_depth: f64,
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
    /// Start pose.
    pub start: StartSpec,
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
    pub path: Option<PathSpec>,
    /// The translation pair for `control.depths = "estimated"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth_estimation: Option<DepthEstimationSpec>,
}

fn scenario_error(key: &str, reason: impl Into<String>) -> Error {
    // serde_path_to_error names the document root ".".
    let key = if key == "." { "" } else { key };
    Error::Scenario { key: key.to_string(), reason: reason.into() }
}

fn pose_of(position: [f64; 3], rotation_deg: [f64; 3]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(position[0], position[1], position[2]),
        UnitQuaternion::from_scaled_axis(Vector3::from(rotation_deg.map(f64::to_radians))),
    )
}

impl CameraSpec {
    fn intrinsics(&self, key: &str) -> Result<Intrinsics> {
        Intrinsics::new(self.fku, self.fkv, self.u0, self.v0, self.skew_deg.to_radians())
            .map_err(|e| scenario_error(key, e.to_string()))
    }

    fn model(&self, key: &str) -> Result<CameraModel> {
        let image = match (self.width, self.height) {
            (Some(width), Some(height)) => Some(ImageSize { width, height }),
            (None, None) => None,
            _ => return Err(scenario_error(key, "give both width and height, or neither")),
        };
        let zoom = self.zoom.as_ref().map(|z| Zoom {
            times: z.times.clone(),
            fku: z.fku.clone(),
            fkv: z.fkv.clone(),
            u0: z.u0.clone(),
            v0: z.v0.clone(),
        });
        let model = CameraModel { intrinsics: self.intrinsics(key)?, zoom, image };
        model.validate().map_err(|e| scenario_error(key, e.to_string()))?;
        Ok(model)
    }
}

impl Scenario {
    /// Parses TOML text; errors name the key (and line) at fault.
    pub fn from_toml(text: &str) -> Result<Self> {
        let de = toml::Deserializer::parse(text).map_err(|e| scenario_error("", e.to_string().trim().to_string()))?;
        let scenario: Scenario = serde_path_to_error::deserialize(de).map_err(|e| {
            let key = e.path().to_string();
            scenario_error(&key, e.into_inner().message().trim().to_string())
        })?;
        scenario.validate()?;
        Ok(scenario)
    }

    /// Parses JSON text (the form Python dictionaries take on their way in).
    pub fn from_json(text: &str) -> Result<Self> {
        let scenario = Self::parse_json(text)?;
        scenario.validate()?;
        Ok(scenario)
    }

    /// The simulation described by JSON text, parsed and validated once (batch runs).
    pub fn config_from_json(text: &str) -> Result<SimulationConfig> {
        Self::parse_json(text)?.to_config()
    }

    fn parse_json(text: &str) -> Result<Self> {
        let mut de = serde_json::Deserializer::from_str(text);
        serde_path_to_error::deserialize(&mut de).map_err(|e| {
            let key = e.path().to_string();
            let message = e.into_inner().to_string();
            // serde_json appends the position in the JSON text, meaningless for a dictionary.
            let message = message.split(" at line ").next().unwrap_or_default().to_string();
            scenario_error(&key, message)
        })
    }

    /// The scenario as JSON text.
    pub fn to_json(&self) -> Result<String> {
        serde_json::to_string(self).map_err(|e| scenario_error("", e.to_string()))
    }

    /// The scenario as TOML text.
    pub fn to_toml(&self) -> Result<String> {
        toml::to_string(self).map_err(|e| scenario_error("", e.to_string()))
    }

    /// Checks everything that the schema alone cannot: counts, signs, that the object is in
    /// front of the reference camera and of the start pose.
    pub fn validate(&self) -> Result<()> {
        self.to_config().map(|_| ())
    }

    /// The simulation this scenario describes.
    pub fn to_config(&self) -> Result<SimulationConfig> {
        let points = &self.object.points;
        let min_points = match self.control.law {
            LawName::Invariant => crate::jacobian::MIN_POINTS,
            LawName::Ibvs => crate::ibvs::IBVS_MIN_POINTS,
            LawName::None => 3,
        };
        if points.len() < min_points {
            return Err(scenario_error(
                "object.points",
                format!("{} points given, at least {min_points} needed", points.len()),
            ));
        }
        if let Some(i) = points.iter().position(|p| p.iter().any(|v| !v.is_finite())) {
            return Err(scenario_error(&format!("object.points[{i}]"), "non-finite coordinate"));
        }
        if let Some(b) = self.object.basis {
            crate::invariant::validate_basis(b, points.len())
                .map_err(|e| scenario_error("object.basis", e.to_string()))?;
        }
        let bodies = self
            .object
            .bodies
            .iter()
            .map(|b| match *b {
                BodySpec::Cuboid { half_extents, position, rotation } => {
                    Body::Cuboid { half_extents, pose: pose_of(position, rotation) }
                }
                BodySpec::Ball { radius, position } => Body::Ball { radius, center: position },
                BodySpec::Cylinder { half_height, radius, position, rotation } => {
                    Body::Cylinder { half_height, radius, pose: pose_of(position, rotation) }
                }
            })
            .collect();
        let scene = Scene::new(points.clone(), bodies).map_err(|e| scenario_error("object.bodies", e.to_string()))?;

        if self.reference_camera.zoom.is_some() {
            return Err(scenario_error("reference_camera.zoom", "the reference image is taken with one camera"));
        }
        let reference_camera = self.reference_camera.model("reference_camera")?;
        if let Some(i) = points.iter().position(|p| p[2] <= crate::scene::MIN_DEPTH) {
            return Err(scenario_error(
                &format!("object.points[{i}]"),
                format!("the object is behind the reference camera (z = {} m in F*)", points[i][2]),
            ));
        }
        let camera = match &self.camera {
            Some(c) => c.model("camera")?,
            None => reference_camera.clone(),
        };
        let estimate = match &self.estimate {
            Some(e) if e.zoom.is_some() => return Err(scenario_error("estimate.zoom", "K_hat is one fixed estimate")),
            Some(e) => e.intrinsics("estimate")?,
            None => camera.at(0.0).map_err(|e| scenario_error("camera", e.to_string()))?,
        };
        if let Some(i) = self.start.position.iter().chain(&self.start.rotation).position(|v| !v.is_finite()) {
            return Err(scenario_error("start", format!("non-finite value at index {i}")));
        }
        let start = pose_of(self.start.position, self.start.rotation);
        let inv = start.inverse();
        if let Some(i) = points.iter().position(|p| (inv * nalgebra::Point3::from(*p)).z <= crate::scene::MIN_DEPTH) {
            return Err(scenario_error("start", format!("object point {i} is behind the camera at the start pose")));
        }
        let c = &self.control;
        for (key, v) in [("control.gain", c.gain), ("control.gain_rz", c.gain_rz), ("control.dt", c.dt)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(scenario_error(key, format!("must be finite and > 0, got {v}")));
            }
        }
        let law = match c.law {
            LawName::Invariant => Law::Invariant(InvariantControllerConfig {
                gain: c.gain,
                gain_rz: c.gain_rz,
                feedforward: c.feedforward,
                ..Default::default()
            }),
            LawName::None => Law::Observe,
            LawName::Ibvs => Law::Ibvs {
                gain: c.gain,
                interaction: c
                    .interaction
                    .parse()
                    .map_err(|e: Error| scenario_error("control.interaction", e.to_string()))?,
            },
        };
        let depths = match c.depths {
            DepthsName::True => DepthSource::True,
            DepthsName::Reference => DepthSource::Reference,
            DepthsName::Estimated => {
                let d = self.depth_estimation.as_ref().ok_or_else(|| {
                    scenario_error("control.depths", "\"estimated\" needs a [depth_estimation] section")
                })?;
                if d.camera.zoom.is_some() || d.camera.width.is_some() || d.camera.height.is_some() {
                    return Err(scenario_error("depth_estimation.camera", "takes fku, fkv, u0, v0 and skew_deg only"));
                }
                let values = d.position.iter().chain(&d.rotation).chain(&d.translation);
                if values.clone().any(|v| !v.is_finite()) {
                    return Err(scenario_error("depth_estimation", "non-finite position, rotation or translation"));
                }
                if !(d.reference_mean_depth.is_finite() && d.reference_mean_depth > 0.0) {
                    return Err(scenario_error("depth_estimation.reference_mean_depth", "must be finite and > 0"));
                }
                if d.translation.iter().all(|&v| v == 0.0) {
                    return Err(scenario_error("depth_estimation.translation", "must not be zero"));
                }
                DepthSource::Estimated(std::sync::Arc::new(TranslationPairDepths {
                    camera: d.camera.intrinsics("depth_estimation.camera")?,
                    first_pose: pose_of(d.position, d.rotation),
                    translation: Vector3::from(d.translation),
                    reference_mean_depth: d.reference_mean_depth,
                }))
            }
        };
        if self.depth_estimation.is_some() && c.depths != DepthsName::Estimated {
            return Err(scenario_error("depth_estimation", "is used only with control.depths = \"estimated\""));
        }
        let path_samples = match &self.path {
            Some(p) if p.samples == 0 => return Err(scenario_error("path.samples", "must be >= 1")),
            Some(_) if c.law != LawName::Invariant => {
                return Err(scenario_error("path", "path planning drives the invariant law only"));
            }
            Some(p) => Some(p.samples),
            None => None,
        };
        let robot = match self.robot.kind {
            RobotKind::Free => {
                if self.robot.joint_min.is_some()
                    || self.robot.joint_max.is_some()
                    || self.robot.joint_velocity.is_some()
                {
                    return Err(scenario_error("robot", "joint limits apply to kind = \"cartesian\" only"));
                }
                Robot::FreeFlying
            }
            RobotKind::Cartesian => {
                let d = JointLimits::default();
                let conv = |v: [f64; 6]| [v[0], v[1], v[2], v[3].to_radians(), v[4].to_radians(), v[5].to_radians()];
                let limits = JointLimits {
                    min: self.robot.joint_min.map_or(d.min, conv),
                    max: self.robot.joint_max.map_or(d.max, conv),
                    velocity: self.robot.joint_velocity.map_or(d.velocity, conv),
                };
                limits.validate().map_err(|e| scenario_error("robot", e.to_string()))?;
                let robot = Robot::Cartesian(limits);
                // The start must be reachable; the goal need not be (the run then ends at the
                // limits, which is worth simulating).
                robot.check_reachable(&start).map_err(|e| scenario_error("start", e.to_string()))?;
                robot
            }
        };
        let n = &self.noise;
        if !(n.pixel_sigma.is_finite() && n.pixel_sigma >= 0.0) {
            return Err(scenario_error("noise.pixel_sigma", "must be finite and >= 0"));
        }
        let s = &self.stop;
        if s.max_iterations == 0 || s.window == 0 {
            return Err(scenario_error("stop", "max_iterations and window must be >= 1"));
        }
        for (key, v) in [
            ("stop.pixel_error", s.pixel_error),
            ("stop.invariant_error", s.invariant_error),
            ("stop.tau21", s.tau21),
            ("stop.divergence_distance", s.divergence_distance),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(scenario_error(key, format!("must be finite and > 0, got {v}")));
            }
        }
        Ok(SimulationConfig {
            scene,
            basis: self.object.basis,
            reference_camera,
            camera,
            estimate,
            start,
            robot,
            law,
            depths,
            dt: c.dt,
            noise: *n,
            stop: *s,
            path_samples,
            record: true,
        })
    }
}

/// The built-in scenarios: (name, TOML text).
pub const BUILTIN: &[(&str, &str)] = &[
    ("zoom-stationary", include_str!("../scenarios/zoom-stationary.toml")),
    ("lens-12-12", include_str!("../scenarios/lens-12-12.toml")),
    ("lens-12-6", include_str!("../scenarios/lens-12-6.toml")),
    ("lens-25-12", include_str!("../scenarios/lens-25-12.toml")),
    ("lens-6-12", include_str!("../scenarios/lens-6-12.toml")),
    ("ibvs-12-12", include_str!("../scenarios/ibvs-12-12.toml")),
    ("ibvs-12-6", include_str!("../scenarios/ibvs-12-6.toml")),
    ("ibvs-25-12", include_str!("../scenarios/ibvs-25-12.toml")),
    ("ibvs-6-12", include_str!("../scenarios/ibvs-6-12.toml")),
    ("zoom-servo", include_str!("../scenarios/zoom-servo.toml")),
    ("path-500", include_str!("../scenarios/path-500.toml")),
    ("path-3000", include_str!("../scenarios/path-3000.toml")),
    ("path-500-feedforward", include_str!("../scenarios/path-500-feedforward.toml")),
    ("noise-12-6", include_str!("../scenarios/noise-12-6.toml")),
    ("cartesian-12-6", include_str!("../scenarios/cartesian-12-6.toml")),
    ("occlusion", include_str!("../scenarios/occlusion.toml")),
    ("planar", include_str!("../scenarios/planar.toml")),
];

/// A built-in scenario by name (parsed once, then cloned).
pub fn builtin(name: &str) -> Result<Scenario> {
    static PARSED: std::sync::OnceLock<Vec<Result<Scenario>>> = std::sync::OnceLock::new();
    let parsed = PARSED.get_or_init(|| BUILTIN.iter().map(|(_, text)| Scenario::from_toml(text)).collect());
    match BUILTIN.iter().position(|(n, _)| *n == name) {
        Some(i) => parsed[i].clone(),
        None => {
            let names: Vec<&str> = BUILTIN.iter().map(|(n, _)| *n).collect();
            Err(scenario_error("", format!("no built-in scenario {name:?}; known: {}", names.join(", "))))
        }
    }
}
