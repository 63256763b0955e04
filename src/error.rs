//! The core's error type, [`enum@Error`], and what every layer's error shares ([`Located`]).
//!
//! Each layer has its own error, in its own file, and its functions return it:
//!
//! | layer | error | file |
//! |---|---|---|
//! | the control core, and the servo session (`servo`), which adds no error of its own | [`enum@Error`] | `src/error.rs` |
//! | images (`vision`) | `vision::VisionError` | `src/vision/error.rs` |
//! | calibration files and hand-eye calibration (`calibration`) | `calibration::CalibrationError` | `src/calibration/error.rs` |
//! | the simulator (`sim`, with `sim::batch`) | `sim::SimError` | `src/sim/error.rs` |
//!
//! [`enum@Error`] holds the core's variants only, whatever the features: the core speaks only of
//! its own inputs (arrays, intrinsics, parameters, the scene's geometry). A higher layer's
//! error holds that layer's own variants and wraps the error of each layer below it that it
//! calls in a transparent variant (`VisionError::Core(Error)`, `SimError::Vision(VisionError)`):
//! `?` converts a lower error (`From`), and the wrapped error's message, location and family
//! are the wrapper's. The Python bindings map any layer's error to the package's exception
//! classes through [`Located`].
//!
//! A higher layer words a core error in its own terms where it reports one (the remedy of
//! [`Error::DegenerateStructure`], see [`degenerate_structure_text`]).
//!
//! An error about one position of its input says where as data, [`Located::location`] (a
//! [`Location`]: keys and indices, the core's vocabulary), rendered in its message as
//! `control.gain`, `object.points[2][1]` or `[3].camera.fku`; Python sees it as `err.location`.

use thiserror::Error;

pub use crate::location::{Location, Step};

/// Everything that can go wrong in the control core (and the servo session): the error of
/// `vsinv` with `default-features = false`, and the one every higher layer's error wraps.
///
/// The variants fall into two families, which the Python bindings map to
/// `vsinv.InvalidInput` and `vsinv.DegenerateGeometry` (see [`Error::is_degenerate`]).
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum Error {
    /// A value is NaN or infinite.
    #[error("{what}: non-finite value at index {index}")]
    NonFinite {
        /// Which input.
        what: &'static str,
        /// Flat index of the first offending value.
        index: usize,
    },
    /// An entry of a 2-d array (points, a matrix) is NaN or infinite.
    #[error("{what}: non-finite value at row {row}, column {column}")]
    NonFinitePoint {
        /// Which input.
        what: &'static str,
        /// The point (row of the `(n, 2)` or `(n, 3)` array).
        row: usize,
        /// The coordinate (0: u, 1: v; or 0: x, 1: y, 2: z).
        column: usize,
    },
    /// An array does not have the expected size.
    #[error("{what}: expected {expected}, got {got}")]
    Shape {
        /// Which input.
        what: &'static str,
        /// What was expected, in words (e.g. "12 points").
        expected: String,
        /// What was given.
        got: String,
    },
    /// Intrinsic parameters that do not describe a camera (eq. 4).
    #[error("invalid intrinsics: {reason}")]
    InvalidIntrinsics {
        /// What is wrong.
        reason: String,
    },
    /// A tuning parameter out of its domain (gain <= 0, bad basis index, ...).
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// Not enough points for the task.
    #[error("too few points: {needed} needed ({why}), got {got}")]
    TooFewPoints {
        /// Minimum number of points.
        needed: usize,
        /// Number given.
        got: usize,
        /// Why that many are needed.
        why: &'static str,
    },
    /// The three basis points are (nearly) collinear in an image, so Q is singular.
    #[error(
        "basis points {basis:?} are collinear in the {image} image (normalised area {ratio:.3e}); choose three points well spread in the image"
    )]
    CollinearBasis {
        /// The basis indices.
        basis: [usize; 3],
        /// "current" or "reference".
        image: &'static str,
        /// Twice the triangle area divided by the square of its longest side.
        ratio: f64,
    },
    /// A point is at or behind the camera centre (depth <= 0).
    #[error("point {index} is at or behind the camera (depth {})", Short(*depth))]
    PointBehindCamera {
        /// Index of the point.
        index: usize,
        /// Its depth in metres (or the given estimate).
        depth: f64,
    },
    /// The invariant Jacobian has lost rank: planar object, equal depth estimates,
    /// or points too close to a plane (paper-corrections: planar object).
    #[error("{}", degenerate_structure_text(*ratio, *threshold, ""))]
    DegenerateStructure {
        /// sigma_5 / sigma_1 of `J_hat diag(Z, Z, Z, 1, 1)`.
        ratio: f64,
        /// The threshold that was applied.
        threshold: f64,
    },
    /// A geometric estimation without a unique answer: plane + parallax of a planar object
    /// or without translation, an epipole without motion, a resection of coplanar points.
    #[error("degenerate {what}: singular-value ratio {ratio:.3e}; {hint}")]
    DegenerateEstimate {
        /// What was being estimated.
        what: &'static str,
        /// The singular-value ratio that failed (0 when not applicable).
        ratio: f64,
        /// What usually causes it.
        hint: &'static str,
    },
    /// Lens distortion without an answer at one point: undistortion that does not converge,
    /// a pixel beyond the image of the fold (the model folds back there), or a rational model
    /// whose denominator is not positive.
    #[error("distortion: point {index}: {reason}")]
    Distortion {
        /// Index of the point.
        index: usize,
        /// What happened.
        reason: String,
    },
    /// The coefficient `a_hat` of eq. (23) vanishes (rotation about the optical axis near
    /// +-90 degrees), so the rz law (24) is undefined.
    #[error("rz law singular: a_hat = {a_hat:.3e} (rotation about the optical axis near +-90 degrees)")]
    RzSingular {
        /// The estimated coefficient.
        a_hat: f64,
    },
}

/// The message of [`Error::DegenerateStructure`]; `remedy` is a higher layer's own way to
/// pass depths, in its words, added to the core's (`"; scenario control.depths = ..."`).
pub fn degenerate_structure_text(ratio: f64, threshold: f64, remedy: &str) -> String {
    format!(
        "degenerate structure: sigma_5/sigma_1 of the depth-balanced invariant Jacobian is {ratio:.3e} (< {threshold:.1e}); the object is planar or the depth estimates are all equal, and the invariant error cannot control five dof; with a constant-depth guess, pass the reference depths zeta* or estimated depths (appendix A: depths_from_translation, ResectionDepths{remedy}) instead"
    )
}

impl Error {
    /// The message, with `remedy` (a higher layer's way to pass depths, in its words) added to
    /// the core's remedies where the error has some ([`Error::DegenerateStructure`]); the
    /// `Display` text otherwise.
    pub fn message_with_remedy(&self, remedy: &str) -> String {
        match self {
            Error::DegenerateStructure { ratio, threshold } => degenerate_structure_text(*ratio, *threshold, remedy),
            other => other.to_string(),
        }
    }

    /// Where in its input the error is, as data: the argument and its row and column
    /// (`pixels[4][1]`), the parameter (`gain`), the point of a distortion; `None` for errors
    /// about no one position (intrinsics, a collinear basis, a planar object). Its `Display` is
    /// the text the message shows. (The higher layers' errors answer for their own variants, a
    /// scenario key or a calibration file's entry, through [`Located::location`].)
    pub fn location(&self) -> Option<Location> {
        match self {
            Error::NonFinite { what, index } => Some(Location::key(*what).then_index(*index)),
            Error::NonFinitePoint { what, row, column } => {
                Some(Location::key(*what).then_index(*row).then_index(*column))
            }
            Error::Shape { what, .. } => Some(Location::key(*what)),
            Error::InvalidParameter { name, .. } => Some(Location::key(*name)),
            Error::Distortion { index, .. } => Some(Location::root().then_index(*index)),
            _ => None,
        }
    }

    /// True for errors caused by the scene geometry (collinear basis, planar object,
    /// points behind the camera, too few points, an estimate the data do not determine) rather
    /// than by malformed input. (Degenerate hand-eye motions are the calibration layer's:
    /// [`Located::is_degenerate`].)
    pub fn is_degenerate(&self) -> bool {
        matches!(
            self,
            Error::TooFewPoints { .. }
                | Error::CollinearBasis { .. }
                | Error::PointBehindCamera { .. }
                | Error::DegenerateStructure { .. }
                | Error::DegenerateEstimate { .. }
                | Error::RzSingular { .. }
        )
    }
}

/// What every layer's error tells about itself, whatever layer raised it: where in its input
/// it is and which family it belongs to. The core's [`enum@Error`] implements it, and so does the
/// error of each higher layer (`VisionError`, `CalibrationError`, `SimError`), answering for
/// its own variants and delegating to the lower error it wraps; the Python bindings map any of
/// them to the package's exception classes through it.
pub trait Located: std::error::Error {
    /// The core error this error is or wraps (through any number of layers); `None` for a
    /// layer's own variant.
    fn core(&self) -> Option<&Error>;

    /// Where in its input the error is, as data (see [`Error::location`]); `None` for errors
    /// about no one position.
    fn location(&self) -> Option<Location> {
        self.core().and_then(Error::location)
    }

    /// True for errors caused by the scene geometry rather than by malformed input (see
    /// [`Error::is_degenerate`]).
    fn is_degenerate(&self) -> bool {
        self.core().is_some_and(Error::is_degenerate)
    }
}

/// Checks that `lower` passes through `?` into the higher layer's error `E` unchanged: the same
/// message, location, family and core error (the test every layer's error runs on the errors it
/// wraps).
#[cfg(test)]
pub(crate) fn assert_passes_through<L, E>(lower: L) -> E
where
    L: Located + Clone,
    E: Located + From<L>,
{
    let through = |r: std::result::Result<(), L>| -> std::result::Result<(), E> { Ok(r?) };
    let Err(err) = through(Err(lower.clone())) else { unreachable!("an error stays an error") };
    assert_eq!(err.to_string(), lower.to_string());
    assert_eq!(err.location(), lower.location());
    assert_eq!(err.is_degenerate(), lower.is_degenerate());
    assert_eq!(err.core(), lower.core());
    err
}

impl Located for Error {
    fn core(&self) -> Option<&Error> {
        Some(self)
    }

    fn location(&self) -> Option<Location> {
        Error::location(self)
    }

    fn is_degenerate(&self) -> bool {
        Error::is_degenerate(self)
    }
}

/// A number as error messages print it: the shortest text that reads back to the same `f64`
/// for ordinary magnitudes (`0.25`, `1200`), scientific notation with four significant digits
/// for very small or very large ones (`1.0e-320`, `1.235e300`), where `{}` would print
/// hundreds of digits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Short(pub f64);

impl std::fmt::Display for Short {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let x = self.0;
        let magnitude = x.abs();
        if x == 0.0 || !x.is_finite() || (1e-3..1e15).contains(&magnitude) {
            // At most 17 significant digits after at most two zeros: no long runs.
            return write!(f, "{x}");
        }
        let text = format!("{x:.3e}");
        let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
        let mantissa = mantissa.trim_end_matches('0');
        let mantissa = if mantissa.ends_with('.') { format!("{mantissa}0") } else { mantissa.to_string() };
        write!(f, "{mantissa}e{exponent}")
    }
}

/// `value` with `decimals` decimals when that is short (|value| < 1e9), else [`Short`]: for
/// status lines and reprs that print a fixed number of decimals.
pub fn fixed_or_short(value: f64, decimals: usize) -> String {
    if value.abs() < 1e9 { format!("{value:.decimals$}") } else { Short(value).to_string() }
}

/// Shorthand for `Result<T, vsinv::Error>`.
pub type Result<T> = std::result::Result<T, Error>;

/// Checks that every value is finite.
pub(crate) fn check_finite(what: &'static str, values: &[f64]) -> Result<()> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(Error::NonFinite { what, index }),
        None => Ok(()),
    }
}

/// Checks that a nalgebra matrix (column-major storage) is finite, with the row and column
/// of the first offending entry as the user writes them.
pub(crate) fn check_finite_matrix<R: nalgebra::Dim, C: nalgebra::Dim, S: nalgebra::RawStorage<f64, R, C>>(
    what: &'static str,
    m: &nalgebra::Matrix<f64, R, C, S>,
) -> Result<()> {
    let (rows, cols) = m.shape();
    for row in 0..rows {
        for column in 0..cols {
            if !m[(row, column)].is_finite() {
                return Err(Error::NonFinitePoint { what, row, column });
            }
        }
    }
    Ok(())
}

/// Checks that pixels are finite (row and column in the error).
pub(crate) fn check_finite_points(what: &'static str, points: &[[f64; 2]]) -> Result<()> {
    check_finite_rows(what, points)
}

/// Checks that the rows of an `(n, N)` array are finite (row and column in the error).
pub(crate) fn check_finite_rows<const N: usize>(what: &'static str, rows: &[[f64; N]]) -> Result<()> {
    match rows.as_flattened().iter().position(|v| !v.is_finite()) {
        Some(i) => Err(Error::NonFinitePoint { what, row: i / N, column: i % N }),
        None => Ok(()),
    }
}

/// Fails when a result computed from finite inputs is not finite: inputs at the edge of the
/// f64 range (a pixel of 1e300, a depth of 1e-300) overflow, and the error names them
/// instead of returning inf or NaN.
#[inline]
pub(crate) fn check_overflow(inputs: &'static str, result: &str, parts: &[&[f64]]) -> Result<()> {
    // Branch-free per value (it runs on every control step): OR of the non-finite flags.
    let overflow = parts.iter().fold(false, |bad, values| values.iter().fold(bad, |bad, v| bad | !v.is_finite()));
    if !overflow {
        return Ok(());
    }
    overflow_error(inputs, result)
}

#[cold]
fn overflow_error(inputs: &'static str, result: &str) -> Result<()> {
    Err(Error::InvalidParameter {
        name: inputs,
        reason: format!("out of range: the {result} overflow (non-finite) for these values"),
    })
}

/// Checks that every depth is finite and strictly positive.
pub(crate) fn check_depths(depths: &[f64], n: usize) -> Result<()> {
    if depths.len() != n {
        return Err(Error::Shape {
            what: "depths",
            expected: format!("{n} values (one per point)"),
            got: format!("{} values", depths.len()),
        });
    }
    check_finite("depths", depths)?;
    match depths.iter().position(|&z| z <= 0.0) {
        Some(index) => Err(Error::PointBehindCamera { index, depth: depths[index] }),
        None => Ok(()),
    }
}

/// Checks the inputs of a control step: `depths` (and `visible`, if given) have one value per
/// pixel, and every point in use (all, or the visible ones) has a finite pixel and a finite
/// positive depth. Pixels and depths of hidden points are ignored.
pub(crate) fn check_step_inputs(pixels: &[[f64; 2]], depths: &[f64], visible: Option<&[bool]>) -> Result<()> {
    let n = pixels.len();
    if let Some(v) = visible
        && v.len() != n
    {
        return Err(Error::Shape {
            what: "visible",
            expected: format!("{n} flags (one per point)"),
            got: format!("{} flags", v.len()),
        });
    }
    let Some(visible) = visible else {
        check_finite_points("pixels", pixels)?;
        return check_depths(depths, n);
    };
    if depths.len() != n {
        return check_depths(depths, n);
    }
    for index in 0..n {
        if !visible[index] {
            continue;
        }
        let (p, z) = (pixels[index], depths[index]);
        if !(p[0].is_finite() && p[1].is_finite()) {
            return Err(Error::NonFinitePoint { what: "pixels", row: index, column: usize::from(p[0].is_finite()) });
        }
        if !z.is_finite() {
            return Err(Error::NonFinite { what: "depths", index });
        }
        if z <= 0.0 {
            return Err(Error::PointBehindCamera { index, depth: z });
        }
    }
    Ok(())
}

/// Checks that a parameter (a gain, a depth, a noise) is finite and positive.
pub(crate) fn check_positive(name: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidParameter { name, reason: format!("must be finite and > 0, got {}", Short(value)) })
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::{Error, Located, Short};

    /// The core words its own remedies; a layer adds its own (the scenario key) and gets the
    /// message the crate gave before the split, to the letter.
    #[test]
    fn degenerate_structure_remedy_is_the_layers() {
        let e = Error::DegenerateStructure { ratio: 2.464e-4, threshold: 1e-3 };
        let core = e.to_string();
        assert!(!core.contains("scenario") && !core.contains("control."), "{core}");
        assert!(core.ends_with("(appendix A: depths_from_translation, ResectionDepths) instead"), "{core}");
        let before = "degenerate structure: sigma_5/sigma_1 of the depth-balanced invariant Jacobian is 2.464e-4 \
                      (< 1.0e-3); the object is planar or the depth estimates are all equal, and the invariant error \
                      cannot control five dof; with a constant-depth guess, pass the reference depths zeta* or \
                      estimated depths (appendix A: depths_from_translation, ResectionDepths; scenario control.depths \
                      = \"reference\" or \"estimated\") instead";
        let layer = "; scenario control.depths = \"reference\" or \"estimated\"";
        assert_eq!(e.message_with_remedy(layer), before);
        let other = Error::RzSingular { a_hat: 1e-9 };
        assert_eq!(other.message_with_remedy(layer), other.to_string());
    }

    /// One value of every variant, named (an exhaustive match: a variant added under a
    /// feature, or only without one, fails to compile here with one feature set or the other).
    fn every_variant() -> Vec<(&'static str, Error)> {
        let all = vec![
            Error::NonFinite { what: "pixels", index: 3 },
            Error::NonFinitePoint { what: "pixels", row: 4, column: 1 },
            Error::Shape { what: "depths", expected: "12 values".into(), got: "11 values".into() },
            Error::InvalidIntrinsics { reason: "fku must be > 0".into() },
            Error::InvalidParameter { name: "gain", reason: "must be > 0".into() },
            Error::TooFewPoints { needed: 6, got: 5, why: "five dof" },
            Error::CollinearBasis { basis: [0, 1, 2], image: "current", ratio: 1e-9 },
            Error::PointBehindCamera { index: 2, depth: -0.5 },
            Error::DegenerateStructure { ratio: 1e-5, threshold: 1e-3 },
            Error::DegenerateEstimate { what: "plane", ratio: 0.0, hint: "no translation" },
            Error::Distortion { index: 7, reason: "no convergence".into() },
            Error::RzSingular { a_hat: 1e-9 },
        ];
        all.into_iter()
            .map(|e| {
                let name = match &e {
                    Error::NonFinite { .. } => "NonFinite",
                    Error::NonFinitePoint { .. } => "NonFinitePoint",
                    Error::Shape { .. } => "Shape",
                    Error::InvalidIntrinsics { .. } => "InvalidIntrinsics",
                    Error::InvalidParameter { .. } => "InvalidParameter",
                    Error::TooFewPoints { .. } => "TooFewPoints",
                    Error::CollinearBasis { .. } => "CollinearBasis",
                    Error::PointBehindCamera { .. } => "PointBehindCamera",
                    Error::DegenerateStructure { .. } => "DegenerateStructure",
                    Error::DegenerateEstimate { .. } => "DegenerateEstimate",
                    Error::Distortion { .. } => "Distortion",
                    Error::RzSingular { .. } => "RzSingular",
                };
                (name, e)
            })
            .collect()
    }

    /// The core's error has no variant of a feature (its declaration has no `cfg`), and its
    /// messages use none of a higher layer's words: scenarios, URDF files, images, calibration
    /// files, hand-eye poses are the layers' own errors.
    #[test]
    fn the_core_error_is_the_cores_alone() {
        let source = include_str!("error.rs");
        let start = source.find("pub enum Error {").unwrap_or(0);
        let end = start + source[start..].find("\n}\n").unwrap_or(0);
        assert!(end > start, "the declaration of Error");
        let declaration = &source[start..end];
        assert!(!declaration.contains("#[cfg"), "a feature-gated variant in the core's Error");
        let variants = declaration.lines().filter(|l| l.starts_with("    ") && l.trim_end().ends_with('{')).count();
        let all = every_variant();
        assert_eq!(variants, all.len(), "every_variant lists every variant");
        for (name, e) in all {
            let text = e.to_string().to_lowercase();
            for word in ["scenario", "urdf", "image:", "calibration", "hand-eye", "rigid transform", "toml"] {
                assert!(!text.contains(word), "{name}: {text}");
            }
            assert!(e.core() == Some(&e) && Located::location(&e) == e.location());
            assert_eq!(Located::is_degenerate(&e), e.is_degenerate(), "{name}");
        }
    }

    #[test]
    fn short_numbers() {
        let cases = [
            (1e-320, "1.0e-320"),
            (1e300, "1.0e300"),
            (-1.23456e300, "-1.235e300"),
            (5e-324, "4.941e-324"),
            (f64::MAX, "1.798e308"),
            (0.25, "0.25"),
            (1200.0, "1200"),
            (-0.001, "-0.001"),
            (0.0, "0"),
            (-0.0, "-0"),
            (f64::NAN, "NaN"),
            (f64::NEG_INFINITY, "-inf"),
            (1e15, "1.0e15"),
            (0.1 + 0.2, "0.30000000000000004"),
        ];
        for (x, text) in cases {
            assert_eq!(Short(x).to_string(), text, "{x:e}");
        }
        // Ordinary magnitudes read back exactly.
        for x in [0.1 + 0.2, 123456.789, 1e-3, 999999999999999.9, -7.25e-2] {
            assert_eq!(Short(x).to_string().parse::<f64>().ok(), Some(x));
        }
        assert_eq!(super::fixed_or_short(1.5, 2), "1.50");
        assert_eq!(super::fixed_or_short(-1e300, 2), "-1.0e300");
    }
}
