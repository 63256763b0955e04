//! Hand-eye calibration: the pose of the camera on the robot's flange from pairs of robot and
//! target poses, the equation `A X = X B` (Shiu and Ahmad, IEEE Trans. Robotics and
//! Automation 5(1), 1989), in OpenCV's convention (`cv::calibrateHandEye`).
//!
//! **Inputs.** For each station `i` the robot reports `gripper_poses[i]`, the gripper
//! (flange) frame in the base frame (gripper-to-base, `G_i`), and the camera measures
//! `target_poses[i]`, the calibration target in the camera frame (target-to-camera, `C_i`;
//! e.g. from `solvePnP`). The target is fixed in the base frame.
//!
//! **Result.** `X`, the camera frame in the gripper frame (camera-to-gripper): a point `p_c`
//! in camera coordinates is `X p_c` in gripper coordinates. For every pair of stations
//! `i < j`, `A = G_j^-1 G_i` and `B = C_j C_i^-1` satisfy `A X = X B` (module `motions`);
//! all pairs are used, as OpenCV does.
//!
//! **Eye-to-hand** ([`HandEyeSetup::EyeToHand`]): the camera is fixed in the base frame and the
//! target rides on the flange. The inputs are the same (gripper-to-base from the robot,
//! target-to-camera from the camera); the result is `Y`, the camera frame in the base frame
//! (camera-to-base). The gripper poses are inverted (base-to-gripper) and the same solvers,
//! residuals and refusals run on them (module `setup`: the reduction). The residuals and
//! axes are then those of `A = G_j G_i^-1`, motions in the base frame.
//!
//! | concept | file | reference |
//! |---|---|---|
//! | eye-in-hand or eye-to-hand, the reduction of one to the other | `setup.rs` | Tsai-Lenz sec. I |
//! | poses checked rigid, relative motions | `motions.rs` | Tsai-Lenz eqs. 6-7 |
//! | quaternions and rotation vectors | `rotation.rs` | Shepperd 1978 |
//! | Tsai-Lenz | `tsai.rs` | IEEE T-RA 5(3), 1989 |
//! | Park-Martin | `park.rs` | IEEE T-RA 10(5), 1994 |
//! | Daniilidis (dual quaternions) | `daniilidis.rs` | IJRR 18(3), 1999 |
//! | the translation once the rotation is known | `translation.rs` | Tsai-Lenz eq. 15 |
//! | residuals, axis spread, agreement of the methods | `diagnostics.rs` | |
//!
//! **Refused.** Target poses not one per gripper pose ([`Error::Shape`]); a pose that is
//! not a rigid transform within [`RIGID_TOLERANCE`] ([`CalibrationError::InvalidPose`], naming the
//! argument and the pose); fewer than 3 poses, no gripper motion rotating by
//! [`MIN_MOTION_ROTATION_DEG`], or rotation axes spread by less than [`MIN_AXIS_SPREAD_DEG`]
//! ([`CalibrationError::DegenerateMotion`]): rotations about one axis leave the translation along it
//! undetermined.
//!
//! ```
//! use vsinv::calibration::{HandEyeMethod, HandEyeSetup, calibrate_hand_eye};
//! use vsinv::nalgebra::{Isometry3, Matrix4, Vector3};
//! let x = Isometry3::new(Vector3::new(0.05, 0.0, 0.1), Vector3::new(0.0, 0.0, 0.3)); // camera on flange
//! let target_in_base = Isometry3::new(Vector3::new(0.6, 0.0, 0.0), Vector3::zeros());
//! let (mut gripper, mut target) = (Vec::<Matrix4<f64>>::new(), Vec::new());
//! for (k, axis) in [Vector3::x(), Vector3::y(), Vector3::z(), Vector3::new(1.0, 1.0, 0.0)].iter().enumerate() {
//!     let g = Isometry3::new(Vector3::new(0.3, 0.1 * k as f64, 0.5), axis.normalize() * 0.6);
//!     gripper.push(g.to_homogeneous());
//!     target.push(((g * x).inverse() * target_in_base).to_homogeneous());
//! }
//! let calibration = calibrate_hand_eye(&gripper, &target, HandEyeMethod::ParkMartin, HandEyeSetup::EyeInHand)?;
//! assert!((calibration.transform.to_homogeneous() - x.to_homogeneous()).amax() < 1e-9);
//! # Ok::<(), vsinv::calibration::CalibrationError>(())
//! ```

mod daniilidis;
mod diagnostics;
mod motions;
mod park;
mod rotation;
mod setup;
mod translation;
mod tsai;

use nalgebra::{Isometry3, Matrix4, Rotation3, Translation3, UnitQuaternion};

pub use diagnostics::{AxisSpread, HandEyeAgreement, MIN_AXIS_SPREAD_DEG, MIN_MOTION_ROTATION_DEG, PairResidual};
pub use motions::{MAX_POSE_TRANSLATION_M, MAX_POSES, RIGID_TOLERANCE};
use motions::{Motion, Rigid, motions, rigid_poses};
pub use setup::HandEyeSetup;
pub use tsai::TSAI_BAND;

use crate::calibration::error::{CalibrationError, Result};
use crate::error::Error;

/// A hand-eye calibration method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum HandEyeMethod {
    /// Tsai and Lenz 1989: rotation first, from the modified Rodrigues vectors of the motions
    /// rotating 17 to 116 degrees ([`TSAI_BAND`]), then the translation (OpenCV's
    /// `CALIB_HAND_EYE_TSAI`).
    TsaiLenz,
    /// Park and Martin 1994: the rotation as the polar factor of the correlation of the
    /// rotation vectors, then the translation (`CALIB_HAND_EYE_PARK`).
    ParkMartin,
    /// Daniilidis 1999: rotation and translation at once, with dual quaternions
    /// (`CALIB_HAND_EYE_DANIILIDIS`).
    Daniilidis,
}

impl HandEyeMethod {
    /// Every method, in the order of comparisons.
    pub const ALL: [HandEyeMethod; 3] = [HandEyeMethod::TsaiLenz, HandEyeMethod::ParkMartin, HandEyeMethod::Daniilidis];

    /// The method's name: `tsai`, `park` or `daniilidis`.
    pub fn name(self) -> &'static str {
        match self {
            HandEyeMethod::TsaiLenz => "tsai",
            HandEyeMethod::ParkMartin => "park",
            HandEyeMethod::Daniilidis => "daniilidis",
        }
    }

    /// The method of a name: `tsai` (or `tsai-lenz`), `park` (or `park-martin`),
    /// `daniilidis`; case-insensitive, `_` read as `-`.
    pub fn from_name(name: &str) -> Result<HandEyeMethod> {
        match name.to_ascii_lowercase().replace('_', "-").as_str() {
            "tsai" | "tsai-lenz" => Ok(HandEyeMethod::TsaiLenz),
            "park" | "park-martin" => Ok(HandEyeMethod::ParkMartin),
            "daniilidis" => Ok(HandEyeMethod::Daniilidis),
            _ => Err(Error::InvalidParameter {
                name: "method",
                reason: format!(
                    "unknown hand-eye method {:?}: expected 'tsai', 'park' or 'daniilidis'",
                    name.chars().take(40).collect::<String>()
                ),
            }
            .into()),
        }
    }
}

/// A hand-eye calibration and its diagnostics.
#[derive(Debug, Clone, PartialEq)]
pub struct HandEyeCalibration {
    /// The method that computed it.
    pub method: HandEyeMethod,
    /// Where the camera is, which says what [`transform`](Self::transform) is.
    pub setup: HandEyeSetup,
    /// `X`: camera-to-gripper (eye_in_hand) or camera-to-base (eye_to_hand): the camera frame
    /// in the gripper frame, or in the base frame.
    pub transform: Isometry3<f64>,
    /// The residual of `A X = X B` for every pair of stations `i < j`, in order (for
    /// eye-to-hand, `A = G_j G_i^-1`: translations in the base frame).
    pub residuals: Vec<PairResidual>,
    /// The spread of the rotation axes of the gripper motions.
    pub axis_spread: AxisSpread,
    /// The motions (pairs of stations) the method used: all but, for Tsai-Lenz, those
    /// outside its band of rotations.
    pub motions_used: usize,
}

impl HandEyeCalibration {
    /// The root mean square of the rotation residuals, degrees.
    pub fn rms_rotation_deg(&self) -> f64 {
        rms(self.residuals.iter().map(|r| r.rotation_deg))
    }
    /// The root mean square of the translation residuals, metres.
    pub fn rms_translation_m(&self) -> f64 {
        rms(self.residuals.iter().map(|r| r.translation_m))
    }
    /// The largest rotation residual, degrees.
    pub fn max_rotation_deg(&self) -> f64 {
        self.residuals.iter().map(|r| r.rotation_deg).fold(0.0, f64::max)
    }
    /// The largest translation residual, metres.
    pub fn max_translation_m(&self) -> f64 {
        self.residuals.iter().map(|r| r.translation_m).fold(0.0, f64::max)
    }
}

fn rms(values: impl ExactSizeIterator<Item = f64>) -> f64 {
    let n = values.len().max(1) as f64;
    (values.map(|v| v * v).sum::<f64>() / n).sqrt()
}

/// A method's estimate: `X` and the number of motions it used.
pub(crate) struct Solution {
    x: Rigid,
    motions_used: usize,
}

/// The motions of checked poses, and their axis spread (refusing degenerate sets). For
/// eye-to-hand the gripper poses are inverted once checked (module `setup`).
fn prepare(
    gripper_poses: &[Matrix4<f64>],
    target_poses: &[Matrix4<f64>],
    setup: HandEyeSetup,
) -> Result<(Vec<Motion>, AxisSpread)> {
    let n = gripper_poses.len();
    if target_poses.len() != n {
        let expected = format!("{n} poses (one per gripper pose)");
        return Err(
            Error::Shape { what: "target_poses", expected, got: format!("{} poses", target_poses.len()) }.into()
        );
    }
    if n > MAX_POSES {
        let expected = format!("at most {MAX_POSES} poses");
        return Err(Error::Shape { what: "gripper_poses", expected, got: format!("{n} poses") }.into());
    }
    if n < 3 {
        let reason = "at least 3 poses are needed (two motions about different axes)".to_string();
        return Err(CalibrationError::DegenerateMotion { poses: n, reason });
    }
    let (mut g, c) = (rigid_poses("gripper_poses", gripper_poses)?, rigid_poses("target_poses", target_poses)?);
    if setup == HandEyeSetup::EyeToHand {
        g = g.iter().map(Rigid::inverse).collect();
    }
    let motions = motions(&g, &c);
    let spread = AxisSpread::of(&motions);
    spread.check(n)?;
    Ok((motions, spread))
}

fn solve(
    method: HandEyeMethod,
    setup: HandEyeSetup,
    motions: &[Motion],
    spread: AxisSpread,
    poses: usize,
) -> Result<HandEyeCalibration> {
    let solution = match method {
        HandEyeMethod::TsaiLenz => tsai::solve(motions, poses)?,
        HandEyeMethod::ParkMartin => park::solve(motions, poses)?,
        HandEyeMethod::Daniilidis => daniilidis::solve(motions, poses)?,
    };
    let x = solution.x;
    if !(x.r.iter().chain(x.t.iter()).all(|v| v.is_finite())) {
        let reason = format!("{}: the solution is not finite", method.name());
        return Err(CalibrationError::DegenerateMotion { poses, reason });
    }
    let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(x.r));
    let transform = Isometry3::from_parts(Translation3::from(x.t), rotation);
    let residuals = diagnostics::residuals(motions, &x);
    let motions_used = solution.motions_used;
    Ok(HandEyeCalibration { method, setup, transform, residuals, axis_spread: spread, motions_used })
}

/// The camera-to-gripper (eye_in_hand) or camera-to-base (eye_to_hand) transform from
/// gripper-to-base `gripper_poses` and target-to-camera `target_poses` (one per station, 4x4
/// homogeneous), by `method`, with its diagnostics (module docs: convention and refusals).
pub fn calibrate_hand_eye(
    gripper_poses: &[Matrix4<f64>],
    target_poses: &[Matrix4<f64>],
    method: HandEyeMethod,
    setup: HandEyeSetup,
) -> Result<HandEyeCalibration> {
    let (motions, spread) = prepare(gripper_poses, target_poses, setup)?;
    solve(method, setup, &motions, spread, gripper_poses.len())
}

/// Runs every method on the same poses and reports how far apart their results are: methods
/// that agree to within the residuals confirm the calibration; a method that disagrees
/// points at noise its assumptions do not absorb. Fails when the poses are refused, or when
/// every method fails (with the first method's error).
pub fn compare_hand_eye_methods(
    gripper_poses: &[Matrix4<f64>],
    target_poses: &[Matrix4<f64>],
    setup: HandEyeSetup,
) -> Result<HandEyeAgreement> {
    let (motions, spread) = prepare(gripper_poses, target_poses, setup)?;
    let (mut calibrations, mut failures, mut first_error) = (Vec::new(), Vec::new(), None);
    for method in HandEyeMethod::ALL {
        match solve(method, setup, &motions, spread, gripper_poses.len()) {
            Ok(c) => calibrations.push(c),
            Err(e) => {
                failures.push((method, e.to_string()));
                first_error.get_or_insert(e);
            }
        }
    }
    match (calibrations.is_empty(), first_error) {
        (true, Some(e)) => Err(e),
        _ => Ok(HandEyeAgreement::new(setup, calibrations, failures)),
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::type_complexity)]
mod tests;
