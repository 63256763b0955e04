//! From a parsed scenario to a [`SimulationConfig`], one table at a time, checking what the
//! schema alone cannot (counts, signs, an object in front of the cameras) with errors that
//! name the key at fault.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

use super::schema::{BodySpec, CameraSpec, ControlSpec, DepthEstimationSpec, DepthsName, Engine, LawName, RobotKind};
use super::{FileScope, Scenario, scenario_error};
use crate::core::camera::Intrinsics;
use crate::core::distortion::Distortion;
use crate::core::ibvs::IBVS_MIN_POINTS;
use crate::core::jacobian::MIN_POINTS;
use crate::error::Short;
use crate::sim::camera_model::CameraModel;
use crate::sim::config::{Law, SimulationConfig};
use crate::sim::depth_source::{DepthSource, TranslationPairDepths};
use crate::sim::error::Result;
use crate::sim::robot::{CartesianRobot, JointLimits, Robot};
use crate::sim::scene::{Body, MIN_DEPTH, Scene};

mod arm;
mod camera;
mod tags;
mod vision_limits;

pub use vision_limits::MIN_TAG_SIDE_PIXELS;

/// A pose from a position (metres) and a theta-u rotation in degrees.
pub(super) fn pose_of(position: [f64; 3], rotation_deg: [f64; 3]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(position[0], position[1], position[2]),
        UnitQuaternion::from_scaled_axis(Vector3::from(rotation_deg.map(f64::to_radians))),
    )
}

fn check_positive(key: &str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(scenario_error(key, format!("must be finite and > 0, got {}", Short(v))))
    }
}

/// Lengths (m), angles (deg) and pixel coordinates of a scenario: finite and within +-1e6.
const MAX_MAGNITUDE: f64 = 1e6;
/// The largest image side, pixels.
const MAX_IMAGE_SIDE: f64 = 65536.0;
/// The longest run, iterations.
const MAX_ITERATIONS: usize = 10_000_000;
/// The most object points of a scenario.
pub const MAX_OBJECT_POINTS: usize = 10_000;

/// The largest `[world] latency_frames`: 1000 frames (40 s at 25 Hz).
pub const MAX_LATENCY_FRAMES: u32 = 1000;

/// Refuses more than [`MAX_OBJECT_POINTS`] object points, naming `object.points` (also
/// checked on a Python dictionary before it is written as JSON).
pub fn check_point_count(n: usize) -> Result<()> {
    if n <= MAX_OBJECT_POINTS {
        return Ok(());
    }
    let reason = format!(
        "{n} points given, at most {MAX_OBJECT_POINTS} (an iteration's work grows with them: about 40 ms at 10,000, 1.7 s at 100,000)"
    );
    Err(scenario_error("object.points", reason))
}

pub(super) fn check_values(key: &str, values: &[f64]) -> Result<()> {
    match values.iter().position(|v| !(v.abs() <= MAX_MAGNITUDE)) {
        Some(i) => Err(scenario_error(
            &format!("{key}[{i}]"),
            format!("must be finite and within +-{MAX_MAGNITUDE:e}, got {}", Short(values[i])),
        )),
        None => Ok(()),
    }
}

/// The first of `(key, given)` pairs that is given.
fn first_given<const N: usize>(keys: [(&str, bool); N]) -> Option<&str> {
    keys.into_iter().find_map(|(key, given)| given.then_some(key))
}

impl Scenario {
    /// Where the files this scenario names are resolved.
    fn files(&self) -> FileScope<'_> {
        FileScope { directory: self.directory.as_deref(), access: self.file_access }
    }

    /// Checks everything that the schema alone cannot: counts, signs, that the object is in
    /// front of the reference camera and of the start pose.
    /// Every engine's scenario is checked as the kinematic simulator reads it.
    pub fn validate(&self) -> Result<()> {
        self.check_world()?;
        if self.world.eye_to_hand.is_some() {
            self.arm()?;
        }
        self.simulation().map(|_| ())
    }

    /// The simulation this scenario describes: the kinematic simulator's (`[world] engine =
    /// "mujoco"` is refused, naming `world.engine`: that world runs in Python).
    pub fn to_config(&self) -> Result<SimulationConfig> {
        self.check_world()?;
        if self.world.engine == Engine::Mujoco {
            return Err(scenario_error(
                "world.engine",
                "\"mujoco\" is not run by the Rust simulator: run the scenario from Python \
                 (vsinv.run_scenario or the vsinv command) with the mujoco extra, pip install 'vsinv[mujoco]'",
            ));
        }
        self.simulation()
    }

    /// The arm of `[robot] kind = "urdf"` as the kinematic simulator reads it (model, base,
    /// mount, believed mount, start joints solved from `[start]` if need be, limits, damping),
    /// for a world that moves the arm itself (`vsinv.mujoco`); `None` for the other robots.
    ///
    /// With `[world] eye_to_hand`, the arm carrying the target: its "camera" is the target's
    /// frame F* (`target_mount` on the end effector) in the fixed camera's frame (`base` is
    /// in that frame), so its start joints put F* at the inverse of `[start]`.
    pub fn arm(&self) -> Result<Option<crate::sim::arm::ArmRobot>> {
        if let Some(e) = &self.world.eye_to_hand {
            return arm::eye_to_hand(e, self.start.as_ref(), self.files()).map(Some);
        }
        match self.robot()? {
            Robot::Arm(arm) => Ok(Some((*arm).clone())),
            _ => Ok(None),
        }
    }

    /// `[world]`: a latency only where a world applies it, within [`MAX_LATENCY_FRAMES`].
    fn check_world(&self) -> Result<()> {
        let w = &self.world;
        if w.latency_frames > MAX_LATENCY_FRAMES {
            let reason = format!("{} frames, more than {MAX_LATENCY_FRAMES}", w.latency_frames);
            return Err(scenario_error("world.latency_frames", reason));
        }
        if w.latency_frames > 0 && w.engine == Engine::Kinematic {
            let reason =
                "a latency is applied by the \"mujoco\" engine only (world.engine); the kinematic simulator has none";
            return Err(scenario_error("world.latency_frames", reason));
        }
        if w.supersample == 0 {
            // The largest factor is the MuJoCo world's (`vsinv.mujoco`: the supersampled side).
            return Err(scenario_error("world.supersample", "expected a positive whole number, got 0"));
        }
        if w.supersample > 1 && w.engine == Engine::Kinematic {
            let reason = "MuJoCo's images are supersampled (world.engine = \"mujoco\"); the kinematic \
                          simulator's renderer already integrates each pixel's area";
            return Err(scenario_error("world.supersample", reason));
        }
        if w.eye_to_hand.is_some() && w.engine == Engine::Kinematic {
            let reason = "a fixed camera and an arm carrying the target are simulated by the \"mujoco\" engine only";
            return Err(scenario_error("world.eye_to_hand", reason));
        }
        if w.eye_to_hand.is_some() && self.robot.kind != RobotKind::Free {
            let reason = "the camera is fixed: [robot] must be the free camera (the arm is world.eye_to_hand's)";
            return Err(scenario_error("world.eye_to_hand", reason));
        }
        if w.engine == Engine::Mujoco { self.check_mujoco() } else { Ok(()) }
    }

    /// What the `mujoco` engine's loop (a free camera, or a built-in arm or a URDF arm with
    /// inertials, with mass, servoed through MuJoCo's pinhole renders with the reference depths) does not do is refused by its key, rather than ignored.
    fn check_mujoco(&self) -> Result<()> {
        let refuse = |key: &str, what: &str| {
            Err(scenario_error(key, format!("{what} is not simulated by the \"mujoco\" engine (world.engine)")))
        };
        let distorted = |c: &CameraSpec| c.distortion.is_some() || c.calibration.is_some();
        if self.robot.kind == RobotKind::Cartesian {
            return refuse("robot.kind", "a Cartesian robot (a free camera or a built-in arm are)");
        }
        if self.control.depths.is_some_and(|d| d != DepthsName::Reference) {
            return refuse("control.depths", "depths other than \"reference\"");
        }
        if self.noise.pixel_sigma > 0.0 {
            return refuse("noise.pixel_sigma", "pixel noise (its images carry their own)");
        }
        if self.path.is_some() {
            return refuse("path", "a planned path");
        }
        if distorted(&self.reference_camera) || self.camera.as_ref().is_some_and(distorted) {
            return refuse("camera.distortion", "a lens distortion or a calibration file (MuJoCo renders a pinhole)");
        }
        Ok(())
    }

    /// The kinematic simulation of the scenario, whatever its engine.
    fn simulation(&self) -> Result<SimulationConfig> {
        // The law first: it decides which `[control]` keys are read, and how many points.
        super::law_keys::check_law_keys(&self.control)?;
        let scene = self.scene()?;
        let (reference_camera, camera, estimate, estimate_distortion) = self.cameras()?;
        let robot = self.robot()?;
        let start = self.start_pose(&robot)?;
        let c = &self.control;
        self.check_numbers()?;
        let vision = self.vision_config(&reference_camera, &camera)?;
        Ok(SimulationConfig {
            scene,
            basis: self.object.basis,
            reference_camera,
            camera,
            estimate,
            estimate_distortion,
            start,
            robot,
            law: law_of(c)?,
            depths: self.depth_source()?,
            dt: c.dt,
            noise: self.noise,
            stop: self.stop,
            path: self.path_plan()?,
            vision,
            record: true,
            record_bytes: crate::sim::MAX_RECORD_BYTES,
        })
    }

    /// The object's points: `object.points`, or the corners of its tags.
    fn object_points(&self) -> Result<(Vec<[f64; 3]>, Option<crate::vision::TagRig>)> {
        let rig = self.object.tag_rig()?;
        let points = match &rig {
            Some(tags) => tags.tags().iter().flat_map(|t| t.corners()).collect(),
            None => self.object.points.clone(),
        };
        Ok((points, rig))
    }

    /// `[object]`: enough finite points (or tags), a valid basis, valid bodies.
    fn scene(&self) -> Result<Scene> {
        let (points, rig) = self.object_points()?;
        let points = &points;
        // A point of a tag rig is a tag's corner.
        let point_key = |i: usize| match rig {
            Some(_) => format!("object.tags[{}]", i / 4),
            None => format!("object.points[{i}]"),
        };
        let min_points = match self.control.law {
            LawName::Invariant => MIN_POINTS,
            LawName::Ibvs => IBVS_MIN_POINTS,
            LawName::None => 3,
        };
        if points.len() < min_points {
            let reason = format!("{} points given, at least {min_points} needed", points.len());
            let key = if rig.is_some() { "object.tags" } else { "object.points" };
            return Err(scenario_error(key, reason));
        }
        check_point_count(points.len())?;
        if let Some(i) = points.iter().position(|p| p.iter().any(|v| !v.is_finite())) {
            return Err(scenario_error(&point_key(i), "non-finite coordinate"));
        }
        if let Some(i) = points.iter().position(|p| p[2] <= MIN_DEPTH) {
            let reason = format!("the object is behind the reference camera (z = {} m in F*)", Short(points[i][2]));
            return Err(scenario_error(&point_key(i), reason));
        }
        if let Some(b) = self.object.basis {
            crate::core::invariant::validate_basis(b, points.len())
                .map_err(|e| scenario_error("object.basis", e.to_string()))?;
        }
        let bodies = self.object.bodies.iter().map(body_of).collect();
        let scene = Scene::new(points.clone(), bodies).map_err(|e| scenario_error("object.bodies", e.to_string()))?;
        if let Some(tags) = rig {
            return scene.with_tags(tags).map_err(|e| scenario_error("object.tags", e.to_string()));
        }
        match &self.object.normals {
            Some(normals) => {
                scene.with_normals(normals.clone()).map_err(|e| scenario_error("object.normals", e.to_string()))
            }
            None => Ok(scene),
        }
    }

    /// `[reference_camera]`, `[camera]`, `[estimate]`: K*, K(t), K_hat and the distortion
    /// the controller removes (the servo camera's unless `[estimate]` gives its own).
    fn cameras(&self) -> Result<(CameraModel, CameraModel, Intrinsics, Distortion)> {
        if self.reference_camera.zoom.is_some() {
            return Err(scenario_error("reference_camera.zoom", "the reference image is taken with one camera"));
        }
        let dir = self.files();
        let reference_camera = self.reference_camera.model("reference_camera", dir)?;
        let camera = match &self.camera {
            Some(c) => c.model("camera", dir)?,
            None => reference_camera.clone(),
        };
        let (estimate, distortion) = match &self.estimate {
            Some(e) if e.zoom.is_some() => return Err(scenario_error("estimate.zoom", "K_hat is one fixed estimate")),
            Some(e) => {
                let lens = e.lens("estimate", dir)?;
                let own = e.distortion.is_some() || e.calibration.is_some();
                (lens.intrinsics, if own { lens.distortion } else { camera.distortion })
            }
            None => (camera.at(0.0).map_err(|e| scenario_error("camera", e.to_string()))?, camera.distortion),
        };
        Ok((reference_camera, camera, estimate, distortion))
    }

    /// `[start]` (or an arm's camera pose at its start joints): a finite pose with the whole
    /// object in front of the camera, reachable by the robot.
    fn start_pose(&self, robot: &Robot) -> Result<Isometry3<f64>> {
        let given = match &self.start {
            Some(s) => {
                check_values("start.position", &s.position)?;
                check_values("start.rotation_deg", &s.rotation_deg)?;
                Some(pose_of(s.position, s.rotation_deg))
            }
            None => None,
        };
        let start = match (robot, given) {
            (Robot::Arm(arm), given) => arm_start(arm, given)?,
            (_, Some(start)) => start,
            (_, None) => {
                return Err(scenario_error("start", "missing (only an arm's start may follow from robot.joints)"));
            }
        };
        let inv = start.inverse();
        if let Some(i) = self.object_points()?.0.iter().position(|p| (inv * Point3::from(*p)).z <= MIN_DEPTH) {
            let from = if matches!(robot, Robot::Arm(_)) {
                " (robot.base * FK(start joints) * robot.camera_mount)"
            } else {
                ""
            };
            return Err(scenario_error(
                "start",
                format!("object point {i} is behind the camera at the start pose{from}"),
            ));
        }
        // The start must be reachable; the goal need not be (the run then ends at the
        // limits, which is worth simulating).
        robot.check_reachable(&start).map_err(|e| scenario_error("start", e.to_string()))?;
        Ok(start)
    }

    /// `[control]` options and period, `[noise]` and `[stop]`.
    fn check_numbers(&self) -> Result<()> {
        let c = &self.control;
        c.law_options()?;
        check_positive("control.dt", c.dt)?;
        if c.dt > 1.0 {
            return Err(scenario_error(
                "control.dt",
                format!("a control period of at most 1 s, got {} s", Short(c.dt)),
            ));
        }
        if !(self.noise.pixel_sigma >= 0.0 && self.noise.pixel_sigma <= 1000.0) {
            return Err(scenario_error(
                "noise.pixel_sigma",
                format!("pixels, from 0 to 1000, got {}", Short(self.noise.pixel_sigma)),
            ));
        }
        let s = &self.stop;
        for (key, v) in [("stop.max_iterations", s.max_iterations), ("stop.window", s.window)] {
            if v == 0 || v > MAX_ITERATIONS {
                return Err(scenario_error(key, format!("from 1 to {MAX_ITERATIONS}, got {v}")));
            }
        }
        for (key, v) in [
            ("stop.pixel_error", s.pixel_error),
            ("stop.invariant_error", s.invariant_error),
            ("stop.tau21", s.tau21),
            ("stop.divergence_distance", s.divergence_distance),
            ("stop.max_translation_uncertainty", s.max_translation_uncertainty),
            ("stop.max_rotation_uncertainty_deg", s.max_rotation_uncertainty_deg),
        ] {
            check_positive(key, v)?;
        }
        if s.stall_window < 4 || s.stall_window > MAX_ITERATIONS {
            return Err(scenario_error(
                "stop.stall_window",
                format!("from 4 to {MAX_ITERATIONS}, got {}", s.stall_window),
            ));
        }
        if !(s.stall_motion > 0.0 && s.stall_motion <= 1.0) {
            return Err(scenario_error(
                "stop.stall_motion",
                format!("a fraction of the pose tolerance in (0, 1], got {}", Short(s.stall_motion)),
            ));
        }
        if let Some(sigma) = s.reference_pixel_sigma
            && !(0.0..=1000.0).contains(&sigma)
        {
            return Err(scenario_error(
                "stop.reference_pixel_sigma",
                format!("pixels, from 0 to 1000, got {}", Short(sigma)),
            ));
        }
        Ok(())
    }

    /// `control.depths` and `[depth_estimation]`.
    fn depth_source(&self) -> Result<DepthSource> {
        let depths = self.control.depths();
        if self.depth_estimation.is_some() && depths != DepthsName::Estimated {
            return Err(scenario_error("depth_estimation", "is used only with control.depths = \"estimated\""));
        }
        Ok(match depths {
            DepthsName::True => DepthSource::True,
            DepthsName::Reference => DepthSource::Reference,
            DepthsName::Estimated => {
                let d = self.depth_estimation.as_ref().ok_or_else(|| {
                    scenario_error("control.depths", "\"estimated\" needs a [depth_estimation] section")
                })?;
                DepthSource::Estimated(std::sync::Arc::new(translation_pair(d)?))
            }
        })
    }

    /// `[path]`: drives the invariant law only.
    fn path_plan(&self) -> Result<Option<crate::sim::config::PathPlan>> {
        match self.path {
            Some(p) if p.samples == 0 => Err(scenario_error("path.samples", "must be >= 1")),
            Some(_) if self.control.law != LawName::Invariant => {
                Err(scenario_error("path", "path planning drives the invariant law only"))
            }
            other => Ok(other),
        }
    }

    /// `[vision]`: valid values, image sizes for both cameras, no coordinate noise on top.
    fn vision_config(
        &self,
        reference: &CameraModel,
        camera: &CameraModel,
    ) -> Result<Option<crate::vision::RenderConfig>> {
        let Some(v) = self.vision else { return Ok(None) };
        v.validate().map_err(|e| scenario_error("vision", e.to_string()))?;
        let tables =
            [("reference_camera", Some(&self.reference_camera), reference), ("camera", self.camera.as_ref(), camera)];
        for (key, spec, model) in tables {
            if model.image.is_some() {
                continue;
            }
            if spec.is_some_and(|c| c.calibration.is_some()) {
                let reason = "the file has no image_width and image_height, which [vision] needs (images are rendered at that size)";
                return Err(scenario_error(&format!("{key}.calibration"), reason));
            }
            return Err(scenario_error("vision", "images need width and height in the camera tables"));
        }
        if self.noise.pixel_sigma > 0.0 {
            return Err(scenario_error(
                "noise.pixel_sigma",
                "with [vision] the noise is in the images (vision.noise_sigma)",
            ));
        }
        let camera_key = if self.camera.is_some() { "camera" } else { "reference_camera" };
        vision_limits::check_image_pixels("reference_camera", reference)?;
        vision_limits::check_image_pixels(camera_key, camera)?;
        if let (_, Some(rig)) = self.object_points()? {
            let k = reference.at(0.0).map_err(|e| scenario_error("reference_camera", e.to_string()))?;
            vision_limits::check_tags_readable(&rig, &k)?;
        }
        Ok(Some(v))
    }

    /// `[robot]`: joint values are metres for x, y, z and degrees for the wrist of the
    /// Cartesian robot; degrees (revolute) or metres (prismatic) for an arm.
    fn robot(&self) -> Result<Robot> {
        let r = &self.robot;
        let arm_key = [
            ("robot.urdf", r.urdf.is_some()),
            ("robot.end_effector", r.end_effector.is_some()),
            ("robot.camera_mount", r.camera_mount.is_some()),
            ("robot.mount_error", r.mount_error.is_some()),
            ("robot.base", r.base.is_some()),
            ("robot.joints", r.joints.is_some()),
            ("robot.ik_seed", r.ik_seed.is_some()),
            ("robot.min_manipulability", r.min_manipulability.is_some()),
            ("robot.damping", r.damping.is_some()),
        ];
        match (r.kind, first_given(arm_key)) {
            (RobotKind::Urdf, _) => arm::robot(r, self.start.as_ref(), self.files()),
            (_, Some(key)) => Err(scenario_error(key, "applies to kind = \"urdf\" only")),
            (RobotKind::Free, None) => {
                if r.joint_min.is_some() || r.joint_max.is_some() || r.joint_velocity.is_some() {
                    return Err(scenario_error("robot", "joint limits apply to kind = \"cartesian\" or \"urdf\" only"));
                }
                Ok(Robot::FreeFlying)
            }
            (RobotKind::Cartesian, None) => cartesian(r),
        }
    }
}

/// The Cartesian robot's limits: x, y, z in metres, the wrist in degrees.
fn cartesian(r: &super::schema::RobotSpec) -> Result<Robot> {
    let d = JointLimits::default();
    let six = |key: &str, v: &Option<Vec<f64>>, default: [f64; 6]| -> Result<[f64; 6]> {
        let Some(v) = v else { return Ok(default) };
        let v: [f64; 6] = v
            .as_slice()
            .try_into()
            .map_err(|_| scenario_error(key, format!("the Cartesian robot has 6 joints, {} values given", v.len())))?;
        Ok([v[0], v[1], v[2], v[3].to_radians(), v[4].to_radians(), v[5].to_radians()])
    };
    let limits = JointLimits {
        min: six("robot.joint_min", &r.joint_min, d.min)?,
        max: six("robot.joint_max", &r.joint_max, d.max)?,
        velocity: six("robot.joint_velocity", &r.joint_velocity, d.velocity)?,
    };
    limits.validate().map_err(|e| scenario_error("robot", e.to_string()))?;
    Ok(Robot::Cartesian(CartesianRobot { limits }))
}

/// An arm's start pose: the camera pose at its start joints (given as `robot.joints`, or
/// solved from `[start]` by inverse kinematics, which must then agree with it).
fn arm_start(arm: &crate::sim::arm::ArmRobot, given: Option<Isometry3<f64>>) -> Result<Isometry3<f64>> {
    let start = arm.camera_pose(&arm.start).map_err(|e| scenario_error("robot.joints", e.to_string()))?;
    if let Some(given) = given {
        let (dt, dr) = crate::core::se3::pose_error(&start, &given);
        if dt > 1e-6 || dr > 1e-6 {
            let reason = format!(
                "the arm's camera at the start joints is {:.3e} mm and {:.3e} degrees away from [start]",
                dt * 1e3,
                dr.to_degrees()
            );
            return Err(scenario_error("start", reason));
        }
    }
    Ok(start)
}

fn body_of(b: &BodySpec) -> Body {
    match *b {
        BodySpec::Cuboid { half_extents, position, rotation_deg } => {
            Body::Cuboid { half_extents, pose: pose_of(position, rotation_deg) }
        }
        BodySpec::Ball { radius, position } => Body::Ball { radius, center: position },
        BodySpec::Cylinder { half_height, radius, position, rotation_deg } => {
            Body::Cylinder { half_height, radius, pose: pose_of(position, rotation_deg) }
        }
    }
}

/// The law and its options (each checked against the servo layer's table, errors naming
/// the scenario key).
fn law_of(c: &ControlSpec) -> Result<Law> {
    let options = c.law_options()?;
    Law::from_options(c.law.name(), &options).map_err(|e| scenario_error("control", e.to_string()))
}

/// `[depth_estimation]`: the pure-translation image pair of appendix A.
fn translation_pair(d: &DepthEstimationSpec) -> Result<TranslationPairDepths> {
    let c = &d.camera;
    let extra = [
        c.zoom.is_some(),
        c.width.is_some(),
        c.height.is_some(),
        c.distortion.is_some(),
        c.distortion_model.is_some(),
        c.calibration.is_some(),
    ];
    if extra.into_iter().any(|given| given) {
        return Err(scenario_error("depth_estimation.camera", "takes fku, fkv, u0, v0 and skew_deg only"));
    }
    check_values("depth_estimation.position", &d.position)?;
    check_values("depth_estimation.rotation_deg", &d.rotation_deg)?;
    check_values("depth_estimation.translation", &d.translation)?;
    if !(d.reference_mean_depth.is_finite() && d.reference_mean_depth > 0.0) {
        return Err(scenario_error("depth_estimation.reference_mean_depth", "must be finite and > 0"));
    }
    if d.translation.iter().all(|&v| v == 0.0) {
        return Err(scenario_error("depth_estimation.translation", "must not be zero"));
    }
    Ok(TranslationPairDepths {
        camera: d.camera.intrinsics("depth_estimation.camera")?,
        first_pose: pose_of(d.position, d.rotation_deg),
        translation: Vector3::from(d.translation),
        reference_mean_depth: d.reference_mean_depth,
    })
}
