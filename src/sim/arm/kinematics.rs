//! Forward kinematics and geometric Jacobians of an [`ArmModel`].
//!
//! Jacobian columns are twists `(v, w)`: the linear velocity of the end-effector origin on
//! top, the angular velocity below, per unit joint speed, as the crate's camera twists.
//! [`ArmModel::jacobian_base`] expresses them in the base frame;
//! [`ArmModel::jacobian_end_effector`] in the end-effector frame, so that with `J_e dq = twist`
//! the end-effector pose moves as `pose * exp_twist(twist dt)` to first order.

use nalgebra::{Isometry3, Matrix6xX, Vector3};

use super::model::{ArmModel, JointKind};
use crate::sim::error::Result;

impl ArmModel {
    /// Pose of the end-effector link in the base frame at joint positions `q`.
    pub fn fk(&self, q: &[f64]) -> Result<Isometry3<f64>> {
        self.check_joints(q)?;
        Ok(self.chain_pose(q, self.dof()) * self.tip())
    }

    /// Pose of any link of the chain (see [`ArmModel::link_names`]) in the base frame.
    pub fn fk_link(&self, q: &[f64], link: &str) -> Result<Isometry3<f64>> {
        self.check_joints(q)?;
        let link = self.link(link)?;
        Ok(self.chain_pose(q, link.joints) * link.offset)
    }

    /// The 6 x dof geometric Jacobian in the base frame: rows `(vx, vy, vz, wx, wy, wz)`.
    pub fn jacobian_base(&self, q: &[f64]) -> Result<Matrix6xX<f64>> {
        self.check_joints(q)?;
        Ok(self.jacobian_and_pose(q).0)
    }

    /// The 6 x dof geometric Jacobian in the end-effector frame: `blockdiag(R^T, R^T) J_base`
    /// with `R` the end-effector orientation.
    pub fn jacobian_end_effector(&self, q: &[f64]) -> Result<Matrix6xX<f64>> {
        self.check_joints(q)?;
        let (mut jac, pose) = self.jacobian_and_pose(q);
        let inv = pose.rotation.inverse();
        for mut col in jac.column_iter_mut() {
            let v = inv * Vector3::new(col[0], col[1], col[2]);
            let w = inv * Vector3::new(col[3], col[4], col[5]);
            col.copy_from_slice(&[v.x, v.y, v.z, w.x, w.y, w.z]);
        }
        Ok(jac)
    }

    /// Yoshikawa's manipulability `sqrt(det(J J^T))`, the product of the Jacobian's singular
    /// values (the same in either frame); `sqrt(det(J^T J))` for arms with fewer than six
    /// joints, whose `J J^T` is always singular. Computed as `|prod diag(R)|` of the QR
    /// factorisation `J^T = Q R` (`J = Q R` below six joints), which stays accurate (~1e-17,
    /// not the square root of rounding errors) at singular configurations.
    pub fn manipulability(&self, q: &[f64]) -> Result<f64> {
        let jac = self.jacobian_base(q)?;
        let k = jac.ncols().min(6);
        let prod: f64 = if jac.ncols() >= 6 {
            let r = jac.transpose().qr().unpack_r();
            (0..k).map(|i| r[(i, i)]).product()
        } else {
            let r = jac.qr().unpack_r();
            (0..k).map(|i| r[(i, i)]).product()
        };
        Ok(prod.abs())
    }

    /// From the last actuated joint's frame (after its motion) to the end-effector.
    fn tip(&self) -> Isometry3<f64> {
        self.links[self.links.len() - 1].offset
    }

    /// Product of the first `n` joint transforms `origin_i * motion_i(q_i)`.
    fn chain_pose(&self, q: &[f64], n: usize) -> Isometry3<f64> {
        self.joints[..n]
            .iter()
            .zip(q)
            .fold(Isometry3::identity(), |t, (joint, &qi)| t * joint.origin * joint.motion(qi))
    }

    /// The base-frame Jacobian and the end-effector pose, for checked `q`.
    fn jacobian_and_pose(&self, q: &[f64]) -> (Matrix6xX<f64>, Isometry3<f64>) {
        let mut jac = Matrix6xX::zeros(self.dof());
        // First pass: each joint's axis (rows 3..6) and origin (rows 0..3) in the base frame.
        let mut t = Isometry3::identity();
        for (i, (joint, &qi)) in self.joints.iter().zip(q).enumerate() {
            let frame = t * joint.origin;
            let axis = frame.rotation * joint.axis.into_inner();
            jac.fixed_view_mut::<3, 1>(0, i).copy_from(&frame.translation.vector);
            jac.fixed_view_mut::<3, 1>(3, i).copy_from(&axis);
            t = frame * joint.motion(qi);
        }
        let pose = t * self.tip();
        // Second pass: revolute `(z x (p_e - p_i), z)`, prismatic `(z, 0)`.
        for (i, joint) in self.joints.iter().enumerate() {
            let axis: Vector3<f64> = jac.fixed_view::<3, 1>(3, i).into_owned();
            let (v, w) = match joint.kind {
                JointKind::Prismatic => (axis, Vector3::zeros()),
                _ => (axis.cross(&(pose.translation.vector - jac.fixed_view::<3, 1>(0, i))), axis),
            };
            jac.fixed_view_mut::<3, 1>(0, i).copy_from(&v);
            jac.fixed_view_mut::<3, 1>(3, i).copy_from(&w);
        }
        (jac, pose)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    /// A planar 2R arm (links 1 and 0.5 along x, axes z) and a prismatic z joint after it.
    const PLANAR: &str = r#"<robot name="planar">
      <link name="a"/><link name="b"/><link name="c"/><link name="d"/><link name="e"/>
      <joint name="j1" type="revolute"><parent link="a"/><child link="b"/>
        <axis xyz="0 0 1"/><limit lower="-3" upper="3" velocity="1"/></joint>
      <joint name="j2" type="revolute"><parent link="b"/><child link="c"/>
        <origin xyz="1 0 0"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" velocity="1"/></joint>
      <joint name="j3" type="prismatic"><parent link="c"/><child link="d"/>
        <axis xyz="0 0 1"/><limit lower="0" upper="1" velocity="1"/></joint>
      <joint name="tip" type="fixed"><parent link="d"/><child link="e"/><origin xyz="0.5 0 0"/></joint>
    </robot>"#;

    #[test]
    fn planar_arm_matches_the_textbook_jacobian() {
        let arm = ArmModel::from_urdf_str(PLANAR, "e").unwrap();
        let (q1, q2, q3) = (0.4, -0.9, 0.2);
        let pose = arm.fk(&[q1, q2, q3]).unwrap();
        let (s1, c1, s12, c12) = (q1.sin(), q1.cos(), (q1 + q2).sin(), (q1 + q2).cos());
        let p = Vector3::new(c1 + 0.5 * c12, s1 + 0.5 * s12, q3);
        assert!((pose.translation.vector - p).norm() < 1e-15);
        assert!((pose.rotation.angle() - (q1 + q2).abs()).abs() < 1e-15);
        let jac = arm.jacobian_base(&[q1, q2, q3]).unwrap();
        #[rustfmt::skip]
        let expected = Matrix6xX::from_row_slice(&[
            -s1 - 0.5 * s12, -0.5 * s12, 0.0,
            c1 + 0.5 * c12, 0.5 * c12, 0.0,
            0.0, 0.0, 1.0,
            0.0, 0.0, 0.0,
            0.0, 0.0, 0.0,
            1.0, 1.0, 0.0,
        ]);
        assert!((jac - expected).abs().max() < 1e-15);
    }

    #[test]
    fn end_effector_jacobian_is_the_base_one_rotated() {
        let arm = ArmModel::from_urdf_str(PLANAR, "e").unwrap();
        let q = [0.4, -0.9, 0.2];
        let (jb, je) = (arm.jacobian_base(&q).unwrap(), arm.jacobian_end_effector(&q).unwrap());
        let r = arm.fk(&q).unwrap().rotation;
        for c in 0..3 {
            let v = r * Vector3::new(je[(0, c)], je[(1, c)], je[(2, c)]);
            let w = r * Vector3::new(je[(3, c)], je[(4, c)], je[(5, c)]);
            assert!((v - jb.fixed_view::<3, 1>(0, c)).norm() < 1e-15);
            assert!((w - jb.fixed_view::<3, 1>(3, c)).norm() < 1e-15);
        }
    }

    #[test]
    fn manipulability_below_six_joints_uses_j_transpose_j() {
        let arm = ArmModel::from_urdf_str(PLANAR, "e").unwrap();
        let q = [0.4, -0.9, 0.2];
        let jac = arm.jacobian_base(&q).unwrap();
        let expected = (jac.transpose() * &jac).determinant().sqrt();
        assert!((arm.manipulability(&q).unwrap() - expected).abs() < 1e-12);
        // Stretched (q2 = 0): the three columns stay independent thanks to w and the slider.
        assert!(arm.manipulability(&[0.4, 0.0, 0.2]).unwrap() > 0.1);
    }

    #[test]
    fn intermediate_links() {
        let arm = ArmModel::from_urdf_str(PLANAR, "e").unwrap();
        let q = [0.4, -0.9, 0.2];
        let c = arm.fk_link(&q, "c").unwrap().translation.vector;
        assert!((c - Vector3::new(0.4f64.cos(), 0.4f64.sin(), 0.0)).norm() < 1e-15);
        assert_eq!(arm.fk_link(&q, "e").unwrap(), arm.fk(&q).unwrap());
    }
}
