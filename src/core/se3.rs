//! Rigid motions: the SE(3) exponential used to integrate a camera twist exactly, and
//! conversions between poses and 4x4 homogeneous matrices.
//!
//! Poses are `Isometry3` values `c*M_c`: the camera frame expressed in the reference frame
//! F*. A point `X*` given in F* has camera coordinates `M^-1 X*` (eq. 2: `R`, `t` of the paper
//! are the rotation and translation of `M^-1`).

use nalgebra::{Isometry3, Matrix3, Matrix4, Matrix6, Rotation3, Translation3, UnitQuaternion, Vector3};

use crate::error::{Error, Result, check_finite, check_finite_matrix, check_overflow};

/// `exp` of a twist `(vx, vy, vz, wx, wy, wz)`: the rigid motion produced by holding that
/// twist constant for one unit of time. With `twist * dt` for a camera velocity expressed in
/// the current camera frame, the new pose is `pose * exp_twist(twist * dt)?`.
///
/// Fails for a non-finite twist and for one so large that the motion overflows (an angle
/// beyond about 1e154 rad, a translation near `f64::MAX`).
#[inline]
pub fn exp_twist(twist: &[f64; 6]) -> Result<Isometry3<f64>> {
    check_finite("twist", twist)?;
    let motion = exp_twist_unchecked(twist);
    let (t, q) = (motion.translation.vector, motion.rotation.coords);
    check_overflow("twist", "motion (translation, rotation)", &[t.as_slice(), q.as_slice()])?;
    Ok(motion)
}

fn exp_twist_unchecked(twist: &[f64; 6]) -> Isometry3<f64> {
    let v = Vector3::new(twist[0], twist[1], twist[2]);
    let w = Vector3::new(twist[3], twist[4], twist[5]);
    let theta = w.norm();
    let rotation = UnitQuaternion::from_scaled_axis(w);
    let wx = w.cross_matrix();
    // V = I + (1 - cos th)/th^2 [w]x + (th - sin th)/th^3 [w]x^2, with series near 0.
    let (b, c) = if theta < 1e-5 {
        let t2 = theta * theta;
        (0.5 - t2 / 24.0, 1.0 / 6.0 - t2 / 120.0)
    } else {
        let t2 = theta * theta;
        ((1.0 - theta.cos()) / t2, (theta - theta.sin()) / (t2 * theta))
    };
    let vmat = Matrix3::identity() + wx * b + wx * wx * c;
    Isometry3::from_parts(Translation3::from(vmat * v), rotation)
}

/// Pose from a camera centre and a theta-u rotation vector (radians), both in F*; fails for
/// non-finite values and for an angle too large to represent (beyond about 1e154 rad).
pub fn pose_from_position_thetau(position: [f64; 3], thetau: [f64; 3]) -> Result<Isometry3<f64>> {
    check_finite("position", &position)?;
    check_finite("thetau", &thetau)?;
    let rotation = UnitQuaternion::from_scaled_axis(Vector3::from(thetau));
    check_overflow("thetau", "rotation (angle too large)", &[rotation.coords.as_slice()])?;
    Ok(Isometry3::from_parts(Translation3::new(position[0], position[1], position[2]), rotation))
}

/// The theta-u rotation vector (radians) of a pose's rotation, theta in [0, pi]; finite for
/// the poses this module builds (a non-finite `Isometry3` assembled by hand stays non-finite).
pub fn thetau_from_pose(pose: &Isometry3<f64>) -> [f64; 3] {
    pose.rotation.scaled_axis().into()
}

/// The theta-u rotation vector (radians, theta in [0, pi]) of a rotation matrix, orthonormal
/// with determinant +1 within 1e-6 (the rule of [`pose_from_matrix`]).
pub fn thetau_from_rotation(r: &Matrix3<f64>) -> Result<[f64; 3]> {
    check_finite_matrix("rotation", r)?;
    if !is_rotation(r) {
        return Err(Error::InvalidParameter {
            name: "rotation",
            reason: "not a rotation matrix (orthonormal with det +1, within 1e-6)".into(),
        });
    }
    Ok(UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*r)).scaled_axis().into())
}

/// Whether `r` is orthonormal with determinant +1 within 1e-6.
fn is_rotation(r: &Matrix3<f64>) -> bool {
    (r.transpose() * r - Matrix3::identity()).iter().all(|x| x.abs() <= 1e-6) && r.determinant() > 0.0
}

/// The twist transform (adjoint) of a rigid motion `(R, t)`: a twist `(v, w)` in the moving
/// frame to the same motion's twist in the parent frame, `(R v + t x R w, R w)`. `R` and `t`
/// are used as given.
pub fn twist_adjoint(r: &Matrix3<f64>, t: &Vector3<f64>) -> Matrix6<f64> {
    let mut m = Matrix6::zeros();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(r);
    m.fixed_view_mut::<3, 3>(0, 3).copy_from(&(t.cross_matrix() * r));
    m.fixed_view_mut::<3, 3>(3, 3).copy_from(r);
    m
}

/// [`twist_adjoint`] of a pose.
pub fn twist_transform(pose: &Isometry3<f64>) -> Matrix6<f64> {
    twist_adjoint(&pose.rotation.to_rotation_matrix().into_inner(), &pose.translation.vector)
}

/// The 4x4 homogeneous matrix of a pose.
pub fn pose_to_matrix(pose: &Isometry3<f64>) -> Matrix4<f64> {
    pose.to_homogeneous()
}

/// A pose from a 4x4 homogeneous matrix; the rotation block must be orthonormal (1e-6) with
/// determinant +1 and the last row (0, 0, 0, 1).
pub fn pose_from_matrix(m: &Matrix4<f64>) -> Result<Isometry3<f64>> {
    check_finite_matrix("pose", m)?;
    let r: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
    let last = [m[(3, 0)], m[(3, 1)], m[(3, 2)], m[(3, 3)]];
    if !is_rotation(&r) || last != [0.0, 0.0, 0.0, 1.0] {
        return Err(Error::InvalidParameter {
            name: "pose",
            reason: "not a rigid motion (rotation block must be orthonormal with det +1, last row 0 0 0 1)".into(),
        });
    }
    let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
    Ok(Isometry3::from_parts(Translation3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]), rotation))
}

/// Translation error (metres) and rotation error (radians) between two poses; finite for
/// finite poses (the translation error overflows only for translations near `f64::MAX`).
pub fn pose_error(a: &Isometry3<f64>, b: &Isometry3<f64>) -> (f64, f64) {
    let d = a.inverse() * b;
    (d.translation.vector.norm(), d.rotation.angle())
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// Integrating a constant twist with many tiny steps approaches the closed form.
    #[test]
    fn exp_matches_fine_integration() {
        let tw = [0.1, -0.2, 0.3, 0.4, -0.5, 0.9];
        let exact = exp_twist(&tw).unwrap();
        let steps = 20000;
        let mut pose = Isometry3::identity();
        for _ in 0..steps {
            let small: [f64; 6] = tw.map(|x| x / steps as f64);
            // first-order step: translation then rotation
            let step = Isometry3::from_parts(
                Translation3::new(small[0], small[1], small[2]),
                UnitQuaternion::from_scaled_axis(Vector3::new(small[3], small[4], small[5])),
            );
            pose *= step;
        }
        let (dt, dr) = pose_error(&exact, &pose);
        assert!(dt < 1e-4 && dr < 1e-9, "{dt} {dr}");
    }

    /// A pure rotation about an axis through the origin with a translation along it: screw.
    #[test]
    fn exp_of_screw_closed_form() {
        // twist with w = (0,0,wz), v = (vx, 0, vz): rotation about z through point
        // c = (w x v)/|w|^2 = (0, vx/wz, 0) combined with translation vz along z.
        let (vx, vz, wz) = (0.3_f64, 0.2_f64, 1.1_f64);
        let m = exp_twist(&[vx, 0.0, vz, 0.0, 0.0, wz]).unwrap();
        let c = Vector3::new(0.0, vx / wz, 0.0);
        let r = Rotation3::from_axis_angle(&Vector3::z_axis(), wz);
        let expected_t = c - r * c + Vector3::new(0.0, 0.0, vz);
        assert_relative_eq!(m.translation.vector, expected_t, epsilon = 1e-12);
        assert_relative_eq!(m.rotation.angle(), wz, epsilon = 1e-12);
        // tiny angle branch agrees with the pure translation limit
        let small = exp_twist(&[1.0, 2.0, 3.0, 1e-9, 0.0, 0.0]).unwrap();
        assert_relative_eq!(small.translation.vector, Vector3::new(1.0, 2.0, 3.0), epsilon = 1e-8);
    }

    #[test]
    fn matrix_round_trip() {
        let p = pose_from_position_thetau([0.1, 0.2, -0.3], [0.3, -0.2, 1.0]).unwrap();
        let back = pose_from_matrix(&pose_to_matrix(&p)).unwrap();
        let (dt, dr) = pose_error(&p, &back);
        assert!(dt < 1e-12 && dr < 1e-9);
        let mut bad = pose_to_matrix(&p);
        bad[(0, 0)] *= 2.0;
        assert!(pose_from_matrix(&bad).is_err());
    }

    /// Regression (issue 16): huge or non-finite twists and rotation vectors gave NaN poses.
    #[test]
    fn non_finite_and_overflowing_motions_are_errors() {
        for tw in
            [[0.0, 0.0, 0.0, 1e300, 0.0, 0.0], [1.0, 0.0, 0.0, 1e200, 0.0, 0.0], [f64::NAN; 6], [f64::INFINITY; 6]]
        {
            assert!(exp_twist(&tw).is_err(), "{tw:?}");
        }
        assert!(pose_from_position_thetau([0.0; 3], [f64::NAN, 0.0, 0.0]).is_err());
        assert!(pose_from_position_thetau([f64::INFINITY, 0.0, 0.0], [0.0; 3]).is_err());
        assert!(pose_from_position_thetau([0.0; 3], [1e300, 1e300, 0.0]).is_err());
        // Large but representable motions are fine and finite.
        let m = exp_twist(&[1e6, 0.0, 0.0, 0.0, 0.0, 1e6]).unwrap();
        assert!(m.translation.vector.iter().all(|v| v.is_finite()));
    }
}
