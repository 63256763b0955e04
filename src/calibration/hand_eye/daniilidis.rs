//! Daniilidis, "Hand-eye calibration using dual quaternions", Int. J. Robotics Research
//! 18(3), 1999: with the motions as unit dual quaternions `a + eps a'` (gripper) and
//! `b + eps b'` (camera), the real parts of the same sign, each motion gives six linear
//! equations in the dual quaternion `q + eps q'` of `X` (eq. 31):
//!
//! ```text
//! | a - b     [a + b]x   0         0        | (q, q') = 0
//! | a' - b'   [a' + b']x a - b     [a + b]x |
//! ```
//!
//! (vector parts only). The stacked matrix `T` has a two-dimensional null space `(u1, v1)`,
//! `(u2, v2)`; the solution `lambda1 (u1, v1) + lambda2 (u2, v2)` is the one with
//! `|q| = 1` and `q . q' = 0` (eqs. 34-35, a quadratic in `lambda1 / lambda2`).

use nalgebra::{SMatrix, SymmetricEigen, Vector3, Vector4};

use super::Solution;
use super::motions::{Motion, Rigid};
use super::rotation::{quaternion, quaternion_product, rotation_from_quaternion, vector_part};
use crate::calibration::error::{CalibrationError, Result};

/// The unit dual quaternion `(q, q')` of a rigid motion: `q` its rotation (`w >= 0`),
/// `q' = (0, t) q / 2`.
fn dual_quaternion(m: &Rigid) -> (Vector4<f64>, Vector4<f64>) {
    let q = quaternion(&m.r);
    let q_dual = quaternion_product(&Vector4::new(0.0, m.t[0], m.t[1], m.t[2]), &q) * 0.5;
    (q, q_dual)
}

/// `T^T T` of eq. 31 over the motions.
fn normal_matrix(motions: &[Motion]) -> SMatrix<f64, 8, 8> {
    let mut normal = SMatrix::<f64, 8, 8>::zeros();
    for m in motions {
        let ((qa, qa_dual), (qb, qb_dual)) = (dual_quaternion(&m.gripper), dual_quaternion(&m.camera));
        let (a, b) = (vector_part(&qa), vector_part(&qb));
        let (a_dual, b_dual): (Vector3<f64>, Vector3<f64>) = (vector_part(&qa_dual), vector_part(&qb_dual));
        let mut s = SMatrix::<f64, 6, 8>::zeros();
        s.fixed_view_mut::<3, 1>(0, 0).copy_from(&(a - b));
        s.fixed_view_mut::<3, 3>(0, 1).copy_from(&(a + b).cross_matrix());
        s.fixed_view_mut::<3, 1>(3, 0).copy_from(&(a_dual - b_dual));
        s.fixed_view_mut::<3, 3>(3, 1).copy_from(&(a_dual + b_dual).cross_matrix());
        s.fixed_view_mut::<3, 1>(3, 4).copy_from(&(a - b));
        s.fixed_view_mut::<3, 3>(3, 5).copy_from(&(a + b).cross_matrix());
        normal += s.transpose() * s;
    }
    normal
}

/// The camera-to-gripper transform by Daniilidis; `poses` is the number of stations.
pub(crate) fn solve(motions: &[Motion], poses: usize) -> Result<Solution> {
    let degenerate =
        |reason: &str| CalibrationError::DegenerateMotion { poses, reason: format!("Daniilidis: {reason}") };
    let eigen = SymmetricEigen::new(normal_matrix(motions));
    let mut order: Vec<usize> = (0..8).collect();
    order.sort_by(|&i, &j| eigen.eigenvalues[i].total_cmp(&eigen.eigenvalues[j]));
    // The null space: the eigenvectors of the two smallest eigenvalues of T^T T.
    let (w1, w2) = (eigen.eigenvectors.column(order[1]).into_owned(), eigen.eigenvectors.column(order[0]).into_owned());
    let (u1, v1) = (w1.fixed_rows::<4>(0).into_owned(), w1.fixed_rows::<4>(4).into_owned());
    let (u2, v2) = (w2.fixed_rows::<4>(0).into_owned(), w2.fixed_rows::<4>(4).into_owned());
    // q . q' = 0 (eq. 34) as a quadratic in s = lambda1 / lambda2.
    let (a, b, c) = (u1.dot(&v1), u1.dot(&v2) + u2.dot(&v1), u2.dot(&v2));
    let roots: Vec<f64> = if a.abs() > 1e-12 * (b.abs() + c.abs()) {
        let root = (b * b - 4.0 * a * c).max(0.0).sqrt();
        vec![(-b + root) / (2.0 * a), (-b - root) / (2.0 * a)]
    } else {
        vec![-c / b]
    };
    // |q| = 1 (eq. 35): lambda2^2 (s^2 u1.u1 + 2 s u1.u2 + u2.u2) = 1; the root of larger value.
    let value = |s: f64| s * s * u1.dot(&u1) + 2.0 * s * u1.dot(&u2) + u2.dot(&u2);
    let s = roots.into_iter().filter(|s| s.is_finite()).max_by(|x, y| value(*x).total_cmp(&value(*y)));
    let Some(s) = s.filter(|s| value(*s) > 0.0) else {
        return Err(degenerate("no unit dual quaternion in the null space of eq. 31"));
    };
    let lambda2 = 1.0 / value(s).sqrt();
    let (q, q_dual) = ((u1 * s + u2) * lambda2, (v1 * s + v2) * lambda2);
    let q_conj = Vector4::new(q[0], -q[1], -q[2], -q[3]);
    let t = vector_part(&quaternion_product(&q_dual, &q_conj)) * 2.0;
    let r = rotation_from_quaternion(q[0], &vector_part(&q));
    if !(r.iter().chain(t.iter()).all(|v| v.is_finite())) {
        return Err(degenerate("the solution is not finite"));
    }
    Ok(Solution { x: Rigid { r, t }, motions_used: motions.len() })
}
