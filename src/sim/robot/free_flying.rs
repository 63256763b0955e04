//! A camera that follows any twist exactly.

use nalgebra::{Isometry3, Vector6};

use crate::core::se3::exp_twist;
use crate::error::check_finite;
use crate::sim::error::Result;
use crate::sim::robot::{CameraRobot, RobotMotion};

/// The free-flying camera: its joints are `(x, y, z, theta-u)` of the pose.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FreeFlying;

/// `(x, y, z, theta-u)` of a pose.
fn joints(pose: &Isometry3<f64>) -> Vec<f64> {
    let (t, r) = (pose.translation.vector, pose.rotation.scaled_axis());
    vec![t.x, t.y, t.z, r.x, r.y, r.z]
}

impl CameraRobot for FreeFlying {
    fn dof(&self) -> usize {
        6
    }
    fn start(&self, pose: &Isometry3<f64>) -> Result<(Vec<f64>, Option<f64>)> {
        Ok((joints(pose), None))
    }
    /// `pose * exp(twist dt)`, exactly.
    fn step(&self, pose: &Isometry3<f64>, _joints: &[f64], twist: &Vector6<f64>, dt: f64) -> Result<RobotMotion> {
        check_finite("twist", twist.as_slice())?;
        let pose = pose * exp_twist(&(twist * dt).into())?;
        Ok(RobotMotion::moved(pose, joints(&pose), *twist, false))
    }
}
