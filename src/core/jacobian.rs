//! Jacobians in the invariant space (sec. 4.1) and the coefficients of the rz task (eq. 23).
//!
//! For a non-basis point k, `dq_k/dt = Q^-1 (L_k - q_1k L_1 - q_2k L_2 - q_3k L_3) (v, w)`
//! (eq. 12 with correction 1: `P` reads `Q`), where `L_i` is the pixel interaction matrix
//! of point i. The sixth column (w_z) vanishes, so `J_k` is the first five columns. The same
//! matrix factors as `J_k = [Phi_k Psi_k] diag(K, F(K))` (correction 2).

use nalgebra::{DMatrix, Matrix2x6, Matrix3, Matrix5, Vector3, Vector5};

use crate::core::camera::{Intrinsics, f_of_matrix, pixel_interaction_unchecked};
use crate::core::invariant::{BasisFrame, RzReference, non_basis_indices, validate_basis};
use crate::error::{Error, Result, check_depths, check_finite_matrix, check_finite_points, check_overflow};

/// Minimum number of points for the five-dof law: each non-basis point gives two
/// independent rows, so rank J = 5 needs `n >= 6` (paper-corrections, "How many points").
pub const MIN_POINTS: usize = 6;

/// Default threshold on `sigma_5 / sigma_1` of the depth-balanced invariant Jacobian below
/// which the structure counts as degenerate (planar object or equal depth estimates; a
/// planar object gives about 1e-15, +-20 mm of relief at 600 mm about 0.08).
pub const DEFAULT_MIN_STRUCTURE_RATIO: f64 = 1e-3;

/// Fails with `TooFewPoints` when fewer than `min_points` points are given.
pub(crate) fn check_point_count(n: usize, min_points: usize) -> Result<()> {
    if n < min_points {
        return Err(Error::TooFewPoints {
            needed: min_points,
            got: n,
            why: "three basis points plus three more to control five dof",
        });
    }
    Ok(())
}

/// Validates pixels and depths (all but the basis: what can be checked before choosing one).
pub(crate) fn check_pixels_and_depths(pixels: &[[f64; 2]], depths: &[f64], min_points: usize) -> Result<()> {
    check_finite_points("pixels", pixels)?;
    let n = pixels.len();
    check_point_count(n, min_points)?;
    check_depths(depths, n)
}

/// Validates pixels and depths and the basis; returns the basis.
pub(crate) fn check_inputs(
    pixels: &[[f64; 2]],
    depths: &[f64],
    basis: [usize; 3],
    min_points: usize,
) -> Result<[usize; 3]> {
    check_pixels_and_depths(pixels, depths, min_points)?;
    validate_basis(basis, pixels.len())
}

/// `L_k - q_1k L_1 - q_2k L_2 - q_3k L_3` for the two image rows (the third row is zero).
#[inline]
pub(crate) fn combined_interaction(
    l_k: &Matrix2x6<f64>,
    l_basis: &[Matrix2x6<f64>; 3],
    q_k: &Vector3<f64>,
) -> Matrix2x6<f64> {
    l_k - l_basis[0] * q_k.x - l_basis[1] * q_k.y - l_basis[2] * q_k.z
}

/// The invariant interaction matrix in the direct form of sec. 4.1, all six columns:
/// `3 (n - 3) x 6`, rows in the order of `s`. Its last column is zero up to rounding.
pub fn invariant_interaction(
    pixels: &[[f64; 2]],
    depths: &[f64],
    intrinsics: &Intrinsics,
    basis: [usize; 3],
) -> Result<DMatrix<f64>> {
    let basis = check_inputs(pixels, depths, basis, 4)?;
    let frame = BasisFrame::new(pixels, basis, "current")?;
    let k = intrinsics.matrix();
    let k_inv = k.try_inverse().ok_or_else(|| Error::InvalidIntrinsics { reason: "K is singular".into() })?;
    let l_basis = basis.map(|i| pixel_interaction_unchecked(&k, &k_inv, pixels[i], depths[i]));
    let q_inv_2 = frame.q_inv.fixed_columns::<2>(0).into_owned();
    let others = non_basis_indices(pixels.len(), basis);
    let mut j = DMatrix::zeros(3 * others.len(), 6);
    for (row, &idx) in others.iter().enumerate() {
        let q_k = frame.transform(pixels[idx]);
        let l_k = pixel_interaction_unchecked(&k, &k_inv, pixels[idx], depths[idx]);
        let block = q_inv_2 * combined_interaction(&l_k, &l_basis, &q_k);
        j.fixed_view_mut::<3, 6>(3 * row, 0).copy_from(&block);
    }
    check_overflow("pixels, depths", "Jacobian entries", &[j.as_slice()])?;
    Ok(j)
}

/// The invariant Jacobian J of eq. (11), `3 (n - 3) x 5`: `ds/dt = J (vx, vy, vz, wx, wy)`.
/// With estimated intrinsics and depth estimates it is the `J_hat` of eq. (13).
pub fn invariant_jacobian(
    pixels: &[[f64; 2]],
    depths: &[f64],
    intrinsics: &Intrinsics,
    basis: [usize; 3],
) -> Result<DMatrix<f64>> {
    Ok(invariant_interaction(pixels, depths, intrinsics, basis)?.columns(0, 5).into_owned())
}

/// The factors `Phi(zeta)` (`3 (n-3) x 3`) and `Psi` (`3 (n-3) x 2`) of sec. 4.1, which depend
/// only on the pixels and depths: `J = [Phi K, Psi F(K)]` for any intrinsics K.
pub fn jacobian_factors(
    pixels: &[[f64; 2]],
    depths: &[f64],
    basis: [usize; 3],
) -> Result<(DMatrix<f64>, DMatrix<f64>)> {
    let basis = check_inputs(pixels, depths, basis, 4)?;
    let frame = BasisFrame::new(pixels, basis, "current")?;
    let others = non_basis_indices(pixels.len(), basis);
    let mut phi = DMatrix::zeros(3 * others.len(), 3);
    let mut psi = DMatrix::zeros(3 * others.len(), 2);
    let [u, v, z] = [0, 1, 2].map(|c| {
        Vector3::from_iterator(basis.iter().map(|&i| match c {
            0 => pixels[i][0],
            1 => pixels[i][1],
            _ => depths[i],
        }))
    });
    for (row, &idx) in others.iter().enumerate() {
        let q = frame.transform(pixels[idx]);
        let (uk, vk, zk) = (pixels[idx][0], pixels[idx][1], depths[idx]);
        let qz = q.component_div(&z);
        // Diagonal term read as sum_i q_ik/zeta_i - 1/zeta_k (correction 2).
        let diag = qz.sum() - 1.0 / zk;
        let inner_phi = Matrix3::new(diag, 0.0, uk / zk - u.dot(&qz), 0.0, diag, vk / zk - v.dot(&qz), 0.0, 0.0, 0.0);
        let uv = u.component_mul(&v);
        let inner_psi = nalgebra::Matrix3x2::new(
            uk * vk - uv.dot(&q),
            u.component_mul(&u).dot(&q) - uk * uk,
            vk * vk - v.component_mul(&v).dot(&q),
            uv.dot(&q) - uk * vk,
            0.0,
            0.0,
        );
        phi.fixed_view_mut::<3, 3>(3 * row, 0).copy_from(&(frame.q_inv * inner_phi));
        psi.fixed_view_mut::<3, 2>(3 * row, 0).copy_from(&(frame.q_inv * inner_psi));
    }
    check_overflow("pixels, depths", "Jacobian factors", &[phi.as_slice(), psi.as_slice()])?;
    Ok((phi, psi))
}

/// `[Phi K, Psi F(K)]`: the Jacobian assembled from its factors for a (possibly estimated)
/// upper-triangular K (eq. 13 with `Phi(zeta_hat) = Phi(zeta) / kappa`, correction 3).
/// Fails for factors of the wrong shapes (`Phi` with 3 columns, `Psi` with 2 and as many
/// rows), non-finite entries, a K that is not upper triangular with a nonzero diagonal, and
/// entries that overflow.
pub fn jacobian_from_factors(phi: &DMatrix<f64>, psi: &DMatrix<f64>, k: &Matrix3<f64>) -> Result<DMatrix<f64>> {
    let rows = phi.nrows();
    for (what, m, cols) in [("phi", phi, 3), ("psi", psi, 2)] {
        if m.ncols() != cols || m.nrows() != rows {
            return Err(Error::Shape {
                what,
                expected: format!("a {rows} x {cols} matrix"),
                got: format!("{} x {}", m.nrows(), m.ncols()),
            });
        }
        check_finite_matrix(what, m)?;
    }
    let f = f_of_matrix(k)?;
    let mut j = DMatrix::zeros(rows, 5);
    j.columns_mut(0, 3).copy_from(&(phi * k));
    j.columns_mut(3, 2).copy_from(&(psi * f));
    check_overflow("phi, psi, K", "Jacobian entries", &[j.as_slice()])?;
    Ok(j)
}

/// The coefficients of eq. (23), `d eps_z/dt = a w_z + c^T (vx, vy, vz, wx, wy)`, from the
/// current pixels and depths, the reference basis pixels and intrinsics (estimated ones give
/// `a_hat`, `c_hat` of eq. 24).
pub fn rz_coefficients(
    pixels: &[[f64; 2]],
    depths: &[f64],
    reference_pixels: &[[f64; 2]],
    intrinsics: &Intrinsics,
    basis: [usize; 3],
) -> Result<(f64, Vector5<f64>)> {
    let basis = check_inputs(pixels, depths, basis, 3)?;
    check_finite_points("reference_pixels", reference_pixels)?;
    if reference_pixels.len() != pixels.len() {
        return Err(Error::Shape {
            what: "reference_pixels",
            expected: format!("{} points", pixels.len()),
            got: format!("{} points", reference_pixels.len()),
        });
    }
    let reference = RzReference::new(&BasisFrame::new(reference_pixels, basis, "reference")?);
    let k = intrinsics.matrix();
    let k_inv = k.try_inverse().ok_or_else(|| Error::InvalidIntrinsics { reason: "K is singular".into() })?;
    let l_basis = basis.map(|i| pixel_interaction_unchecked(&k, &k_inv, pixels[i], depths[i]));
    let (a, c) = rz_from_interactions(&reference, &l_basis);
    check_overflow("pixels, depths", "rz coefficients", &[&[a], c.as_slice()])?;
    Ok((a, c))
}

/// `a`, `c` from the basis points' interaction matrices: `eps_z = sum_j adj(Q*)[j,0] v_j`,
/// so its derivative is the same combination of the v-rows of `L_j`.
#[inline]
pub(crate) fn rz_from_interactions(reference: &RzReference, l_basis: &[Matrix2x6<f64>; 3]) -> (f64, Vector5<f64>) {
    let w = &reference.adj_col0;
    let row = l_basis[0].row(1) * w.x + l_basis[1].row(1) * w.y + l_basis[2].row(1) * w.z;
    (row[5], Vector5::new(row[0], row[1], row[2], row[3], row[4]))
}

/// `sigma_5 / sigma_1` of the depth-balanced Jacobian `J diag(Z, Z, Z, 1, 1)`, Z the mean
/// depth: the degenerate-structure measure (paper corrections, "Planar object"), independent of the depth scale.
pub fn structure_ratio(pixels: &[[f64; 2]], depths: &[f64], intrinsics: &Intrinsics, basis: [usize; 3]) -> Result<f64> {
    let basis = check_inputs(pixels, depths, basis, MIN_POINTS)?;
    let j = invariant_jacobian(pixels, depths, intrinsics, basis)?;
    let jtj = j.transpose() * &j;
    let z = depths.iter().sum::<f64>() / depths.len() as f64;
    Ok(balanced_ratio(&Matrix5::from_iterator(jtj.iter().copied()), z))
}

/// `sigma_5/sigma_1` of `J D` from `J^T J`, with `D = diag(Z, Z, Z, 1, 1)`.
pub(crate) fn balanced_ratio(jtj: &Matrix5<f64>, mean_depth: f64) -> f64 {
    let d = Vector5::new(mean_depth, mean_depth, mean_depth, 1.0, 1.0);
    let balanced = Matrix5::from_fn(|r, c| jtj[(r, c)] * d[r] * d[c]);
    let eig = balanced.symmetric_eigenvalues();
    let (lo, hi) = (eig.min().max(0.0), eig.max());
    if hi > 0.0 && hi.is_finite() { (lo / hi).sqrt() } else { 0.0 }
}
