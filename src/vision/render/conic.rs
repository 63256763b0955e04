//! The image of a disc: under perspective, a disc of radius `r` is the conic
//! `C = H^-T diag(1, 1, -r^2) H^-1` of the ideal image, with `H = K [E1 E2 C_c]` the
//! homography from the disc's plane (orthonormal axes E1, E2 and centre C_c in the camera
//! frame) to the image, so the ellipse is exact; its bounding box comes from the tangent lines
//! of the dual conic (or, through a lens, from points of its distorted rim).

use nalgebra::{Isometry3, Matrix3, Point3, Vector2, Vector3};

use super::lens::Warp;
use super::raster::Shape;
use crate::core::camera::Intrinsics;
use crate::vision::render::Disc;

/// The image of a disc: its conic and bounding box.
pub(super) struct ImageEllipse {
    /// `x^T C x <= 0` inside, for `x = (u, v, 1)`.
    pub(super) conic: Matrix3<f64>,
    /// `[u_min, v_min, u_max, v_max]`.
    pub(super) bbox: [f64; 4],
}

impl ImageEllipse {
    /// The ellipse of a disc seen from `pose`; None when the disc is not entirely in front of
    /// the camera or is seen (nearly) edge-on.
    pub(super) fn of(disc: &Disc, pose: &Isometry3<f64>, k: &Intrinsics, warp: &Warp) -> Option<Self> {
        let rt = pose.rotation.inverse();
        let center = rt * (Point3::from(disc.center) - pose.translation.vector).coords;
        let normal = rt * disc.normal;
        let e1 = normal.cross(&if normal.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() }).normalize();
        let e2 = normal.cross(&e1);
        let r = disc.radius;
        // The disc's nearest point to the camera plane must be in front of it.
        if center.z - r * (e1.z * e1.z + e2.z * e2.z).sqrt() <= 1e-9 {
            return None;
        }
        // Edge-on: the camera centre (nearly) in the disc's plane.
        if normal.dot(&center).abs() <= 1e-9 * center.norm() {
            return None;
        }
        let h = k.matrix() * Matrix3::from_columns(&[e1, e2, center]);
        let h_inv = h.try_inverse()?;
        let d = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -r * r));
        let conic = h_inv.transpose() * d * h_inv;
        // Tangent lines u = c and v = c from the dual conic H diag(1, 1, -1/r^2) H^T.
        let dual = h * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0 / (r * r))) * h.transpose();
        let (u_min, u_max) = tangent_range(dual[(0, 0)], dual[(0, 2)], dual[(2, 2)])?;
        let (v_min, v_max) = tangent_range(dual[(1, 1)], dual[(1, 2)], dual[(2, 2)])?;
        let bbox = match warp {
            Warp::Pinhole => [u_min, v_min, u_max, v_max],
            Warp::Lens { .. } => warp.bbox_of_circle(&h, r)?,
        };
        Some(Self { conic, bbox })
    }
}

impl Shape for ImageEllipse {
    fn bbox(&self) -> [f64; 4] {
        self.bbox
    }

    /// The box of the tangent lines (without a lens) holds the ellipse (tested below).
    fn bbox_holds_shape(&self) -> bool {
        true
    }

    #[inline]
    fn value(&self, u: f64, v: f64) -> f64 {
        let c = &self.conic;
        c[(0, 0)] * u * u
            + 2.0 * c[(0, 1)] * u * v
            + c[(1, 1)] * v * v
            + 2.0 * (c[(0, 2)] * u + c[(1, 2)] * v)
            + c[(2, 2)]
    }

    #[inline]
    fn gradient(&self, u: f64, v: f64) -> Vector2<f64> {
        let c = &self.conic;
        Vector2::new(
            2.0 * (c[(0, 0)] * u + c[(0, 1)] * v + c[(0, 2)]),
            2.0 * (c[(0, 1)] * u + c[(1, 1)] * v + c[(1, 2)]),
        )
    }

    #[inline]
    fn quadratic_scale(&self, u: f64, v: f64) -> Option<f64> {
        let c = self.conic.map(f64::abs);
        Some(
            c[(0, 0)] * u * u
                + 2.0 * c[(0, 1)] * u * v
                + c[(1, 1)] * v * v
                + 2.0 * (c[(0, 2)] * u + c[(1, 2)] * v)
                + c[(2, 2)],
        )
    }

    #[inline]
    fn second_order(&self) -> [f64; 3] {
        [self.conic[(0, 0)], self.conic[(0, 1)], self.conic[(1, 1)]]
    }
}

/// The roots of `a - 2 b x + c x^2 = 0` (a tangent line `x = const` of a dual conic), sorted.
fn tangent_range(a: f64, b: f64, c: f64) -> Option<(f64, f64)> {
    let disc = b * b - a * c;
    if !(disc >= 0.0) || c == 0.0 {
        return None;
    }
    let (x1, x2) = ((b - disc.sqrt()) / c, (b + disc.sqrt()) / c);
    let (lo, hi) = (x1.min(x2), x1.max(x2));
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    fn camera() -> Intrinsics {
        Intrinsics::new(800.0, 760.0, 320.0, 240.0, 85f64.to_radians()).unwrap()
    }

    fn pose() -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(0.05, -0.03, -0.1),
            UnitQuaternion::from_scaled_axis(Vector3::new(0.1, -0.2, 0.3)),
        )
    }

    #[test]
    fn conic_passes_through_the_projected_circle() {
        let disc = Disc::new([0.05, 0.02, 0.6], [0.2, -0.1, -1.0], 0.01).unwrap();
        let ell = ImageEllipse::of(&disc, &pose(), &camera(), &Warp::Pinhole).unwrap();
        let e1 = disc.normal.cross(&Vector3::x()).normalize();
        let e2 = disc.normal.cross(&e1);
        let inv = pose().inverse();
        let scale = ell.conic.norm();
        for t in 0..64 {
            let a = t as f64 / 64.0 * std::f64::consts::TAU;
            let p = disc.center + disc.radius * (a.cos() * e1 + a.sin() * e2);
            let (px, _) = camera().project(&(inv * Point3::from(p))).unwrap();
            // Normalised by |C| |x|^2, the conic vanishes on the boundary.
            let x2 = px[0] * px[0] + px[1] * px[1] + 1.0;
            assert!(ell.value(px[0], px[1]).abs() / (scale * x2) < 1e-12, "t = {t}");
            assert!(px[0] >= ell.bbox[0] - 1e-9 && px[0] <= ell.bbox[2] + 1e-9);
            assert!(px[1] >= ell.bbox[1] - 1e-9 && px[1] <= ell.bbox[3] + 1e-9);
        }
        // The centre's projection is inside.
        let (c, _) = camera().project(&(inv * Point3::from(disc.center))).unwrap();
        assert!(ell.value(c[0], c[1]) < 0.0);
    }
}
