//! `[robot] kind = "urdf"`: the model, the mount, the base, the start joints (given, or
//! solved from the camera's start pose by inverse kinematics) and the limits, each checked
//! with an error naming its key.

use std::sync::Arc;

use super::{check_values, pose_of};
use crate::error::Error;
use crate::sim::arm::{ArmModel, ArmRobot, BUILTIN_ARMS, JointKind};
use crate::sim::error::{Result, SimError};
use crate::sim::robot::Robot;
use crate::sim::scenario::schema::{EyeToHandSpec, PoseSpec, RobotKind, RobotSpec, StartSpec};
use crate::sim::scenario::{FileScope, scenario_error};

/// The arm of `[robot]`, placed by `robot.joints` or by the camera's pose `start`; `files`
/// resolves a URDF path.
pub(super) fn robot(r: &RobotSpec, start: Option<&StartSpec>, files: FileScope<'_>) -> Result<Robot> {
    let model = model(r, files)?;
    let units = Units::of(&model);
    let n = model.dof();
    let joints = match (&r.joints, start, &r.ik_seed) {
        (Some(_), Some(_), _) => return Err(scenario_error("start", BOTH_GIVEN)),
        (Some(_), None, Some(_)) => {
            return Err(scenario_error("robot.ik_seed", "applies when [start] places the arm, not with robot.joints"));
        }
        (Some(joints), None, None) => units.convert("robot.joints", joints, n, &model)?,
        (None, Some(_), _) => vec![0.0; n], // solved below, once the limits are final
        (None, None, _) => return Err(scenario_error("robot.joints", NEITHER_GIVEN)),
    };
    let mount = pose("robot.camera_mount", &r.camera_mount)?;
    let mut arm = ArmRobot::new(model, pose("robot.base", &r.base)?, mount, joints);
    if r.mount_error.is_some() {
        arm.believed_mount = Some(mount * pose("robot.mount_error", &r.mount_error)?);
    }
    override_limits(&mut arm, r, &units)?;
    if let Some(d) = r.damping {
        arm.damping = d;
    }
    if let Some(w) = r.min_manipulability {
        arm.min_manipulability = w;
    }
    if let Some(s) = start {
        arm.start = start_joints(&arm, s, r.ik_seed.as_deref(), &units)?;
    }
    arm.validate().map_err(|e| match e {
        SimError::Core(Error::InvalidParameter { name, reason }) if name.starts_with("robot.") => {
            scenario_error(name, reason)
        }
        other => scenario_error("robot", other.to_string()),
    })?;
    Ok(Robot::Arm(Arc::new(arm)))
}

/// The arm of `[world] eye_to_hand` as an eye-in-hand arm whose "camera" is the target's frame
/// F* in the fixed camera's frame: `base * fk(q) * target_mount`, placed by inverse kinematics
/// at the inverse of the camera's start pose in F*. Errors name `world.eye_to_hand.*`.
pub(super) fn eye_to_hand(e: &EyeToHandSpec, start: Option<&StartSpec>, files: FileScope<'_>) -> Result<ArmRobot> {
    let start = start.ok_or_else(|| scenario_error("start", "missing: the camera's start pose in F*"))?;
    check_values("start.position", &start.position)?;
    check_values("start.rotation_deg", &start.rotation_deg)?;
    if let Some(c) = &e.camera_to_base {
        check_values("world.eye_to_hand.camera_to_base.position", &c.position)?;
        check_values("world.eye_to_hand.camera_to_base.rotation_deg", &c.rotation_deg)?;
    }
    let target = pose_of(start.position, start.rotation_deg).inverse();
    let (axis, angle) =
        target.rotation.axis_angle().map_or((nalgebra::Vector3::x(), 0.0), |(a, t)| (a.into_inner(), t));
    let thetau = axis * angle.to_degrees();
    let t = target.translation.vector;
    let spec = RobotSpec {
        kind: RobotKind::Urdf,
        urdf: Some(e.urdf.clone()),
        end_effector: e.end_effector.clone(),
        camera_mount: Some(e.target_mount.clone()),
        base: Some(e.base.clone()),
        ik_seed: e.ik_seed.clone(),
        ..RobotSpec::default()
    };
    let at = StartSpec { position: [t.x, t.y, t.z], rotation_deg: [thetau.x, thetau.y, thetau.z] };
    match robot(&spec, Some(&at), files) {
        Ok(Robot::Arm(arm)) => Ok((*arm).clone()),
        Ok(_) => Err(scenario_error("world.eye_to_hand", "not an arm")),
        Err(SimError::Scenario { key, reason }) => {
            let key = key.to_string();
            let key = key.replacen("robot.camera_mount", "target_mount", 1).replacen("robot.", "", 1);
            Err(scenario_error(&format!("world.eye_to_hand.{key}"), reason))
        }
        Err(other) => Err(other),
    }
}

const BOTH_GIVEN: &str = "the arm is placed twice: by robot.joints and by [start] (start.position, \
     start.rotation_deg); give one (the other follows from it)";
const NEITHER_GIVEN: &str = "missing: the start joint positions, or the camera's start pose [start] \
     (start.position, start.rotation_deg) to place the arm by inverse kinematics";

/// The joints that put the camera at `start` (F*): inverse kinematics from `robot.ik_seed`
/// (or the middle of the limits) within the arm's limits and above its `min_manipulability`.
fn start_joints(arm: &ArmRobot, start: &StartSpec, seed: Option<&[f64]>, units: &Units) -> Result<Vec<f64>> {
    check_values("start.position", &start.position)?;
    check_values("start.rotation_deg", &start.rotation_deg)?;
    let seed = seed.map(|q| units.convert("robot.ik_seed", q, arm.dof(), &arm.model)).transpose()?;
    let camera = pose_of(start.position, start.rotation_deg);
    let solution = arm.ik_camera(&camera, seed.as_deref()).map_err(|e| scenario_error("start", e.to_string()))?;
    Ok(solution.joints)
}

/// `robot.urdf` (a built-in name or a file) up to `robot.end_effector`.
fn model(r: &RobotSpec, files: FileScope<'_>) -> Result<ArmModel> {
    let urdf = r.urdf.as_deref().ok_or_else(|| {
        scenario_error("robot.urdf", format!("missing: a built-in arm ({}) or a URDF file", BUILTIN_ARMS.join(", ")))
    })?;
    let loaded = match (BUILTIN_ARMS.contains(&urdf), r.end_effector.as_deref()) {
        (true, None) => ArmModel::builtin(urdf),
        (true, Some(link)) => ArmModel::builtin_with_end_effector(urdf, link),
        (false, None) => {
            return Err(scenario_error("robot.end_effector", "needed with a URDF file: the link carrying the camera"));
        }
        (false, Some(link)) => {
            let looks_like_a_path = urdf.contains(['/', '.']);
            let path = match files.resolve("robot.urdf", urdf) {
                Ok(path) => path,
                Err(e) if looks_like_a_path => return Err(e),
                Err(_) => files.directory.unwrap_or(std::path::Path::new(".")).join(urdf),
            };
            if !path.exists() {
                let reason = format!(
                    "`{urdf}` is neither a built-in arm ({}) nor a file ({} not found)",
                    BUILTIN_ARMS.join(", "),
                    path.display()
                );
                return Err(scenario_error("robot.urdf", reason));
            }
            ArmModel::from_urdf_file(&path, link)
        }
    };
    loaded.map_err(|e| {
        let message = e.to_string();
        let link_error = message.contains("no link `") || message.contains("is not on the chain");
        scenario_error(if link_error { "robot.end_effector" } else { "robot.urdf" }, message)
    })
}

/// A `{ position, rotation_deg }` table, identity when absent.
fn pose(key: &str, spec: &Option<PoseSpec>) -> Result<nalgebra::Isometry3<f64>> {
    let Some(p) = spec else { return Ok(nalgebra::Isometry3::identity()) };
    check_values(&format!("{key}.position"), &p.position)?;
    check_values(&format!("{key}.rotation_deg"), &p.rotation_deg)?;
    Ok(pose_of(p.position, p.rotation_deg))
}

/// Scenario units per joint: degrees for revolute and continuous joints, metres for
/// prismatic ones.
struct Units {
    degrees: Vec<bool>,
}

impl Units {
    fn of(model: &ArmModel) -> Self {
        Self { degrees: model.joints().iter().map(|j| j.kind() != JointKind::Prismatic).collect() }
    }

    /// Values of `key` in the crate's units (radians, metres), one per joint.
    fn convert(&self, key: &str, values: &[f64], n: usize, model: &ArmModel) -> Result<Vec<f64>> {
        if values.len() != n {
            let names = model.joint_names().join(", ");
            let reason = format!("{} values given, the arm {} has {n} joints ({names})", values.len(), model.name());
            return Err(scenario_error(key, reason));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(scenario_error(key, format!("non-finite value for {}", model.joint_names()[i])));
        }
        Ok(values.iter().zip(&self.degrees).map(|(v, &deg)| if deg { v.to_radians() } else { *v }).collect())
    }
}

/// `robot.joint_min`, `joint_max`, `joint_velocity` replace the URDF's limits.
fn override_limits(arm: &mut ArmRobot, r: &RobotSpec, units: &Units) -> Result<()> {
    let n = arm.dof();
    let model = &arm.model;
    let limits = &mut arm.limits;
    for (key, given, target) in [
        ("robot.joint_min", &r.joint_min, &mut limits.lower),
        ("robot.joint_max", &r.joint_max, &mut limits.upper),
        ("robot.joint_velocity", &r.joint_velocity, &mut limits.velocity),
    ] {
        if let Some(values) = given {
            *target = units.convert(key, values, n, model)?;
        }
    }
    let l = &arm.limits;
    if let Some(i) = (0..n).find(|&i| !(l.lower[i] < l.upper[i])) {
        return Err(scenario_error("robot.joint_max", format!("{}: must be above joint_min", model.joint_names()[i])));
    }
    if let Some(i) = (0..n).find(|&i| !(l.velocity[i] > 0.0)) {
        return Err(scenario_error("robot.joint_velocity", format!("{}: must be > 0", model.joint_names()[i])));
    }
    Ok(())
}
