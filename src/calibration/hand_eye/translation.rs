//! The translation of the hand-eye transform once its rotation is known: the translation
//! rows of `A X = X B`, `(R_A - I) t_X = R_X t_B - t_A` (Tsai and Lenz 1989, eq. 15; Park
//! and Martin 1994 solve the same rows), in least squares over the motions.

use nalgebra::{Matrix3, Vector3};

use super::motions::Motion;
use crate::calibration::error::{CalibrationError, Result};

/// Solves `(R_A - I) t = R_X t_B - t_A` over `motions` in least squares.
pub(crate) fn solve_translation<'a>(
    motions: impl Iterator<Item = &'a Motion>,
    r_x: &Matrix3<f64>,
    poses: usize,
) -> Result<Vector3<f64>> {
    let (mut normal, mut rhs) = (Matrix3::zeros(), Vector3::zeros());
    for m in motions {
        let lhs = m.gripper.r - Matrix3::identity();
        normal += lhs.transpose() * lhs;
        rhs += lhs.transpose() * (r_x * m.camera.t - m.gripper.t);
    }
    least_squares(&normal, &rhs, poses, "the translation")
}

/// The minimum-norm solution of the normal equations `N x = r` (SVD), refused when `N` has
/// lost rank: the motions do not determine `what`.
pub(crate) fn least_squares(
    normal: &Matrix3<f64>,
    rhs: &Vector3<f64>,
    poses: usize,
    what: &str,
) -> Result<Vector3<f64>> {
    let svd = normal.svd(true, true);
    let (largest, smallest) = (svd.singular_values[0], svd.singular_values[2]);
    // The normal matrix squares the condition number: 1e-12 here is 1e-6 on the motions.
    if !(smallest > 1e-12 * largest) {
        return Err(CalibrationError::DegenerateMotion {
            poses,
            reason: format!(
                "the motions do not determine {what} (singular-value ratio {:.3e} of the normal equations); rotate about at least two different axes",
                if largest > 0.0 { smallest / largest } else { 0.0 }
            ),
        });
    }
    let x = svd
        .solve(rhs, 0.0)
        .map_err(|reason| CalibrationError::DegenerateMotion { poses, reason: reason.to_string() })?;
    Ok(x)
}
