//! Lens distortion: OpenCV's Brown-Conrady model (`plumb_bob` in ROS), its rational
//! model (`rational_polynomial`) and its fisheye model (`equidistant`, Kannala-Brandt, module
//! [`fisheye`] for its formula and range), with the coefficients in
//! OpenCV's order.
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
//! The fisheye model maps `m` to `m_d = (theta_d / r) m` with `theta = atan(r)`; rays at 90
//! degrees from the axis and beyond have no `m`, and only [`distort_rays`] and
//! [`undistort_rays`] express them.
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
//! and [`undistort_points`] names it in an [`Error::Distortion`]. The fisheye model is
//! undistorted by Newton's method on the angle `theta` instead (one unknown), within its range.

use nalgebra::{Matrix2, Vector2};

use crate::core::camera::Intrinsics;
use crate::core::fisheye;
use crate::error::{Error, Result, Short, check_finite, check_finite_points, check_finite_rows, check_overflow};

/// The distortion models OpenCV and ROS share.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DistortionModel {
    /// Brown-Conrady, `(k1, k2, p1, p2, k3)`: ROS's `plumb_bob`, OpenCV's 4 or 5 coefficients.
    PlumbBob,
    /// OpenCV's rational model, `(k1, k2, p1, p2, k3, k4, k5, k6)`: ROS's `rational_polynomial`.
    RationalPolynomial,
    /// OpenCV's fisheye model (Kannala-Brandt, `cv2.fisheye`), `(k1, k2, k3, k4)`:
    /// ROS's `equidistant`.
    Equidistant,
}

impl DistortionModel {
    /// The ROS name: `plumb_bob`, `rational_polynomial` or `equidistant`.
    pub fn name(self) -> &'static str {
        match self {
            DistortionModel::PlumbBob => "plumb_bob",
            DistortionModel::RationalPolynomial => "rational_polynomial",
            DistortionModel::Equidistant => "equidistant",
        }
    }

    /// The model of a ROS name, `None` for any other.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "plumb_bob" => Some(DistortionModel::PlumbBob),
            "rational_polynomial" => Some(DistortionModel::RationalPolynomial),
            "equidistant" => Some(DistortionModel::Equidistant),
            _ => None,
        }
    }

    /// The names [`DistortionModel::from_name`] knows, for error messages.
    pub const NAMES: &'static str = "\"plumb_bob\", \"rational_polynomial\" or \"equidistant\"";

    /// The number of coefficients the model has: 5, 8 or 4.
    pub fn len(self) -> usize {
        match self {
            DistortionModel::PlumbBob => 5,
            DistortionModel::RationalPolynomial => 8,
            DistortionModel::Equidistant => 4,
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
    /// `(k1, k2, p1, p2, k3, k4, k5, k6)`, the last three zero for `plumb_bob`;
    /// `(k1, k2, k3, k4, 0, 0, 0, 0)` for `equidistant`.
    c: [f64; 8],
    /// The fisheye model's range (module [`fisheye`]), 90 degrees for
    /// the others (in radians).
    max_angle: f64,
}

impl Default for Distortion {
    fn default() -> Self {
        Self::none()
    }
}

impl Distortion {
    /// No distortion (`plumb_bob` with all coefficients zero).
    pub fn none() -> Self {
        Self { model: DistortionModel::PlumbBob, c: [0.0; 8], max_angle: std::f64::consts::FRAC_PI_2 }
    }

    /// Coefficients in OpenCV's order, of a length OpenCV accepts for these models:
    /// 4 `(k1, k2, p1, p2)` and 5 (`+ k3`) give `plumb_bob`, 8 (`+ k4, k5, k6`) gives
    /// `rational_polynomial`. Other lengths (12 and 14 are OpenCV's thin-prism and tilted
    /// models, not supported here) and non-finite values are errors. The fisheye model's 4
    /// coefficients are told from `plumb_bob`'s by its name: [`Distortion::with_model`].
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

    /// Coefficients for a given model: `plumb_bob` takes 4 or 5, `rational_polynomial` 8,
    /// `equidistant` 4 `(k1, k2, k3, k4)`.
    pub fn with_model(model: DistortionModel, coefficients: &[f64]) -> Result<Self> {
        let n = coefficients.len();
        let want = match model {
            DistortionModel::PlumbBob => "4 or 5",
            DistortionModel::RationalPolynomial => "8",
            DistortionModel::Equidistant => "4 (k1, k2, k3, k4)",
        };
        let ok = match model {
            DistortionModel::PlumbBob => n == 4 || n == 5,
            DistortionModel::RationalPolynomial => n == 8,
            DistortionModel::Equidistant => n == 4,
        };
        if !ok {
            return Err(Error::InvalidParameter {
                name: "distortion coefficients",
                reason: format!("the {} model takes {want} values, got {n}", model.name()),
            });
        }
        check_finite("distortion coefficients", coefficients)?;
        let mut c = [0.0; 8];
        c[..n].copy_from_slice(coefficients);
        let max_angle = match model {
            DistortionModel::Equidistant => fisheye::max_angle(&[c[0], c[1], c[2], c[3]]),
            _ => std::f64::consts::FRAC_PI_2,
        };
        Ok(Self { model, c, max_angle })
    }

    /// The largest angle from the optical axis (radians) the model images one-to-one, not
    /// included: for `equidistant` its fold or 180 degrees, whichever comes first (module
    /// [`fisheye`]); 90 degrees for the others, whose normalised
    /// coordinates cover the half-space in front of the camera (and whose fold depends on the
    /// direction, checked point by point).
    pub fn max_angle(&self) -> f64 {
        self.max_angle
    }

    /// The fisheye coefficients `(k1, k2, k3, k4)`.
    #[inline]
    fn kb(&self) -> [f64; 4] {
        [self.c[0], self.c[1], self.c[2], self.c[3]]
    }

    /// True for the fisheye model.
    #[inline]
    fn is_fisheye(&self) -> bool {
        self.model == DistortionModel::Equidistant
    }

    /// The model.
    pub fn model(&self) -> DistortionModel {
        self.model
    }

    /// The coefficients in OpenCV's order: 5 for `plumb_bob` (`k3` = 0 when 4 were given),
    /// 8 for `rational_polynomial`, 4 for `equidistant`.
    pub fn coefficients(&self) -> &[f64] {
        &self.c[..self.model.len()]
    }

    /// True when the lens is a pinhole: every coefficient zero, and not the fisheye model
    /// (which with zero coefficients is the equidistant projection `theta_d = theta`).
    pub fn is_identity(&self) -> bool {
        !self.is_fisheye() && self.c.iter().all(|&v| v == 0.0)
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
    /// and where `d(m)` overflows (`|m|` beyond about 1e50 with a nonzero `k3`, 1e154 in any
    /// case). The fisheye model never overflows, and is evaluated here beyond its fold too
    /// ([`Distortion::distort_valid`] is `None` there).
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
        if self.is_fisheye() {
            let (s, _) = self.fisheye_scales(m);
            return [s * m[0], s * m[1]];
        }
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
    /// The model folds where its determinant is <= 0. For `equidistant`, with `u = m / r`,
    /// `s = theta_d / r` and `theta_d' = d theta_d / d theta`:
    ///
    /// ```text
    /// J = s (I - u u^T) + theta_d' / (1 + r^2) u u^T      (J = I at m = 0)
    /// ```
    ///
    /// whose determinant `s theta_d' / (1 + r^2)` is <= 0 from the fold on. Fails for a
    /// non-finite `m` and where an entry overflows.
    pub fn jacobian(&self, m: [f64; 2]) -> Result<Matrix2<f64>> {
        check_finite("m", &m)?;
        let j = self.jacobian_unchecked(m);
        check_overflow("m", "distortion Jacobian", &[j.as_slice()])?;
        Ok(j)
    }

    /// [`Distortion::jacobian`] without the checks.
    #[inline]
    pub(crate) fn jacobian_unchecked(&self, m: [f64; 2]) -> Matrix2<f64> {
        if self.is_fisheye() {
            let (s, radial) = self.fisheye_scales(m);
            let r = m[0].hypot(m[1]);
            let (ux, uy) = if r > 0.0 { (m[0] / r, m[1] / r) } else { (0.0, 0.0) };
            let g = radial - s;
            return Matrix2::new(s + g * ux * ux, g * ux * uy, g * ux * uy, s + g * uy * uy);
        }
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
    /// The fisheye model's scales at `m`: the tangential `s = theta_d / r` and the radial
    /// `d theta_d / d r = theta_d'(theta) / (1 + r^2)` (both 1 at `m = 0`).
    #[inline]
    fn fisheye_scales(&self, m: [f64; 2]) -> (f64, f64) {
        let k = self.kb();
        let r = m[0].hypot(m[1]);
        let theta = r.atan();
        // atan(r) / r is accurate for any r > 0: no cancellation.
        let over_r = if r > 0.0 { theta / r } else { 1.0 };
        let t2 = theta * theta;
        let s = over_r * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
        (s, fisheye::theta_d_slope(&k, theta) / (1.0 + r * r))
    }

    /// True where the model is one-to-one at `m` (the rational model's denominator and the
    /// Jacobian determinant positive; the fisheye's angle below its range).
    #[inline]
    fn regular(&self, m: [f64; 2]) -> bool {
        if self.is_fisheye() {
            return m[0].hypot(m[1]).atan() < self.max_angle;
        }
        let (_, _, den) = self.radial(m[0] * m[0] + m[1] * m[1]);
        den > 0.0 && self.jacobian_unchecked(m).determinant() > 0.0
    }

    /// `d(m)` where `m` lies on the principal point's side of the model's fold: the rational
    /// model's denominator and the Jacobian determinant positive at `m` and at 32 points of
    /// the segment from the origin to `m` (past a fold the determinant can turn positive
    /// again). `None` beyond the fold, where a lens does not image the point where the
    /// model says, and for a non-finite `m` or `d(m)` (an overflow): `Some` is always finite.
    /// The fisheye model: `Some` where `atan |m|` is below [`Distortion::max_angle`].
    #[inline]
    pub fn distort_valid(&self, m: [f64; 2]) -> Option<[f64; 2]> {
        if !(m[0].is_finite() && m[1].is_finite()) {
            return None;
        }
        if self.is_identity() {
            return Some(m);
        }
        if self.is_fisheye() {
            return self.regular(m).then(|| self.distort_unchecked(m));
        }
        let regular = |s: f64| self.regular([s * m[0], s * m[1]]);
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
/// Fails for a non-finite pixel, for a point where the rational model's denominator
/// `1 + k4 r^2 + k5 r^4 + k6 r^6` is not positive (the model is undefined there), and for a
/// point at or beyond the fisheye model's fold ([`Distortion::max_angle`]). For the fisheye
/// model and zero skew this is `cv2.fisheye.distortPoints` of the points `K^-1 p`.
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
            if distortion.is_fisheye() && !distortion.regular(m) {
                return Err(Error::Distortion { index, reason: beyond_range(m[0].hypot(m[1]).atan(), distortion) });
            }
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

/// Why a ray at `theta` (radians) from the axis has no fisheye image.
fn beyond_range(theta: f64, d: &Distortion) -> String {
    let what = if d.max_angle() < std::f64::consts::PI { "the equidistant model's fold" } else { "180 degrees" };
    format!(
        "the ray is {:.4} deg from the optical axis, at or beyond {what} at {:.4} deg: the lens does not image it",
        theta.to_degrees(),
        d.max_angle().to_degrees()
    )
}

/// The distorted pixels of rays `(X, Y, Z)` in the camera frame (any length but zero): for
/// the fisheye model `K m_d` with `m_d = theta_d (X, Y) / sqrt(X^2 + Y^2)` (module
/// [`fisheye`]), which images rays beyond 90 degrees from the axis
/// where its range reaches; for the others `K d(X/Z, Y/Z)`, which needs `Z > 0`.
///
/// Errors: [`Error::Distortion`] naming the first ray at or beyond [`Distortion::max_angle`]
/// (the fisheye's fold or 180 degrees; `Z <= 0` or beyond the fold for the others) or whose
/// pixel overflows; [`Error::NonFinitePoint`] for a non-finite ray, [`Error::InvalidParameter`]
/// for a zero one.
pub fn distort_rays(rays: &[[f64; 3]], intrinsics: &Intrinsics, distortion: &Distortion) -> Result<Vec<[f64; 2]>> {
    check_finite_rows("rays", rays)?;
    let k = intrinsics.matrix();
    rays.iter()
        .enumerate()
        .map(|(index, &[x, y, z])| {
            let rho = x.hypot(y);
            if rho == 0.0 && z == 0.0 {
                return Err(Error::InvalidParameter { name: "rays", reason: format!("ray {index} is zero") });
            }
            let theta = rho.atan2(z);
            let md = if distortion.is_fisheye() {
                if !(theta < distortion.max_angle()) {
                    return Err(Error::Distortion { index, reason: beyond_range(theta, distortion) });
                }
                let td = fisheye::theta_d(&distortion.kb(), theta);
                if rho > 0.0 { [td * x / rho, td * y / rho] } else { [0.0, 0.0] }
            } else {
                let m = if z > 0.0 { Some([x / z, y / z]) } else { None };
                m.and_then(|m| distortion.distort_valid(m)).ok_or_else(|| Error::Distortion {
                    index,
                    reason: format!(
                        "the ray is {:.4} deg from the optical axis: the {} model images rays in front of the camera (Z > 0) on the principal point's side of its fold only",
                        theta.to_degrees(),
                        distortion.model().name()
                    ),
                })?
            };
            let p = to_pixel(&k, md);
            if !(p[0].is_finite() && p[1].is_finite()) {
                return Err(Error::Distortion { index, reason: "the distorted pixel overflows (non-finite)".into() });
            }
            Ok(p)
        })
        .collect()
}

/// The unit rays `(X, Y, Z)` of distorted pixels, the inverse of [`distort_rays`]: for the
/// fisheye model Newton's method on `theta` (module [`fisheye`]),
/// which gives rays beyond 90 degrees (`Z < 0`) where the range reaches; for the others
/// [`undistort_points`]' normalised point `m`, as `(m, 1) / |(m, 1)|`.
///
/// Errors as [`undistort_points`]: [`Error::Distortion`] naming the first pixel beyond the
/// image of the fold (or of 180 degrees) or that does not converge in `max_iter` iterations.
pub fn undistort_rays(
    pixels: &[[f64; 2]],
    intrinsics: &Intrinsics,
    distortion: &Distortion,
    tol: f64,
    max_iter: usize,
) -> Result<Vec<[f64; 3]>> {
    if !distortion.is_fisheye() {
        let ideal = undistort_points(pixels, intrinsics, distortion, tol, max_iter)?;
        return Ok(ideal
            .iter()
            .map(|&p| {
                let [x, y] = intrinsics.normalise_unchecked(p);
                let n = (x * x + y * y + 1.0).sqrt();
                [x / n, y / n, 1.0 / n]
            })
            .collect());
    }
    check_undistort_args(pixels, tol, max_iter)?;
    let k = distortion.kb();
    pixels
        .iter()
        .enumerate()
        .map(|(index, &p)| {
            let md = intrinsics.normalise_unchecked(p);
            let rd = md[0].hypot(md[1]);
            let theta = fisheye::solve_theta(&k, distortion.max_angle(), rd, max_iter)
                .map_err(|reason| Error::Distortion { index, reason })?;
            let (sin, cos) = theta.sin_cos();
            let u = if rd > 0.0 { [md[0] / rd, md[1] / rd] } else { [0.0, 0.0] };
            Ok([sin * u[0], sin * u[1], cos])
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
    check_undistort_args(pixels, tol, max_iter)?;
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

/// The pixels finite, `tol` finite and > 0, `max_iter` >= 1.
fn check_undistort_args(pixels: &[[f64; 2]], tol: f64, max_iter: usize) -> Result<()> {
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
    Ok(())
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
    if d.is_fisheye() {
        return undistort_fisheye(k, k2, d, target, tol, max_iter);
    }
    let valid = |m: [f64; 2]| d.regular(m);
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

/// [`undistort_one`] for the fisheye model: `theta` by Newton's method, then
/// `m = tan(theta) m_d / |m_d|`, checked against `tol` (pixels) by distorting it back.
fn undistort_fisheye(
    k: &nalgebra::Matrix3<f64>,
    k2: &Matrix2<f64>,
    d: &Distortion,
    target: [f64; 2],
    tol: f64,
    max_iter: usize,
) -> std::result::Result<[f64; 2], String> {
    let rd = target[0].hypot(target[1]);
    let theta = fisheye::solve_theta(&d.kb(), d.max_angle(), rd, max_iter)?;
    if !(theta < std::f64::consts::FRAC_PI_2) {
        return Err(format!(
            "the ray is {:.4} deg from the optical axis (>= 90): behind the image plane, it has no pinhole pixel (undistort_rays gives it as a ray)",
            theta.to_degrees()
        ));
    }
    let scale = if rd > 0.0 { theta.tan() / rd } else { 1.0 };
    let m = [scale * target[0], scale * target[1]];
    let (_, err) = residual(d, k2, m, target);
    if !(err <= tol) {
        return Err(format!("the residual {err:.3e} px is above tol {tol:.1e} after Newton's method on theta"));
    }
    let p = to_pixel(k, m);
    if !(p[0].is_finite() && p[1].is_finite()) {
        return Err("the undistorted pixel overflows (non-finite): the ray is at 90 degrees from the axis".into());
    }
    Ok(p)
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    fn barrel() -> Distortion {
        Distortion::from_coefficients(&[-0.35, 0.12, 0.001, -0.0015, -0.02]).unwrap()
    }
    /// A fisheye of about 190 degrees (a real lens's size of coefficients), without a fold
    /// before 180 degrees.
    fn fisheye() -> Distortion {
        Distortion::with_model(DistortionModel::Equidistant, &[-0.02, 0.004, -0.0006, 0.00004]).unwrap()
    }
    /// A fisheye whose fold is at sqrt(1 / 0.3) rad = 104.6 degrees.
    fn folding_fisheye() -> Distortion {
        Distortion::with_model(DistortionModel::Equidistant, &[-0.1, 0.0, 0.0, 0.0]).unwrap()
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
        assert_eq!(DistortionModel::from_name("equidistant"), Some(DistortionModel::Equidistant));
        assert_eq!(DistortionModel::from_name("fisheye"), None);
        assert_eq!(fisheye().coefficients(), &[-0.02, 0.004, -0.0006, 0.00004]);
        for n in [3, 5, 8] {
            assert!(matches!(
                Distortion::with_model(DistortionModel::Equidistant, &vec![0.0; n]),
                Err(Error::InvalidParameter { .. })
            ));
        }
        assert!(matches!(
            Distortion::with_model(DistortionModel::Equidistant, &[0.0, 0.0, f64::NAN, 0.0]),
            Err(Error::NonFinite { index: 2, .. })
        ));
        // Zero coefficients are the equidistant projection, not a pinhole.
        let equi = Distortion::with_model(DistortionModel::Equidistant, &[0.0; 4]).unwrap();
        assert!(!equi.is_identity());
        assert!((equi.distort([1.0, 0.0]).unwrap()[0] - std::f64::consts::FRAC_PI_4).abs() < 1e-15);
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let h = 1e-6;
        let near = [[0.3, -0.2], [-0.5, 0.4], [0.05, 0.6], [0.0, 0.0]];
        let wide = [[0.3, -0.2], [-0.5, 0.4], [0.05, 0.6], [0.0, 0.0], [1e-7, -2e-7], [2.5, -1.5], [-8.0, 3.0]];
        for (d, points) in [(barrel(), &near[..]), (rational(), &near), (fisheye(), &wide), (folding_fisheye(), &wide)]
        {
            for &m in points {
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
            for d in [barrel(), rational(), Distortion::none(), fisheye(), folding_fisheye()] {
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

    #[test]
    fn fisheye_rays_beyond_ninety_degrees_round_trip() {
        let k = Intrinsics::new(300.0, 310.0, 640.0, 480.0, 1.5).unwrap();
        for d in [fisheye(), folding_fisheye()] {
            let rays: Vec<[f64; 3]> = (0..400)
                .map(|i| {
                    let theta = d.max_angle() * 0.9999 * f64::from(i) / 400.0;
                    let phi = f64::from(i) * 2.4;
                    [theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()]
                })
                .collect();
            let px = distort_rays(&rays, &k, &d).unwrap();
            let back = undistort_rays(&px, &k, &d, 1e-10, 50).unwrap();
            for (a, b) in rays.iter().zip(&back) {
                assert!((0..3).all(|c| (a[c] - b[c]).abs() < 1e-12), "{a:?} vs {b:?}");
            }
        }
        // Beyond 90 degrees there is a ray but no pinhole pixel.
        let d = fisheye();
        let behind = distort_rays(&[[1.0, 0.0, -0.2]], &k, &d).unwrap();
        match undistort_points(&behind, &k, &d, 1e-10, 50) {
            Err(Error::Distortion { index: 0, reason }) => assert!(reason.contains("behind"), "{reason}"),
            other => panic!("{other:?}"),
        }
        // Pinhole models: rays in front only.
        assert!(matches!(distort_rays(&[[0.1, 0.0, -1.0]], &k, &barrel()), Err(Error::Distortion { index: 0, .. })));
        let front = distort_rays(&[[0.1, 0.2, 1.0]], &k, &barrel()).unwrap();
        let ray = undistort_rays(&front, &k, &barrel(), 1e-10, 50).unwrap()[0];
        assert!((ray[0] / ray[2] - 0.1).abs() < 1e-12 && (ray[1] / ray[2] - 0.2).abs() < 1e-12);
        assert!(matches!(distort_rays(&[[0.0, 0.0, 0.0]], &k, &d), Err(Error::InvalidParameter { name: "rays", .. })));
    }

    #[test]
    fn fisheye_fold_is_an_error_naming_the_point() {
        let k = Intrinsics::pinhole(300.0, 300.0, 320.0, 240.0).unwrap();
        let d = folding_fisheye();
        let fold = (1.0f64 / 0.3).sqrt();
        assert!((d.max_angle() - fold).abs() < 1e-12);
        let ray = |t: f64| [t.sin(), 0.0, t.cos()];
        match distort_rays(&[ray(0.5), ray(fold + 1e-6)], &k, &d) {
            Err(Error::Distortion { index: 1, reason }) => assert!(reason.contains("fold"), "{reason}"),
            other => panic!("{other:?}"),
        }
        // A pixel beyond the image of the fold has no ray.
        let edge = fisheye::theta_d(&[-0.1, 0.0, 0.0, 0.0], fold);
        let far = [[320.0, 240.0], [320.0 + 300.0 * edge * 1.001, 240.0]];
        match undistort_rays(&far, &k, &d, 1e-10, 50) {
            Err(Error::Distortion { index: 1, reason }) => assert!(reason.contains("fold"), "{reason}"),
            other => panic!("{other:?}"),
        }
        // In normalised coordinates the fold is beyond 90 degrees here: every m is valid.
        assert!(d.distort_valid([1e6, 0.0]).is_some());
        // A fold before 90 degrees: k1 = -0.2 folds at sqrt(1 / 0.6) rad = 73.97 degrees.
        let d = Distortion::with_model(DistortionModel::Equidistant, &[-0.2, 0.0, 0.0, 0.0]).unwrap();
        assert!(d.distort_valid([3.4, 0.0]).is_some() && d.distort_valid([3.5, 0.0]).is_none());
        match distort_points(&[[320.0, 240.0], [320.0 + 1200.0, 240.0]], &k, &d) {
            Err(Error::Distortion { index: 1, reason }) => assert!(reason.contains("fold"), "{reason}"),
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
