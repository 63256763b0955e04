//! Path planning in the invariant space (sec. 3): the plane + parallax factorization of
//! eq. (9) estimated from the current and the reference invariant points, and the path of
//! eq. (10) along which the camera follows a straight line in Cartesian space.
//!
//! Eq. (9), `gamma_k q_k = Gamma (q_k* + mu_k* e*)`, makes `q_k`, `Gamma q_k*` and
//! `Gamma e*` linearly dependent, so `q_k^T F q_k* = 0` with `F = [Gamma e*]_x Gamma`: a
//! matrix with a zero diagonal, six unknowns up to scale and `det F = 0` (paper-corrections, "How many
//! points"). Each non-basis point gives one equation: the linear method needs 5 of them
//! (n >= 8), the minimal method 4 (n = 7) closed by the cubic `det F = 0`.

use nalgebra::{DMatrix, Vector3};

use crate::error::{Error, Result, Short, check_finite, check_finite_rows};

/// Off-diagonal entries of F in the order (01, 02, 10, 12, 20, 21).
const OFF: [(usize, usize); 6] = [(0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)];

/// Below this ratio of singular values the epipolar system counts as degenerate (planar
/// object, no translation, points too few or too close to a plane).
pub const DEGENERATE_RATIO: f64 = 1e-9;

fn degenerate(ratio: f64) -> Error {
    Error::DegenerateEstimate {
        what: "plane + parallax (eq. 9)",
        ratio,
        hint: "the object is planar, the camera did not translate, or the points are too few",
    }
}

/// The plane + parallax parameters of eq. (9), with `gamma_3 = 1`.
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneParallax {
    /// `Gamma = diag(gamma_1, gamma_2, gamma_3)` divided by `gamma_3` (all > 0).
    pub gamma: Vector3<f64>,
    /// The epipole `e*` in the reference invariant space, unit norm.
    pub epipole: Vector3<f64>,
    /// `mu_k* e*` for each non-basis point (the identifiable product, correction 7).
    pub mu_e: Vec<Vector3<f64>>,
    /// `gamma_k / gamma_3` for each non-basis point.
    pub gamma_k: Vec<f64>,
    /// RMS distance between the measured current invariant points and those eq. (9) predicts.
    pub residual: f64,
    /// How many det F = 0 candidates the minimal method had (1 for the linear method).
    pub candidates: usize,
}

fn normalised(q: &Vector3<f64>) -> Vector3<f64> {
    q / q.sum()
}

impl PlaneParallax {
    /// The current invariant point that eq. (9) predicts for non-basis point `j`:
    /// `Gamma (q_j* + mu_j* e*)`, scaled to sum to 1. Fails for `j` out of range, a non-finite
    /// `q_star` and a prediction that is not finite (a sum of zero).
    pub fn predict(&self, q_star: &Vector3<f64>, j: usize) -> Result<Vector3<f64>> {
        let Some(mu_e) = self.mu_e.get(j) else {
            let reason = format!("non-basis point {j} out of range: the estimate has {}", self.mu_e.len());
            return Err(Error::InvalidParameter { name: "j", reason });
        };
        check_finite("q_star", q_star.as_slice())?;
        let q = normalised(&self.gamma.component_mul(&(q_star + mu_e)));
        crate::error::check_overflow("q_star", "predicted invariant point", &[q.as_slice()])?;
        Ok(q)
    }
}

/// `det F` for a zero-diagonal F: `F01 F12 F20 + F02 F10 F21`.
fn det_zero_diag(e: &[f64; 6]) -> f64 {
    e[0] * e[3] * e[4] + e[1] * e[2] * e[5]
}

/// Real roots of `a x^3 + b x^2 + c x + d` (degree drops handled).
fn real_cubic_roots(a: f64, b: f64, c: f64, d: f64) -> Vec<f64> {
    let scale = a.abs().max(b.abs()).max(c.abs()).max(d.abs());
    if scale == 0.0 {
        return vec![];
    }
    if a.abs() < 1e-12 * scale {
        if b.abs() < 1e-12 * scale {
            return if c.abs() < 1e-12 * scale { vec![] } else { vec![-d / c] };
        }
        let disc = c * c - 4.0 * b * d;
        if disc < 0.0 {
            return vec![];
        }
        let s = disc.sqrt();
        return vec![(-c + s) / (2.0 * b), (-c - s) / (2.0 * b)];
    }
    // Companion matrix eigenvalues: robust and good enough for three roots.
    let m = nalgebra::Matrix3::new(-b / a, -c / a, -d / a, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0);
    if !m.iter().all(|v| v.is_finite()) {
        return vec![];
    }
    let roots: Vec<f64> =
        m.complex_eigenvalues().iter().filter(|z| z.im.abs() <= 1e-9 * (1.0 + z.re.abs())).map(|z| z.re).collect();
    // One Newton step each, to polish.
    roots
        .into_iter()
        .map(|x| {
            let f = ((a * x + b) * x + c) * x + d;
            let df = (3.0 * a * x + 2.0 * b) * x + c;
            if df != 0.0 { x - f / df } else { x }
        })
        .collect()
}

/// Gamma, the epipole and per-point parameters from a zero-diagonal F, then the residual.
fn decompose(f: &[f64; 6], q: &[Vector3<f64>], q_star: &[Vector3<f64>]) -> Option<PlaneParallax> {
    let [f01, f02, f10, f12, f20, f21] = *f;
    // F = [t]x Gamma: F01 = -t2 g1, F10 = t2 g0, F02 = t1 g2, F20 = -t1 g0, F12 = -t0 g2, F21 = t0 g1.
    // Ratios g1/g0, g2/g0, g2/g1, combined in the log domain (least squares, det F ~ 0).
    let (r10, r20, r21) = (-f01 / f10, -f02 / f20, -f12 / f21);
    if !(r10 > 0.0 && r20 > 0.0 && r21 > 0.0 && r10.is_finite() && r20.is_finite() && r21.is_finite()) {
        return None;
    }
    let (l10, l20, l21) = (r10.ln(), r20.ln(), r21.ln());
    // Unknowns x1 = ln g1/g0, x2 = ln g2/g0: x1 = l10, x2 = l20, x2 - x1 = l21.
    let x1 = (2.0 * l10 + l20 - l21) / 3.0;
    let x2 = (l10 + 2.0 * l20 + l21) / 3.0;
    let g = Vector3::new(1.0, x1.exp(), x2.exp());
    let gamma = g / g.z;
    let t = Vector3::new(
        0.5 * (f21 / gamma.y - f12 / gamma.z),
        0.5 * (f02 / gamma.z - f20 / gamma.x),
        0.5 * (f10 / gamma.x - f01 / gamma.y),
    );
    let e = t.component_div(&gamma);
    let norm = e.norm();
    if !(norm > 0.0 && norm.is_finite()) {
        return None;
    }
    let epipole = e / norm;
    let ge = gamma.component_mul(&epipole);
    let mut mu_e = Vec::with_capacity(q.len());
    let mut gamma_k = Vec::with_capacity(q.len());
    let mut err2 = 0.0;
    for (qk, qs) in q.iter().zip(q_star) {
        // gamma_k q_k - mu_k Gamma e* = Gamma q_k*: two unknowns, three equations.
        let a = nalgebra::Matrix3x2::from_columns(&[*qk, -ge]);
        let rhs = gamma.component_mul(qs);
        let sol = (a.transpose() * a).lu().solve(&(a.transpose() * rhs))?;
        gamma_k.push(sol.x);
        let me = epipole * sol.y;
        let pred = normalised(&gamma.component_mul(&(qs + me)));
        err2 += (pred - qk).norm_squared();
        mu_e.push(me);
    }
    if gamma_k.iter().any(|&g| !(g > 0.0)) {
        return None;
    }
    Some(PlaneParallax { gamma, epipole, mu_e, gamma_k, residual: (err2 / q.len() as f64).sqrt(), candidates: 1 })
}

/// Estimates eq. (9) from the invariant points of the non-basis points in the current image
/// (`q`) and in the reference image (`q_star`): the linear method for 5 or more points
/// (n >= 8), the minimal method with the cubic `det F = 0` for exactly 4 (n = 7).
/// Coordinates are scaled per component (which keeps F's zero diagonal) before solving.
pub fn estimate_plane_parallax(q: &[Vector3<f64>], q_star: &[Vector3<f64>]) -> Result<PlaneParallax> {
    check_plane_parallax_inputs(q, q_star)?;
    let null_dim = if q.len() >= 5 { 1 } else { 2 };
    let (null_space, ratio) = scaled_null_space(q, q_star, null_dim)?;
    match null_space.as_slice() {
        [f] => decompose(f, q, q_star).ok_or(degenerate(ratio)),
        [f1, f2] => minimal_method(f1, f2, q, q_star).ok_or(degenerate(ratio)),
        _ => Err(degenerate(ratio)),
    }
}

fn check_plane_parallax_inputs(q: &[Vector3<f64>], q_star: &[Vector3<f64>]) -> Result<()> {
    let m = q.len();
    if q_star.len() != m {
        return Err(Error::Shape {
            what: "q_star",
            expected: format!("{m} invariant points"),
            got: format!("{}", q_star.len()),
        });
    }
    if m < 4 {
        return Err(Error::TooFewPoints {
            needed: 7,
            got: m + 3,
            why: "plane + parallax needs four non-basis points (seven in all)",
        });
    }
    for (what, points) in [("q", q), ("q_star", q_star)] {
        let rows: Vec<[f64; 3]> = points.iter().map(|v| (*v).into()).collect();
        check_finite_rows(what, &rows)?;
    }
    Ok(())
}

/// The `null_dim` right singular vectors of the smallest singular values of the linear
/// system `q_k^T F q*_k = 0` (F with a zero diagonal, six unknowns), solved on per-component
/// scaled coordinates and unscaled, with the ratio of the last kept singular value to the
/// largest (which must not be near zero).
fn scaled_null_space(q: &[Vector3<f64>], q_star: &[Vector3<f64>], null_dim: usize) -> Result<(Vec<[f64; 6]>, f64)> {
    // Per-component scaling: q' = D q, q*' = D* q*, F' = D^-1 F D*^-1 keeps the zero diagonal.
    let rms = |pts: &[Vector3<f64>]| {
        Vector3::from_fn(|i, _| {
            let s = (pts.iter().map(|p| p[i] * p[i]).sum::<f64>() / pts.len() as f64).sqrt();
            if s > 0.0 { 1.0 / s } else { 1.0 }
        })
    };
    let (d, ds) = (rms(q), rms(q_star));
    let m = q.len();
    let mut a = DMatrix::zeros(m.max(6), 6);
    for k in 0..m {
        let (u, w) = (q[k].component_mul(&d), q_star[k].component_mul(&ds));
        for (c, &(i, j)) in OFF.iter().enumerate() {
            a[(k, c)] = u[i] * w[j];
        }
    }
    // The SVD of a non-finite matrix may not terminate: refuse overflowed coordinates.
    crate::error::check_overflow("q, q_star", "scaled epipolar system", &[a.as_slice()])?;
    let svd = a.svd(false, true);
    let v_t = svd.v_t.as_ref().ok_or(degenerate(0.0))?;
    // Sort the singular values decreasingly (nalgebra does not promise an order).
    let mut order: Vec<usize> = (0..6).collect();
    order.sort_by(|&x, &y| svd.singular_values[y].total_cmp(&svd.singular_values[x]));
    let sv: Vec<f64> = order.iter().map(|&i| svd.singular_values[i]).collect();
    // The last `null_dim` singular values are (near) zero; the one before must not be.
    let ratio = sv[5 - null_dim] / sv[0].max(f64::MIN_POSITIVE);
    if !(ratio > DEGENERATE_RATIO) {
        return Err(degenerate(ratio));
    }
    // F = D F' D* (undo the scaling).
    let unscaled = |row: usize| -> [f64; 6] {
        std::array::from_fn(|c| {
            let (i, j) = OFF[c];
            v_t[(order[row], c)] * d[i] * ds[j]
        })
    };
    Ok(((6 - null_dim..6).map(unscaled).collect(), ratio))
}

/// Minimal method: F = F1 + x F2 with det F = 0, a cubic in x (plus F2 alone, x -> inf);
/// the candidate with the smallest residual wins.
fn minimal_method(f1: &[f64; 6], f2: &[f64; 6], q: &[Vector3<f64>], q_star: &[Vector3<f64>]) -> Option<PlaneParallax> {
    let det_at = |x: f64| det_zero_diag(&std::array::from_fn(|c| f1[c] + x * f2[c]));
    // Fit the cubic through four samples of det (exact for a cubic).
    let xs = [-1.0, 0.0, 1.0, 2.0];
    let ys = xs.map(det_at);
    let vander = nalgebra::Matrix4::from_fn(|r, c| xs[r].powi(3 - c as i32));
    let coeffs = vander.lu().solve(&nalgebra::Vector4::from(ys))?;
    let mut candidates: Vec<[f64; 6]> = real_cubic_roots(coeffs[0], coeffs[1], coeffs[2], coeffs[3])
        .into_iter()
        .map(|x| std::array::from_fn(|c| f1[c] + x * f2[c]))
        .collect();
    if det_zero_diag(f2).abs() <= 1e-12 * f2.iter().map(|v| v.abs()).fold(0.0, f64::max).powi(3) {
        candidates.push(*f2);
    }
    let count = candidates.len();
    let mut best =
        candidates.iter().filter_map(|f| decompose(f, q, q_star)).min_by(|a, b| a.residual.total_cmp(&b.residual))?;
    best.candidates = count;
    Some(best)
}

/// The path of eq. (10) from the current image (t = 0) to the reference image (t = T), for
/// the non-basis points, with its analytic time derivative (feed-forward of eq. 17).
#[derive(Debug, Clone, PartialEq)]
pub struct InvariantPath {
    q_star: Vec<Vector3<f64>>,
    beta0_e: Vec<Vector3<f64>>,
    delta0: Vector3<f64>,
    duration: f64,
}

/// The shortest path, seconds: the rates divide by the duration, and a shorter one only
/// overflows them (a control period is milliseconds).
pub const MIN_PATH_DURATION: f64 = 1e-6;

impl InvariantPath {
    /// Checks a path duration (finite, at least [`MIN_PATH_DURATION`]), before any work.
    pub fn check_duration(duration: f64) -> Result<()> {
        if !(duration.is_finite() && duration >= MIN_PATH_DURATION) {
            let reason = format!("must be finite and at least {MIN_PATH_DURATION:e} s, got {}", Short(duration));
            return Err(Error::InvalidParameter { name: "path duration", reason });
        }
        Ok(())
    }

    /// The path for the reference invariant points `q_star`, the plane + parallax estimate
    /// and a duration `T` (the paper samples it N times at the control period: T = N dt).
    /// `beta_k(0) e*/||e*|| = mu_k* e*` (correction 7), `Delta(0) = Gamma / gamma_3`.
    pub fn new(q_star: &[Vector3<f64>], estimate: &PlaneParallax, duration: f64) -> Result<Self> {
        Self::check_duration(duration)?;
        if q_star.len() != estimate.mu_e.len() {
            return Err(Error::Shape {
                what: "q_star",
                expected: format!("{} invariant points", estimate.mu_e.len()),
                got: format!("{}", q_star.len()),
            });
        }
        // The rates divide by the duration: a tiny one overflows them.
        let rates = (Vector3::repeat(1.0) - estimate.gamma) / duration;
        let beta_rates: Vec<f64> = estimate.mu_e.iter().flat_map(|v| <[f64; 3]>::from(v / duration)).collect();
        crate::error::check_overflow("path duration", "path rates", &[rates.as_slice(), &beta_rates])?;
        Ok(Self { q_star: q_star.to_vec(), beta0_e: estimate.mu_e.clone(), delta0: estimate.gamma, duration })
    }

    /// T, in seconds.
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// The number of non-basis points: the length `points` and `rates` of
    /// [`InvariantPath::sample`] must have.
    pub fn len(&self) -> usize {
        self.q_star.len()
    }

    /// True for a path without points (never built by [`InvariantPath::new`], which needs
    /// the points of a plane + parallax estimate).
    pub fn is_empty(&self) -> bool {
        self.q_star.is_empty()
    }

    /// Writes `q_k*(t)` and `dq_k*/dt` for every non-basis point into `points` and `rates`
    /// (constant at the reference after T; `t < 0` gives the start with the start's rate,
    /// `t = +inf` the end). Fails, writing nothing, when either slice does not have one entry
    /// per non-basis point ([`InvariantPath::len`]) or `t` is NaN.
    pub fn sample(&self, t: f64, points: &mut [[f64; 3]], rates: &mut [[f64; 3]]) -> Result<()> {
        let n = self.q_star.len();
        for (what, len) in [("points", points.len()), ("rates", rates.len())] {
            if len != n {
                return Err(Error::Shape {
                    what,
                    expected: format!("{n} rows (one per non-basis point)"),
                    got: format!("{len} rows"),
                });
            }
        }
        if t.is_nan() {
            return Err(Error::NonFinite { what: "t", index: 0 });
        }
        self.sample_unchecked(t, points, rates);
        Ok(())
    }

    fn sample_unchecked(&self, t: f64, points: &mut [[f64; 3]], rates: &mut [[f64; 3]]) {
        let tau = (t / self.duration).clamp(0.0, 1.0);
        let moving = t < self.duration;
        let delta = self.delta0 + (Vector3::repeat(1.0) - self.delta0) * tau;
        let d_delta = (Vector3::repeat(1.0) - self.delta0) / self.duration;
        for (k, (p, r)) in points.iter_mut().zip(rates.iter_mut()).enumerate() {
            let inner = self.q_star[k] + self.beta0_e[k] * (1.0 - tau);
            let v = delta.component_mul(&inner);
            let s = v.sum();
            let q = v / s;
            *p = q.into();
            *r = if moving {
                let dv = d_delta.component_mul(&inner) - delta.component_mul(&self.beta0_e[k]) / self.duration;
                ((dv - q * dv.sum()) / s).into()
            } else {
                [0.0; 3]
            };
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    #[test]
    fn cubic_roots() {
        let mut r = real_cubic_roots(1.0, -6.0, 11.0, -6.0);
        r.sort_by(f64::total_cmp);
        assert!((r[0] - 1.0).abs() < 1e-9 && (r[1] - 2.0).abs() < 1e-9 && (r[2] - 3.0).abs() < 1e-9);
        assert_eq!(real_cubic_roots(1.0, 0.0, 1.0, 0.0).len(), 1);
        assert_eq!(real_cubic_roots(0.0, 1.0, -3.0, 2.0).len(), 2);
    }
}
