//! Depth estimation up to scale without calibration (appendix A, correction 10).
//!
//! Off line, two images of the object related by an unknown pure translation, taken with
//! any camera, give the depths `zeta^I` of the first image up to one scale (eq. 26). Then
//! `X'_k = zeta^I_k p^I_k` is a reconstruction of the object up to an unknown linear map,
//! and at every iteration a DLT resection of the current camera against it gives the current
//! depths as the third row of `P (X'_k, 1)`, up to the scale of P. Holding `|det P[:, :3]|` at
//! its value for the reference image makes that scale `kappa(t) = kappa_ref (det K* /
//! det K(t))^(1/3) > 0`.

use nalgebra::{DMatrix, Matrix3, Matrix3x4, Vector3, Vector4};

use crate::error::{Error, Result, Short, check_finite_points, check_finite_rows, check_overflow, check_positive};

/// Below this ratio of singular values a resection or an epipole counts as degenerate.
const DEGENERATE: f64 = 1e-10;

/// Depths of the first image of a pure-translation pair, up to one positive scale.
#[derive(Debug, Clone, PartialEq)]
pub struct TranslationDepths {
    /// `zeta^I_k`, scaled to a mean of 1 over the usable points (NaN where not usable).
    pub depths: Vec<f64>,
    /// The epipole `e = K_bar t` (homogeneous pixels, unit norm).
    pub epipole: Vector3<f64>,
    /// RMS residual of eq. (26) in pixels (homogeneous, first two coordinates), over the
    /// usable points.
    pub residual: f64,
    /// Each point's distance from its epipolar line ([`epipolar_residual`], pixels).
    pub residuals: Vec<f64>,
    /// Whether each point's depth is usable; `depths` is NaN where it is not (robust estimate
    /// only: [`depths_from_translation`] marks every point usable or fails).
    pub usable: Vec<bool>,
}

pub(crate) const EPIPOLE: (&str, &str) =
    ("epipole of the translation pair (eq. 26)", "the camera did not move, or all points lie on one line");
const RESECTION: (&str, &str) = ("resection (DLT)", "the visible points are coplanar or fewer than 6");

pub(crate) fn degenerate((what, hint): (&'static str, &'static str), ratio: f64) -> Error {
    Error::DegenerateEstimate { what, ratio, hint }
}

pub(crate) fn homog(p: [f64; 2]) -> Vector3<f64> {
    Vector3::new(p[0], p[1], 1.0)
}

/// Hartley normalisation of 2D points: centroid to 0, mean distance sqrt(2).
pub(crate) fn normalise_2d(points: &[[f64; 2]]) -> Matrix3<f64> {
    let n = points.len() as f64;
    let (cx, cy) = points.iter().fold((0.0, 0.0), |(x, y), p| (x + p[0] / n, y + p[1] / n));
    let mean = points.iter().map(|p| (p[0] - cx).hypot(p[1] - cy)).sum::<f64>() / n;
    let s = if mean > 0.0 { std::f64::consts::SQRT_2 / mean } else { 1.0 };
    Matrix3::new(s, 0.0, -s * cx, 0.0, s, -s * cy, 0.0, 0.0, 1.0)
}

/// Eq. (26): from the two images of a pure translation (any camera), the depths of the
/// points in the first image up to one positive scale. The epipole is the least-squares
/// common point of the lines through `p^I_k` and `p^II_k`: exact pixels only (one bad track
/// pulls it; with tracked keypoints use
/// [`robust_depths_from_translation`](crate::core::robust_depth::robust_depths_from_translation)).
pub fn depths_from_translation(first: &[[f64; 2]], second: &[[f64; 2]]) -> Result<TranslationDepths> {
    check_pair(first, second, 3)?;
    let n = first.len();
    let e = epipole_least_squares(first, second)?;
    // p^I = a p^II + b e with b = |e| / zeta^I (eq. 26): depths ~ 1 / b.
    let mut inv_depth = Vec::with_capacity(n);
    let mut err2 = 0.0;
    for k in 0..n {
        let (b, r2) = inverse_depth(first[k], second[k], &e)?;
        err2 += r2;
        inv_depth.push(b);
    }
    let sign = inv_depth.iter().sum::<f64>().signum();
    if let Some(index) = inv_depth.iter().position(|&b| !(b * sign > 0.0)) {
        return Err(Error::InvalidParameter {
            name: "depth_estimation",
            reason: format!(
                "point {index} shows no parallax of the right sign: the two images are not related by a \
                 translation with every point in front of both cameras"
            ),
        });
    }
    let depths: Vec<f64> = inv_depth.iter().map(|b| 1.0 / (b * sign)).collect();
    let mean = depths.iter().sum::<f64>() / n as f64;
    Ok(TranslationDepths {
        depths: depths.iter().map(|d| d / mean).collect(),
        epipole: e,
        residual: (err2 / n as f64).sqrt(),
        residuals: (0..n).map(|k| epipolar_residual(first[k], second[k], &e)).collect(),
        usable: vec![true; n],
    })
}

/// The shapes and values of a translation pair: finite, as many points in both, at least `needed`.
pub(crate) fn check_pair(first: &[[f64; 2]], second: &[[f64; 2]], needed: usize) -> Result<()> {
    check_finite_points("first image", first)?;
    check_finite_points("second image", second)?;
    let n = first.len();
    if second.len() != n {
        return Err(Error::Shape {
            what: "second image",
            expected: format!("{n} points"),
            got: format!("{}", second.len()),
        });
    }
    if n < needed {
        return Err(Error::TooFewPoints { needed, got: n, why: "the epipole of a translation needs several points" });
    }
    Ok(())
}

/// The least-squares common point (unit norm, homogeneous pixels) of the lines through
/// `p^I_k` and `p^II_k`, in Hartley-normalised coordinates.
pub(crate) fn epipole_least_squares(first: &[[f64; 2]], second: &[[f64; 2]]) -> Result<Vector3<f64>> {
    let n = first.len();
    let all: Vec<[f64; 2]> = first.iter().chain(second).copied().collect();
    let t = normalise_2d(&all);
    let mut lines = DMatrix::zeros(n.max(3), 3);
    for k in 0..n {
        let l = (t * homog(first[k])).cross(&(t * homog(second[k])));
        let norm = l.norm();
        if norm > 0.0 {
            lines.row_mut(k).copy_from(&(l / norm).transpose());
        }
    }
    check_overflow("first image, second image", "normalised epipolar lines", &[lines.as_slice()])?;
    let svd = lines.svd(false, true);
    let v_t = svd.v_t.as_ref().ok_or(degenerate(EPIPOLE, 0.0))?;
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
    let ratio = svd.singular_values[order[1]] / svd.singular_values[order[0]].max(f64::MIN_POSITIVE);
    if !(ratio > DEGENERATE) {
        // All lines through one line of points, or no motion at all.
        return Err(degenerate(EPIPOLE, ratio));
    }
    let e_n = Vector3::from_iterator(v_t.row(order[2]).iter().copied());
    let t_inv = t.try_inverse().ok_or(degenerate(EPIPOLE, 0.0))?;
    Ok((t_inv * e_n).normalize())
}

/// Eq. (26) for one point: `p^I = a p^II + b e` by least squares; returns `b` (proportional
/// to `1 / zeta^I_k`) and the squared residual (homogeneous pixels).
pub(crate) fn inverse_depth(first: [f64; 2], second: [f64; 2], e: &Vector3<f64>) -> Result<(f64, f64)> {
    let a = nalgebra::Matrix3x2::from_columns(&[homog(second), *e]);
    let rhs = homog(first);
    let sol = (a.transpose() * a).lu().solve(&(a.transpose() * rhs)).ok_or(degenerate(EPIPOLE, 0.0))?;
    Ok((sol.y, (a * sol - rhs).norm_squared()))
}

/// The residual of eq. (26) in pixels: the distance of `p^I` from the line through `p^II` and
/// the epipole `e` (for a pure translation both lie on it; 0 when `p^II` is the epipole).
pub fn epipolar_residual(first: [f64; 2], second: [f64; 2], e: &Vector3<f64>) -> f64 {
    let m = homog(second).cross(e);
    let across = m.x.hypot(m.y);
    if across > 0.0 { m.dot(&homog(first)).abs() / across } else { 0.0 }
}

/// Normalised DLT resection of a 3x4 camera from `X_k <-> p_k` (at least 6 non-coplanar
/// points).
pub fn resect(points: &[Vector3<f64>], pixels: &[[f64; 2]]) -> Result<Matrix3x4<f64>> {
    let n = points.len();
    if n < 6 || pixels.len() != n {
        return Err(Error::TooFewPoints { needed: 6, got: n.min(pixels.len()), why: "a DLT resection" });
    }
    check_finite_points("pixels", pixels)?;
    let rows: Vec<[f64; 3]> = points.iter().map(|p| (*p).into()).collect();
    check_finite_rows("points", &rows)?;
    let t2 = normalise_2d(pixels);
    let c = points.iter().sum::<Vector3<f64>>() / n as f64;
    let mean = points.iter().map(|p| (p - c).norm()).sum::<f64>() / n as f64;
    let s = if mean > 0.0 { 3f64.sqrt() / mean } else { 1.0 };
    let mut t3 = nalgebra::Matrix4::identity() * s;
    t3[(3, 3)] = 1.0;
    t3.fixed_view_mut::<3, 1>(0, 3).copy_from(&(-c * s));
    let mut a = DMatrix::zeros(2 * n, 12);
    for k in 0..n {
        let x = (t3 * Vector4::new(points[k].x, points[k].y, points[k].z, 1.0)).transpose();
        let p = t2 * homog(pixels[k]);
        for j in 0..4 {
            a[(2 * k, 4 + j)] = -x[j];
            a[(2 * k, 8 + j)] = p.y * x[j];
            a[(2 * k + 1, j)] = x[j];
            a[(2 * k + 1, 8 + j)] = -p.x * x[j];
        }
    }
    // Values at the edge of the f64 range overflow the normalisation (the SVD of a non-finite
    // matrix may not terminate).
    check_overflow("points, pixels", "normalised DLT system", &[a.as_slice()])?;
    let svd = a.svd(false, true);
    let v_t = svd.v_t.as_ref().ok_or(degenerate(RESECTION, 0.0))?;
    let mut order: Vec<usize> = (0..12).collect();
    order.sort_by(|&x, &y| svd.singular_values[y].total_cmp(&svd.singular_values[x]));
    let ratio = svd.singular_values[order[10]] / svd.singular_values[order[0]].max(f64::MIN_POSITIVE);
    if !(ratio > DEGENERATE) {
        // Coplanar (or collinear) points leave a family of cameras.
        return Err(degenerate(RESECTION, ratio));
    }
    let row: Vec<f64> = v_t.row(order[11]).iter().copied().collect();
    let p_n = Matrix3x4::from_row_slice(&row);
    let t2_inv = t2.try_inverse().ok_or(degenerate(RESECTION, 0.0))?;
    Ok(t2_inv * p_n * t3)
}

/// The depth `z` of the point `X' = z p^I` of the reconstruction that the camera `p` sees at
/// `pixel` (least squares over the two rows of `pixel x P X' = 0`); point `index` of the first
/// image, which must end up in front of it.
fn depth_on_ray(p: &Matrix3x4<f64>, first: [f64; 2], pixel: [f64; 2], index: usize) -> Result<f64> {
    let ray = p.fixed_view::<3, 3>(0, 0) * homog(first);
    let (mut num, mut den) = (0.0, 0.0);
    for (row, coord) in [(0, pixel[0]), (1, pixel[1])] {
        let a = coord * ray.z - ray[row];
        let c = coord * p[(2, 3)] - p[(row, 3)];
        num -= a * c;
        den += a * a;
    }
    let z = num / den;
    if z.is_finite() && z > 0.0 {
        Ok(z)
    } else {
        Err(Error::InvalidParameter {
            name: "first_depths",
            reason: format!(
                "point {index} has no depth (NaN) and the reference image does not place it in front of the first \
                 camera (got {}): the two views see it along the same line",
                Short(z)
            ),
        })
    }
}

/// The on-line part of appendix A: depths of the current image up to `kappa(t) > 0`.
#[derive(Debug, Clone)]
pub struct ResectionDepths {
    reconstruction: Vec<Vector3<f64>>,
    det_reference: f64,
    scratch_points: Vec<Vector3<f64>>,
    scratch_pixels: Vec<[f64; 2]>,
}

impl ResectionDepths {
    /// From the first image of the translation pair with its depths up to scale (NaN for a
    /// point without a usable depth: it is placed on its ray where the reference image sees
    /// it), and the reference image, which fixes the scale of every later resection: the estimated depths
    /// of the reference image average `reference_mean_depth` (a rough guess of the distance
    /// to the object in metres, or 1 for "unknown"; the law is stable for any positive scale,
    /// which only sets the speed of the translation, sec. 4.1).
    pub fn new(
        first: &[[f64; 2]],
        first_depths: &[f64],
        reference_pixels: &[[f64; 2]],
        reference_mean_depth: f64,
    ) -> Result<Self> {
        check_positive("reference_mean_depth", reference_mean_depth)?;
        if first_depths.len() != first.len() || reference_pixels.len() != first.len() {
            return Err(Error::Shape {
                what: "depth estimation",
                expected: format!("{} points in every image", first.len()),
                got: format!("{} depths, {} reference pixels", first_depths.len(), reference_pixels.len()),
            });
        }
        // The resection of the reference camera from the points with a depth; a point without
        // one (NaN: unusable, see `robust_depths_from_translation`) is then placed on its ray of
        // the first image where the reference camera sees it.
        let known: Vec<usize> = (0..first.len()).filter(|&k| first_depths[k].is_finite()).collect();
        let mut reconstruction: Vec<Vector3<f64>> =
            first.iter().zip(first_depths).map(|(p, z)| homog(*p) * *z).collect();
        let p = resect(
            &known.iter().map(|&k| reconstruction[k]).collect::<Vec<_>>(),
            &known.iter().map(|&k| reference_pixels[k]).collect::<Vec<_>>(),
        )?;
        for k in (0..first.len()).filter(|&k| !first_depths[k].is_finite()) {
            reconstruction[k] = homog(first[k]) * depth_on_ray(&p, first[k], reference_pixels[k], k)?;
        }
        let det = p.fixed_view::<3, 3>(0, 0).determinant().abs();
        if !(det > 0.0 && det.is_finite()) {
            return Err(degenerate(RESECTION, 0.0));
        }
        // Depths scale as det^(1/3): pick the det that gives the requested mean depth.
        let row = p.row(2);
        let mean = reconstruction.iter().map(|x| row[0] * x.x + row[1] * x.y + row[2] * x.z + row[3]).sum::<f64>()
            / reconstruction.len() as f64;
        let det_reference = det * (reference_mean_depth / mean.abs()).powi(3);
        Ok(Self { reconstruction, det_reference, scratch_points: Vec::new(), scratch_pixels: Vec::new() })
    }

    /// Depths of every point (hidden ones extrapolated from the resected camera) up to one
    /// positive scale, from the visible points' pixels.
    pub fn estimate(&mut self, pixels: &[[f64; 2]], visible: &[bool], depths: &mut [f64]) -> Result<()> {
        let n = self.reconstruction.len();
        for (what, len) in [("pixels", pixels.len()), ("visible", visible.len()), ("depths", depths.len())] {
            if len != n {
                return Err(Error::Shape {
                    what,
                    expected: format!("{n} values (one per point)"),
                    got: format!("{len}"),
                });
            }
        }
        if let Some(row) = (0..n).find(|&k| visible[k] && !(pixels[k][0].is_finite() && pixels[k][1].is_finite())) {
            return Err(Error::NonFinitePoint { what: "pixels", row, column: usize::from(pixels[row][0].is_finite()) });
        }
        self.scratch_points.clear();
        self.scratch_pixels.clear();
        for k in 0..self.reconstruction.len() {
            if visible[k] {
                self.scratch_points.push(self.reconstruction[k]);
                self.scratch_pixels.push(pixels[k]);
            }
        }
        let p = resect(&self.scratch_points, &self.scratch_pixels)?;
        let det = p.fixed_view::<3, 3>(0, 0).determinant().abs();
        let scale = (self.det_reference / det).cbrt();
        let row = p.row(2) * scale;
        for (d, x) in depths.iter_mut().zip(&self.reconstruction) {
            *d = row[0] * x.x + row[1] * x.y + row[2] * x.z + row[3];
        }
        // P is known up to sign: the visible points are in front of the camera.
        let sign = (0..depths.len()).filter(|&k| visible[k]).map(|k| depths[k]).sum::<f64>().signum();
        depths.iter_mut().for_each(|d| *d *= sign);
        crate::error::check_overflow("reference_mean_depth, pixels", "depths", &[depths])?;
        if let Some(index) = (0..depths.len()).find(|&k| visible[k] && !(depths[k] > 0.0)) {
            return Err(Error::PointBehindCamera { index, depth: depths[index] });
        }
        Ok(())
    }
}
