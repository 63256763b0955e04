//! Lens distortion: OpenCV's Brown-Conrady model (`plumb_bob` in ROS) and its rational
//! model (`rational_polynomial`), with the coefficients in OpenCV's order.
//!
//! The distortion acts on normalised coordinates `m = (x, y)`, with `r^2 = x^2 + y^2`:
//!
//! ```text
//!          1 + k1 r^2 + k2 r^4 + k3 r^6
//! c(r^2) = ----------------------------          (denominator 1 for plumb_bob)
//!          1 + k4 r^2 + k5 r^4 + k6 r^6
//!
//! x_d = x c + 2 p1 x y + p2 (r^2 + 2 x^2)
//! y_d = y c + p1 (r^2 + 2 y^2) + 2 p2 x y
//! ```
//!
//! Pixels map through the full K of eq. (4), skew included: a pixel `p` of the ideal pinhole
//! image has `m = K^-1 p`, and its distorted pixel is `p_d = K d(m)`. With zero skew this is
//! `cv2.projectPoints` (whose camera matrix has no skew term); with skew the distortion still
//! applies in normalised coordinates, and only the last step uses `K[0,1]`.
//!
//! Undistortion solves `d(m) = K^-1 p_d` for `m` by Newton's method with the analytic
//! Jacobian of [`Distortion::jacobian`], damped so that every iterate keeps a positive
//! Jacobian determinant: the answer is the pre-image on the origin's side of the fold, the
//! one a physical lens produces. A pixel beyond the image of the fold has no such pre-image,
//! and [`undistort_points`] names it in an [`Error::Distortion`].

use nalgebra::{Matrix2, Vector2};

use crate::core::camera::Intrinsics;
use crate::error::{Error, Result, Short, check_finite, check_finite_points, check_overflow};

/// The distortion models OpenCV and ROS share.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DistortionModel {
    /// Brown-Conrady, `(k1, k2, p1, p2, k3)`: ROS's `plumb_bob`, OpenCV's 4 or 5 coefficients.
    PlumbBob,
    /// OpenCV's rational model, `(k1, k2, p1, p2, k3, k4, k5, k6)`: ROS's `rational_polynomial`.
    RationalPolynomial,
}

impl DistortionModel {
    /// The ROS name: `plumb_bob` or `rational_polynomial`.
    pub fn name(self) -> &'static str {
        match self {
            DistortionModel::PlumbBob => "plumb_bob",
            DistortionModel::RationalPolynomial => "rational_polynomial",
        }
    }

    /// The model of a ROS name, `None` for any other (`equidistant`, ...).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "plumb_bob" => Some(DistortionModel::PlumbBob),
            "rational_polynomial" => Some(DistortionModel::RationalPolynomial),
            _ => None,
        }
    }

    /// The number of coefficients the model has: 5 or 8.
    pub fn len(self) -> usize {
        match self {
            DistortionModel::PlumbBob => 5,
            DistortionModel::RationalPolynomial => 8,
        }
    }

    /// Always false: a model has coefficients (for clippy's `len_without_is_empty`).
    pub fn is_empty(self) -> bool {
        false
    }
}

/// Distortion coefficients of one of the [`DistortionModel`]s (module docs for the formulas).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Distortion {
    model: DistortionModel,
    /// `(k1, k2, p1, p2, k3, k4, k5, k6)`, the last three zero for `plumb_bob`.
    c: [f64; 8],
}

impl Default for Distortion {
    fn default() -> Self {
        Self::none()
    }
}

impl Distortion {
    /// No distortion (`plumb_bob` with all coefficients zero).
    pub fn none() -> Self {
        Self { model: DistortionModel::PlumbBob, c: [0.0; 8] }
    }

    /// Coefficients in OpenCV's order, of a length OpenCV accepts for these models:
    /// 4 `(k1, k2, p1, p2)` and 5 (`+ k3`) give `plumb_bob`, 8 (`+ k4, k5, k6`) gives
    /// `rational_polynomial`. Other lengths (12 and 14 are OpenCV's thin-prism and tilted
    /// models, not supported here) and non-finite values are errors.
    pub fn from_coefficients(coefficients: &[f64]) -> Result<Self> {
        let model = match coefficients.len() {
            4 | 5 => DistortionModel::PlumbBob,
            8 => DistortionModel::RationalPolynomial,
            n => {
                return Err(Error::InvalidParameter {
                    name: "distortion coefficients",
                    reason: format!(
                        "expected 4 or 5 (plumb_bob: k1, k2, p1, p2[, k3]) or 8 (rational_polynomial: k1, k2, p1, p2, k3, k4, k5, k6) values, got {n}"
                    ),
                });
            }
        };
        Self::with_model(model, coefficients)
    }

    /// Coefficients for a given model: `plumb_bob` takes 4 or 5, `rational_polynomial` 8.
    pub fn with_model(model: DistortionModel, coefficients: &[f64]) -> Result<Self> {
        let n = coefficients.len();
        let ok = match model {
            DistortionModel::PlumbBob => n == 4 || n == 5,
            DistortionModel::RationalPolynomial => n == 8,
        };
        if !ok {
            let want = if model == DistortionModel::PlumbBob { "4 or 5" } else { "8" };
            return Err(Error::InvalidParameter {
                name: "distortion coefficients",
                reason: format!("the {} model takes {want} values, got {n}", model.name()),
            });
        }
        check_finite("distortion coefficients", coefficients)?;
        let mut c = [0.0; 8];
        c[..n].copy_from_slice(coefficients);
        Ok(Self { model, c })
    }

    /// The model.
    pub fn model(&self) -> DistortionModel {
        self.model
    }

    /// The coefficients in OpenCV's order: 5 for `plumb_bob` (`k3` = 0 when 4 were given),
    /// 8 for `rational_polynomial`.
    pub fn coefficients(&self) -> &[f64] {
        &self.c[..self.model.len()]
    }

    /// True when every coefficient is zero.
    pub fn is_identity(&self) -> bool {
        self.c.iter().all(|&v| v == 0.0)
    }

    /// The radial factor `c(r^2)`, its derivative `dc/d(r^2)` and the denominator
    /// `1 + k4 r^2 + k5 r^4 + k6 r^6`.
    #[inline]
    fn radial(&self, r2: f64) -> (f64, f64, f64) {
        let [k1, k2, _, _, k3, k4, k5, k6] = self.c;
        let a = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
        let da = k1 + r2 * (2.0 * k2 + 3.0 * r2 * k3);
        let b = 1.0 + r2 * (k4 + r2 * (k5 + r2 * k6));
        let db = k4 + r2 * (2.0 * k5 + 3.0 * r2 * k6);
        (a / b, (da * b - a * db) / (b * b), b)
    }

    /// The distorted normalised coordinates `d(m)` (module docs); fails for a non-finite `m`
    /// and where `d(m)` overflows (`|m|` beyond about 1e50 with a nonzero `k3`, 1e154 in any case).
    pub fn distort(&self, m: [f64; 2]) -> Result<[f64; 2]> {
        check_finite("m", &m)?;
        if self.is_identity() {
            return Ok(m);
        }
        let d = self.distort_unchecked(m);
        check_overflow("m", "distorted coordinates", &[&d])?;
        Ok(d)
    }

    /// [`Distortion::distort`] without the checks.
    #[inline]
    pub(crate) fn distort_unchecked(&self, m: [f64; 2]) -> [f64; 2] {
        let [x, y] = m;
        let [_, _, p1, p2, ..] = self.c;
        let r2 = x * x + y * y;
        let (c, _, _) = self.radial(r2);
        [x * c + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x), y * c + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y]
    }

    /// The Jacobian `dd/dm` at `m`, with `c' = dc/d(r^2)`:
    ///
    /// ```text
    /// | c + 2 x^2 c' + 2 p1 y + 6 p2 x     2 x y c' + 2 p1 x + 2 p2 y  |
    /// | 2 x y c' + 2 p1 x + 2 p2 y         c + 2 y^2 c' + 6 p1 y + 2 p2 x |
    /// ```
    ///
    /// The model folds where its determinant is <= 0. Fails for a non-finite `m` and where an
    /// entry overflows.
    pub fn jacobian(&self, m: [f64; 2]) -> Result<Matrix2<f64>> {
        check_finite("m", &m)?;
        let j = self.jacobian_unchecked(m);
        check_overflow("m", "distortion Jacobian", &[j.as_slice()])?;
        Ok(j)
    }

    /// [`Distortion::jacobian`] without the checks.
    #[inline]
    pub(crate) fn jacobian_unchecked(&self, m: [f64; 2]) -> Matrix2<f64> {
        let [x, y] = m;
        let [_, _, p1, p2, ..] = self.c;
        let (c, dc, _) = self.radial(x * x + y * y);
        let off = 2.0 * x * y * dc + 2.0 * p1 * x + 2.0 * p2 * y;
        Matrix2::new(
            c + 2.0 * x * x * dc + 2.0 * p1 * y + 6.0 * p2 * x,
            off,
            off,
            c + 2.0 * y * y * dc + 6.0 * p1 * y + 2.0 * p2 * x,
        )
    }
}

impl Distortion {
    /// `d(m)` where `m` lies on the principal point's side of the model's fold: the rational
    /// model's denominator and the Jacobian determinant positive at `m` and at 32 points of
    /// the segment from the origin to `m` (past a fold the determinant can turn positive
    /// again). `None` beyond the fold, where a lens does not image the point where the
    /// model says, and for a non-finite `m` or `d(m)` (an overflow): `Some` is always finite.
    #[inline]
    pub fn distort_valid(&self, m: [f64; 2]) -> Option<[f64; 2]> {
        if !(m[0].is_finite() && m[1].is_finite()) {
            return None;
        }
        if self.is_identity() {
            return Some(m);
        }
        let regular = |s: f64| {
            let p = [s * m[0], s * m[1]];
            let (_, _, den) = self.radial(p[0] * p[0] + p[1] * p[1]);
            den > 0.0 && self.jacobian_unchecked(p).determinant() > 0.0
        };
        let d = (1..=32).all(|i| regular(f64::from(i) / 32.0)).then(|| self.distort_unchecked(m))?;
        (d[0].is_finite() && d[1].is_finite()).then_some(d)
    }
}

/// The distorted pixel `K d(m)` of normalised coordinates `m` (`None` beyond the fold, see
/// [`Distortion::distort_valid`], and where the pixel overflows: `Some` is always finite).
#[inline]
pub fn distort_normalised(m: [f64; 2], intrinsics: &Intrinsics, distortion: &Distortion) -> Option<[f64; 2]> {
    let p = to_pixel(&intrinsics.matrix(), distortion.distort_valid(m)?);
    (p[0].is_finite() && p[1].is_finite()).then_some(p)
}

/// One pixel of [`undistort_points`] with the default tolerance and iteration cap.
pub fn undistort_point(pixel: [f64; 2], intrinsics: &Intrinsics, distortion: &Distortion) -> Result<[f64; 2]> {
    if distortion.is_identity() {
        return Ok(pixel);
    }
    let k = intrinsics.matrix();
    let k2 = k.fixed_view::<2, 2>(0, 0).into_owned();
    undistort_one(&k, &k2, intrinsics, distortion, pixel, DEFAULT_UNDISTORT_TOL, DEFAULT_UNDISTORT_MAX_ITER)
        .map_err(|reason| Error::Distortion { index: 0, reason })
}

/// `K m` for normalised coordinates `m`.
#[inline]
fn to_pixel(k: &nalgebra::Matrix3<f64>, m: [f64; 2]) -> [f64; 2] {
    [k[(0, 0)] * m[0] + k[(0, 1)] * m[1] + k[(0, 2)], k[(1, 1)] * m[1] + k[(1, 2)]]
}

/// Distorts pixels of the ideal pinhole image: `p_d = K d(K^-1 p)` (module docs). With zero
/// skew this is what `cv2.projectPoints` returns for the points `(K^-1 p)` at depth 1.
/// Fails for a non-finite pixel, and for a point where the rational model's denominator
/// `1 + k4 r^2 + k5 r^4 + k6 r^6` is not positive (the model is undefined there).
pub fn distort_points(pixels: &[[f64; 2]], intrinsics: &Intrinsics, distortion: &Distortion) -> Result<Vec<[f64; 2]>> {
    check_finite_points("pixels", pixels)?;
    if distortion.is_identity() {
        return Ok(pixels.to_vec());
    }
    let k = intrinsics.matrix();
    pixels
        .iter()
        .enumerate()
        .map(|(index, &p)| {
            let m = intrinsics.normalise_unchecked(p);
            let (_, _, den) = distortion.radial(m[0] * m[0] + m[1] * m[1]);
            if !(den > 0.0) {
                return Err(Error::Distortion {
                    index,
                    reason: format!("the rational model's denominator is {den:.3e} <= 0 at this point"),
                });
            }
            let p = to_pixel(&k, distortion.distort_unchecked(m));
            if !(p[0].is_finite() && p[1].is_finite()) {
                return Err(Error::Distortion { index, reason: "the distorted pixel overflows (non-finite)".into() });
            }
            Ok(p)
        })
        .collect()
}

/// Default pixel tolerance of [`undistort_points`].
pub const DEFAULT_UNDISTORT_TOL: f64 = 1e-10;
/// Default iteration cap of [`undistort_points`].
pub const DEFAULT_UNDISTORT_MAX_ITER: usize = 50;
/// Newton steps in a row that do not lower the residual before undistortion gives up.
const STALLED_STEPS: usize = 8;
/// A residual this small (pixels) that no longer decreases is rounding error.
const ROUNDING_PX: f64 = 1e-6;

/// Undistorts pixels: the inverse of [`distort_points`], `p = K m` with `d(m) = K^-1 p_d`.
///
/// Newton's method from `m = K^-1 p_d`, `m <- m - t J(m)^-1 (d(m) - K^-1 p_d)`, with `t`
/// halved until the iterate keeps `det J > 0` and does not increase the residual; it stops
/// when the residual `|K d(m) - p_d|` (max norm, pixels) is at most `tol`, after one more
/// full Newton step that takes the answer to rounding error.
///
/// Errors: [`Error::Distortion`] naming the first point whose residual is still above `tol`
/// after `max_iter` iterations, or for which no step can keep `det J > 0` (the pixel lies
/// beyond the image of the fold, where the model folds back); [`Error::InvalidParameter`]
/// for `tol <= 0` or `max_iter == 0`; [`Error::NonFinite`] for a non-finite pixel. The work
/// is bounded whatever `max_iter`: it stops when a step no longer lowers the residual.
pub fn undistort_points(
    pixels: &[[f64; 2]],
    intrinsics: &Intrinsics,
    distortion: &Distortion,
    tol: f64,
    max_iter: usize,
) -> Result<Vec<[f64; 2]>> {
    check_finite_points("pixels", pixels)?;
    if !(tol > 0.0) || !tol.is_finite() {
        return Err(Error::InvalidParameter {
            name: "tol",
            reason: format!(
                "must be finite and > 0 pixels (the residual stops at rounding error, about 1e-13 px, so 0 is never met), got {}",
                Short(tol)
            ),
        });
    }
    if max_iter == 0 {
        return Err(Error::InvalidParameter { name: "max_iter", reason: "must be >= 1".into() });
    }
    let k = intrinsics.matrix();
    let k2 = k.fixed_view::<2, 2>(0, 0).into_owned();
    pixels
        .iter()
        .enumerate()
        .map(|(index, &p)| {
            undistort_one(&k, &k2, intrinsics, distortion, p, tol, max_iter)
                .map_err(|reason| Error::Distortion { index, reason })
        })
        .collect()
}

/// Residual in normalised coordinates and its max norm in pixels (infinite where the model
/// is undefined or folds).
#[inline]
fn residual(d: &Distortion, k2: &Matrix2<f64>, m: [f64; 2], target: [f64; 2]) -> (Vector2<f64>, f64) {
    let dm = d.distort_unchecked(m);
    let r = Vector2::new(dm[0] - target[0], dm[1] - target[1]);
    let px = k2 * r;
    let norm = px.x.abs().max(px.y.abs());
    (r, if norm.is_finite() { norm } else { f64::INFINITY })
}

#[allow(clippy::too_many_arguments)]
fn undistort_one(
    k: &nalgebra::Matrix3<f64>,
    k2: &Matrix2<f64>,
    intrinsics: &Intrinsics,
    d: &Distortion,
    p: [f64; 2],
    tol: f64,
    max_iter: usize,
) -> std::result::Result<[f64; 2], String> {
    let target = intrinsics.normalise_unchecked(p);
    if d.is_identity() {
        return Ok(p);
    }
    let valid = |m: [f64; 2]| {
        let (_, _, den) = d.radial(m[0] * m[0] + m[1] * m[1]);
        den > 0.0 && d.jacobian_unchecked(m).determinant() > 0.0
    };
    // Start at the distorted point, moved towards the origin (where J = I) if the model folds there.
    let mut m = target;
    let mut shrink = 0;
    while !valid(m) {
        shrink += 1;
        if shrink > 60 {
            return Err("the model folds on the whole segment from the principal point to this pixel".into());
        }
        m = [m[0] * 0.5, m[1] * 0.5];
    }
    let (mut r, mut err) = residual(d, k2, m, target);
    // Within tolerance: one more full Newton step (kept if it does not increase the residual)
    // takes the answer to rounding error at the price of one iteration.
    let polish = |m: [f64; 2], r: Vector2<f64>, err: f64| {
        let Some(step) = d.jacobian_unchecked(m).try_inverse().map(|ji| ji * r) else { return m };
        let cand = [m[0] - step.x, m[1] - step.y];
        if valid(cand) && residual(d, k2, cand, target).1 <= err { cand } else { m }
    };
    let mut stalled = 0;
    for _ in 0..max_iter {
        if err <= tol {
            return Ok(to_pixel(k, polish(m, r, err)));
        }
        let j = d.jacobian_unchecked(m);
        let Some(step) = j.try_inverse().map(|ji| ji * r) else {
            return Err(format!("the distortion Jacobian is singular at ({}, {})", Short(m[0]), Short(m[1])));
        };
        let mut t = 1.0;
        let mut accepted = false;
        let before = err;
        for _ in 0..60 {
            let cand = [m[0] - t * step.x, m[1] - t * step.y];
            if valid(cand) {
                let (rc, ec) = residual(d, k2, cand, target);
                if ec <= err {
                    (m, r, err) = (cand, rc, ec);
                    accepted = true;
                    break;
                }
            }
            t *= 0.5;
        }
        // Steps that no longer lower the residual: at rounding error, or stuck at the fold.
        // A few in a row end the work, whatever `max_iter`.
        stalled = if accepted && !(err < before) { stalled + 1 } else { 0 };
        if stalled >= STALLED_STEPS && err <= ROUNDING_PX {
            return Err(format!(
                "the residual stopped decreasing at {err:.3e} px (rounding error), above tol {tol:.1e}"
            ));
        }
        if !accepted || stalled >= STALLED_STEPS {
            return Err(format!(
                "the model folds: no pre-image with a positive Jacobian determinant (residual {err:.3e} px at the fold); the pixel lies beyond the image of the fold, det J = {:.3e}",
                d.jacobian_unchecked(m).determinant()
            ));
        }
    }
    if err <= tol {
        return Ok(to_pixel(k, polish(m, r, err)));
    }
    Err(format!("did not converge in {max_iter} iterations (residual {err:.3e} px > tol {tol:.1e})"))
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    fn barrel() -> Distortion {
        Distortion::from_coefficients(&[-0.35, 0.12, 0.001, -0.0015, -0.02]).unwrap()
    }
    fn rational() -> Distortion {
        Distortion::from_coefficients(&[0.8, -0.2, 0.0008, 0.0012, 0.05, 1.1, 0.05, 0.01]).unwrap()
    }

    #[test]
    fn coefficient_lengths_and_values() {
        assert_eq!(Distortion::from_coefficients(&[0.1, 0.0, 0.0, 0.0]).unwrap().coefficients().len(), 5);
        assert_eq!(rational().model(), DistortionModel::RationalPolynomial);
        assert_eq!(rational().coefficients().len(), 8);
        for n in [0, 1, 3, 6, 7, 12, 14] {
            assert!(matches!(Distortion::from_coefficients(&vec![0.0; n]), Err(Error::InvalidParameter { .. })));
        }
        assert!(matches!(
            Distortion::from_coefficients(&[0.1, f64::NAN, 0.0, 0.0, 0.0]),
            Err(Error::NonFinite { index: 1, .. })
        ));
        assert!(Distortion::with_model(DistortionModel::RationalPolynomial, &[0.0; 5]).is_err());
        assert_eq!(DistortionModel::from_name("plumb_bob"), Some(DistortionModel::PlumbBob));
        assert_eq!(DistortionModel::from_name("equidistant"), None);
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let h = 1e-6;
        for d in [barrel(), rational()] {
            for m in [[0.3, -0.2], [-0.5, 0.4], [0.05, 0.6], [0.0, 0.0]] {
                let j = d.jacobian(m).unwrap();
                for c in 0..2 {
                    let (mut a, mut b) = (m, m);
                    a[c] += h;
                    b[c] -= h;
                    let (da, db) = (d.distort(a).unwrap(), d.distort(b).unwrap());
                    for r in 0..2 {
                        let fd = (da[r] - db[r]) / (2.0 * h);
                        assert!((fd - j[(r, c)]).abs() < 1e-8, "{m:?} ({r}, {c}): {fd} vs {}", j[(r, c)]);
                    }
                }
            }
        }
    }

    #[test]
    fn round_trips_with_and_without_skew() {
        for k in [
            Intrinsics::pinhole(800.0, 780.0, 320.0, 240.0).unwrap(),
            Intrinsics::new(800.0, 780.0, 330.0, 250.0, 1.3).unwrap(),
        ] {
            for d in [barrel(), rational(), Distortion::none()] {
                let pixels: Vec<[f64; 2]> = (0..200)
                    .map(|i| {
                        let a = i as f64 * 0.37;
                        let r = 330.0 * (i as f64 / 200.0);
                        [320.0 + r * a.cos(), 240.0 + 0.75 * r * a.sin()]
                    })
                    .collect();
                let dist = distort_points(&pixels, &k, &d).unwrap();
                let back = undistort_points(&dist, &k, &d, 1e-11, 50).unwrap();
                for (p, q) in pixels.iter().zip(&back) {
                    assert!((p[0] - q[0]).abs() < 1e-9 && (p[1] - q[1]).abs() < 1e-9, "{p:?} vs {q:?}");
                }
            }
        }
    }

    #[test]
    fn skew_applies_in_normalised_coordinates() {
        let k = Intrinsics::new(800.0, 780.0, 330.0, 250.0, 1.3).unwrap();
        let d = barrel();
        let p = [500.0, 100.0];
        let m = k.normalise(p).unwrap();
        let md = d.distort(m).unwrap();
        let km = k.matrix();
        let expected = km * nalgebra::Vector3::new(md[0], md[1], 1.0);
        let got = distort_points(&[p], &k, &d).unwrap()[0];
        assert!((got[0] - expected.x).abs() < 1e-9 && (got[1] - expected.y).abs() < 1e-9);
        assert!(km[(0, 1)] != 0.0);
    }

    #[test]
    fn beyond_the_fold_is_an_error_naming_the_point() {
        // k1 = -0.4: r_d = r (1 - 0.4 r^2) peaks at r = 0.913, r_d = 0.609.
        let k = Intrinsics::pinhole(500.0, 500.0, 320.0, 240.0).unwrap();
        let d = Distortion::from_coefficients(&[-0.4, 0.0, 0.0, 0.0]).unwrap();
        let pixels = [[320.0, 240.0], [320.0 + 0.5 * 500.0, 240.0], [320.0 + 0.7 * 500.0, 240.0]];
        match undistort_points(&pixels, &k, &d, 1e-10, 50) {
            Err(Error::Distortion { index, reason }) => {
                assert_eq!(index, 2);
                assert!(reason.contains("folds"), "{reason}");
            }
            other => panic!("{other:?}"),
        }
        assert!(undistort_points(&pixels[..2], &k, &d, 1e-10, 50).is_ok());
        assert!(matches!(undistort_points(&pixels, &k, &d, 1e-10, 0), Err(Error::InvalidParameter { .. })));
        assert!(matches!(undistort_points(&pixels, &k, &d, -1.0, 5), Err(Error::InvalidParameter { .. })));
    }

    #[test]
    fn non_convergence_is_reported() {
        let k = Intrinsics::pinhole(500.0, 500.0, 320.0, 240.0).unwrap();
        let d = barrel();
        match undistort_points(&[[600.0, 400.0]], &k, &d, 1e-12, 1) {
            Err(Error::Distortion { index: 0, reason }) => assert!(reason.contains("converge"), "{reason}"),
            other => panic!("{other:?}"),
        }
    }

    /// Regression (issue 16): `distort` of huge points returned inf or NaN without an error.
    #[test]
    fn huge_points_are_errors_or_none() {
        let d = Distortion::from_coefficients(&[1.0, 0.5, 0.0, 0.0, 0.1]).unwrap();
        let k = Intrinsics::pinhole(800.0, 800.0, 320.0, 240.0).unwrap();
        for m in [[1e150, 0.0], [1e60, 1e60], [f64::NAN, 0.0], [0.0, f64::INFINITY]] {
            assert!(d.distort(m).is_err(), "{m:?}");
            assert!(d.distort_valid(m).is_none(), "{m:?}");
            assert!(distort_normalised(m, &k, &d).is_none(), "{m:?}");
        }
        assert!(d.jacobian([1e200, 0.0]).is_err());
        assert!(d.jacobian([f64::NAN, 0.0]).is_err());
        assert!(Distortion::none().distort([1e300, 1e300]).is_ok_and(|v| v == [1e300, 1e300]));
        assert_eq!(d.distort([0.1, 0.2]).unwrap(), d.distort_valid([0.1, 0.2]).unwrap());
    }
}
