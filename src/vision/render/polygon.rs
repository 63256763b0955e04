//! The image of planar convex polygons (a tag's white cells): under perspective a convex
//! polygon entirely in front of the camera projects to a convex polygon of the ideal image
//! (a projective map preserves lines and, away from the vanishing line, convexity), so its
//! image is exact. The coverage of a pixel is the exact area of the polygon clipped to the
//! pixel's footprint (Sutherland-Hodgman clipping against the footprint's four edges; through
//! a lens the footprint is the parallelogram of the local Jacobian), summed over disjoint
//! polygons so that two cells sharing an edge leave no seam.

use nalgebra::{Isometry3, Matrix2, Point3, Vector2};

use super::lens::{Local, Warp};
use super::raster::{Patch, Shape};
use crate::core::camera::Intrinsics;
use crate::core::distortion::distort_normalised;

/// Samples per edge for the bounding box of a polygon seen through a lens (its edges curve).
const EDGE_SAMPLES: usize = 16;

/// A convex polygon of the ideal image, counter-clockwise in the `(u, v)` plane (positive
/// shoelace area).
#[derive(Debug, Clone)]
pub(super) struct ImagePolygon {
    vertices: Vec<[f64; 2]>,
    /// Per edge `i` (from vertex `i` to `i + 1`): the outward unit normal `n` and offset `c`,
    /// `n . x - c` the signed distance (pixels, > 0 outside).
    edges: Vec<([f64; 2], f64)>,
    /// `[u_min, v_min, u_max, v_max]` in the rendered image.
    bbox: [f64; 4],
}

impl ImagePolygon {
    /// `[u_min, v_min, u_max, v_max]` in the rendered image.
    pub(super) fn bbox(&self) -> [f64; 4] {
        self.bbox
    }

    /// The image of a convex polygon of F* seen from `pose`; None when a vertex is not in
    /// front of the camera or part of it lies beyond the lens model's fold, Some(None) when it
    /// is seen edge-on (no area).
    pub(super) fn of(
        vertices: &[Point3<f64>],
        pose: &Isometry3<f64>,
        k: &Intrinsics,
        warp: &Warp,
    ) -> Option<Option<Self>> {
        let inverse = pose.inverse();
        let m = k.matrix();
        let mut ideal = Vec::with_capacity(vertices.len());
        for p in vertices {
            let x = m * (inverse * p).coords;
            if !(x.z > 1e-9) {
                return None;
            }
            ideal.push([x.x / x.z, x.y / x.z]);
        }
        let area = signed_area(&ideal);
        if !(area.abs() > 1e-12) {
            return Some(None);
        }
        if area < 0.0 {
            ideal.reverse();
        }
        let bbox = match warp {
            Warp::Pinhole => bbox_of(ideal.iter().copied()),
            Warp::Lens { k, distortion } => {
                let mut rim = Vec::with_capacity(ideal.len() * EDGE_SAMPLES);
                for (i, a) in ideal.iter().enumerate() {
                    let b = ideal[(i + 1) % ideal.len()];
                    for s in 0..EDGE_SAMPLES {
                        let t = s as f64 / EDGE_SAMPLES as f64;
                        let p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
                        rim.push(distort_normalised(k.normalise(p).ok()?, k, distortion)?);
                    }
                }
                let [u0, v0, u1, v1] = bbox_of(rim.into_iter());
                [u0 - 1.0, v0 - 1.0, u1 + 1.0, v1 + 1.0]
            }
        };
        Some(Some(Self::with_bbox(ideal, bbox)))
    }

    /// A counter-clockwise convex polygon of the ideal image and its bounding box.
    pub(super) fn with_bbox(vertices: Vec<[f64; 2]>, bbox: [f64; 4]) -> Self {
        let n = vertices.len();
        let edges = (0..n)
            .map(|i| {
                let (a, b) = (vertices[i], vertices[(i + 1) % n]);
                let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
                let length = dx.hypot(dy).max(1e-300);
                // Counter-clockwise: the inside is on the left of each edge, the outside on its right.
                let normal = [dy / length, -dx / length];
                (normal, normal[0] * a[0] + normal[1] * a[1])
            })
            .collect();
        Self { vertices, edges, bbox }
    }

    /// The signed distance of `(u, v)` to the polygon's farthest edge line (<= 0 inside).
    fn value(&self, u: f64, v: f64) -> (f64, usize) {
        let mut best = (f64::NEG_INFINITY, 0);
        for (i, (n, c)) in self.edges.iter().enumerate() {
            let d = n[0] * u + n[1] * v - c;
            if d > best.0 {
                best = (d, i);
            }
        }
        best
    }

    /// The area of the polygon inside the footprint `corners` (a counter-clockwise convex
    /// quadrilateral), exact.
    fn area_in(&self, corners: &[[f64; 2]; 4]) -> f64 {
        let mut inside = true;
        for (n, c) in &self.edges {
            let d = corners.map(|p| n[0] * p[0] + n[1] * p[1] - c);
            if d.iter().all(|&x| x >= 0.0) {
                return 0.0;
            }
            inside &= d.iter().all(|&x| x <= 0.0);
        }
        if inside {
            return signed_area(corners);
        }
        let mut clipped = self.vertices.clone();
        for i in 0..4 {
            let (a, b) = (corners[i], corners[(i + 1) % 4]);
            clipped = clip(&clipped, a, b);
            if clipped.len() < 3 {
                return 0.0;
            }
        }
        signed_area(&clipped)
    }
}

/// Disjoint convex polygons painted as one shape (the white cells of a tag).
pub(super) struct ImagePolygons {
    pub(super) polygons: Vec<ImagePolygon>,
}

impl Shape for ImagePolygons {
    fn bbox(&self) -> [f64; 4] {
        let mut b = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
        for p in &self.polygons {
            b = [b[0].min(p.bbox[0]), b[1].min(p.bbox[1]), b[2].max(p.bbox[2]), b[3].max(p.bbox[3])];
        }
        b
    }

    fn value(&self, u: f64, v: f64) -> f64 {
        self.polygons.iter().map(|p| p.value(u, v).0).fold(f64::INFINITY, f64::min)
    }

    fn gradient(&self, u: f64, v: f64) -> Vector2<f64> {
        let nearest =
            self.polygons.iter().map(|p| p.value(u, v)).zip(&self.polygons).min_by(|a, b| a.0.0.total_cmp(&b.0.0));
        nearest.map_or(Vector2::zeros(), |((_, edge), p)| Vector2::from(p.edges[edge].0))
    }

    /// Per polygon, over the pixels of its own bounding box: the exact area of the polygon in
    /// each pixel's footprint, summed over the polygons (disjoint: at most the footprint).
    fn coverage(&self, patch: &Patch, warp: &Warp) -> Vec<f32> {
        let locals: Option<Vec<Option<Local>>> = match warp {
            Warp::Pinhole => None,
            Warp::Lens { .. } => Some(patch.pixels().map(|(u, v)| warp.local(u, v)).collect()),
        };
        let mut area = vec![0.0f64; patch.w * patch.h];
        for polygon in &self.polygons {
            let [u0, v0, u1, v1] = polygon.bbox;
            let (i0, j0) = ((u0.floor() as i64 - 1 - patch.u0).max(0), (v0.floor() as i64 - 1 - patch.v0).max(0));
            let i1 = (u1.ceil() as i64 + 1 - patch.u0).min(patch.w as i64 - 1);
            let j1 = (v1.ceil() as i64 + 1 - patch.v0).min(patch.h as i64 - 1);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let index = j as usize * patch.w + i as usize;
                    let (u, v) = ((patch.u0 + i) as f64, (patch.v0 + j) as f64);
                    area[index] += match &locals {
                        None => polygon.area_in(&footprint([u, v], &Matrix2::identity())),
                        Some(locals) => locals[index].as_ref().map_or(0.0, |local| {
                            polygon.area_in(&footprint(local.ideal, &local.jacobian))
                                / local.jacobian.determinant().abs()
                        }),
                    };
                }
            }
        }
        area.into_iter().map(|a| a.min(1.0) as f32).collect()
    }
}

/// The footprint of a pixel in the ideal image: the parallelogram `ideal + J [+-0.5, +-0.5]`,
/// counter-clockwise.
fn footprint(ideal: [f64; 2], jacobian: &Matrix2<f64>) -> [[f64; 2]; 4] {
    let corner = |du: f64, dv: f64| {
        [
            ideal[0] + jacobian[(0, 0)] * du + jacobian[(0, 1)] * dv,
            ideal[1] + jacobian[(1, 0)] * du + jacobian[(1, 1)] * dv,
        ]
    };
    let quad = [corner(-0.5, -0.5), corner(-0.5, 0.5), corner(0.5, 0.5), corner(0.5, -0.5)];
    if signed_area(&quad) >= 0.0 { quad } else { [quad[3], quad[2], quad[1], quad[0]] }
}

/// The area of a polygon, positive when counter-clockwise in the `(u, v)` plane (shoelace).
fn signed_area(p: &[[f64; 2]]) -> f64 {
    let n = p.len();
    0.5 * (0..n).map(|i| p[i][0] * p[(i + 1) % n][1] - p[(i + 1) % n][0] * p[i][1]).sum::<f64>()
}

/// The part of `polygon` on the inner side of the directed edge `a -> b` of a counter-clockwise
/// clip region (Sutherland-Hodgman, one edge).
fn clip(polygon: &[[f64; 2]], a: [f64; 2], b: [f64; 2]) -> Vec<[f64; 2]> {
    // The inside of a counter-clockwise region is on the left of a -> b: `side >= 0`.
    let side = |p: [f64; 2]| (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
    let mut out = Vec::with_capacity(polygon.len() + 2);
    for i in 0..polygon.len() {
        let (p, q) = (polygon[i], polygon[(i + 1) % polygon.len()]);
        let (sp, sq) = (side(p), side(q));
        if sp >= 0.0 {
            out.push(p);
        }
        if (sp < 0.0 && sq > 0.0) || (sp > 0.0 && sq < 0.0) {
            let t = sp / (sp - sq);
            out.push([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]);
        }
    }
    out
}

/// The bounding box `[u_min, v_min, u_max, v_max]` of points.
fn bbox_of(points: impl Iterator<Item = [f64; 2]>) -> [f64; 4] {
    points.fold([f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY], |b, p| {
        [b[0].min(p[0]), b[1].min(p[1]), b[2].max(p[0]), b[3].max(p[1])]
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::core::distortion::Distortion;

    fn polygons(list: &[&[[f64; 2]]]) -> ImagePolygons {
        let polygons = list
            .iter()
            .map(|p| {
                let mut v = p.to_vec();
                if signed_area(&v) < 0.0 {
                    v.reverse();
                }
                ImagePolygon::with_bbox(v.clone(), bbox_of(v.into_iter()))
            })
            .collect();
        ImagePolygons { polygons }
    }

    fn patch() -> Patch {
        Patch { u0: 0, v0: 0, w: 12, h: 10 }
    }

    #[test]
    fn pixel_coverage_is_the_exact_area() {
        // The rectangle [1.25, 4.5] x [2.0, 3.75].
        let rect = polygons(&[&[[1.25, 2.0], [4.5, 2.0], [4.5, 3.75], [1.25, 3.75]]]);
        let c = rect.coverage(&patch(), &Warp::Pinhole);
        let at = |u: usize, v: usize| f64::from(c[v * 12 + u]);
        // Pixel (u, v) covers [u - 0.5, u + 0.5] x [v - 0.5, v + 0.5].
        assert!((at(1, 2) - 0.25 * 0.5).abs() < 1e-7);
        assert!((at(2, 3) - 1.0).abs() < 1e-7);
        assert!((at(4, 4) - 1.0 * 0.25).abs() < 1e-7);
        assert!((at(5, 3) - 0.0).abs() < 1e-7);
        assert!((at(1, 4) - 0.25 * 0.25).abs() < 1e-7);
        // A triangle: the coverage sums to its area (shoelace), whatever the winding.
        let triangle = [[0.3, 0.2], [7.9, 1.4], [2.2, 6.7]];
        let area = signed_area(&triangle).abs();
        let sum: f64 = polygons(&[&triangle]).coverage(&patch(), &Warp::Pinhole).iter().map(|&x| f64::from(x)).sum();
        assert!((sum - area).abs() < 1e-5, "{sum} vs {area}");
        // A pixel cut through its centre by the hypotenuse u + v = 9: half.
        let square = polygons(&[&[[0.5, 0.5], [8.5, 0.5], [0.5, 8.5]]]);
        assert!((square.coverage(&patch(), &Warp::Pinhole)[4 * 12 + 5] - 0.5).abs() < 1e-7);
    }

    #[test]
    fn polygons_sharing_an_edge_leave_no_seam() {
        // Two triangles of one square, sharing its diagonal; and two rectangles sharing x = 4.3.
        let split = polygons(&[
            &[[1.0, 1.0], [7.0, 1.0], [7.0, 7.0]],
            &[[1.0, 1.0], [7.0, 7.0], [1.0, 7.0]],
            &[[8.0, 1.0], [9.3, 1.0], [9.3, 8.0], [8.0, 8.0]],
            &[[9.3, 1.0], [11.0, 1.0], [11.0, 8.0], [9.3, 8.0]],
        ]);
        let c = split.coverage(&patch(), &Warp::Pinhole);
        for v in 2..7 {
            for u in (2..7).chain(9..11) {
                assert!((c[v * 12 + u] - 1.0).abs() < 1e-6, "({u}, {v}): {}", c[v * 12 + u]);
            }
        }
    }

    #[test]
    fn through_a_lens_the_coverage_is_the_distorted_area() {
        let k = Intrinsics::pinhole(600.0, 600.0, 416.0, 312.0).unwrap();
        let d = Distortion::from_coefficients(&[-0.30, 0.10, 0.0005, -0.0008, -0.02]).unwrap();
        let warp = Warp::new(&k, &d);
        // A square of 0.02 m at 0.5 m near a corner of the image, fronto-parallel.
        let corners = [[0.26, 0.18], [0.28, 0.18], [0.28, 0.2], [0.26, 0.2]];
        let vertices: Vec<Point3<f64>> = corners.iter().map(|c| Point3::new(c[0], c[1], 0.5)).collect();
        let polygon = ImagePolygon::of(&vertices, &Isometry3::identity(), &k, &warp).unwrap().unwrap();
        let shape = ImagePolygons { polygons: vec![polygon] };
        let [u0, v0, u1, v1] = shape.bbox();
        let patch = Patch {
            u0: u0.floor() as i64 - 2,
            v0: v0.floor() as i64 - 2,
            w: (u1 - u0) as usize + 5,
            h: (v1 - v0) as usize + 5,
        };
        let sum: f64 = shape.coverage(&patch, &warp).iter().map(|&x| f64::from(x)).sum();
        // The distorted outline, 200 points an edge, by the core's distort_points.
        let mut rim = Vec::new();
        for i in 0..4 {
            let (a, b) = (corners[i], corners[(i + 1) % 4]);
            for s in 0..200 {
                let t = f64::from(s) / 200.0;
                let (x, y) = (a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]));
                rim.push([416.0 + 600.0 * x / 0.5, 312.0 + 600.0 * y / 0.5]);
            }
        }
        let area = signed_area(&crate::core::distortion::distort_points(&rim, &k, &d).unwrap()).abs();
        assert!(area < 0.85 * 24.0 * 24.0, "{area}");
        assert!((sum / area - 1.0).abs() < 2e-3, "{sum} vs {area}");
    }

    #[test]
    fn behind_and_edge_on_polygons_are_refused_or_skipped() {
        let k = Intrinsics::pinhole(600.0, 600.0, 100.0, 100.0).unwrap();
        let at = |z: [f64; 3]| [Point3::new(0.0, 0.0, z[0]), Point3::new(0.1, 0.0, z[1]), Point3::new(0.0, 0.1, z[2])];
        let of = |v: &[Point3<f64>]| ImagePolygon::of(v, &Isometry3::identity(), &k, &Warp::Pinhole);
        assert!(of(&at([0.5, 0.5, -0.1])).is_none());
        assert!(of(&at([0.5, 0.5, 0.5])).unwrap().is_some());
        // In a plane through the camera centre: edge-on.
        let edge_on = [Point3::new(0.0, 0.1, 0.5), Point3::new(0.0, 0.1, 1.0), Point3::new(0.0, 0.2, 1.0)];
        assert!(of(&edge_on).unwrap().is_none());
    }
}
