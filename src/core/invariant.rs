//! The projective invariant transform (sec. 2.3): the basis matrix `Q = [p1 p2 p3]`
//! (eqs. 6-7), the invariant points `q = Q^-1 p`, the task vector `s` and the matrix
//! `T = Q Q*^-1` (eq. 21) that carries the rotation about the optical axis.

use nalgebra::{Matrix3, Vector3};

use crate::core::widest_triangle::widest_triangle;
use crate::error::{Error, Result, check_finite_points};

/// Below this normalised triangle area (twice the area over the squared longest side) the
/// basis points count as collinear.
pub const COLLINEAR_RATIO: f64 = 1e-6;

/// Checks that a basis names three distinct points among `n`.
pub fn validate_basis(basis: [usize; 3], n: usize) -> Result<[usize; 3]> {
    if basis.iter().any(|&i| i >= n) {
        return Err(Error::InvalidParameter {
            name: "basis",
            reason: format!("indices {basis:?} out of range for {n} points"),
        });
    }
    if basis[0] == basis[1] || basis[0] == basis[2] || basis[1] == basis[2] {
        return Err(Error::InvalidParameter { name: "basis", reason: format!("indices {basis:?} must be distinct") });
    }
    Ok(basis)
}

fn triangle_ratio(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    let (abx, aby) = (b[0] - a[0], b[1] - a[1]);
    let (acx, acy) = (c[0] - a[0], c[1] - a[1]);
    let twice_area = (abx * acy - aby * acx).abs();
    let d2 = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
    let longest = d2(a, b).max(d2(a, c)).max(d2(b, c));
    if longest == 0.0 { 0.0 } else { twice_area / longest }
}

/// Chooses three points well spread in the image, as the paper does (sec. 5.1): the triangle
/// of largest area, ties broken by the smallest indices (the first `(i, j, k)` in
/// lexicographic order). The result is sorted.
///
/// `O(n log n)` for `n` points (a convex hull, then an exhaustive search over the points on
/// its boundary; see [`crate::core::widest_triangle`]): 10^6 points take about 0.2 s. Fails
/// with `InvalidParameter("pixels")` when more than
/// [`MAX_HULL_POINTS`](crate::core::widest_triangle::MAX_HULL_POINTS) points are vertices of
/// the convex hull (e.g. that many points on a circle), and with `CollinearBasis` when the
/// widest triangle is flat.
pub fn choose_basis(pixels: &[[f64; 2]]) -> Result<[usize; 3]> {
    check_finite_points("pixels", pixels)?;
    let n = pixels.len();
    if n < 3 {
        return Err(Error::TooFewPoints { needed: 3, got: n, why: "a basis needs three points" });
    }
    let (_, basis) = widest_triangle(pixels)?;
    let [i, j, k] = basis;
    let ratio = triangle_ratio(pixels[i], pixels[j], pixels[k]);
    if ratio < COLLINEAR_RATIO {
        return Err(Error::CollinearBasis { basis, image: "reference", ratio });
    }
    Ok(basis)
}

/// The basis matrix Q of eq. (6) and its inverse, from the pixels of the three basis points.
#[derive(Debug, Clone, Copy)]
pub struct BasisFrame {
    /// `Q = [p1 p2 p3]` with homogeneous pixels as columns.
    pub q: Matrix3<f64>,
    /// `Q^-1`.
    pub q_inv: Matrix3<f64>,
}

impl BasisFrame {
    /// Builds Q from `pixels[basis]`; fails for a basis that does not name three distinct
    /// points of `pixels` (it panicked for an index out of range before issue 16) and when the
    /// three pixels are (nearly) collinear or not finite.
    pub fn new(pixels: &[[f64; 2]], basis: [usize; 3], image: &'static str) -> Result<Self> {
        validate_basis(basis, pixels.len())?;
        let [a, b, c] = basis.map(|i| pixels[i]);
        let ratio = triangle_ratio(a, b, c);
        if ratio.is_nan() || ratio < COLLINEAR_RATIO {
            return Err(Error::CollinearBasis { basis, image, ratio });
        }
        let q = Matrix3::new(a[0], b[0], c[0], a[1], b[1], c[1], 1.0, 1.0, 1.0);
        // 3x3 closed-form inverse (cofactors); the ratio test above bounds its conditioning.
        let q_inv = q.try_inverse().ok_or(Error::CollinearBasis { basis, image, ratio })?;
        Ok(Self { q, q_inv })
    }

    /// `q = Q^-1 p` (sec. 2.3); its three coordinates sum to 1. Contract: finite for a finite
    /// pixel of moderate size (the callers check pixels and the overflow of their results).
    #[inline]
    pub fn transform(&self, pixel: [f64; 2]) -> Vector3<f64> {
        self.q_inv * Vector3::new(pixel[0], pixel[1], 1.0)
    }
}

/// The invariant points `q_k = Q^-1 p_k` of all `n` points (basis points map to the unit
/// vectors), as an `n x 3` list.
pub fn invariant_points(pixels: &[[f64; 2]], basis: [usize; 3]) -> Result<Vec<[f64; 3]>> {
    check_finite_points("pixels", pixels)?;
    validate_basis(basis, pixels.len())?;
    let frame = BasisFrame::new(pixels, basis, "current")?;
    Ok(pixels.iter().map(|&p| frame.transform(p).into()).collect())
}

/// The indices of the non-basis points, increasing: the order of the blocks of `s`.
pub fn non_basis_indices(n: usize, basis: [usize; 3]) -> Vec<usize> {
    (0..n).filter(|i| !basis.contains(i)).collect()
}

/// The task vector `s = (q_4, ..., q_n)` (sec. 4.1): the invariant points of the non-basis
/// points stacked in increasing index order, `3 (n - 3)` values.
pub fn task_vector(pixels: &[[f64; 2]], basis: [usize; 3]) -> Result<Vec<f64>> {
    let q = invariant_points(pixels, basis)?;
    Ok(non_basis_indices(pixels.len(), basis).into_iter().flat_map(|k| q[k]).collect())
}

/// What the reference image contributes to the rz task (sec. 4.2): `det(Q*)`, the first
/// column of `adj(Q*) = det(Q*) Q*^-1`, and `Q*^-1`.
#[derive(Debug, Clone, Copy)]
pub struct RzReference {
    /// `det(Q*)`.
    pub det_q_star: f64,
    /// `adj(Q*)[:, 0]`, so that `eps_z = sum_j v_j adj[j]` (sec. 4.2).
    pub adj_col0: Vector3<f64>,
    /// `Q*^-1`.
    pub q_star_inv: Matrix3<f64>,
}

impl RzReference {
    /// From the reference basis frame.
    pub fn new(reference: &BasisFrame) -> Self {
        let det_q_star = reference.q.determinant();
        Self { det_q_star, adj_col0: reference.q_inv.column(0) * det_q_star, q_star_inv: reference.q_inv }
    }

    /// `T = Q Q*^-1` (eq. 21).
    pub fn t_matrix(&self, current: &BasisFrame) -> Matrix3<f64> {
        current.q * self.q_star_inv
    }

    /// `eps_z = det(Q*) tau_21 = v1*(v3 - v2) + v2*(v1 - v3) + v3*(v2 - v1)` (sec. 4.2),
    /// from the current basis pixels' ordinates `v`.
    #[inline]
    pub fn eps_z(&self, v: &Vector3<f64>) -> f64 {
        self.adj_col0.dot(v)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn basis_points_map_to_unit_vectors_and_sum_to_one() {
        let px = [[10.0, 20.0], [300.0, 40.0], [150.0, 280.0], [123.0, 111.0], [-50.0, 400.0]];
        let q = invariant_points(&px, [0, 1, 2]).unwrap();
        assert_relative_eq!(q[0][0], 1.0, epsilon = 1e-12);
        assert_relative_eq!(q[1][1], 1.0, epsilon = 1e-12);
        assert_relative_eq!(q[2][2], 1.0, epsilon = 1e-12);
        for qk in q {
            assert_relative_eq!(qk.iter().sum::<f64>(), 1.0, epsilon = 1e-12);
        }
    }

    #[test]
    fn eps_z_matches_paper_expression_and_t_matrix() {
        let star = [[10.0, 20.0], [300.0, 40.0], [150.0, 280.0]];
        let cur = [[40.0, 10.0], [280.0, 90.0], [100.0, 260.0]];
        let rf = RzReference::new(&BasisFrame::new(&star, [0, 1, 2], "reference").unwrap());
        let cf = BasisFrame::new(&cur, [0, 1, 2], "current").unwrap();
        let v = Vector3::new(cur[0][1], cur[1][1], cur[2][1]);
        let (v1s, v2s, v3s) = (star[0][1], star[1][1], star[2][1]);
        let paper = v1s * (v.z - v.y) + v2s * (v.x - v.z) + v3s * (v.y - v.x);
        assert_relative_eq!(rf.eps_z(&v), paper, max_relative = 1e-12);
        let t = rf.t_matrix(&cf);
        assert_relative_eq!(rf.eps_z(&v), rf.det_q_star * t[(1, 0)], max_relative = 1e-12);
        assert_relative_eq!(t[(2, 0)], 0.0, epsilon = 1e-12);
        assert_relative_eq!(t[(2, 2)], 1.0, epsilon = 1e-12);
    }

    #[test]
    fn collinear_and_bad_basis_rejected() {
        let px = [[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [5.0, 1.0]];
        assert!(matches!(invariant_points(&px, [0, 1, 2]), Err(Error::CollinearBasis { .. })));
        assert!(matches!(invariant_points(&px, [0, 1, 7]), Err(Error::InvalidParameter { .. })));
        assert!(matches!(invariant_points(&px, [0, 0, 3]), Err(Error::InvalidParameter { .. })));
        assert!(invariant_points(&px, [0, 1, 3]).is_ok());
    }

    #[test]
    fn choose_basis_takes_the_largest_triangle() {
        let px = [[50.0, 50.0], [0.0, 0.0], [60.0, 40.0], [100.0, 0.0], [0.0, 100.0], [55.0, 45.0]];
        let b = choose_basis(&px).unwrap();
        assert!(b == [1, 3, 4], "{b:?}");
        assert!(choose_basis(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]).is_err());
    }

    /// Regression (issue 16 sweep): a basis index out of range panicked.
    #[test]
    fn basis_frame_checks_its_indices() {
        let px = [[10.0, 20.0], [300.0, 40.0], [150.0, 280.0]];
        assert!(BasisFrame::new(&px, [0, 1, 3], "current").is_err());
        assert!(BasisFrame::new(&px, [0, 1, 1], "current").is_err());
        assert!(BasisFrame::new(&px[..2], [0, 1, 2], "current").is_err());
        assert!(BasisFrame::new(&[[f64::NAN, 0.0], [1.0, 0.0], [0.0, 1.0]], [0, 1, 2], "current").is_err());
        assert!(BasisFrame::new(&px, [2, 0, 1], "current").is_ok());
    }
}
