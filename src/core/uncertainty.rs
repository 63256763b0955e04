//! How far from the goal the camera may still be when the images say it is there: the pose
//! uncertainty that pixel noise leaves, by first-order propagation (not in the paper).
//!
//! The stop rules compare image measurements `m` with their reference values `m*`: the
//! invariant points and `tau_21` for different cameras (sec. 4, eq. 21), the pixels for the
//! same camera or IBVS. Near the goal, a camera displacement `x = (t, r)` (translation,
//! rotation vector, current camera frame) changes them by `dm = J x`, with `J` the law's
//! Jacobian evaluated with `K_hat` and the depth estimates (eqs. 11-13 and 23, all six
//! columns). Pixel noise of standard deviation `sigma` per coordinate moves `m` by
//! `dm = G dp` with `G = dm/dp`, so the loop settles where `J x = G dp - G* dp*`, and
//!
//! `Cov(x) = J^+ (sigma^2 G G^T / N + sigma*^2 G* G*^T) J^+T`
//!
//! where `N` images were averaged by the stop rule and `sigma*` is the reference image's
//! noise. The mean error left when the rule stops adds the offset `J^+ (m - m*)`.
//!
//! Assumptions, which the figures inherit: the depths are the true ones up to the common
//! scale `kappa` of sec. 4.1 (the translation figures are in that scale: with depths off by
//! a factor, so is the translation uncertainty); `K_hat` is close to the servo camera's K
//! (a relative error in `K_hat` is a relative error of the figures, first order); the
//! noise is independent between points, coordinates and images; and the pixel rule assumes
//! that the reference image was taken with the servo camera (otherwise `p = p*` is not the
//! goal, whatever the noise).

use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, Vector3, Vector6};

use crate::core::camera::{Intrinsics, pixel_interaction_unchecked};
use crate::core::invariant::{BasisFrame, RzReference, non_basis_indices, validate_basis};
use crate::core::jacobian::{combined_interaction, rz_from_interactions};
use crate::error::{Error, Result, check_depths, check_finite_points};

/// The largest pixel standard deviation accepted, pixels.
pub const MAX_PIXEL_SIGMA: f64 = 1e6;

/// How many standard deviations the bounds of [`PoseUncertainty`] span by default.
pub const DEFAULT_SIGMAS: f64 = 3.0;

/// The pixel noise the measurements carry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageNoise {
    /// Standard deviation of each pixel coordinate in one current image, pixels.
    pub current: f64,
    /// Standard deviation of each pixel coordinate of the reference image, pixels.
    pub reference: f64,
    /// Number of current images whose measurements were averaged (the stop rule's window).
    pub averaged_images: usize,
}

impl ImageNoise {
    fn validate(&self) -> Result<()> {
        for (name, value) in [("noise.current", self.current), ("noise.reference", self.reference)] {
            if !(value.is_finite() && (0.0..=MAX_PIXEL_SIGMA).contains(&value)) {
                return Err(Error::InvalidParameter {
                    name,
                    reason: format!("must be a pixel standard deviation in [0, 1e6], got {value:.4e}"),
                });
            }
        }
        if self.averaged_images == 0 {
            return Err(Error::InvalidParameter { name: "noise.averaged_images", reason: "must be >= 1".into() });
        }
        Ok(())
    }
}

/// The camera displacement from the goal that the measurements still allow, in the current
/// camera frame: translation in metres (in the depth estimates' scale), rotation in radians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseUncertainty {
    /// Covariance of `(tx, ty, tz, rx, ry, rz)` caused by the pixel noise.
    pub covariance: Matrix6<f64>,
    /// `J^+ (m - m*)`: the displacement the measured error itself still implies.
    pub offset: Vector6<f64>,
    /// The disagreement floor: the per-coordinate pixel RMS `sigma_b` of a systematic error
    /// (detection biases that differ between the reference and the current images) that
    /// explains the residual `(I - J J^+)(m - m*)` the pose cannot remove. See
    /// the module documentation.
    pub floor_pixel_sigma: f64,
    /// The covariance such a systematic error leaves in the pose, `sigma_b^2 J^+ (G G^T +
    /// G* G*^T) J^+T` (not reduced by averaging images: it is the same in every image).
    pub floor_covariance: Matrix6<f64>,
}

impl PoseUncertainty {
    /// RMS distance of the camera centre from where the measurements put it, metres:
    /// `sqrt(trace Cov(t))`.
    pub fn translation_sigma(&self) -> f64 {
        self.covariance.fixed_view::<3, 3>(0, 0).trace().max(0.0).sqrt()
    }
    /// RMS rotation angle, radians: `sqrt(trace Cov(r))`.
    pub fn rotation_sigma(&self) -> f64 {
        self.covariance.fixed_view::<3, 3>(3, 3).trace().max(0.0).sqrt()
    }
    /// `sigmas * translation_sigma + |offset_t|`: how far from the goal the camera centre may
    /// be, metres.
    pub fn translation_bound(&self, sigmas: f64) -> f64 {
        sigmas * self.translation_sigma() + self.offset.fixed_rows::<3>(0).norm()
    }
    /// `sigmas * rotation_sigma + |offset_r|`, radians.
    pub fn rotation_bound(&self, sigmas: f64) -> f64 {
        sigmas * self.rotation_sigma() + self.offset.fixed_rows::<3>(3).norm()
    }
    /// The translation bound with the disagreement floor: `sigmas * sqrt(trace(Cov_t +
    /// Cov_floor_t)) + |offset_t|`, metres.
    pub fn translation_bound_with_floor(&self, sigmas: f64) -> f64 {
        let c = self.covariance + self.floor_covariance;
        sigmas * c.fixed_view::<3, 3>(0, 0).trace().max(0.0).sqrt() + self.offset.fixed_rows::<3>(0).norm()
    }
    /// The same for the rotation, radians.
    pub fn rotation_bound_with_floor(&self, sigmas: f64) -> f64 {
        let c = self.covariance + self.floor_covariance;
        sigmas * c.fixed_view::<3, 3>(3, 3).trace().max(0.0).sqrt() + self.offset.fixed_rows::<3>(3).norm()
    }
}

/// The images and calibration the propagation starts from.
#[derive(Debug, Clone, Copy)]
pub struct Measurement<'a> {
    /// Current pixels (or their average over the stop rule's window), `n` points.
    pub pixels: &'a [[f64; 2]],
    /// The law's depth estimates, one per point.
    pub depths: &'a [f64],
    /// The reference image's pixels.
    pub reference_pixels: &'a [[f64; 2]],
    /// Points in use (`None`: all); a hidden point drops out.
    pub visible: Option<&'a [bool]>,
    /// The estimated intrinsics of the servo camera.
    pub k_hat: &'a Intrinsics,
}

impl Measurement<'_> {
    fn check(&self) -> Result<Vec<usize>> {
        let n = self.pixels.len();
        check_finite_points("reference_pixels", self.reference_pixels)?;
        for (what, len) in
            [("reference_pixels", self.reference_pixels.len()), ("visible", self.visible.map_or(n, <[bool]>::len))]
        {
            if len != n {
                return Err(Error::Shape { what, expected: format!("{n} (one per point)"), got: format!("{len}") });
            }
        }
        let used: Vec<usize> = (0..n).filter(|&i| self.visible.is_none_or(|v| v[i])).collect();
        let pixels: Vec<[f64; 2]> = used.iter().map(|&i| self.pixels[i]).collect();
        let depths: Vec<f64> = used.iter().map(|&i| self.depths.get(i).copied().unwrap_or(f64::NAN)).collect();
        if self.depths.len() != n {
            return Err(Error::Shape {
                what: "depths",
                expected: format!("{n} values (one per point)"),
                got: format!("{} values", self.depths.len()),
            });
        }
        check_finite_points("pixels", &pixels)?;
        check_depths(&depths, used.len())?;
        Ok(used)
    }
}

/// Pose uncertainty under the invariant stop rule (different cameras): `m = (s, tau_21)`.
/// The basis points and at least three others must be in use.
pub fn invariant_pose_uncertainty(
    m: &Measurement<'_>,
    basis: [usize; 3],
    noise: ImageNoise,
) -> Result<PoseUncertainty> {
    noise.validate()?;
    let used = m.check()?;
    let basis = validate_basis(basis, m.pixels.len())?;
    let mut in_use = vec![false; m.pixels.len()];
    used.iter().for_each(|&i| in_use[i] = true);
    let others: Vec<usize> = non_basis_indices(m.pixels.len(), basis).into_iter().filter(|&i| in_use[i]).collect();
    if basis.iter().any(|&b| !in_use[b]) || others.len() < 3 {
        return Err(Error::TooFewPoints {
            needed: 6,
            got: others.len() + basis.iter().filter(|&&b| in_use[b]).count(),
            why: "the three basis points and three more must be in use",
        });
    }
    let current = BasisFrame::new(m.pixels, basis, "current")?;
    let star = BasisFrame::new(m.reference_pixels, basis, "reference")?;
    let rz = RzReference::new(&star);
    let t = rz.t_matrix(&current);
    let rows = 3 * others.len() + 1;
    let (mut jac, mut error) = (DMatrix::zeros(rows, 6), DVector::zeros(rows));
    let k = m.k_hat.matrix();
    let k_inv = k.try_inverse().ok_or_else(|| Error::InvalidIntrinsics { reason: "K_hat is singular".into() })?;
    // Depths are checked positive; an overflow is caught with the Jacobians in `propagate`.
    let l_of = |i: usize| pixel_interaction_unchecked(&k, &k_inv, m.pixels[i], m.depths[i]);
    let l_basis = basis.map(l_of);
    let q_inv_2 = current.q_inv.fixed_columns::<2>(0).into_owned();
    for (row, &i) in others.iter().enumerate() {
        let q = current.transform(m.pixels[i]);
        let l_i = l_of(i);
        jac.fixed_view_mut::<3, 6>(3 * row, 0).copy_from(&(q_inv_2 * combined_interaction(&l_i, &l_basis, &q)));
        error.fixed_rows_mut::<3>(3 * row).copy_from(&(q - star.transform(m.reference_pixels[i])));
    }
    // tau_21 = eps_z / det(Q*) (sec. 4.2); its rate is (c, a) / det(Q*) (eq. 23).
    let (a, c) = rz_from_interactions(&rz, &l_basis);
    let last = rows - 1;
    for col in 0..5 {
        jac[(last, col)] = c[col] / rz.det_q_star;
    }
    jac[(last, 5)] = a / rz.det_q_star;
    error[last] = t[(1, 0)];
    let g = invariant_pixel_jacobian(m.pixels, &current, basis, &others, &rz.q_star_inv, None);
    let g_star = invariant_pixel_jacobian(m.reference_pixels, &star, basis, &others, &rz.q_star_inv, Some(&t));
    propagate(&jac, &error, &g, &g_star, noise)
}

/// The derivative of the error `e = (s - s*, tau_21)` with respect to the pixels of the
/// current image (`t = None`) or of the reference image (`t = Some(T)`, then `s*` enters with
/// its minus sign): rows in the order of `s` (the non-basis points `others`) then `tau_21`,
/// columns `(u_0, v_0, u_1, v_1, ...)` of all points. `q_k = Q^-1 p_k` gives
/// `dq_k/dp_k = Q^-1[:, 0..2]` and `dq_k/dp_j = -Q^-1[:, 0..2] q_k[b]` for the basis point
/// `j = basis[b]`. `tau_21 = T[1, 0]` with `T = Q Q*^-1` (eq. 21): on the current image
/// `dtau_21/dv_j = Q*^-1[b, 0]`; on the reference, `dT = -T dQ* Q*^-1`, so
/// `dtau_21/du*_j = -T[1, 0] Q*^-1[b, 0]` and `dtau_21/dv*_j = -T[1, 1] Q*^-1[b, 0]`.
fn invariant_pixel_jacobian(
    pixels: &[[f64; 2]],
    frame: &BasisFrame,
    basis: [usize; 3],
    others: &[usize],
    q_star_inv: &Matrix3<f64>,
    t: Option<&Matrix3<f64>>,
) -> Sparse {
    let rows = 3 * others.len() + 1;
    let mut g = Sparse { cols: 2 * pixels.len(), entries: Vec::with_capacity(24 * others.len() + 6) };
    let sign = if t.is_some() { -1.0 } else { 1.0 };
    for (row, &i) in others.iter().enumerate() {
        let q: Vector3<f64> = frame.transform(pixels[i]);
        for axis in 0..2 {
            let column = frame.q_inv.column(axis) * sign;
            for r in 0..3 {
                g.entries.push((3 * row + r, 2 * i + axis, column[r]));
                for (b, &j) in basis.iter().enumerate() {
                    g.entries.push((3 * row + r, 2 * j + axis, -column[r] * q[b]));
                }
            }
        }
    }
    for (b, &j) in basis.iter().enumerate() {
        let w = q_star_inv[(b, 0)];
        match t {
            None => g.entries.push((rows - 1, 2 * j + 1, w)),
            Some(t) => {
                g.entries.push((rows - 1, 2 * j, -t[(1, 0)] * w));
                g.entries.push((rows - 1, 2 * j + 1, -t[(1, 1)] * w));
            }
        }
    }
    g
}

/// A sparse matrix as `(row, column, value)` entries (repeated entries add up): the
/// measurement Jacobians `G` have at most eight entries a row, so they are never formed densely.
struct Sparse {
    cols: usize,
    entries: Vec<(usize, usize, f64)>,
}

impl Sparse {
    fn identity(n: usize) -> Self {
        Self { cols: n, entries: (0..n).map(|i| (i, i, 1.0)).collect() }
    }

    /// `|G|_F^2`, repeated entries added up first, in the entries' order (a `BTreeMap`: a
    /// hashed map's random order changed the sum's last bits from process to process).
    fn frobenius_squared(&self) -> f64 {
        let mut sums = std::collections::BTreeMap::new();
        for &(r, c, v) in &self.entries {
            *sums.entry((r, c)).or_insert(0.0) += v;
        }
        sums.values().map(|v: &f64| v * v).sum()
    }

    /// `P G` for a dense `P` with one column per row of `G`.
    fn left_mul(&self, p: &DMatrix<f64>) -> DMatrix<f64> {
        let mut out = DMatrix::zeros(p.nrows(), self.cols);
        for &(r, c, v) in &self.entries {
            for k in 0..p.nrows() {
                out[(k, c)] += p[(k, r)] * v;
            }
        }
        out
    }
}

/// Pose uncertainty under the pixel stop rule (the same camera, or IBVS): `m = p`, the
/// stacked pixels, with `J` the stacked pixel interaction matrices.
pub fn pixel_pose_uncertainty(m: &Measurement<'_>, noise: ImageNoise) -> Result<PoseUncertainty> {
    noise.validate()?;
    let used = m.check()?;
    if used.len() < 3 {
        return Err(Error::TooFewPoints { needed: 3, got: used.len(), why: "six pose dof need three points" });
    }
    let k = m.k_hat.matrix();
    let k_inv = k.try_inverse().ok_or_else(|| Error::InvalidIntrinsics { reason: "K_hat is singular".into() })?;
    let rows = 2 * used.len();
    let (mut jac, mut error) = (DMatrix::zeros(rows, 6), DVector::zeros(rows));
    for (row, &i) in used.iter().enumerate() {
        let l = pixel_interaction_unchecked(&k, &k_inv, m.pixels[i], m.depths[i]);
        jac.fixed_view_mut::<2, 6>(2 * row, 0).copy_from(&l);
        error[2 * row] = m.pixels[i][0] - m.reference_pixels[i][0];
        error[2 * row + 1] = m.pixels[i][1] - m.reference_pixels[i][1];
    }
    let identity = Sparse::identity(rows);
    propagate(&jac, &error, &identity, &identity, noise)
}

/// `Cov(x) = J^+ (sigma^2 G G^T / N + sigma*^2 G* G*^T) J^+T` and the offset `J^+ e`.
fn propagate(
    jac: &DMatrix<f64>,
    error: &DVector<f64>,
    g: &Sparse,
    g_star: &Sparse,
    noise: ImageNoise,
) -> Result<PoseUncertainty> {
    let values = [jac.as_slice(), error.as_slice()];
    crate::error::check_overflow("pixels, depths", "measurement Jacobians", &values)?;
    let svd = jac.clone().svd(true, true);
    let (s_max, s_min) = (svd.singular_values.max(), svd.singular_values.min());
    if !(s_min > 1e-12 * s_max) {
        return Err(Error::DegenerateEstimate {
            what: "pose uncertainty",
            ratio: if s_max > 0.0 { s_min / s_max } else { 0.0 },
            hint: "the measurements do not constrain six dof (too few points, points in a plane or a line)",
        });
    }
    let pinv = svd.pseudo_inverse(0.0).map_err(|_| Error::DegenerateEstimate {
        what: "pose uncertainty",
        ratio: 0.0,
        hint: "the measurement Jacobian has no pseudo-inverse",
    })?;
    let current = g.left_mul(&pinv);
    let reference = g_star.left_mul(&pinv);
    let n = noise.averaged_images as f64;
    let cov = (&current * current.transpose()) * (noise.current * noise.current / n)
        + (&reference * reference.transpose()) * (noise.reference * noise.reference);
    let offset = &pinv * error;
    let floor_pixel_sigma = floor_sigma(jac, error, &offset, [(g, &current), (g_star, &reference)]);
    let floor = ((&current * current.transpose()) + (&reference * reference.transpose())) * floor_pixel_sigma.powi(2);
    let covariance = Matrix6::from_iterator(cov.iter().copied());
    let offset = Vector6::from_iterator(offset.iter().copied());
    let floor_covariance = Matrix6::from_iterator(floor.iter().copied());
    let values = [covariance.as_slice(), offset.as_slice(), floor_covariance.as_slice()];
    crate::error::check_overflow("pixels, depths", "pose covariance", &values)?;
    Ok(PoseUncertainty { covariance, offset, floor_pixel_sigma, floor_covariance })
}

/// The disagreement floor `sigma_b`: at the loop's equilibrium the error `e = m - m*` left by
/// per-point pixel biases `b` (current image) and `b*` (reference) is `G b - G* b*`; the pose
/// removes its part in the range of `J` (that part *is* the pose error, `J^+ e`, and cannot be
/// seen), and leaves the residual `r = P e`, `P = I - J J^+`. With biases of RMS `sigma_b`
/// per coordinate, independent between points and images, `E|r|^2 = sigma_b^2 (|P G|_F^2 +
/// |P G*|_F^2)`, so the measured residual gives `sigma_b = |r| / sqrt(|P G|_F^2 + |P G*|_F^2)`,
/// which is then propagated to the pose like the noise (`floor_covariance`). Pixel noise left
/// in the averaged images adds to `r` and to this estimate (a conservative bias).
fn floor_sigma(
    jac: &DMatrix<f64>,
    error: &DVector<f64>,
    offset: &DVector<f64>,
    spread: [(&Sparse, &DMatrix<f64>); 2],
) -> f64 {
    // P is never formed (rows x rows): r = e - J (J^+ e), and since P is an orthogonal
    // projector, |P G|_F^2 = |G|_F^2 - |J (J^+ G)|_F^2, with J^+ G the 6-row matrix at hand.
    let residual = (error - jac * offset).norm();
    let jtj = jac.transpose() * jac;
    let seen: f64 =
        spread.iter().map(|(g, pinv_g)| g.frobenius_squared() - (&jtj * (*pinv_g * pinv_g.transpose())).trace()).sum();
    if seen > 0.0 && residual.is_finite() { residual / seen.sqrt() } else { 0.0 }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::core::camera::project_points;
    use crate::core::invariant::invariant_points;

    fn object() -> Vec<[f64; 3]> {
        vec![
            [-0.1, -0.08, 0.6],
            [0.12, -0.1, 0.62],
            [0.0, 0.11, 0.58],
            [0.05, 0.02, 0.66],
            [-0.07, 0.05, 0.55],
            [0.09, 0.07, 0.61],
            [-0.03, -0.04, 0.64],
            [0.02, -0.09, 0.57],
        ]
    }

    /// `e = (s - s*, tau_21)` of an image against a reference, by the public invariant functions.
    fn measure(pixels: &[[f64; 2]], reference: &[[f64; 2]], basis: [usize; 3]) -> Vec<f64> {
        let (q, q_star) = (invariant_points(pixels, basis).unwrap(), invariant_points(reference, basis).unwrap());
        let others = non_basis_indices(pixels.len(), basis);
        let mut m: Vec<f64> =
            others.iter().flat_map(|&i| (0..3).map(move |c| (i, c))).map(|(i, c)| q[i][c] - q_star[i][c]).collect();
        let star = RzReference::new(&BasisFrame::new(reference, basis, "reference").unwrap());
        m.push(star.t_matrix(&BasisFrame::new(pixels, basis, "current").unwrap())[(1, 0)]);
        m
    }

    fn bump(p: &[[f64; 2]], col: usize, d: f64) -> Vec<[f64; 2]> {
        let mut p = p.to_vec();
        p[col / 2][col % 2] += d;
        p
    }

    fn central(f: &dyn Fn(f64) -> Vec<f64>) -> Vec<f64> {
        let h = 1e-5;
        f(h).iter().zip(f(-h)).map(|(a, b)| (a - b) / (2.0 * h)).collect()
    }

    #[test]
    fn pixel_jacobians_match_finite_differences() {
        let k = Intrinsics::pinhole(800.0, 780.0, 320.0, 240.0).unwrap();
        let (reference, _) = project_points(&object(), &k).unwrap();
        let mut pixels = reference.clone();
        pixels.iter_mut().enumerate().for_each(|(i, p)| p[i % 2] += 0.7 * i as f64 - 2.0);
        let basis = [0, 1, 2];
        let others = non_basis_indices(8, basis);
        let cur = BasisFrame::new(&pixels, basis, "current").unwrap();
        let star = BasisFrame::new(&reference, basis, "reference").unwrap();
        let rz = RzReference::new(&star);
        let dense = |g: Sparse| g.left_mul(&DMatrix::identity(3 * others.len() + 1, 3 * others.len() + 1));
        let g = dense(invariant_pixel_jacobian(&pixels, &cur, basis, &others, &rz.q_star_inv, None));
        let t = rz.t_matrix(&cur);
        let g_star = dense(invariant_pixel_jacobian(&reference, &star, basis, &others, &rz.q_star_inv, Some(&t)));
        for col in 0..16 {
            let d_cur = central(&|d| measure(&bump(&pixels, col, d), &reference, basis));
            let d_ref = central(&|d| measure(&pixels, &bump(&reference, col, d), basis));
            for row in 0..d_cur.len() {
                assert!((g[(row, col)] - d_cur[row]).abs() < 1e-8, "current: row {row}, column {col}");
                assert!((g_star[(row, col)] - d_ref[row]).abs() < 1e-8, "reference: row {row}, column {col}");
            }
        }
    }

    /// Gaussian samples from a fixed linear congruential sequence (Box-Muller).
    struct Gauss(u64);
    impl Gauss {
        fn uniform(&mut self) -> f64 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        }
        fn sample(&mut self, sigma: f64) -> f64 {
            let (a, b) = (self.uniform(), self.uniform());
            sigma * (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
        }
        fn noisy(&mut self, p: &[[f64; 2]], sigma: f64) -> Vec<[f64; 2]> {
            p.iter().map(|q| [q[0] + self.sample(sigma), q[1] + self.sample(sigma)]).collect()
        }
    }

    /// The pixels of the object seen from the goal displaced by `x = (t, r)` in its frame.
    fn view(x: &[f64; 6], k: &Intrinsics) -> Vec<[f64; 2]> {
        let pose = nalgebra::Isometry3::new(Vector3::new(x[0], x[1], x[2]), Vector3::new(x[3], x[4], x[5]));
        let points: Vec<[f64; 3]> =
            object().iter().map(|p| (pose.inverse() * nalgebra::Point3::from(*p)).coords.into()).collect();
        project_points(&points, k).unwrap().0
    }

    /// Where the loop settles: the displacement that zeroes the measured error, by Gauss-Newton
    /// with a finite-difference Jacobian of the nonlinear measurement (independent of `J`).
    fn settle(residual: &dyn Fn(&[f64; 6]) -> Vec<f64>) -> [f64; 6] {
        let mut x = [0.0; 6];
        for _ in 0..6 {
            let r0 = residual(&x);
            let mut jac = DMatrix::zeros(r0.len(), 6);
            for c in 0..6 {
                let mut y = x;
                y[c] += 1e-7;
                let r1 = residual(&y);
                for row in 0..r0.len() {
                    jac[(row, c)] = (r1[row] - r0[row]) / 1e-7;
                }
            }
            let step = jac.svd(true, true).solve(&DVector::from_vec(r0), 1e-14).unwrap();
            (0..6).for_each(|c| x[c] -= step[c]);
        }
        x
    }

    /// The empirical covariance of settled poses against the propagated one: the traces of
    /// the translation and rotation blocks agree within the Monte Carlo error.
    fn compare(predicted: &PoseUncertainty, settled: &[[f64; 6]]) {
        let n = settled.len() as f64;
        let mean: Vec<f64> = (0..6).map(|c| settled.iter().map(|x| x[c]).sum::<f64>() / n).collect();
        let var = |c: usize| settled.iter().map(|x| (x[c] - mean[c]).powi(2)).sum::<f64>() / (n - 1.0);
        let (t2, r2) = ((0..3).map(var).sum::<f64>(), (3..6).map(var).sum::<f64>());
        let (pt, pr) = (predicted.translation_sigma(), predicted.rotation_sigma());
        assert!((t2.sqrt() / pt - 1.0).abs() < 0.08, "translation: Monte Carlo {} m, propagated {pt} m", t2.sqrt());
        assert!((r2.sqrt() / pr - 1.0).abs() < 0.08, "rotation: Monte Carlo {} rad, propagated {pr} rad", r2.sqrt());
        for c in 0..6 {
            assert!((var(c).sqrt() / predicted.covariance[(c, c)].sqrt() - 1.0).abs() < 0.15, "axis {c}");
        }
    }

    #[test]
    fn invariant_uncertainty_matches_monte_carlo_of_the_settled_pose() {
        // Reference with a 12 mm-like lens, servo with a 6 mm-like one (sec. 5.2).
        let k_star = Intrinsics::pinhole(1600.0, 1600.0, 400.0, 300.0).unwrap();
        let k = Intrinsics::pinhole(800.0, 790.0, 330.0, 250.0).unwrap();
        let (reference, goal) = (view(&[0.0; 6], &k_star), view(&[0.0; 6], &k));
        let depths: Vec<f64> = object().iter().map(|p| p[2]).collect();
        let basis = [0, 1, 2];
        let (sigma, sigma_star) = (0.5, 0.8);
        let m = Measurement { pixels: &goal, depths: &depths, reference_pixels: &reference, visible: None, k_hat: &k };
        let noise = ImageNoise { current: sigma, reference: sigma_star, averaged_images: 1 };
        let predicted = invariant_pose_uncertainty(&m, basis, noise).unwrap();
        assert!(predicted.offset.norm() < 1e-9, "at the goal the error implies no offset");
        let mut gauss = Gauss(7);
        let settled: Vec<[f64; 6]> = (0..600)
            .map(|_| {
                let (star, noise) = (gauss.noisy(&reference, sigma_star), [0.0; 16].map(|_| gauss.sample(sigma)));
                settle(&|x| {
                    let p: Vec<[f64; 2]> = view(x, &k)
                        .iter()
                        .enumerate()
                        .map(|(i, p)| [p[0] + noise[2 * i], p[1] + noise[2 * i + 1]])
                        .collect();
                    measure(&p, &star, basis)
                })
            })
            .collect();
        compare(&predicted, &settled);
    }

    /// The disagreement floor (issue 27): fixed per-point biases of RMS `sigma_b`, a different
    /// pattern in the reference and the current image, no noise. At the pose where the loop
    /// settles (Gauss-Newton on the nonlinear measurements, independent of `J`), the floor
    /// measured from the residual recovers `sigma_b` on average
    /// (`E floor^2 = sigma_b^2`), and the bound with the floor holds the true pose error in
    /// (nearly) every draw without being absurdly loose.
    #[test]
    fn disagreement_floor_recovers_the_bias_and_bounds_the_settled_pose() {
        let k_star = Intrinsics::pinhole(1600.0, 1600.0, 400.0, 300.0).unwrap();
        let k = Intrinsics::pinhole(800.0, 790.0, 330.0, 250.0).unwrap();
        let reference = view(&[0.0; 6], &k_star);
        let depths: Vec<f64> = object().iter().map(|p| p[2]).collect();
        let (basis, sigma_b, draws) = ([0, 1, 2], 0.3, 300);
        let noise = ImageNoise { current: 0.0, reference: 0.0, averaged_images: 1 };
        let mut gauss = Gauss(23);
        let (mut floor2, mut held, mut ratios) = (0.0, 0, Vec::new());
        for _ in 0..draws {
            let star = gauss.noisy(&reference, sigma_b);
            let bias = [0.0; 16].map(|_| gauss.sample(sigma_b));
            let biased = |x: &[f64; 6]| -> Vec<[f64; 2]> {
                view(x, &k).iter().enumerate().map(|(i, p)| [p[0] + bias[2 * i], p[1] + bias[2 * i + 1]]).collect()
            };
            let x = settle(&|x| measure(&biased(x), &star, basis));
            let pixels = biased(&x);
            let m = Measurement { pixels: &pixels, depths: &depths, reference_pixels: &star, visible: None, k_hat: &k };
            let u = invariant_pose_uncertainty(&m, basis, noise).unwrap();
            floor2 += u.floor_pixel_sigma.powi(2) / draws as f64;
            // The true error of the settled pose (x is the displacement from the goal).
            let (t, r) = (Vector3::new(x[0], x[1], x[2]).norm(), Vector3::new(x[3], x[4], x[5]).norm());
            let (bt, br) =
                (u.translation_bound_with_floor(DEFAULT_SIGMAS), u.rotation_bound_with_floor(DEFAULT_SIGMAS));
            held += usize::from(t <= bt && r <= br);
            ratios.push(bt / t);
        }
        ratios.sort_by(f64::total_cmp);
        let median = ratios[draws / 2];
        let recovered = floor2.sqrt();
        println!("floor {recovered:.4} px for {sigma_b} px; bound held {held}/{draws}; median bound/true {median:.2}");
        assert!((recovered / sigma_b - 1.0).abs() < 0.1, "floor {recovered} px for biases of {sigma_b} px");
        // 3 sigma of a 3-dof error leaves about 3 % outside for each of t and r.
        assert!(held as f64 >= 0.94 * draws as f64, "bound held in {held} of {draws}");
        assert!(median < 8.0, "median bound / true translation error {median}");
    }

    #[test]
    fn pixel_uncertainty_matches_monte_carlo_and_averaging() {
        let k = Intrinsics::pinhole(800.0, 790.0, 330.0, 250.0).unwrap();
        let goal = view(&[0.0; 6], &k);
        let depths: Vec<f64> = object().iter().map(|p| p[2]).collect();
        let m = Measurement { pixels: &goal, depths: &depths, reference_pixels: &goal, visible: None, k_hat: &k };
        let predicted =
            pixel_pose_uncertainty(&m, ImageNoise { current: 1.0, reference: 0.5, averaged_images: 4 }).unwrap();
        let mut gauss = Gauss(11);
        let settled: Vec<[f64; 6]> = (0..600)
            .map(|_| {
                let star = gauss.noisy(&goal, 0.5);
                let noise = [0.0; 16].map(|_| gauss.sample(0.5)); // the mean of 4 images of sigma 1
                settle(&|x| {
                    let p = view(x, &k);
                    (0..16).map(|c| p[c / 2][c % 2] + noise[c] - star[c / 2][c % 2]).collect()
                })
            })
            .collect();
        compare(&predicted, &settled);
    }

    #[test]
    fn offset_is_the_displacement_the_error_implies() {
        let k = Intrinsics::pinhole(800.0, 790.0, 330.0, 250.0).unwrap();
        let k_star = Intrinsics::pinhole(1600.0, 1600.0, 400.0, 300.0).unwrap();
        let x = [0.002, -0.001, 0.003, 0.001, -0.002, 0.0015];
        let (pixels, reference) = (view(&x, &k), view(&[0.0; 6], &k_star));
        let depths: Vec<f64> = object().iter().map(|p| p[2]).collect();
        let m =
            Measurement { pixels: &pixels, depths: &depths, reference_pixels: &reference, visible: None, k_hat: &k };
        let u =
            invariant_pose_uncertainty(&m, [0, 1, 2], ImageNoise { current: 0.0, reference: 0.0, averaged_images: 1 })
                .unwrap();
        // First order: the offset is the displacement, to within its square.
        for (c, (got, want)) in u.offset.iter().zip(x).enumerate() {
            assert!((got - want).abs() < 2e-5, "component {c}: {got} vs {want}");
        }
        assert_eq!(u.covariance, Matrix6::zeros());
        assert_eq!(u.translation_bound(3.0), u.offset.fixed_rows::<3>(0).norm());
    }

    #[test]
    fn bad_inputs_are_refused_by_name() {
        let k = Intrinsics::pinhole(800.0, 790.0, 330.0, 250.0).unwrap();
        let goal = view(&[0.0; 6], &k);
        let depths: Vec<f64> = object().iter().map(|p| p[2]).collect();
        let m = Measurement { pixels: &goal, depths: &depths, reference_pixels: &goal, visible: None, k_hat: &k };
        let noise = ImageNoise { current: 0.5, reference: 0.5, averaged_images: 1 };
        let bad_noise = ImageNoise { current: f64::NAN, ..noise };
        assert!(matches!(
            pixel_pose_uncertainty(&m, bad_noise),
            Err(Error::InvalidParameter { name: "noise.current", .. })
        ));
        let none = ImageNoise { averaged_images: 0, ..noise };
        assert!(matches!(invariant_pose_uncertainty(&m, [0, 1, 2], none), Err(Error::InvalidParameter { .. })));
        let short = Measurement { depths: &depths[..7], ..m };
        assert!(matches!(pixel_pose_uncertainty(&short, noise), Err(Error::Shape { what: "depths", .. })));
        let hidden = [true, true, true, true, true, false, false, false];
        let few = Measurement { visible: Some(&hidden), ..m };
        assert!(matches!(invariant_pose_uncertainty(&few, [0, 1, 2], noise), Err(Error::TooFewPoints { .. })));
        let mut behind = depths.clone();
        behind[3] = -1.0;
        let behind = Measurement { depths: &behind, ..m };
        assert!(matches!(pixel_pose_uncertainty(&behind, noise), Err(Error::PointBehindCamera { index: 3, .. })));
        // Three images of one point cannot fix six dof.
        let same = [[100.0, 100.0]; 3];
        let flat = Measurement { pixels: &same, depths: &[0.5; 3], reference_pixels: &same, visible: None, k_hat: &k };
        assert!(matches!(pixel_pose_uncertainty(&flat, noise), Err(Error::DegenerateEstimate { .. })));
    }

    #[test]
    fn many_points_take_memory_in_proportion() {
        // 50,000 points: a dense G would be 100,000 x 100,000 (80 GB); the sparse one is 8 MB.
        let k = Intrinsics::pinhole(800.0, 790.0, 330.0, 250.0).unwrap();
        let points: Vec<[f64; 3]> = (0..50_000)
            .map(|i| [(i % 250) as f64 * 1e-3 - 0.12, (i / 250) as f64 * 1e-3 - 0.1, 0.5 + (i % 7) as f64 * 0.02])
            .collect();
        let (pixels, depths) = project_points(&points, &k).unwrap();
        let m = Measurement { pixels: &pixels, depths: &depths, reference_pixels: &pixels, visible: None, k_hat: &k };
        let noise = ImageNoise { current: 0.5, reference: 0.5, averaged_images: 1 };
        let few = pixel_pose_uncertainty(
            &Measurement { pixels: &pixels[..500], depths: &depths[..500], reference_pixels: &pixels[..500], ..m },
            noise,
        )
        .unwrap();
        let many = pixel_pose_uncertainty(&m, noise).unwrap();
        assert!(many.translation_sigma() < few.translation_sigma());
        let basis = [0, 249, 49_999];
        assert!(invariant_pose_uncertainty(&m, basis, noise).unwrap().translation_sigma().is_finite());
    }
}
