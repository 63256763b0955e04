//! Robots carrying the camera on their end-effector, behind one interface
//! ([`CameraRobot`]): a free-flying camera, a six-axis Cartesian robot like the paper's AFMA
//! with joint limits, and a serial arm from URDF ([`ArmRobot`]). The robot base frame is
//! F*; a robot takes a camera twist and returns the new pose, joints and events.

mod cartesian;
mod free_flying;

use std::sync::Arc;

use nalgebra::{Isometry3, Vector6};

use crate::error::Short;
use crate::sim::arm::ArmRobot;
use crate::sim::error::Result;

pub use self::cartesian::{
    CartesianRobot, JointLimits, cartesian_joint_velocities, cartesian_joints, cartesian_pose, cartesian_twist,
};
pub use self::free_flying::FreeFlying;

/// A robot that carries the camera: one period under a camera twist at a time.
pub trait CameraRobot: Send + Sync + std::fmt::Debug {
    /// Number of joints.
    fn dof(&self) -> usize;
    /// The joint positions at the start pose and, where the robot has one, its
    /// manipulability there; fails when the robot cannot start there.
    fn start(&self, pose: &Isometry3<f64>) -> Result<(Vec<f64>, Option<f64>)>;
    /// Moves from `pose` (with `joints`, the robot's state) under `twist` (camera frame) for
    /// `dt` seconds.
    fn step(&self, pose: &Isometry3<f64>, joints: &[f64], twist: &Vector6<f64>, dt: f64) -> Result<RobotMotion>;
}

/// What one robot step did.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotMotion {
    /// New camera pose in F*.
    pub pose: Isometry3<f64>,
    /// New joint positions.
    pub joints: Vec<f64>,
    /// The twist actually executed (after saturation), camera frame.
    pub twist: Vector6<f64>,
    /// Joint velocities applied (after saturation), for a robot that reports them.
    pub joint_velocities: Option<Vec<f64>>,
    /// Manipulability at the new joints, for a robot that has one.
    pub manipulability: Option<f64>,
    /// Whether a velocity or position limit changed the motion.
    pub limited: bool,
    /// Set when the motion must end the run (once the image it leads to is recorded).
    pub event: Option<RobotEvent>,
}

impl RobotMotion {
    /// A motion without joint velocities, manipulability or event.
    pub fn moved(pose: Isometry3<f64>, joints: Vec<f64>, twist: Vector6<f64>, limited: bool) -> Self {
        Self { pose, joints, twist, joint_velocities: None, manipulability: None, limited, event: None }
    }
}

/// Why a robot step ends the run.
#[derive(Debug, Clone, PartialEq)]
pub enum RobotEvent {
    /// A joint would have left its limits: it was clamped there.
    JointLimit {
        /// The joint's name.
        joint: String,
        /// Where integration would have taken it.
        value: f64,
        /// The limit it stopped at.
        bound: f64,
    },
    /// The manipulability fell below the threshold.
    Singular {
        /// The manipulability reached.
        manipulability: f64,
    },
}

impl RobotEvent {
    /// The reason, in words.
    pub fn message(&self) -> String {
        match self {
            RobotEvent::JointLimit { joint, value, bound } => {
                format!(
                    "joint {joint} would reach {}, beyond its limit {}: stopped there",
                    Short(*value),
                    Short(*bound)
                )
            }
            RobotEvent::Singular { manipulability } => {
                format!("manipulability {manipulability:.3e} below robot.min_manipulability: near a singularity")
            }
        }
    }
}

/// The robot a scenario chooses.
#[derive(Debug, Clone, PartialEq)]
pub enum Robot {
    /// A camera that follows any twist exactly.
    FreeFlying,
    /// A Cartesian robot with a three-axis wrist and joint limits.
    Cartesian(CartesianRobot),
    /// A serial arm whose joint positions are its state.
    Arm(Arc<ArmRobot>),
}

impl Robot {
    /// The robot behind the one interface.
    pub fn as_robot(&self) -> &dyn CameraRobot {
        match self {
            Robot::FreeFlying => &FreeFlying,
            Robot::Cartesian(robot) => robot,
            Robot::Arm(arm) => arm.as_ref(),
        }
    }

    /// Checks that the robot can start at a pose (inside its limits; for an arm, the pose is
    /// the camera pose at its start joints).
    pub fn check_reachable(&self, pose: &Isometry3<f64>) -> Result<()> {
        self.as_robot().start(pose).map(|_| ())
    }
}
