//! The calibration layer's error: [`CalibrationError`], what every function of
//! [`crate::calibration`] returns (through [`Result`]). It holds the layer's own variants (a
//! camera calibration file, a pose that is not a rigid motion, hand-eye motions that do not
//! determine the answer) and wraps, unchanged, the error of the layer below (the core's
//! [`enum@Error`]). `?` converts a core error (`From`); its message, location and family pass
//! through untouched ([`Located`]).

use thiserror::Error;

use crate::error::{Error, Located};
use crate::location::Location;

/// Everything that can go wrong in calibration: files, poses, hand-eye motions.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum CalibrationError {
    /// A camera calibration file (ROS camera_info YAML, OpenCV FileStorage YAML or XML) that
    /// cannot be read or is malformed; `field` names the entry at fault.
    #[error("calibration file {file}: {}{reason}", if field.is_empty() { String::new() } else { format!("{field}: ") })]
    File {
        /// The file path.
        file: String,
        /// The entry at fault (e.g. `camera_matrix.data`; empty for the whole file).
        field: Location,
        /// What is wrong.
        reason: String,
    },
    /// A pose (a 4x4 homogeneous matrix) that is not a rigid motion: a non-finite entry, a
    /// last row other than `(0, 0, 0, 1)`, or a rotation block that is not orthonormal with
    /// determinant +1.
    #[error("{what}[{index}]: not a rigid transform: {reason}")]
    InvalidPose {
        /// Which input (e.g. `gripper_poses`).
        what: &'static str,
        /// The pose at fault.
        index: usize,
        /// What is wrong.
        reason: String,
    },
    /// Robot motions that do not determine the hand-eye transform (AX = XB): too few poses,
    /// no rotation, or rotations about (nearly) parallel axes only.
    #[error("degenerate hand-eye motions ({poses} poses): {reason}")]
    DegenerateMotion {
        /// The number of poses given.
        poses: usize,
        /// What is missing and how to fix it.
        reason: String,
    },
    /// An error of the core, unchanged.
    #[error(transparent)]
    Core(#[from] Error),
}

/// Shorthand for `Result<T, CalibrationError>`.
pub type Result<T, E = CalibrationError> = std::result::Result<T, E>;

impl Located for CalibrationError {
    fn core(&self) -> Option<&Error> {
        match self {
            CalibrationError::Core(e) => Some(e),
            CalibrationError::File { .. }
            | CalibrationError::InvalidPose { .. }
            | CalibrationError::DegenerateMotion { .. } => None,
        }
    }

    /// The file's entry, or the pose's argument and index; the core error's location
    /// otherwise.
    fn location(&self) -> Option<Location> {
        match self {
            CalibrationError::File { field, .. } => Some(field.clone()),
            CalibrationError::InvalidPose { what, index, .. } => Some(Location::key(*what).then_index(*index)),
            CalibrationError::DegenerateMotion { .. } => None,
            CalibrationError::Core(e) => e.location(),
        }
    }

    /// Degenerate motions, and the core's degenerate geometry.
    fn is_degenerate(&self) -> bool {
        match self {
            CalibrationError::DegenerateMotion { .. } => true,
            other => other.core().is_some_and(Error::is_degenerate),
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::{CalibrationError, Located};
    use crate::error::{Error, assert_passes_through};

    /// A core error passes through `?` with its message, location and family.
    #[test]
    fn core_errors_pass_through() {
        let err: CalibrationError = assert_passes_through(Error::NonFinitePoint { what: "K", row: 1, column: 2 });
        assert_eq!(Located::location(&err).map(|l| l.to_string()).as_deref(), Some("K[1][2]"));
        assert!(!err.is_degenerate());
        let degenerate = Error::DegenerateEstimate { what: "rotation", ratio: 0.0, hint: "no motion" };
        let err: CalibrationError = assert_passes_through(degenerate.clone());
        assert!(err.is_degenerate());
        assert_eq!(err, CalibrationError::Core(degenerate));
    }

    /// The layer's own variants: where they are and which family.
    #[test]
    fn own_variants() {
        let file =
            CalibrationError::File { file: "c.yaml".into(), field: "camera_matrix.data".into(), reason: "x".into() };
        assert_eq!(file.to_string(), "calibration file c.yaml: camera_matrix.data: x");
        assert_eq!(file.location().map(|l| l.to_string()).as_deref(), Some("camera_matrix.data"));
        let whole = CalibrationError::File { file: "c.yaml".into(), field: "".into(), reason: "empty".into() };
        assert_eq!(whole.to_string(), "calibration file c.yaml: empty");
        let pose = CalibrationError::InvalidPose { what: "gripper_poses", index: 3, reason: "r".into() };
        assert_eq!(pose.location().map(|l| l.to_string()).as_deref(), Some("gripper_poses[3]"));
        let motion = CalibrationError::DegenerateMotion { poses: 2, reason: "r".into() };
        assert!(motion.is_degenerate() && motion.location().is_none());
        assert!(!file.is_degenerate() && !pose.is_degenerate());
    }
}
