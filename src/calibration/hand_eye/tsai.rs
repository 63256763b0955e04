//! Tsai and Lenz, "A new technique for fully autonomous and efficient 3D robotics hand/eye
//! calibration", IEEE Trans. Robotics and Automation 5(3), 1989: the rotation from the
//! modified Rodrigues vectors `P = 2 sin(theta/2) u` of the motions (eq. 12:
//! `[P_A + P_B]x P' = P_B - P_A`, then `P = 2 P' / sqrt(1 + |P'|^2)`, eq. 14), the translation
//! from eq. 15.
//!
//! Eq. 12 is ill-conditioned for motions that rotate little (their axes are noise) or close
//! to half a turn (`P_A + P_B` shrinks): motions with `|P|` outside [`TSAI_BAND`] for the
//! gripper or the camera are left out of both steps, as OpenCV does since 4.10 (the paper's
//! own advice: large rotations between stations).

use nalgebra::{Matrix3, Vector3};

use super::Solution;
use super::motions::{Motion, Rigid};
use super::rotation::{quaternion, rotation_from_quaternion, vector_part};
use super::translation::{least_squares, solve_translation};
use crate::calibration::error::{CalibrationError, Result};

/// The range of `|P| = 2 sin(theta/2)` of the motions that the method uses: rotations of
/// about 17.3 to 116.4 degrees.
pub const TSAI_BAND: (f64, f64) = (0.3, 1.7);

/// `P = 2 sin(theta/2) u` of a rotation (theta in [0, pi]).
fn modified_rodrigues(r: &Matrix3<f64>) -> Vector3<f64> {
    vector_part(&quaternion(r)) * 2.0
}

fn in_band(p: &Vector3<f64>) -> bool {
    let norm = p.norm();
    (TSAI_BAND.0..=TSAI_BAND.1).contains(&norm)
}

/// The camera-to-gripper transform by Tsai-Lenz; `poses` is the number of stations.
pub(crate) fn solve(motions: &[Motion], poses: usize) -> Result<Solution> {
    let (mut normal, mut rhs) = (Matrix3::zeros(), Vector3::zeros());
    let mut used = Vec::new();
    for m in motions {
        let (pa, pb) = (modified_rodrigues(&m.gripper.r), modified_rodrigues(&m.camera.r));
        if !(in_band(&pa) && in_band(&pb)) {
            continue;
        }
        let lhs = (pa + pb).cross_matrix();
        normal += lhs.transpose() * lhs;
        rhs += lhs.transpose() * (pb - pa);
        used.push(m);
    }
    if used.len() < 2 {
        let reason = format!(
            "Tsai-Lenz: {} motion(s) rotate between 17.3 and 116.4 degrees (gripper and camera), 2 are needed; include larger rotations between poses, or use Park-Martin",
            used.len()
        );
        return Err(CalibrationError::DegenerateMotion { poses, reason });
    }
    let p_prime = least_squares(&normal, &rhs, poses, "the rotation")?;
    let p = p_prime * (2.0 / (1.0 + p_prime.norm_squared()).sqrt());
    let v = p / 2.0;
    let r = rotation_from_quaternion((1.0 - v.norm_squared()).max(0.0).sqrt(), &v);
    let t = solve_translation(used.iter().copied(), &r, poses)?;
    Ok(Solution { x: Rigid { r, t }, motions_used: used.len() })
}
