//! The inputs of hand-eye calibration: poses checked to be rigid motions, and the relative
//! motions of every pair of stations (Tsai and Lenz 1989, eqs. 6-7, in OpenCV's naming):
//! for stations `i < j`, the gripper motion `A = G_j^-1 G_i` and the camera motion
//! `B = C_j C_i^-1`, with `G` gripper-to-base and `C` target-to-camera poses; the
//! camera-to-gripper transform `X` satisfies `A X = X B`.

use nalgebra::{Matrix3, Matrix4, Vector3};

use crate::calibration::error::{CalibrationError, Result};
use crate::error::Short;

/// The largest deviation from a rigid transform a pose may have: `max |R^T R - I|` and the
/// last row's distance to `(0, 0, 0, 1)` (float64 poses are orthonormal to ~1e-15; poses
/// that went through float32 to ~1e-7).
pub const RIGID_TOLERANCE: f64 = 1e-6;
/// The largest translation of a pose, metres: beyond it the products overflow long before
/// any robot is that large.
pub const MAX_POSE_TRANSLATION_M: f64 = 1e6;
/// The most poses a calibration takes: every pair of stations is a motion, so `n` poses give
/// `n (n - 1) / 2` motions (real calibrations use 10 to 50 poses).
pub const MAX_POSES: usize = 500;

/// A rigid motion as its rotation matrix and translation, kept as given (OpenCV's methods
/// read the matrices as they are, without re-orthonormalising them).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Rigid {
    pub(crate) r: Matrix3<f64>,
    pub(crate) t: Vector3<f64>,
}

impl Rigid {
    /// The inverse motion `(R^T, -R^T t)`.
    pub(crate) fn inverse(&self) -> Rigid {
        let rt = self.r.transpose();
        Rigid { r: rt, t: -(rt * self.t) }
    }

    /// The composition `self * other` (apply `other` first).
    pub(crate) fn compose(&self, other: &Rigid) -> Rigid {
        Rigid { r: self.r * other.r, t: self.r * other.t + self.t }
    }
}

/// The motions of the stations `first < second`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Motion {
    pub(crate) first: usize,
    pub(crate) second: usize,
    /// `A = G_second^-1 G_first`, in the gripper frame.
    pub(crate) gripper: Rigid,
    /// `B = C_second C_first^-1`, in the camera frame.
    pub(crate) camera: Rigid,
}

/// Reads the poses of one argument, refusing any that is not a rigid transform (the error
/// names the argument and the pose).
pub(crate) fn rigid_poses(what: &'static str, poses: &[Matrix4<f64>]) -> Result<Vec<Rigid>> {
    poses.iter().enumerate().map(|(index, m)| rigid(what, index, m)).collect()
}

fn rigid(what: &'static str, index: usize, m: &Matrix4<f64>) -> Result<Rigid> {
    let bad = |reason: String| CalibrationError::InvalidPose { what, index, reason };
    for row in 0..4 {
        for column in 0..4 {
            if !m[(row, column)].is_finite() {
                return Err(bad(format!("non-finite value at row {row}, column {column}")));
            }
        }
    }
    let last = [m[(3, 0)], m[(3, 1)], m[(3, 2)], m[(3, 3)] - 1.0];
    if last.iter().any(|v| v.abs() > RIGID_TOLERANCE) {
        let row = [m[(3, 0)], m[(3, 1)], m[(3, 2)], m[(3, 3)]].map(|v| Short(v).to_string());
        return Err(bad(format!("the last row is ({}), not (0, 0, 0, 1)", row.join(", "))));
    }
    let r: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
    let off = (r.transpose() * r - Matrix3::identity()).amax();
    if off > RIGID_TOLERANCE {
        let reason = format!(
            "the rotation block is not orthonormal (max |R^T R - I| = {}, tolerance {RIGID_TOLERANCE:e})",
            Short(off)
        );
        return Err(bad(reason));
    }
    let det = r.determinant();
    if det < 0.0 {
        return Err(bad(format!("the rotation block has determinant {}: a reflection, not a rotation", Short(det))));
    }
    let t: Vector3<f64> = m.fixed_view::<3, 1>(0, 3).into_owned();
    if t.amax() > MAX_POSE_TRANSLATION_M {
        let reason = format!("translation {} m is beyond {MAX_POSE_TRANSLATION_M:e} m", Short(t.amax()));
        return Err(bad(reason));
    }
    Ok(Rigid { r, t })
}

/// The motions of every pair of stations `i < j`, in OpenCV's order (i, then j).
pub(crate) fn motions(gripper: &[Rigid], camera: &[Rigid]) -> Vec<Motion> {
    let n = gripper.len().min(camera.len());
    let mut out = Vec::with_capacity(n * n.saturating_sub(1) / 2);
    for first in 0..n {
        for second in first + 1..n {
            let a = gripper[second].inverse().compose(&gripper[first]);
            let b = camera[second].compose(&camera[first].inverse());
            out.push(Motion { first, second, gripper: a, camera: b });
        }
    }
    out
}
