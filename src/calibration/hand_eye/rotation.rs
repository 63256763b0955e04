//! Rotations as unit quaternions and rotation vectors, the forms the hand-eye methods read
//! the motions in (Tsai-Lenz: `2 sin(theta/2) u`; Park-Martin: `theta u`; Daniilidis: unit
//! and dual quaternions).

use nalgebra::{Matrix3, Vector3, Vector4};

/// The unit quaternion `(w, x, y, z)` of a rotation matrix, with `w >= 0` (the angle in
/// [0, pi]): Shepperd's method (J. Guidance and Control 1(3), 1978), which divides by the
/// largest of the four `4 q_k^2` for accuracy at every angle.
pub(crate) fn quaternion(r: &Matrix3<f64>) -> Vector4<f64> {
    let (m00, m11, m22) = (r[(0, 0)], r[(1, 1)], r[(2, 2)]);
    let trace = m00 + m11 + m22;
    let q = if trace > 0.0 {
        let s = 2.0 * (trace + 1.0).sqrt();
        Vector4::new(0.25 * s, (r[(2, 1)] - r[(1, 2)]) / s, (r[(0, 2)] - r[(2, 0)]) / s, (r[(1, 0)] - r[(0, 1)]) / s)
    } else if m00 > m11 && m00 > m22 {
        let s = 2.0 * (1.0 + m00 - m11 - m22).sqrt();
        Vector4::new((r[(2, 1)] - r[(1, 2)]) / s, 0.25 * s, (r[(0, 1)] + r[(1, 0)]) / s, (r[(0, 2)] + r[(2, 0)]) / s)
    } else if m11 > m22 {
        let s = 2.0 * (1.0 + m11 - m00 - m22).sqrt();
        Vector4::new((r[(0, 2)] - r[(2, 0)]) / s, (r[(0, 1)] + r[(1, 0)]) / s, 0.25 * s, (r[(1, 2)] + r[(2, 1)]) / s)
    } else {
        let s = 2.0 * (1.0 + m22 - m00 - m11).sqrt();
        Vector4::new((r[(1, 0)] - r[(0, 1)]) / s, (r[(0, 2)] + r[(2, 0)]) / s, (r[(1, 2)] + r[(2, 1)]) / s, 0.25 * s)
    };
    if q[0] < 0.0 { -q } else { q }
}

/// The vector part `(x, y, z)` of a quaternion `(w, x, y, z)`.
pub(crate) fn vector_part(q: &Vector4<f64>) -> Vector3<f64> {
    Vector3::new(q[1], q[2], q[3])
}

/// The rotation vector `theta u` (theta in [0, pi]) of a rotation matrix, through its
/// quaternion: `theta = 2 atan2(|v|, w)`, accurate at small and large angles alike.
pub(crate) fn rotation_vector(r: &Matrix3<f64>) -> Vector3<f64> {
    let q = quaternion(r);
    let v = vector_part(&q);
    let s = v.norm();
    if s == 0.0 { Vector3::zeros() } else { v * (2.0 * s.atan2(q[0]) / s) }
}

/// The rotation angle of a rotation matrix, radians in [0, pi].
pub(crate) fn rotation_angle(r: &Matrix3<f64>) -> f64 {
    let q = quaternion(r);
    2.0 * vector_part(&q).norm().atan2(q[0])
}

/// The rotation matrix of the unit quaternion `(w, v)`:
/// `R = (w^2 - |v|^2) I + 2 v v^T + 2 w [v]x`.
pub(crate) fn rotation_from_quaternion(w: f64, v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::identity() * (w * w - v.norm_squared()) + v * v.transpose() * 2.0 + skew(v) * (2.0 * w)
}

/// The cross-product matrix `[v]x` (`[v]x u = v x u`).
pub(crate) fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0)
}

/// The Hamilton product of quaternions `(w, x, y, z)`.
pub(crate) fn quaternion_product(p: &Vector4<f64>, q: &Vector4<f64>) -> Vector4<f64> {
    let (pv, qv) = (vector_part(p), vector_part(q));
    let w = p[0] * q[0] - pv.dot(&qv);
    let v = qv * p[0] + pv * q[0] + pv.cross(&qv);
    Vector4::new(w, v[0], v[1], v[2])
}

#[cfg(test)]
mod tests {
    use nalgebra::{Rotation3, Vector3};

    use super::*;

    #[test]
    fn quaternion_and_rotation_vector_round_trip_at_every_angle() {
        for angle in [0.0, 1e-9, 0.3, 1.0, 2.0, 3.0, std::f64::consts::PI - 1e-7] {
            for axis in [Vector3::x(), Vector3::y(), Vector3::z(), Vector3::new(1.0, -2.0, 0.5).normalize()] {
                let r = Rotation3::from_scaled_axis(axis * angle).into_inner();
                let q = quaternion(&r);
                assert!(q[0] >= 0.0);
                assert!((rotation_from_quaternion(q[0], &vector_part(&q)) - r).amax() < 1e-14);
                let tu = rotation_vector(&r);
                assert!((tu - axis * angle).amax() < 1e-9, "{angle} {axis:?}: {tu:?}");
                assert!((rotation_angle(&r) - angle).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn quaternion_product_composes_rotations() {
        let a = Rotation3::from_scaled_axis(Vector3::new(0.3, -0.2, 0.5)).into_inner();
        let b = Rotation3::from_scaled_axis(Vector3::new(-0.1, 0.7, 0.2)).into_inner();
        let ab = quaternion_product(&quaternion(&a), &quaternion(&b));
        assert!((rotation_from_quaternion(ab[0], &vector_part(&ab)) - a * b).amax() < 1e-14);
    }
}
