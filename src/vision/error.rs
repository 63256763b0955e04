//! The vision layer's error: [`VisionError`], what every function of [`crate::vision`]
//! returns (through [`Result`]). It holds the layer's own variant (an image that cannot be
//! used) and wraps, unchanged, the error of the layers below (the core's [`enum@Error`], which the
//! servo session also returns). `?` converts a lower error (`From`); its message, location and
//! family pass through untouched ([`Located`]).

use thiserror::Error;

use crate::error::{Error, Located};
use crate::location::Location;

/// Everything that can go wrong with images: rendering, detection, tracking, files.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum VisionError {
    /// An image that cannot be used: wrong size, empty, unreadable file, nothing to detect.
    #[error("{what}: {reason}")]
    InvalidImage {
        /// Which image (argument name or file path).
        what: String,
        /// What is wrong.
        reason: String,
    },
    /// An error of the core (or of the servo session), unchanged.
    #[error(transparent)]
    Core(#[from] Error),
}

/// Shorthand for `Result<T, VisionError>`.
pub type Result<T, E = VisionError> = std::result::Result<T, E>;

impl Located for VisionError {
    fn core(&self) -> Option<&Error> {
        match self {
            VisionError::Core(e) => Some(e),
            VisionError::InvalidImage { .. } => None,
        }
    }

    /// The image's argument (or file path) for an image error; the core error's location
    /// otherwise.
    fn location(&self) -> Option<Location> {
        match self {
            VisionError::InvalidImage { what, .. } => Some(Location::key(what.as_str())),
            other => other.core().and_then(Error::location),
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::{Located, VisionError};
    use crate::error::{Error, assert_passes_through};

    /// A core error passes through `?` with its message, location and family.
    #[test]
    fn core_errors_pass_through() {
        let err: VisionError = assert_passes_through(Error::NonFinite { what: "pixels", index: 3 });
        assert_eq!(Located::location(&err).map(|l| l.to_string()).as_deref(), Some("pixels[3]"));
        assert!(!err.is_degenerate());
        let degenerate = Error::CollinearBasis { basis: [0, 1, 2], image: "current", ratio: 1e-9 };
        let err: VisionError = assert_passes_through(degenerate.clone());
        assert!(err.is_degenerate());
        assert_eq!(err, VisionError::Core(degenerate));
    }

    /// The layer's own variant is located at the image's argument and is not degenerate.
    #[test]
    fn invalid_image() {
        let err = VisionError::InvalidImage { what: "reference".into(), reason: "point 2 not found".into() };
        assert_eq!(err.to_string(), "reference: point 2 not found");
        assert_eq!(err.location(), Some(crate::Location::key("reference")));
        assert!(!err.is_degenerate() && err.core().is_none());
    }
}
