//! Rotations as unit quaternions and rotation vectors, the forms the hand-eye methods read
//! the motions in (Tsai-Lenz: `2 sin(theta/2) u`; Park-Martin: `theta u`; Daniilidis: unit
//! and dual quaternions).

use nalgebra::{Matrix3, Quaternion, Rotation3, UnitQuaternion, Vector3, Vector4};

/// The unit quaternion `(w, x, y, z)` of a rotation matrix, with `w >= 0` (the angle in
/// [0, pi]): nalgebra's conversion (which divides by the largest of the four `4 q_k^2`, as
/// Shepperd's method, for accuracy at every angle), in the order the methods' equations use.
pub(crate) fn quaternion(r: &Matrix3<f64>) -> Vector4<f64> {
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*r));
    let q = Vector4::new(q.w, q.i, q.j, q.k);
    if q[0] < 0.0 { -q } else { q }
}

/// The vector part `(x, y, z)` of a quaternion `(w, x, y, z)`.
pub(crate) fn vector_part(q: &Vector4<f64>) -> Vector3<f64> {
    Vector3::new(q[1], q[2], q[3])
}

/// The rotation vector `theta u` (theta in [0, pi]) of a rotation matrix, through its
/// quaternion: `theta = 2 atan2(|v|, w)`, accurate at small and large angles alike (an
/// `acos(w)` loses the small angles).
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

/// The rotation matrix of the unit quaternion `(w, v)` (nalgebra's).
pub(crate) fn rotation_from_quaternion(w: f64, v: &Vector3<f64>) -> Matrix3<f64> {
    UnitQuaternion::new_unchecked(Quaternion::new(w, v.x, v.y, v.z)).to_rotation_matrix().into_inner()
}

/// The Hamilton product of quaternions `(w, x, y, z)` (nalgebra's).
pub(crate) fn quaternion_product(p: &Vector4<f64>, q: &Vector4<f64>) -> Vector4<f64> {
    let pq = Quaternion::new(p[0], p[1], p[2], p[3]) * Quaternion::new(q[0], q[1], q[2], q[3]);
    Vector4::new(pq.w, pq.i, pq.j, pq.k)
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
