//! The serial chain of an arm read from URDF: the joints from the root link to a chosen
//! end-effector link, with fixed joints folded into the next joint's origin.

use std::path::Path;

use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};

use crate::error::{Error, Short};
use crate::sim::error::{Result, SimError};

/// How an actuated joint moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointKind {
    /// Rotation about the axis (radians) between position limits.
    Revolute,
    /// Rotation about the axis (radians) without position limits.
    Continuous,
    /// Translation along the axis (metres).
    Prismatic,
}

/// One actuated joint of the chain.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmJoint {
    pub(super) name: String,
    pub(super) kind: JointKind,
    pub(super) origin: Isometry3<f64>,
    pub(super) axis: Unit<Vector3<f64>>,
    pub(super) lower: f64,
    pub(super) upper: f64,
    pub(super) velocity: f64,
}

impl ArmJoint {
    /// The URDF joint name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// How it moves.
    pub fn kind(&self) -> JointKind {
        self.kind
    }

    /// The joint frame at `q = 0` in the frame of the previous actuated joint (after its
    /// motion), or of the base link for the first joint; fixed joints in between are folded in.
    pub fn origin(&self) -> &Isometry3<f64> {
        &self.origin
    }

    /// The unit axis, in the joint frame.
    pub fn axis(&self) -> &Unit<Vector3<f64>> {
        &self.axis
    }

    /// Position limits `(lower, upper)`; infinite for a continuous joint.
    pub fn position_limits(&self) -> (f64, f64) {
        (self.lower, self.upper)
    }

    /// Largest speed (rad/s or m/s), > 0; infinite when the URDF gives none.
    pub fn velocity_limit(&self) -> f64 {
        self.velocity
    }

    /// The joint's motion at position `q`.
    pub(super) fn motion(&self, q: f64) -> Isometry3<f64> {
        match self.kind {
            JointKind::Prismatic => {
                Isometry3::from_parts(Translation3::from(self.axis.into_inner() * q), UnitQuaternion::identity())
            }
            _ => Isometry3::from_parts(Translation3::identity(), UnitQuaternion::from_axis_angle(&self.axis, q)),
        }
    }
}

/// A link of the chain: its pose is the product of the first `joints` joint transforms
/// followed by `offset`.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct ChainLink {
    pub(super) name: String,
    pub(super) joints: usize,
    pub(super) offset: Isometry3<f64>,
}

/// Joint limits of an arm, one value per actuated joint.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmLimits {
    /// Lower positions (rad or m; `-inf` for continuous joints).
    pub lower: Vec<f64>,
    /// Upper positions (rad or m; `+inf` for continuous joints).
    pub upper: Vec<f64>,
    /// Largest speeds (rad/s or m/s).
    pub velocity: Vec<f64>,
}

/// A serial arm: the chain of joints from the URDF's root link (the base frame) to an
/// end-effector link. Built from URDF text, a file, or a built-in model
/// ([`ArmModel::builtin`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ArmModel {
    pub(super) name: String,
    pub(super) source: String,
    pub(super) joints: Vec<ArmJoint>,
    pub(super) links: Vec<ChainLink>,
}

fn urdf_error(file: &str, message: String) -> SimError {
    SimError::Urdf { file: file.to_string(), message }
}

impl ArmModel {
    /// The chain from the root link to `end_effector` in URDF text.
    pub fn from_urdf_str(urdf: &str, end_effector: &str) -> Result<Self> {
        Self::parse(urdf, end_effector, "<string>")
    }

    /// The chain from the root link to `end_effector` in a URDF file: a regular file of at
    /// most [`MAX_URDF_BYTES`](crate::input_file::MAX_URDF_BYTES), UTF-8.
    pub fn from_urdf_file(path: impl AsRef<Path>, end_effector: &str) -> Result<Self> {
        let file = path.as_ref().display().to_string();
        let text = crate::input_file::read_text(path.as_ref(), crate::input_file::MAX_URDF_BYTES)
            .map_err(|e| urdf_error(&file, e))?;
        Self::parse(&text, end_effector, &file)
    }

    /// Parses URDF text; `source` labels the errors.
    pub(super) fn parse(urdf: &str, end_effector: &str, source: &str) -> Result<Self> {
        // Bounded depth and size before the recursive parser (module urdf_shape).
        super::urdf_shape::check_urdf_shape(urdf).map_err(|e| urdf_error(source, e))?;
        let robot = urdf_rs::read_from_string(urdf).map_err(|e| urdf_error(source, parse_message(&e.to_string())))?;
        let chain = chain_to(&robot, end_effector, source)?;
        let base = chain.first().map_or(end_effector, |j| j.parent.link.as_str());
        let mut joints = Vec::new();
        let mut links = vec![ChainLink { name: base.to_string(), joints: 0, offset: Isometry3::identity() }];
        let mut offset = Isometry3::identity();
        for joint in chain {
            offset *= pose(&joint.origin, source, &joint.name)?;
            if let Some(kind) = joint_kind(joint, source)? {
                joints.push(actuated(joint, kind, offset, source)?);
                offset = Isometry3::identity();
            }
            links.push(ChainLink { name: joint.child.link.clone(), joints: joints.len(), offset });
        }
        if joints.is_empty() {
            return Err(urdf_error(source, format!("no actuated joint between `{base}` and `{end_effector}`")));
        }
        Ok(Self { name: robot.name, source: source.to_string(), joints, links })
    }

    /// The robot name of the URDF.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Where the model came from: a file path, `builtin:<name>` or `<string>`.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// Number of actuated joints.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// The actuated joints, base to end-effector.
    pub fn joints(&self) -> &[ArmJoint] {
        &self.joints
    }

    /// Names of the actuated joints, base to end-effector.
    pub fn joint_names(&self) -> Vec<&str> {
        self.joints.iter().map(|j| j.name.as_str()).collect()
    }

    /// Names of the links of the chain, base link first, end-effector last.
    pub fn link_names(&self) -> Vec<&str> {
        self.links.iter().map(|l| l.name.as_str()).collect()
    }

    /// The base link (the URDF's root): the frame of [`ArmModel::fk`] and
    /// [`ArmModel::jacobian_base`].
    pub fn base_link(&self) -> &str {
        &self.links[0].name
    }

    /// The end-effector link.
    pub fn end_effector(&self) -> &str {
        &self.links[self.links.len() - 1].name
    }

    /// Position and velocity limits of the actuated joints.
    pub fn limits(&self) -> ArmLimits {
        ArmLimits {
            lower: self.joints.iter().map(|j| j.lower).collect(),
            upper: self.joints.iter().map(|j| j.upper).collect(),
            velocity: self.joints.iter().map(|j| j.velocity).collect(),
        }
    }

    /// Checks that joint positions have one finite value per joint and lie within the
    /// position limits (`Error::InvalidParameter` naming the first joint outside).
    pub fn check_limits(&self, q: &[f64]) -> Result<()> {
        self.check_joints(q)?;
        match self.joints.iter().zip(q).find(|(j, q)| !(j.lower <= **q && **q <= j.upper)) {
            Some((j, q)) => Err(Error::InvalidParameter {
                name: "joint positions",
                reason: format!(
                    "{} = {} is outside its limits [{}, {}]",
                    j.name,
                    Short(*q),
                    Short(j.lower),
                    Short(j.upper)
                ),
            }
            .into()),
            None => Ok(()),
        }
    }

    /// Checks that `q` has one finite value per actuated joint.
    pub(super) fn check_joints(&self, q: &[f64]) -> Result<()> {
        if q.len() != self.dof() {
            return Err(Error::Shape {
                what: "joint positions",
                expected: format!("{} values (one per joint of {})", self.dof(), self.name),
                got: format!("{} values", q.len()),
            }
            .into());
        }
        Ok(crate::error::check_finite("joint positions", q)?)
    }

    /// The chain link called `name`.
    pub(super) fn link(&self, name: &str) -> Result<&ChainLink> {
        Ok(self.links.iter().find(|l| l.name == name).ok_or_else(|| Error::InvalidParameter {
            name: "link",
            reason: format!("`{name}` is not on the chain {} of {}", self.link_names().join(" -> "), self.source),
        })?)
    }
}

/// The joints from the root link to `end_effector`, root first.
fn chain_to<'a>(robot: &'a urdf_rs::Robot, end_effector: &str, source: &str) -> Result<Vec<&'a urdf_rs::Joint>> {
    let known =
        robot.links.iter().any(|l| l.name == end_effector) || robot.joints.iter().any(|j| j.child.link == end_effector);
    if !known {
        let names: Vec<&str> = robot.links.iter().take(20).map(|l| l.name.as_str()).collect();
        let more = if robot.links.len() > 20 { ", ..." } else { "" };
        return Err(urdf_error(source, format!("no link `{end_effector}` (links: {}{more})", names.join(", "))));
    }
    let mut chain = Vec::new();
    let mut link = end_effector;
    while let Some(joint) = parent_joint(robot, link, source)? {
        if chain.len() == robot.joints.len() {
            return Err(urdf_error(source, format!("the joints above link `{end_effector}` form a cycle")));
        }
        chain.push(joint);
        link = &joint.parent.link;
    }
    if let Some(top) = chain.last()
        && !robot.links.iter().any(|l| l.name == top.parent.link)
    {
        let reason = format!(
            "joint `{}` has the parent link `{}`, which is not defined (no <link name=\"{}\">)",
            top.name, top.parent.link, top.parent.link
        );
        return Err(urdf_error(source, reason));
    }
    chain.reverse();
    Ok(chain)
}

/// The parser's error in at most one line of 160 characters, with every bracketed or quoted
/// part (`[...]`, `"..."`, `'...'`, `` `...` ``) elided: urdf-rs quotes the attribute text at
/// fault, which must not carry a file's contents into the error.
fn parse_message(message: &str) -> String {
    let line = message.lines().next().unwrap_or_default();
    let mut out = String::new();
    let mut closing: Option<char> = None;
    for c in line.chars() {
        match closing {
            Some(end) if c == end => {
                out.push(end);
                closing = None;
            }
            Some(_) => {}
            None => {
                out.push(c);
                closing = match c {
                    '[' => Some(']'),
                    '"' | '\'' | '`' => Some(c),
                    _ => None,
                };
                if closing.is_some() {
                    out.push_str("...");
                }
            }
        }
    }
    let short: String = out.chars().take(160).collect();
    let cut = if short.len() < out.len() || message.lines().nth(1).is_some() { " ..." } else { "" };
    format!("not valid URDF: {}{cut}", short.escape_debug())
}

/// The joint whose child is `link`, if any.
fn parent_joint<'a>(robot: &'a urdf_rs::Robot, link: &str, source: &str) -> Result<Option<&'a urdf_rs::Joint>> {
    let mut parents = robot.joints.iter().filter(|j| j.child.link == link);
    let first = parents.next();
    if let (Some(a), Some(b)) = (first, parents.next()) {
        return Err(urdf_error(
            source,
            format!("link `{link}` is the child of two joints, `{}` and `{}`", a.name, b.name),
        ));
    }
    Ok(first)
}

/// The rigid transform of a URDF `<origin xyz rpy>`: `Trans(xyz) Rz(yaw) Ry(pitch) Rx(roll)`.
fn pose(origin: &urdf_rs::Pose, source: &str, joint: &str) -> Result<Isometry3<f64>> {
    let ([x, y, z], [r, p, w]) = (origin.xyz.0, origin.rpy.0);
    if ![x, y, z, r, p, w].iter().all(|v| v.is_finite()) {
        return Err(urdf_error(source, format!("joint `{joint}`: non-finite origin")));
    }
    Ok(Isometry3::from_parts(Translation3::new(x, y, z), UnitQuaternion::from_euler_angles(r, p, w)))
}

/// The kind of an actuated joint, `None` for a fixed one.
fn joint_kind(joint: &urdf_rs::Joint, source: &str) -> Result<Option<JointKind>> {
    use urdf_rs::JointType as T;
    let kind = match joint.joint_type {
        T::Fixed => return Ok(None),
        T::Revolute => JointKind::Revolute,
        T::Continuous => JointKind::Continuous,
        T::Prismatic => JointKind::Prismatic,
        ref other => {
            let message = format!(
                "joint `{}` is {other:?}: a serial arm has revolute, continuous, prismatic and fixed joints only",
                joint.name
            );
            return Err(urdf_error(source, message));
        }
    };
    if joint.mimic.is_some() {
        return Err(urdf_error(source, format!("joint `{}`: mimic joints are not supported", joint.name)));
    }
    Ok(Some(kind))
}

/// An actuated joint with its unit axis and checked limits.
fn actuated(joint: &urdf_rs::Joint, kind: JointKind, origin: Isometry3<f64>, source: &str) -> Result<ArmJoint> {
    let bad = |what: String| urdf_error(source, format!("joint `{}`: {what}", joint.name));
    let axis = Vector3::from(joint.axis.xyz.0);
    let axis = Unit::try_new(axis, 1e-9)
        .filter(|a| a.iter().all(|v| v.is_finite()))
        .ok_or_else(|| bad(format!("axis {:?} is not a non-zero finite vector", joint.axis.xyz.0)))?;
    let limit = &joint.limit;
    let (lower, upper, velocity) = match kind {
        // No <limit> (urdf-rs reads velocity 0) means no speed limit.
        JointKind::Continuous if limit.velocity == 0.0 => (f64::NEG_INFINITY, f64::INFINITY, f64::INFINITY),
        JointKind::Continuous => (f64::NEG_INFINITY, f64::INFINITY, limit.velocity),
        _ => (limit.lower, limit.upper, limit.velocity),
    };
    if !(lower < upper) {
        return Err(bad(format!(
            "position limits [{}, {}] are empty or missing (<limit lower upper>)",
            Short(lower),
            Short(upper)
        )));
    }
    if !(velocity > 0.0) {
        return Err(bad(format!("velocity limit {} must be > 0", Short(velocity))));
    }
    Ok(ArmJoint { name: joint.name.clone(), kind, origin, axis, lower, upper, velocity })
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    /// base -(fixed)- mount -(prismatic x)- slider -(continuous y)- wrist -(fixed)- tool.
    const MIXED: &str = r#"<robot name="mixed">
      <link name="base"/><link name="mount"/><link name="slider"/><link name="wrist"/><link name="tool"/>
      <joint name="mount_joint" type="fixed"><parent link="base"/><child link="mount"/>
        <origin xyz="0 0 0.5" rpy="0 0 1.5707963267948966"/></joint>
      <joint name="slide" type="prismatic"><parent link="mount"/><child link="slider"/>
        <origin xyz="0.1 0 0"/><axis xyz="2 0 0"/><limit lower="-0.2" upper="0.3" velocity="0.5"/></joint>
      <joint name="spin" type="continuous"><parent link="slider"/><child link="wrist"/>
        <axis xyz="0 1 0"/></joint>
      <joint name="tool_joint" type="fixed"><parent link="wrist"/><child link="tool"/>
        <origin xyz="0 0 0.2"/></joint>
    </robot>"#;

    #[test]
    fn fixed_joints_fold_into_the_chain() {
        let arm = ArmModel::from_urdf_str(MIXED, "tool").unwrap();
        assert_eq!((arm.name(), arm.dof(), arm.base_link(), arm.end_effector()), ("mixed", 2, "base", "tool"));
        assert_eq!(arm.joint_names(), ["slide", "spin"]);
        assert_eq!(arm.link_names(), ["base", "mount", "slider", "wrist", "tool"]);
        let slide = &arm.joints()[0];
        assert_eq!(slide.kind(), JointKind::Prismatic);
        assert_eq!(slide.axis().into_inner(), Vector3::x());
        // mount (0, 0, 0.5) turned by pi/2 about z, then 0.1 along the turned x.
        let p = slide.origin().translation.vector;
        assert!((p - Vector3::new(0.0, 0.1, 0.5)).norm() < 1e-15, "{p}");
        assert_eq!(arm.joints()[1].kind(), JointKind::Continuous);
        assert_eq!(arm.joints()[1].origin(), &Isometry3::identity());
        assert_eq!(arm.links[4].offset.translation.vector, Vector3::new(0.0, 0.0, 0.2));
        assert_eq!(arm.links[1].joints, 0);
    }

    #[test]
    fn continuous_joints_have_no_position_limits() {
        let arm = ArmModel::from_urdf_str(MIXED, "tool").unwrap();
        let limits = arm.limits();
        assert_eq!(limits.lower, [-0.2, f64::NEG_INFINITY]);
        assert_eq!(limits.upper, [0.3, f64::INFINITY]);
        assert_eq!(limits.velocity, [0.5, f64::INFINITY]);
        arm.check_limits(&[0.0, 100.0]).unwrap();
        assert!(arm.check_limits(&[0.31, 0.0]).unwrap_err().to_string().contains("slide"));
    }

    #[test]
    fn a_shorter_chain_stops_at_the_chosen_link() {
        let arm = ArmModel::from_urdf_str(MIXED, "slider").unwrap();
        assert_eq!(arm.dof(), 1);
        assert_eq!(arm.link_names(), ["base", "mount", "slider"]);
    }

    #[test]
    fn errors_name_the_source_and_the_joint() {
        let bad = MIXED.replace(r#"velocity="0.5""#, r#"velocity="0""#);
        let err = ArmModel::from_urdf_str(&bad, "tool").unwrap_err();
        assert_eq!(err.to_string(), "URDF <string>: joint `slide`: velocity limit 0 must be > 0");
        let two_parents = MIXED.replace(r#"<child link="wrist"/>"#, r#"<child link="slider"/>"#);
        let err = ArmModel::from_urdf_str(&two_parents, "slider").unwrap_err();
        assert!(err.to_string().contains("two joints, `slide` and `spin`"), "{err}");
    }

    /// Regression (issue 16): a joint whose parent link is not defined was taken silently as
    /// the chain's root.
    #[test]
    fn a_missing_parent_link_is_refused() {
        let orphan = MIXED.replace(r#"<link name="base"/>"#, "");
        let err = ArmModel::from_urdf_str(&orphan, "tool").unwrap_err().to_string();
        assert!(err.contains("joint `mount_joint`") && err.contains("parent link `base`"), "{err}");
    }

    /// Regression (issue 16): the parser's message quoted the attribute text of the file.
    #[test]
    fn parse_errors_do_not_quote_the_file() {
        let bad = MIXED.replace(r#"xyz="0 0 0.2""#, r#"xyz="0 SECRET-MARKER""#);
        let err = ArmModel::from_urdf_str(&bad, "tool").unwrap_err().to_string();
        assert!(err.contains("not valid URDF") && !err.contains("SECRET"), "{err}");
    }
}
