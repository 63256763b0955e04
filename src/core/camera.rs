//! Pinhole camera model (sec. 2.2): intrinsics (eq. 4), projection (eqs. 1-3) and the
//! interaction matrix of an image point in pixels.

use nalgebra::{Matrix2, Matrix2x6, Matrix3, Point3, Vector3};

use crate::error::{Error, Result, Short, check_finite, check_finite_matrix, check_finite_rows, check_overflow};

/// Intrinsic parameters of eq. (4): `f ku`, `f kv` (pixels), principal point `(u0, v0)`
/// (pixels) and the angle `theta` between the image axes (radians, `pi/2` for square pixels).
///
/// ```text
///     | f ku   -f ku cot(theta)   u0 |
/// K = |  0      f kv / sin(theta)  v0 |
///     |  0      0                  1  |
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intrinsics {
    fku: f64,
    fkv: f64,
    u0: f64,
    v0: f64,
    theta: f64,
}

/// The largest principal point coordinate, pixels: beyond it, normalising a pixel overflows.
pub const MAX_PRINCIPAL_POINT: f64 = 1e12;

/// The smallest angle between the image axes, radians (`theta` lies in
/// `[MIN_AXIS_ANGLE, pi - MIN_AXIS_ANGLE]`): nearer to 0 or pi, `cot(theta)` and
/// `1 / sin(theta)` make K's entries up to 1e300 times the focal terms, and every quantity
/// computed from K overflows or loses all its digits. Physical cameras have `theta` within a
/// fraction of a degree of `pi/2`; this limit (0.057 degrees) refuses only degenerate values.
pub const MIN_AXIS_ANGLE: f64 = 1e-3;

impl Intrinsics {
    /// Validated intrinsics: all finite, `fku > 0`, `fkv > 0`, `theta` within
    /// [`MIN_AXIS_ANGLE`] of neither 0 nor pi, the principal point within [`MAX_PRINCIPAL_POINT`].
    pub fn new(fku: f64, fkv: f64, u0: f64, v0: f64, theta: f64) -> Result<Self> {
        for (name, value) in [("fku", fku), ("fkv", fkv), ("u0", u0), ("v0", v0), ("skew", theta)] {
            if !value.is_finite() {
                return Err(Error::InvalidIntrinsics {
                    reason: format!("{name} must be finite, got {}", Short(value)),
                });
            }
        }
        if fku <= 0.0 || fkv <= 0.0 {
            return Err(Error::InvalidIntrinsics {
                reason: format!("focal terms must be > 0, got fku = {}, fkv = {}", Short(fku), Short(fkv)),
            });
        }
        if !(MIN_AXIS_ANGLE..=std::f64::consts::PI - MIN_AXIS_ANGLE).contains(&theta) {
            return Err(Error::InvalidIntrinsics {
                reason: format!(
                    "skew angle must be in [{MIN_AXIS_ANGLE:e}, pi - {MIN_AXIS_ANGLE:e}] rad, got {}",
                    Short(theta)
                ),
            });
        }
        for (name, value) in [("u0", u0), ("v0", v0)] {
            if value.abs() > MAX_PRINCIPAL_POINT {
                return Err(Error::InvalidIntrinsics {
                    reason: format!(
                        "{name} (principal point) must be within +-{MAX_PRINCIPAL_POINT:e} px, got {}",
                        Short(value)
                    ),
                });
            }
        }
        let k = Self { fku, fkv, u0, v0, theta };
        // Extreme values (fkv / sin(theta) or 1 / fku beyond the f64 range) give no usable K.
        if !(k.matrix().iter().chain(k.f_matrix().iter()).all(|v| v.is_finite())) {
            return Err(Error::InvalidIntrinsics {
                reason: format!(
                    "K or F(K) overflows (non-finite) for fku = {}, fkv = {}, theta = {}",
                    Short(fku),
                    Short(fkv),
                    Short(theta)
                ),
            });
        }
        Ok(k)
    }

    /// Square pixels (`theta = pi/2`).
    pub fn pinhole(fku: f64, fkv: f64, u0: f64, v0: f64) -> Result<Self> {
        Self::new(fku, fkv, u0, v0, std::f64::consts::FRAC_PI_2)
    }

    /// Reads eq. (4) back from a 3x3 matrix; the inverse of [`Intrinsics::matrix`].
    pub fn from_matrix(k: &Matrix3<f64>) -> Result<Self> {
        check_finite_matrix("K", k)?;
        if k[(1, 0)] != 0.0 || k[(2, 0)] != 0.0 || k[(2, 1)] != 0.0 || k[(2, 2)] != 1.0 {
            return Err(Error::InvalidIntrinsics {
                reason: format!(
                    "K must be upper triangular with last row (0, 0, 1), got rows [{}, {}, {}], last row ({}, {}, {})",
                    Short(k[(1, 0)]),
                    Short(k[(2, 0)]),
                    Short(k[(2, 1)]),
                    Short(k[(2, 0)]),
                    Short(k[(2, 1)]),
                    Short(k[(2, 2)])
                ),
            });
        }
        let fku = k[(0, 0)];
        if fku <= 0.0 || k[(1, 1)] <= 0.0 {
            return Err(Error::InvalidIntrinsics {
                reason: format!("K[0,0] and K[1,1] must be > 0, got {} and {}", Short(fku), Short(k[(1, 1)])),
            });
        }
        // K01 = -fku cot(theta), K11 = fkv / sin(theta).
        let theta = f64::atan2(1.0, -k[(0, 1)] / fku);
        let fkv = k[(1, 1)] * theta.sin();
        Self::new(fku, fkv, k[(0, 2)], k[(1, 2)], theta)
    }

    /// `f ku` in pixels.
    pub fn fku(&self) -> f64 {
        self.fku
    }
    /// `f kv` in pixels.
    pub fn fkv(&self) -> f64 {
        self.fkv
    }
    /// Principal point abscissa in pixels.
    pub fn u0(&self) -> f64 {
        self.u0
    }
    /// Principal point ordinate in pixels.
    pub fn v0(&self) -> f64 {
        self.v0
    }
    /// Angle between the image axes in radians.
    pub fn theta(&self) -> f64 {
        self.theta
    }

    /// The 3x3 matrix K of eq. (4).
    pub fn matrix(&self) -> Matrix3<f64> {
        let (s, cot) = self.sin_cot();
        Matrix3::new(self.fku, -self.fku * cot, self.u0, 0.0, self.fkv / s, self.v0, 0.0, 0.0, 1.0)
    }

    /// `sin(theta)` and `cot(theta)`, exact for square pixels.
    fn sin_cot(&self) -> (f64, f64) {
        if self.theta == std::f64::consts::FRAC_PI_2 {
            (1.0, 0.0)
        } else {
            let (s, c) = self.theta.sin_cos();
            (s, c / s)
        }
    }

    /// F(K) of sec. 4.1, the 2x2 factor of the rotational columns of J (finite: checked by
    /// [`Intrinsics::new`]).
    pub fn f_matrix(&self) -> Matrix2<f64> {
        f_unchecked(&self.matrix())
    }

    /// Pixel of a point given in the camera frame, with its depth (eqs. 2-3); fails for a
    /// non-finite point, a point at or behind the camera (`z <= 0`) and a pixel that overflows.
    pub fn project(&self, point: &Point3<f64>) -> Result<([f64; 2], f64)> {
        Ok((project_with(&self.matrix(), point)?, point.z))
    }

    /// Normalised coordinates `m = K^-1 p` of a pixel (x, y; the third coordinate is 1); fails
    /// for a non-finite pixel and for one so far out that `m` overflows.
    pub fn normalise(&self, pixel: [f64; 2]) -> Result<[f64; 2]> {
        check_finite("pixel", &pixel)?;
        let m = self.normalise_unchecked(pixel);
        check_overflow("pixel", "normalised coordinates", &[&m])?;
        Ok(m)
    }

    /// [`Intrinsics::normalise`] for a pixel known to be finite, without the overflow check.
    #[inline]
    pub(crate) fn normalise_unchecked(&self, pixel: [f64; 2]) -> [f64; 2] {
        let (s, cot) = self.sin_cot();
        let y = (pixel[1] - self.v0) * s / self.fkv;
        let x = (pixel[0] - self.u0 + self.fku * cot * y) / self.fku;
        [x, y]
    }
}

/// The pixel of a point in the camera frame for a matrix K (eq. 3): `K (X/Z, Y/Z, 1)`; fails
/// for a non-finite point or K, a point at or behind the camera (`z <= 0`) and a pixel that
/// overflows (a point at a tiny depth).
#[inline]
pub fn project_with(k: &Matrix3<f64>, point: &Point3<f64>) -> Result<[f64; 2]> {
    check_finite("point", point.coords.as_slice())?;
    if point.z <= 0.0 {
        let reason = format!("must be in front of the camera (z > 0), got z = {}", Short(point.z));
        return Err(Error::InvalidParameter { name: "point", reason });
    }
    let (x, y) = (point.x / point.z, point.y / point.z);
    let pixel = [k[(0, 0)] * x + k[(0, 1)] * y + k[(0, 2)], k[(1, 1)] * y + k[(1, 2)]];
    check_overflow("point, K", "pixel", &[&pixel])?;
    Ok(pixel)
}

/// Checks that a matrix has the form of eq. (4) up to signs (upper triangular, last row
/// (0, 0, 1), nonzero diagonal): estimates with negative focal terms are allowed here.
pub fn check_upper_triangular(what: &'static str, k: &Matrix3<f64>) -> Result<()> {
    check_finite_matrix(what, k)?;
    if k[(1, 0)] != 0.0 || k[(2, 0)] != 0.0 || k[(2, 1)] != 0.0 || k[(2, 2)] != 1.0 {
        return Err(Error::InvalidIntrinsics {
            reason: format!("{what} must be upper triangular with last row (0, 0, 1)"),
        });
    }
    if k[(0, 0)] == 0.0 || k[(1, 1)] == 0.0 {
        return Err(Error::InvalidIntrinsics { reason: format!("{what} is singular (zero focal term)") });
    }
    Ok(())
}

/// F(K) of sec. 4.1 written with the entries of K:
/// `F = [[sin(th)/fkv, -cos(th)/fkv], [0, 1/fku]] = [[1/K11, K01/(K00 K11)], [0, 1/K00]]`.
/// Valid for any finite upper-triangular K with a nonzero diagonal, including the
/// non-physical estimates that the stability checks explore; fails for any other K and when
/// an entry overflows (a focal term near 1e-308).
pub fn f_of_matrix(k: &Matrix3<f64>) -> Result<Matrix2<f64>> {
    check_upper_triangular("K", k)?;
    let f = f_unchecked(k);
    check_overflow("K", "entries of F(K)", &[f.as_slice()])?;
    Ok(f)
}

/// [`f_of_matrix`] without the checks, for matrices already validated.
#[inline]
pub(crate) fn f_unchecked(k: &Matrix3<f64>) -> Matrix2<f64> {
    Matrix2::new(1.0 / k[(1, 1)], k[(0, 1)] / (k[(0, 0)] * k[(1, 1)]), 0.0, 1.0 / k[(0, 0)])
}

/// Projects points given in the camera frame; fails for a point at or behind the camera.
pub fn project_points(points: &[[f64; 3]], intrinsics: &Intrinsics) -> Result<(Vec<[f64; 2]>, Vec<f64>)> {
    check_finite_rows("points", points)?;
    let mut pixels = Vec::with_capacity(points.len());
    let mut depths = Vec::with_capacity(points.len());
    for (index, p) in points.iter().enumerate() {
        if p[2] <= 0.0 {
            return Err(Error::PointBehindCamera { index, depth: p[2] });
        }
        let (pix, z) = intrinsics.project(&Point3::new(p[0], p[1], p[2])).map_err(|_| Error::InvalidParameter {
            name: "points",
            reason: format!("point {index} (row {index}) projects out of range (non-finite pixel)"),
        })?;
        pixels.push(pix);
        depths.push(z);
    }
    Ok((pixels, depths))
}

/// Pixel interaction matrices of all points (validated pixels, positive depths).
pub fn pixel_interactions(pixels: &[[f64; 2]], depths: &[f64], intrinsics: &Intrinsics) -> Result<Vec<Matrix2x6<f64>>> {
    crate::error::check_finite_points("pixels", pixels)?;
    crate::error::check_depths(depths, pixels.len())?;
    let k = intrinsics.matrix();
    let k_inv = k.try_inverse().ok_or_else(|| Error::InvalidIntrinsics { reason: "K is singular".into() })?;
    let ls: Vec<Matrix2x6<f64>> =
        pixels.iter().zip(depths).map(|(&p, &z)| pixel_interaction_unchecked(&k, &k_inv, p, z)).collect();
    let entries: Vec<&[f64]> = ls.iter().map(|l| l.as_slice()).collect();
    check_overflow("pixels, depths", "interaction matrices", &entries)?;
    Ok(ls)
}

/// Interaction matrix of an image point in normalised coordinates (Espiau et al. 1992):
/// `d(x, y)/dt = L (v, w)` for the camera twist in the camera frame. Fails for a non-finite
/// point, a depth that is not finite and > 0, and entries that overflow (a depth near 1e-308,
/// coordinates beyond 1e154).
#[inline]
pub fn normalised_interaction(x: f64, y: f64, depth: f64) -> Result<Matrix2x6<f64>> {
    check_finite("x, y", &[x, y])?;
    crate::error::check_positive("depth", depth)?;
    let l = normalised_interaction_unchecked(x, y, depth);
    check_overflow("x, y, depth", "interaction matrix", &[l.as_slice()])?;
    Ok(l)
}

/// [`normalised_interaction`] for inputs the caller has validated (no checks).
#[inline]
pub(crate) fn normalised_interaction_unchecked(x: f64, y: f64, depth: f64) -> Matrix2x6<f64> {
    let iz = 1.0 / depth;
    Matrix2x6::new(-iz, 0.0, x * iz, x * y, -(1.0 + x * x), y, 0.0, -iz, y * iz, 1.0 + y * y, -x * y, -x)
}

/// Interaction matrix of a pixel `p = K m`: the first two rows of `L_k` in sec. 4.1
/// (its third row is zero): `dp/dt = K[0..2, 0..2] L(m, depth) (v, w)`. Fails as
/// [`normalised_interaction`] does, and for a pixel whose normalised coordinates overflow.
#[inline]
pub fn pixel_interaction(
    k: &Matrix3<f64>,
    k_inv: &Matrix3<f64>,
    pixel: [f64; 2],
    depth: f64,
) -> Result<Matrix2x6<f64>> {
    check_finite("pixel", &pixel)?;
    let m = k_inv * Vector3::new(pixel[0], pixel[1], 1.0);
    let l = k.fixed_view::<2, 2>(0, 0) * normalised_interaction(m.x, m.y, depth)?;
    check_overflow("pixel, depth, K", "interaction matrix", &[l.as_slice()])?;
    Ok(l)
}

/// [`pixel_interaction`] for inputs the caller has validated: the controllers and Jacobians
/// check pixels and depths first and the overflow of their result after.
#[inline]
pub(crate) fn pixel_interaction_unchecked(
    k: &Matrix3<f64>,
    k_inv: &Matrix3<f64>,
    pixel: [f64; 2],
    depth: f64,
) -> Matrix2x6<f64> {
    let m = k_inv * Vector3::new(pixel[0], pixel[1], 1.0);
    k.fixed_view::<2, 2>(0, 0) * normalised_interaction_unchecked(m.x, m.y, depth)
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn matrix_round_trip_with_skew() {
        let k = Intrinsics::new(1200.0, 1100.0, 390.0, 280.0, 1.4).unwrap();
        let back = Intrinsics::from_matrix(&k.matrix()).unwrap();
        assert_relative_eq!(back.fku(), 1200.0, max_relative = 1e-12);
        assert_relative_eq!(back.fkv(), 1100.0, max_relative = 1e-12);
        assert_relative_eq!(back.theta(), 1.4, max_relative = 1e-12);
        assert_relative_eq!(back.u0(), 390.0);
        assert_relative_eq!(back.v0(), 280.0);
    }

    #[test]
    fn rejects_bad_intrinsics() {
        assert!(Intrinsics::new(-1.0, 1.0, 0.0, 0.0, 1.5).is_err());
        assert!(Intrinsics::new(1.0, 0.0, 0.0, 0.0, 1.5).is_err());
        assert!(Intrinsics::new(1.0, 1.0, f64::NAN, 0.0, 1.5).is_err());
        assert!(Intrinsics::new(1.0, 1.0, 0.0, 0.0, 0.0).is_err());
        assert!(Intrinsics::new(1.0, 1.0, 0.0, 0.0, std::f64::consts::PI).is_err());
        let mut k = Intrinsics::pinhole(1.0, 1.0, 0.0, 0.0).unwrap().matrix();
        k[(2, 2)] = 2.0;
        assert!(Intrinsics::from_matrix(&k).is_err());
    }

    #[test]
    fn f_matrix_matches_eq4_form() {
        let k = Intrinsics::new(900.0, 1300.0, 10.0, 20.0, 1.2).unwrap();
        let (s, c) = k.theta().sin_cos();
        let expected = Matrix2::new(s / k.fkv(), -c / k.fkv(), 0.0, 1.0 / k.fku());
        assert_relative_eq!(k.f_matrix(), expected, max_relative = 1e-12);
    }

    #[test]
    fn normalise_inverts_k() {
        let k = Intrinsics::new(900.0, 1300.0, 10.0, 20.0, 1.2).unwrap();
        let m = k.normalise([300.0, -40.0]).unwrap();
        let p = k.matrix() * Vector3::new(m[0], m[1], 1.0);
        assert_relative_eq!(p.x, 300.0, max_relative = 1e-12);
        assert_relative_eq!(p.y, -40.0, max_relative = 1e-12);
    }

    #[test]
    fn pixel_interaction_matches_finite_differences() {
        use crate::core::se3::exp_twist;
        let k = Intrinsics::new(800.0, 750.0, 320.0, 240.0, 1.45).unwrap();
        let km = k.matrix();
        let kinv = km.try_inverse().unwrap();
        let x = Point3::new(0.1, -0.05, 0.7);
        let (p0, z) = k.project(&x).unwrap();
        let l = pixel_interaction(&km, &kinv, p0, z).unwrap();
        let h = 1e-6;
        for j in 0..6 {
            let mut tw = [0.0; 6];
            tw[j] = h;
            let plus = exp_twist(&tw).unwrap().inverse() * x;
            tw[j] = -h;
            let minus = exp_twist(&tw).unwrap().inverse() * x;
            let (pp, _) = k.project(&plus).unwrap();
            let (pm, _) = k.project(&minus).unwrap();
            for r in 0..2 {
                let fd = (pp[r] - pm[r]) / (2.0 * h);
                assert!(
                    (fd - l[(r, j)]).abs() < 1e-4 * (1.0 + l[(r, j)].abs()),
                    "col {j} row {r}: {fd} vs {}",
                    l[(r, j)]
                );
            }
        }
    }

    /// Regression (issue 16): a skew angle of 1e-300 gave K entries of 1e300; zero depth gave
    /// non-finite pixels and interaction matrices.
    #[test]
    fn degenerate_skew_zero_depth_and_overflow_are_errors() {
        for theta in [1e-300, 1e-4, std::f64::consts::PI - 1e-4] {
            assert!(Intrinsics::new(800.0, 800.0, 0.0, 0.0, theta).is_err(), "{theta}");
        }
        let k = Intrinsics::new(800.0, 800.0, 0.0, 0.0, MIN_AXIS_ANGLE).unwrap();
        assert!(k.matrix().iter().all(|v| v.is_finite() && v.abs() < 1e7));
        let k = Intrinsics::pinhole(800.0, 800.0, 320.0, 240.0).unwrap();
        for z in [0.0, -1.0, f64::NAN] {
            assert!(k.project(&Point3::new(0.1, 0.2, z)).is_err(), "{z}");
            assert!(normalised_interaction(0.1, 0.2, z).is_err(), "{z}");
            let km = k.matrix();
            assert!(pixel_interaction(&km, &km.try_inverse().unwrap(), [1.0, 2.0], z).is_err());
        }
        assert!(k.project(&Point3::new(1.0, 0.0, 1e-320)).is_err());
        assert!(normalised_interaction(0.1, 0.2, 1e-320).is_err());
        assert!(normalised_interaction(1e200, 0.0, 1.0).is_err());
        assert!(project_with(&k.matrix(), &Point3::new(f64::NAN, 0.0, 1.0)).is_err());
        let tiny = Intrinsics::pinhole(1e-150, 1e-150, 0.0, 0.0).unwrap();
        assert!(tiny.normalise([1e200, 1e200]).is_err());
        assert!(tiny.normalise([1.0, 1.0]).is_ok_and(|m| m == [1e150, 1e150]));
        assert!(k.normalise([f64::INFINITY, 0.0]).is_err());
        let mut singular = k.matrix();
        singular[(0, 0)] = 0.0;
        assert!(f_of_matrix(&singular).is_err());
        singular[(0, 0)] = 1e-300;
        singular[(1, 1)] = 1e-300;
        assert!(f_of_matrix(&singular).is_err());
        assert_eq!(f_of_matrix(&k.matrix()).unwrap(), k.f_matrix());
    }
}
