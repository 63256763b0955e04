//! Stability of the five-dof law (sec. 4.1, Props. 1-3, appendix B).
//!
//! Linearised about the reference path, the closed loop is `d eps/dt = -lambda A eps + b`
//! (eq. 19) with `A = J_hat^+ J = blockdiag(kappa K_hat^-1 K, F(K_hat)^-1 F(K))`
//! (corrections 4-5), which holds wherever the depth estimates are `kappa zeta`.

use nalgebra::{Complex, Matrix2, Matrix3, Matrix5};

pub use crate::core::camera::check_upper_triangular;
use crate::core::camera::f_unchecked;
use crate::error::{Error, Result, Short, check_finite, check_overflow};

/// The depth scale `kappa` of sec. 4.1: the depth estimates are `kappa zeta`, so kappa is
/// finite and > 0 (a depth estimate is positive).
fn check_kappa(kappa: f64) -> Result<()> {
    check_finite("kappa", &[kappa])?;
    if kappa > 0.0 {
        return Ok(());
    }
    let reason = format!("the depth scale of sec. 4.1 must be > 0 (depth estimates kappa zeta), got {}", Short(kappa));
    Err(Error::InvalidParameter { name: "kappa", reason })
}

/// `A = blockdiag(kappa K_hat^-1 K, F(K_hat)^-1 F(K))` (eq. 19); `kappa` finite and > 0.
pub fn a_matrix(k: &Matrix3<f64>, k_hat: &Matrix3<f64>, kappa: f64) -> Result<Matrix5<f64>> {
    check_upper_triangular("K", k)?;
    check_upper_triangular("K_hat", k_hat)?;
    check_kappa(kappa)?;
    // K_hat is triangular with nonzero diagonal: solve instead of inverting.
    let top = k_hat
        .solve_upper_triangular(k)
        .ok_or_else(|| Error::InvalidIntrinsics { reason: "K_hat is singular".into() })?
        * kappa;
    let f_hat = f_unchecked(k_hat);
    let bottom: Matrix2<f64> = f_hat
        .solve_upper_triangular(&f_unchecked(k))
        .ok_or_else(|| Error::InvalidIntrinsics { reason: "F(K_hat) is singular".into() })?;
    let mut a = Matrix5::zeros();
    a.fixed_view_mut::<3, 3>(0, 0).copy_from(&top);
    a.fixed_view_mut::<2, 2>(3, 3).copy_from(&bottom);
    check_overflow("K, K_hat, kappa", "entries of A", &[a.as_slice()])?;
    Ok(a)
}

/// Stability verdicts for an estimate `K_hat` against the true intrinsics.
#[derive(Debug, Clone, PartialEq)]
pub struct StabilityReport {
    /// Prop. 1 (constant K, if and only if): `lambda > 0`, `kappa > 0`, `K_hat[0,0] > 0`,
    /// `K_hat[1,1] > 0` (correction 5), for every K of the schedule taken as constant.
    pub prop1: bool,
    /// Prop. 2 (time-varying K, sufficient): `lambda > 0`, `kappa > 0` and the symmetric
    /// parts of both blocks of A positive definite for every K of the schedule.
    pub prop2: bool,
    /// Eigenvalues of A for each K of the schedule (computed numerically).
    pub eigenvalues: Vec<[Complex<f64>; 5]>,
    /// Smallest eigenvalue of `A + A^T` over the schedule: the sigma of Prop. 3 (its minimum
    /// singular value) when positive; zero or negative when `A + A^T` is not positive definite.
    pub sigma: f64,
    /// lambda.
    pub gain: f64,
}

impl StabilityReport {
    /// Prop. 3: the bound `psi/phi` on `||eps(t)||` for `||b(t)|| <= max_b`, with
    /// `psi = 2 max_b` and `phi = lambda sigma` (eq. 20). An error when Prop. 2 fails
    /// (`sigma <= 0`): there is no bound then.
    pub fn tracking_bound(&self, max_b: f64) -> Result<f64> {
        tracking_bound(self.gain, self.sigma, max_b)
    }
}

/// Prop. 3 bound `psi / phi = 2 max_b / (lambda sigma)` (eq. 20), finite. Fails for a
/// non-finite argument, `gain <= 0`, `max_b < 0`, `sigma <= 0` (Prop. 2 does not hold, so
/// Prop. 3 gives no bound) and a bound that overflows (a tiny `gain sigma`).
pub fn tracking_bound(gain: f64, sigma: f64, max_b: f64) -> Result<f64> {
    check_finite("gain", &[gain])?;
    check_finite("sigma", &[sigma])?;
    check_finite("max_b", &[max_b])?;
    if gain <= 0.0 {
        return Err(Error::InvalidParameter { name: "gain", reason: format!("must be > 0, got {}", Short(gain)) });
    }
    if max_b < 0.0 {
        return Err(Error::InvalidParameter { name: "max_b", reason: format!("must be >= 0, got {}", Short(max_b)) });
    }
    if sigma <= 0.0 {
        let reason = format!(
            "must be > 0 (smallest eigenvalue of A + A^T; Prop. 2 fails and Prop. 3 gives no bound), got {}",
            Short(sigma)
        );
        return Err(Error::InvalidParameter { name: "sigma", reason });
    }
    let bound = 2.0 * max_b / (gain * sigma);
    check_overflow("tracking_bound inputs", "bound", &[&[bound]])?;
    Ok(bound)
}

/// Props. 1 and 2 verdicts and sigma only (no eigenvalues of A): what a simulation summary
/// needs, cheaper than [`check_stability`]. `A + A^T` is block diagonal, so its smallest
/// eigenvalue is the smaller of its two blocks'.
pub fn stability_verdicts(
    k_schedule: &[Matrix3<f64>],
    k_hat: &Matrix3<f64>,
    kappa: f64,
    gain: f64,
) -> Result<(bool, bool, f64)> {
    check_finite("gain", &[gain])?;
    check_kappa(kappa)?;
    let mut sigma = f64::INFINITY;
    for k in k_schedule {
        let a = a_matrix(k, k_hat, kappa)?;
        let top = a.fixed_view::<3, 3>(0, 0);
        let bottom = a.fixed_view::<2, 2>(3, 3);
        let s3 = (top + top.transpose()).symmetric_eigenvalues().min();
        let s2 = (bottom + bottom.transpose()).symmetric_eigenvalues().min();
        sigma = sigma.min(s3.min(s2));
    }
    let base = gain > 0.0;
    Ok((base && k_hat[(0, 0)] > 0.0 && k_hat[(1, 1)] > 0.0, base && sigma > 0.0, sigma))
}

/// Props. 1 and 2 for a schedule of true intrinsics `k_schedule` (one matrix for a fixed
/// camera), an estimate `k_hat` (any signs), the depth scale `kappa` (finite and > 0) and the
/// gain lambda.
pub fn check_stability(
    k_schedule: &[Matrix3<f64>],
    k_hat: &Matrix3<f64>,
    kappa: f64,
    gain: f64,
) -> Result<StabilityReport> {
    if k_schedule.is_empty() {
        return Err(Error::Shape { what: "K", expected: "at least one 3x3 matrix".into(), got: "none".into() });
    }
    check_finite("gain", &[gain])?;
    check_kappa(kappa)?;
    let base = gain > 0.0;
    let prop1_hat = k_hat[(0, 0)] > 0.0 && k_hat[(1, 1)] > 0.0;
    let mut eigenvalues = Vec::with_capacity(k_schedule.len());
    let mut sigma = f64::INFINITY;
    for k in k_schedule {
        crate::core::camera::Intrinsics::from_matrix(k)?;
        let a = a_matrix(k, k_hat, kappa)?;
        let ev = a.complex_eigenvalues();
        eigenvalues.push([ev[0], ev[1], ev[2], ev[3], ev[4]]);
        let sym = a + a.transpose();
        sigma = sigma.min(sym.symmetric_eigenvalues().min());
    }
    // Finite but extreme inputs (kappa near f64::MAX) overflow the eigen-decompositions.
    let parts: Vec<f64> = eigenvalues.iter().flatten().flat_map(|z| [z.re, z.im]).chain([sigma]).collect();
    check_overflow("kappa, K, K_hat", "eigenvalues of A", &[&parts])?;
    Ok(StabilityReport { prop1: base && prop1_hat, prop2: base && sigma > 0.0, eigenvalues, sigma, gain })
}
