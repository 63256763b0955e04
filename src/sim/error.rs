//! The simulator's error: [`SimError`], what every function of [`crate::sim`] returns (through
//! [`Result`]). It holds the simulator's own variants (a scenario, a URDF file, a pose out of an
//! arm's reach) and wraps, unchanged, the error of each layer below that the simulator calls:
//! the core's [`enum@Error`] (with the servo session's, which are the core's), the vision
//! layer's [`VisionError`] and the calibration layer's [`CalibrationError`]. `?` converts a lower
//! error (`From`); its message, location and family pass through untouched
//! ([`Located`]).

use thiserror::Error;

use crate::calibration::CalibrationError;
use crate::error::{Error, Located, Short};
use crate::location::Location;
use crate::vision::VisionError;

/// Everything that can go wrong in the simulator.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum SimError {
    /// A scenario file or dictionary that does not describe a valid run; `key` names the
    /// offending entry (e.g. `control.gain`).
    #[error("scenario: {}{reason}", if key.is_empty() { String::new() } else { format!("{key}: ") })]
    Scenario {
        /// The key at fault (`control.gain`, `object.points[2][1]`; empty for the whole
        /// document).
        key: Location,
        /// What is wrong.
        reason: String,
    },
    /// A robot description (URDF) that cannot be read or does not describe a serial arm;
    /// `message` names the link or joint at fault.
    #[error("URDF {file}: {message}")]
    Urdf {
        /// The file path, `builtin:<name>` or `<string>`.
        file: String,
        /// What is wrong.
        message: String,
    },
    /// Inverse kinematics found no joints within the limits that reach a pose: the best
    /// residual over every seed is reported.
    #[error(
        "pose: unreachable by {arm} within its joint limits (position {} m, theta-u {} deg): the best of {seeds} seeds stops {position_residual:.3e} m and {rotation_residual:.3e} rad away",
        Triple(*position), Triple(*thetau_deg)
    )]
    Unreachable {
        /// The arm's name.
        arm: String,
        /// The target position, metres (base frame).
        position: [f64; 3],
        /// The target orientation as theta-u, degrees (base frame).
        thetau_deg: [f64; 3],
        /// The smallest position residual reached, metres.
        position_residual: f64,
        /// The rotation residual of that solution, radians.
        rotation_residual: f64,
        /// How many seeds were tried.
        seeds: usize,
    },
    /// An error of the core (or of the servo session), unchanged.
    #[error(transparent)]
    Core(#[from] Error),
    /// An error of the vision layer (images in the loop, views), unchanged.
    #[error(transparent)]
    Vision(#[from] VisionError),
    /// An error of the calibration layer (a scenario's calibration file), unchanged.
    #[error(transparent)]
    Calibration(#[from] CalibrationError),
}

/// Shorthand for `Result<T, SimError>`.
pub type Result<T, E = SimError> = std::result::Result<T, E>;

/// Three numbers as `[a, b, c]`, each printed by [`Short`] to four significant digits.
struct Triple([f64; 3]);

impl std::fmt::Display for Triple {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [a, b, c] = self.0.map(|v| Short((v * 1e4).round() / 1e4));
        write!(f, "[{a}, {b}, {c}]")
    }
}

impl Located for SimError {
    fn core(&self) -> Option<&Error> {
        match self {
            SimError::Core(e) => Some(e),
            SimError::Vision(e) => e.core(),
            SimError::Calibration(e) => e.core(),
            SimError::Scenario { .. } | SimError::Urdf { .. } | SimError::Unreachable { .. } => None,
        }
    }

    /// The scenario key of a scenario error; the lower error's location otherwise.
    fn location(&self) -> Option<Location> {
        match self {
            SimError::Scenario { key, .. } => Some(key.clone()),
            SimError::Vision(e) => e.location(),
            SimError::Calibration(e) => e.location(),
            other => other.core().and_then(Error::location),
        }
    }

    /// The lower layer's answer (degenerate hand-eye motions, the core's degenerate geometry).
    fn is_degenerate(&self) -> bool {
        match self {
            SimError::Calibration(e) => e.is_degenerate(),
            other => other.core().is_some_and(Error::is_degenerate),
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::{Located, SimError};
    use crate::calibration::CalibrationError;
    use crate::error::{Error, assert_passes_through};
    use crate::vision::VisionError;

    /// A core error passes through `?` with its message, location and family.
    #[test]
    fn core_errors_pass_through() {
        let core = Error::NonFinitePoint { what: "pixels", row: 4, column: 1 };
        let err: SimError = assert_passes_through(core.clone());
        assert_eq!(err, SimError::Core(core));
        assert_eq!(Located::location(&err).map(|l| l.to_string()).as_deref(), Some("pixels[4][1]"));
        assert!(!err.is_degenerate());
        let err: SimError = assert_passes_through(Error::DegenerateStructure { ratio: 1e-5, threshold: 1e-3 });
        assert!(err.is_degenerate() && Located::location(&err).is_none());
    }

    /// The errors of the vision and calibration layers (and the core errors they wrap) pass
    /// through `?` with their message, location and family, two layers down.
    #[test]
    fn vision_and_calibration_errors_pass_through() {
        let err: SimError = assert_passes_through(VisionError::InvalidImage {
            what: "reference".into(),
            reason: "point 2 not found".into(),
        });
        assert_eq!(err.to_string(), "reference: point 2 not found");
        assert_eq!(err.location(), Some(crate::Location::key("reference")));
        assert!(!err.is_degenerate() && err.core().is_none());
        let collinear = Error::CollinearBasis { basis: [0, 1, 2], image: "reference", ratio: 1e-9 };
        let err: SimError = assert_passes_through(VisionError::Core(collinear));
        assert!(err.is_degenerate() && err.location().is_none());
        assert!(matches!(err.core(), Some(Error::CollinearBasis { .. })));
        let motion = CalibrationError::DegenerateMotion { poses: 2, reason: "too few poses".into() };
        let err: SimError = assert_passes_through(motion.clone());
        assert_eq!(err, SimError::Calibration(motion));
        assert!(err.is_degenerate());
        let file = CalibrationError::File { file: "c.yaml".into(), field: "K.data[4]".into(), reason: "x".into() };
        let err: SimError = assert_passes_through(file);
        assert_eq!(err.location().map(|l| l.to_string()).as_deref(), Some("K.data[4]"));
        assert!(!err.is_degenerate());
    }

    /// The simulator's own variants: a scenario error is located at its key, none is
    /// degenerate.
    #[test]
    fn own_variants() {
        let err = SimError::Scenario { key: "control.gain".into(), reason: "must be > 0".into() };
        assert_eq!(err.to_string(), "scenario: control.gain: must be > 0");
        assert_eq!(err.location(), Some(crate::Location::parse("control.gain")));
        assert!(!err.is_degenerate() && err.core().is_none());
        let urdf = SimError::Urdf { file: "<string>".into(), message: "no joint".into() };
        assert!(urdf.location().is_none() && !urdf.is_degenerate());
    }
}
