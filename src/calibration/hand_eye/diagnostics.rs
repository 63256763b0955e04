//! What tells a hand-eye calibration worth keeping from one to redo: the residual of
//! `A X = X B` for every pair of stations, the spread of the rotation axes of the gripper
//! motions (parallel axes leave the translation along them, and the rotation about them,
//! undetermined: Shiu and Ahmad 1989; Tsai and Lenz 1989), and the agreement of
//! the methods on the same data.

use nalgebra::{Matrix3, SymmetricEigen};

use super::motions::{Motion, Rigid};
use super::rotation::{rotation_angle, rotation_vector};
use super::{HandEyeCalibration, HandEyeMethod, HandEyeSetup};
use crate::calibration::error::{CalibrationError, Result};
use crate::error::Short;

/// A gripper motion rotating less than this has no usable axis, degrees.
pub const MIN_MOTION_ROTATION_DEG: f64 = 0.1;
/// The smallest spread of the rotation axes accepted, degrees ([`AxisSpread::spread_deg`]).
pub const MIN_AXIS_SPREAD_DEG: f64 = 1.0;

/// The residual of `A X = X B` for the stations `first < second`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairResidual {
    /// The first station (index into the poses).
    pub first: usize,
    /// The second station.
    pub second: usize,
    /// The angle of `(A X)^-1 (X B)`, degrees.
    pub rotation_deg: f64,
    /// `|t(A X) - t(X B)|`, metres (in the gripper frame).
    pub translation_m: f64,
}

/// How well the rotation axes of the gripper motions span space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisSpread {
    /// `2 atan(sqrt(lambda_2 / lambda_1))` in degrees, with `lambda` the eigenvalues of the
    /// mean of `u u^T` over the unit axes `u` of the motions that rotate: the angle between
    /// the axes for two motions, 0 when all axes are parallel, 90 for axes spread evenly in a
    /// plane or in space.
    pub spread_deg: f64,
    /// The eigenvalues `lambda`, descending, summing to 1 (the third is 0 for axes in a plane).
    pub eigenvalues: [f64; 3],
    /// The number of gripper motions (pairs of stations) that rotate by
    /// [`MIN_MOTION_ROTATION_DEG`] or more.
    pub rotating_motions: usize,
    /// The largest rotation of a gripper motion, degrees.
    pub max_rotation_deg: f64,
}

impl AxisSpread {
    /// The spread of the gripper motions' axes.
    pub(crate) fn of(motions: &[Motion]) -> AxisSpread {
        let mut scatter = Matrix3::zeros();
        let (mut rotating_motions, mut max_rotation_deg) = (0, 0.0_f64);
        for m in motions {
            let tu = rotation_vector(&m.gripper.r);
            let angle_deg = tu.norm().to_degrees();
            max_rotation_deg = max_rotation_deg.max(angle_deg);
            if angle_deg >= MIN_MOTION_ROTATION_DEG {
                let u = tu.normalize();
                scatter += u * u.transpose();
                rotating_motions += 1;
            }
        }
        let mut eigenvalues = [0.0; 3];
        if rotating_motions > 0 {
            let values = SymmetricEigen::new(scatter / rotating_motions as f64).eigenvalues;
            eigenvalues = [values[0].max(0.0), values[1].max(0.0), values[2].max(0.0)];
            eigenvalues.sort_by(|a, b| b.total_cmp(a));
        }
        let spread_deg =
            if eigenvalues[0] > 0.0 { 2.0 * (eigenvalues[1] / eigenvalues[0]).sqrt().atan().to_degrees() } else { 0.0 };
        AxisSpread { spread_deg, eigenvalues, rotating_motions, max_rotation_deg }
    }

    /// Refuses motions that do not determine `X`: none rotates, or all about (nearly) one axis.
    pub(crate) fn check(&self, poses: usize) -> Result<()> {
        if self.rotating_motions == 0 {
            let reason = format!(
                "no gripper motion rotates by {MIN_MOTION_ROTATION_DEG} degrees or more (largest {} degrees): pure translations do not determine the camera's rotation (on the flange, or in the base frame); rotate the gripper between poses, about at least two different axes",
                Short(self.max_rotation_deg)
            );
            return Err(CalibrationError::DegenerateMotion { poses, reason });
        }
        if !(self.spread_deg >= MIN_AXIS_SPREAD_DEG) {
            let reason = format!(
                "the rotation axes of the gripper motions are (nearly) parallel: spread {:.3} degrees < {MIN_AXIS_SPREAD_DEG} degree; rotations about one axis leave the translation along it undetermined; rotate about at least two different axes",
                self.spread_deg
            );
            return Err(CalibrationError::DegenerateMotion { poses, reason });
        }
        Ok(())
    }
}

/// The residuals of `A X = X B` over the motions.
pub(crate) fn residuals(motions: &[Motion], x: &Rigid) -> Vec<PairResidual> {
    motions
        .iter()
        .map(|m| {
            let (ax, xb) = (m.gripper.compose(x), x.compose(&m.camera));
            let rotation_deg = rotation_angle(&(ax.r.transpose() * xb.r)).to_degrees();
            PairResidual { first: m.first, second: m.second, rotation_deg, translation_m: (ax.t - xb.t).norm() }
        })
        .collect()
}

/// The results of every method on the same poses, and how far apart they are.
#[derive(Debug, Clone, PartialEq)]
pub struct HandEyeAgreement {
    /// Where the camera is: every calibration's transform is camera-to-gripper
    /// (eye_in_hand) or camera-to-base (eye_to_hand).
    pub setup: HandEyeSetup,
    /// The calibrations of the methods that succeeded, in [`HandEyeMethod::ALL`]'s order.
    pub calibrations: Vec<HandEyeCalibration>,
    /// The methods that refused the poses, with the reason (e.g. Tsai-Lenz without motions
    /// in its band of rotations).
    pub failures: Vec<(HandEyeMethod, String)>,
    /// The largest rotation between the transforms of two methods, degrees.
    pub max_rotation_deg: f64,
    /// The largest distance between the translations of two methods, metres.
    pub max_translation_m: f64,
}

impl HandEyeAgreement {
    /// Compares the calibrations pairwise.
    pub(crate) fn new(
        setup: HandEyeSetup,
        calibrations: Vec<HandEyeCalibration>,
        failures: Vec<(HandEyeMethod, String)>,
    ) -> Self {
        let (mut max_rotation_deg, mut max_translation_m) = (0.0_f64, 0.0_f64);
        for (k, a) in calibrations.iter().enumerate() {
            for b in &calibrations[k + 1..] {
                let between = a.transform.inverse() * b.transform;
                max_rotation_deg = max_rotation_deg.max(between.rotation.angle().to_degrees());
                max_translation_m =
                    max_translation_m.max((a.transform.translation.vector - b.transform.translation.vector).norm());
            }
        }
        HandEyeAgreement { setup, calibrations, failures, max_rotation_deg, max_translation_m }
    }
}
