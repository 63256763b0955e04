//! A six-axis Cartesian robot like the paper's AFMA: three prismatic axes and a three-axis
//! wrist, with joint position and velocity limits. The camera twist is mapped to joint
//! velocities through the robot Jacobian, saturated, and integrated; with no limit active
//! the new pose is exactly `pose * exp(twist dt)`.

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3, Vector6};

use crate::core::se3::exp_twist;
use crate::error::{Error, Short, check_finite};
use crate::sim::error::Result;
use crate::sim::robot::{CameraRobot, RobotMotion};

/// Joint limits of the Cartesian robot: `q = (x, y, z, a, b, c)` with the camera centre at
/// `(x, y, z)` (metres, in F*) and the orientation `R = Rx(a) Ry(b) Rz(c)` (radians).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointLimits {
    /// Lower joint positions.
    pub min: [f64; 6],
    /// Upper joint positions.
    pub max: [f64; 6],
    /// Largest joint speeds (m/s, rad/s), > 0.
    pub velocity: [f64; 6],
}

impl Default for JointLimits {
    /// An AFMA-like workspace: +-1 m on each axis, +-170 degrees on a and c, +-80 degrees on
    /// b (the wrist singularity is at b = +-90 degrees), 0.5 m/s and 1.5 rad/s.
    fn default() -> Self {
        let (a, b) = (170f64.to_radians(), 80f64.to_radians());
        Self {
            min: [-1.0, -1.0, -1.0, -a, -b, -a],
            max: [1.0, 1.0, 1.0, a, b, a],
            velocity: [0.5, 0.5, 0.5, 1.5, 1.5, 1.5],
        }
    }
}

impl JointLimits {
    /// Checks the limits: finite, `min < max`, velocities > 0, and |b| limits inside the wrist
    /// singularity at +-90 degrees.
    pub fn validate(&self) -> Result<()> {
        check_finite("joint limits", &[self.min, self.max, self.velocity].concat())?;
        let bad = |reason: String| Err(Error::InvalidParameter { name: "robot limits", reason }.into());
        if let Some(i) = (0..6).find(|&i| self.min[i] >= self.max[i]) {
            return bad(format!("joint {i}: min {} must be below max {}", Short(self.min[i]), Short(self.max[i])));
        }
        if let Some(i) = (0..6).find(|&i| self.velocity[i] <= 0.0) {
            return bad(format!("joint {i}: velocity limit must be > 0"));
        }
        let half_pi = std::f64::consts::FRAC_PI_2;
        if self.min[4] <= -half_pi || self.max[4] >= half_pi {
            return bad("joint 4 (b) must stay inside (-90, 90) degrees: the wrist is singular at +-90".into());
        }
        Ok(())
    }
}

/// Orientation `Rx(a) Ry(b) Rz(c)` of the Cartesian robot's wrist.
fn wrist_rotation(a: f64, b: f64, c: f64) -> Rotation3<f64> {
    Rotation3::from_axis_angle(&Vector3::x_axis(), a)
        * Rotation3::from_axis_angle(&Vector3::y_axis(), b)
        * Rotation3::from_axis_angle(&Vector3::z_axis(), c)
}

/// Joint positions of the Cartesian robot for a camera pose (inverse kinematics).
pub fn cartesian_joints(pose: &Isometry3<f64>) -> [f64; 6] {
    let r = pose.rotation.to_rotation_matrix();
    let m = r.matrix();
    // R = Rx(a) Ry(b) Rz(c): R[0,2] = sin b, R[1,2] = -sin a cos b, R[2,2] = cos a cos b,
    // R[0,1] = -cos b sin c, R[0,0] = cos b cos c.
    let b = m[(0, 2)].clamp(-1.0, 1.0).asin();
    let a = (-m[(1, 2)]).atan2(m[(2, 2)]);
    let c = (-m[(0, 1)]).atan2(m[(0, 0)]);
    let t = pose.translation.vector;
    [t.x, t.y, t.z, a, b, c]
}

/// Camera pose of the Cartesian robot at joint positions `q` (forward kinematics).
pub fn cartesian_pose(q: &[f64; 6]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(q[0], q[1], q[2]),
        UnitQuaternion::from_rotation_matrix(&wrist_rotation(q[3], q[4], q[5])),
    )
}

/// `E(a, b)` with `w_base = E (da, db, dc)` for `R = Rx(a) Ry(b) Rz(c)`.
fn euler_rate_matrix(a: f64, b: f64) -> Matrix3<f64> {
    let rx = Rotation3::from_axis_angle(&Vector3::x_axis(), a);
    let ry = Rotation3::from_axis_angle(&Vector3::y_axis(), b);
    let c1 = Vector3::x();
    let c2 = rx * Vector3::y();
    let c3 = rx * (ry * Vector3::z());
    Matrix3::from_columns(&[c1, c2, c3])
}

/// Joint velocities of the Cartesian robot for a camera twist (camera frame) at `q`:
/// the inverse of the robot Jacobian `twist = blockdiag(R^T, R^T E) dq`.
pub fn cartesian_joint_velocities(q: &[f64; 6], twist: &Vector6<f64>) -> Result<[f64; 6]> {
    let r = wrist_rotation(q[3], q[4], q[5]);
    let v = r * twist.fixed_rows::<3>(0);
    let w = r * twist.fixed_rows::<3>(3);
    let e = euler_rate_matrix(q[3], q[4]);
    let rates = e.lu().solve(&w).ok_or(Error::InvalidParameter {
        name: "robot",
        reason: format!("wrist singularity at b = {:.2} degrees", q[4].to_degrees()),
    })?;
    Ok([v.x, v.y, v.z, rates.x, rates.y, rates.z])
}

/// The camera twist (camera frame) produced by joint velocities `dq` at `q`.
pub fn cartesian_twist(q: &[f64; 6], dq: &[f64; 6]) -> Vector6<f64> {
    let rt = wrist_rotation(q[3], q[4], q[5]).transpose();
    let v = rt * Vector3::new(dq[0], dq[1], dq[2]);
    let w = rt * (euler_rate_matrix(q[3], q[4]) * Vector3::new(dq[3], dq[4], dq[5]));
    Vector6::new(v.x, v.y, v.z, w.x, w.y, w.z)
}

/// The Cartesian robot: its joint limits.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CartesianRobot {
    /// Position and speed limits of `(x, y, z, a, b, c)`.
    pub limits: JointLimits,
}

impl CameraRobot for CartesianRobot {
    fn dof(&self) -> usize {
        6
    }

    /// Checks that a pose is inside the joint limits.
    fn start(&self, pose: &Isometry3<f64>) -> Result<(Vec<f64>, Option<f64>)> {
        let (q, limits) = (cartesian_joints(pose), &self.limits);
        if let Some(i) = (0..6).find(|&i| q[i] < limits.min[i] || q[i] > limits.max[i]) {
            return Err(Error::InvalidParameter {
                name: "start",
                reason: format!(
                    "joint {i} = {} is outside the robot's limits [{}, {}]",
                    Short(q[i]),
                    Short(limits.min[i]),
                    Short(limits.max[i])
                ),
            }
            .into());
        }
        Ok((q.to_vec(), None))
    }

    /// Velocity saturation with one common scale (the direction of motion is kept), then
    /// position limits: a joint at a stop does not move further out.
    fn step(&self, pose: &Isometry3<f64>, _joints: &[f64], twist: &Vector6<f64>, dt: f64) -> Result<RobotMotion> {
        check_finite("twist", twist.as_slice())?;
        let limits = &self.limits;
        let q = cartesian_joints(pose);
        let mut dq = cartesian_joint_velocities(&q, twist)?;
        let mut limited = false;
        let scale = (0..6).map(|i| limits.velocity[i] / dq[i].abs()).fold(1.0_f64, f64::min);
        if scale < 1.0 {
            dq.iter_mut().for_each(|v| *v *= scale);
            limited = true;
        }
        for i in 0..6 {
            let next = q[i] + dq[i] * dt;
            if next > limits.max[i] || next < limits.min[i] {
                dq[i] = (next.clamp(limits.min[i], limits.max[i]) - q[i]) / dt;
                limited = true;
            }
        }
        if !limited {
            let pose = pose * exp_twist(&(twist * dt).into())?;
            return Ok(RobotMotion::moved(pose, cartesian_joints(&pose).to_vec(), *twist, false));
        }
        let executed = cartesian_twist(&q, &dq);
        let mut pose = pose * exp_twist(&(executed * dt).into())?;
        let mut joints = cartesian_joints(&pose);
        if (0..6).any(|i| joints[i] < limits.min[i] || joints[i] > limits.max[i]) {
            (0..6).for_each(|i| joints[i] = joints[i].clamp(limits.min[i], limits.max[i]));
            pose = cartesian_pose(&joints);
        }
        Ok(RobotMotion::moved(pose, joints.to_vec(), executed, true))
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::core::se3::pose_error;
    use crate::sim::robot::FreeFlying;

    #[test]
    fn kinematics_round_trip() {
        let q = [0.1, -0.2, 0.3, 0.4, -0.5, 1.2];
        let back = cartesian_joints(&cartesian_pose(&q));
        for i in 0..6 {
            assert!((back[i] - q[i]).abs() < 1e-12, "{back:?}");
        }
    }

    /// The Jacobian maps joint velocities to the twist that finite differences of the
    /// forward kinematics give.
    #[test]
    fn jacobian_matches_finite_differences() {
        let q = [0.1, -0.2, 0.3, 0.4, -0.5, 1.2];
        let dq = [0.05, -0.02, 0.01, 0.3, -0.2, 0.5];
        let tw = cartesian_twist(&q, &dq);
        let h = 1e-6;
        let ahead: [f64; 6] = std::array::from_fn(|i| q[i] + h * dq[i]);
        let rel = cartesian_pose(&q).inverse() * cartesian_pose(&ahead);
        let fd_v = rel.translation.vector / h;
        let fd_w = rel.rotation.scaled_axis() / h;
        for i in 0..3 {
            assert!((fd_v[i] - tw[i]).abs() < 1e-5 && (fd_w[i] - tw[3 + i]).abs() < 1e-5, "{tw} vs {fd_v} {fd_w}");
        }
        let back = cartesian_joint_velocities(&q, &tw).unwrap();
        for i in 0..6 {
            assert!((back[i] - dq[i]).abs() < 1e-12);
        }
    }

    /// Without an active limit both robots move exactly by exp(twist dt).
    #[test]
    fn unlimited_step_is_exact() {
        let start = cartesian_pose(&[0.1, 0.0, -0.2, 0.1, 0.2, 0.5]);
        let tw = Vector6::new(0.05, -0.02, 0.03, 0.2, -0.1, 0.4);
        let expected = start * exp_twist(&(tw * 0.04).into()).unwrap();
        let robots: [&dyn CameraRobot; 2] = [&FreeFlying, &CartesianRobot::default()];
        for robot in robots {
            let s = robot.step(&start, &[], &tw, 0.04).unwrap();
            assert!(!s.limited);
            let (dt, dr) = pose_error(&expected, &s.pose);
            assert!(dt < 1e-14 && dr < 1e-12);
        }
    }

    #[test]
    fn limits_are_respected() {
        let limits = JointLimits { min: [-0.1; 6], max: [0.1, 0.1, 0.1, 0.5, 0.5, 0.5], velocity: [0.2; 6] };
        let robot = CartesianRobot { limits };
        let mut pose = cartesian_pose(&[0.0; 6]);
        for _ in 0..200 {
            let s = robot.step(&pose, &[], &Vector6::new(1.0, -2.0, 0.5, 3.0, 1.0, -2.0), 0.04).unwrap();
            assert!(s.limited);
            for i in 0..6 {
                assert!(s.joints[i] >= limits.min[i] - 1e-12 && s.joints[i] <= limits.max[i] + 1e-12);
            }
            pose = s.pose;
        }
        let q = cartesian_joints(&pose);
        assert!((q[0] - 0.1).abs() < 1e-9 && (q[1] + 0.1).abs() < 1e-9, "{q:?}");
    }
}
