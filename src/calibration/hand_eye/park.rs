//! Park and Martin, "Robot sensor calibration: solving AX = XB on the Euclidean group",
//! IEEE Trans. Robotics and Automation 10(5), 1994: with the rotation vectors `alpha` of the
//! gripper motions and `beta` of the camera motions (`alpha = R_X beta`) and
//! `M = sum beta alpha^T`, the rotation is `R_X = (M^T M)^(-1/2) M^T`, the orthogonal polar
//! factor of `M^T` (computed by SVD, with determinant +1); the translation as Tsai-Lenz eq. 15.

use nalgebra::Matrix3;

use super::Solution;
use super::motions::{Motion, Rigid};
use super::rotation::rotation_vector;
use super::translation::solve_translation;
use crate::calibration::error::{CalibrationError, Result};

/// The camera-to-gripper transform by Park-Martin; `poses` is the number of stations.
pub(crate) fn solve(motions: &[Motion], poses: usize) -> Result<Solution> {
    let mut m = Matrix3::zeros();
    for motion in motions {
        m += rotation_vector(&motion.camera.r) * rotation_vector(&motion.gripper.r).transpose();
    }
    let svd = m.transpose().svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return Err(CalibrationError::DegenerateMotion {
            poses,
            reason: "Park-Martin: the SVD of M did not converge".into(),
        });
    };
    let s = svd.singular_values;
    // Rank 2 suffices (the third axis follows from the other two); parallel axes give rank 1.
    if !(s[1] > 1e-9 * s[0]) {
        let reason = format!(
            "Park-Martin: M = sum beta alpha^T has rank 1 (sigma_2 / sigma_1 = {:.3e}): the rotation axes are parallel",
            if s[0] > 0.0 { s[1] / s[0] } else { 0.0 }
        );
        return Err(CalibrationError::DegenerateMotion { poses, reason });
    }
    // Singular values sorted descending: the sign goes on the smallest.
    let sign = (u * v_t).determinant().signum();
    let r = u * Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, sign)) * v_t;
    let t = solve_translation(motions.iter(), &r, poses)?;
    Ok(Solution { x: Rigid { r, t }, motions_used: motions.len() })
}
