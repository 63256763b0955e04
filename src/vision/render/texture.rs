//! Textured planar faces: a convex planar polygon of the object frame (F*) carrying a grey
//! texture. The map from the ideal image to a face's plane is a homography (the plane's
//! projection inverted), composed with the homography from the plane to the texture given by
//! the corners' texture coordinates. The texture is the continuous surface its texels sample:
//! texel `(i, j)` is its value at `(i, j)`, read between texels by bilinear interpolation
//! (clamped to the edge texels), as OpenGL's and MuJoCo's linear filter reads a texture. A
//! pixel's grey level is the area average of that surface over the pixel's footprint, estimated
//! by `n x n` samples with `n` chosen from the local scale (at least 4 samples per texel and
//! axis: a minification by 2 does not alias). A nearest-texel (piecewise-constant) texture would
//! put a step at every texel edge, whose place in a magnified pixel `n x n` samples find only to
//! `1 / (2n)` of a pixel. Faces turned away from the camera are culled; the nearest face wins
//! per sample.

use std::sync::Arc;

use nalgebra::{Isometry3, Matrix3, Point3, SMatrix, SVector, Vector2, Vector3};

use super::lens::Warp;
use super::polygon::ImagePolygon;
use super::raster::{Paint, Patch, blur};
use super::{Canvas, Drawing};
use crate::core::camera::Intrinsics;
use crate::error::Error;
use crate::vision::error::Result;
use crate::vision::image::GreyImage;

/// The most faces one image is drawn with: each sample of a pixel is tested against every face
/// that may meet it, so the time grows with their number (about 1 s a 640x480 frame for three).
pub const MAX_FACES: usize = 64;
/// Fewest and most samples per pixel and axis.
const MIN_SAMPLES: usize = 4;
const MAX_SAMPLES: usize = 16;
/// Relative tolerance of the planarity and texture-coordinate checks.
const PLANAR_TOLERANCE: f64 = 1e-9;

fn invalid(name: &'static str, reason: String) -> crate::vision::error::VisionError {
    Error::InvalidParameter { name, reason }.into()
}

/// A convex planar polygon of F* with a grey texture; its front side is the one its vertices
/// turn counter-clockwise around.
#[derive(Debug, Clone)]
pub struct TexturedFace {
    vertices: Vec<Point3<f64>>,
    texture: Arc<GreyImage>,
    origin: Point3<f64>,
    /// Orthonormal in-plane axes and the unit front normal.
    axes: [Vector3<f64>; 3],
    /// The polygon in plane coordinates, counter-clockwise.
    outline: Vec<Vector2<f64>>,
    /// Plane coordinates `(a, b, 1)` to homogeneous texture pixels.
    to_texture: Matrix3<f64>,
}

impl TexturedFace {
    /// A face of at least 3 finite vertices (metres, F*) with one texture coordinate (texture
    /// pixels) each; refused when non-planar, degenerate, not convex, or when the texture
    /// coordinates are not a projective image of the vertices.
    pub fn new(vertices: Vec<[f64; 3]>, texture_coords: Vec<[f64; 2]>, texture: Arc<GreyImage>) -> Result<Self> {
        crate::error::check_finite("face vertices", vertices.as_flattened())?;
        crate::error::check_finite("texture coordinates", texture_coords.as_flattened())?;
        crate::vision::image::check_image("texture", texture.as_ref())?;
        if vertices.len() < 3 || texture_coords.len() != vertices.len() {
            let reason = format!(
                "at least 3 vertices and one texture coordinate each, got {} and {}",
                vertices.len(),
                texture_coords.len()
            );
            return Err(invalid("face", reason));
        }
        let points: Vec<Point3<f64>> = vertices.into_iter().map(Point3::from).collect();
        let (origin, axes) = plane_of(&points)?;
        let outline: Vec<Vector2<f64>> =
            points.iter().map(|p| Vector2::new((p - origin).dot(&axes[0]), (p - origin).dot(&axes[1]))).collect();
        check_convex(&outline)?;
        let to_texture = homography(&outline, &texture_coords)?;
        Ok(Self { vertices: points, texture, origin, axes, outline, to_texture })
    }

    /// The vertices.
    pub fn vertices(&self) -> &[Point3<f64>] {
        &self.vertices
    }
}

/// Textured faces as a [`Drawing`]: one point per face, drawn as
/// [`Canvas::draw_textured_faces`] draws them (a face flagged off is left out).
#[derive(Debug, Clone)]
pub struct TexturedFaces(pub Vec<TexturedFace>);

impl Drawing for TexturedFaces {
    fn point_count(&self) -> usize {
        self.0.len()
    }

    fn draw_on(&self, canvas: &mut Canvas<'_>, visible: Option<&[bool]>) -> Vec<bool> {
        let Some(visible) = visible else { return canvas.draw_textured_faces(&self.0) };
        let shown: Vec<TexturedFace> =
            self.0.iter().zip(visible).filter(|(_, v)| **v).map(|(f, _)| f.clone()).collect();
        let mut drawn = canvas.draw_textured_faces(&shown).into_iter();
        visible.iter().map(|v| *v && drawn.next().unwrap_or(false)).collect()
    }
}

/// The plane of the vertices (Newell's normal): origin, in-plane axes and normal.
fn plane_of(points: &[Point3<f64>]) -> Result<(Point3<f64>, [Vector3<f64>; 3])> {
    let mut newell = Vector3::zeros();
    for (i, p) in points.iter().enumerate() {
        newell += p.coords.cross(&points[(i + 1) % points.len()].coords);
    }
    let size = points.iter().map(|p| (p - points[0]).norm()).fold(0.0, f64::max);
    if !(newell.norm() > 1e-12 * size * size && size > 0.0) {
        return Err(invalid("face", "degenerate: no area".into()));
    }
    let normal = newell.normalize();
    let origin = points[0];
    if let Some(i) = points.iter().position(|p| (p - origin).dot(&normal).abs() > PLANAR_TOLERANCE * size) {
        return Err(invalid("face", format!("not planar: vertex {i} is off the plane")));
    }
    let e1 = (points[1] - origin).normalize();
    Ok((origin, [e1, normal.cross(&e1), normal]))
}

fn check_convex(outline: &[Vector2<f64>]) -> Result<()> {
    let n = outline.len();
    for i in 0..n {
        let (a, b, c) = (outline[i], outline[(i + 1) % n], outline[(i + 2) % n]);
        let d1 = b - a;
        let d2 = c - b;
        if !(d1.perp(&d2) > 1e-12 * d1.norm() * d2.norm()) {
            return Err(invalid("face", format!("not strictly convex at vertex {}", (i + 1) % n)));
        }
    }
    Ok(())
}

/// The homography (affine for a triangle) from plane coordinates to texture pixels through
/// the first four correspondences, checked on the others.
fn homography(outline: &[Vector2<f64>], uv: &[[f64; 2]]) -> Result<Matrix3<f64>> {
    let h = if outline.len() == 3 {
        let m = Matrix3::from_fn(|r, c| if r == 2 { 1.0 } else { outline[c][r] });
        let t = Matrix3::from_fn(|r, c| if r == 2 { 1.0 } else { uv[c][r] });
        m.try_inverse().map(|mi| t * mi)
    } else {
        let mut a = SMatrix::<f64, 8, 8>::zeros();
        let mut b = SVector::<f64, 8>::zeros();
        for k in 0..4 {
            let (x, y, u, v) = (outline[k].x, outline[k].y, uv[k][0], uv[k][1]);
            a.set_row(2 * k, &[x, y, 1.0, 0.0, 0.0, 0.0, -u * x, -u * y].into());
            a.set_row(2 * k + 1, &[0.0, 0.0, 0.0, x, y, 1.0, -v * x, -v * y].into());
            b[2 * k] = u;
            b[2 * k + 1] = v;
        }
        a.lu().solve(&b).map(|s| Matrix3::new(s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7], 1.0))
    };
    let h = h.ok_or_else(|| invalid("texture coordinates", "degenerate: no map from the face".into()))?;
    let scale = uv.iter().flatten().fold(1.0f64, |m, x| m.max(x.abs()));
    for (i, (p, t)) in outline.iter().zip(uv).enumerate() {
        let x = h * Vector3::new(p.x, p.y, 1.0);
        let ok = x.z > 0.0 && ((x.x / x.z - t[0]).abs() + (x.y / x.z - t[1]).abs()) <= 1e-6 * scale;
        if !ok {
            return Err(invalid(
                "texture coordinates",
                format!("coordinate {i} is not a projective image of its vertex"),
            ));
        }
    }
    Ok(h)
}

/// A face as the camera sees it: ideal pixel to plane coordinates, and its depth.
struct SeenFace<'f> {
    face: &'f TexturedFace,
    /// Homogeneous ideal pixel to homogeneous plane coordinates.
    from_image: Matrix3<f64>,
    /// Ideal pixel `(a, b)` -> plane coordinates; the camera depth of plane point `(a, b)`
    /// is `depth . (a, b, 1)`.
    depth: Vector3<f64>,
    bbox: [f64; 4],
}

impl<'f> SeenFace<'f> {
    /// None when culled (turned away), behind the camera or straddling it, or edge-on.
    fn of(face: &'f TexturedFace, pose: &Isometry3<f64>, k: &Intrinsics, warp: &Warp) -> Option<Self> {
        let inverse = pose.inverse();
        let centre = pose.translation.vector;
        if !((centre - face.origin.coords).dot(&face.axes[2]) > 0.0) {
            return None;
        }
        let image = ImagePolygon::of(&face.vertices, pose, k, warp)??;
        let r = inverse.rotation;
        let (e1, e2, o) = (r * face.axes[0], r * face.axes[1], (inverse * face.origin).coords);
        let to_camera = Matrix3::from_columns(&[e1, e2, o]);
        let from_image = (k.matrix() * to_camera).try_inverse()?;
        Some(Self { face, from_image, depth: to_camera.row(2).transpose(), bbox: image.bbox() })
    }

    /// The plane point of ideal pixel `p`, and the homogeneous weight it was divided by
    /// (positive in front of the camera).
    fn plane_point(&self, p: [f64; 2]) -> (Vector2<f64>, f64) {
        let x = self.from_image * Vector3::new(p[0], p[1], 1.0);
        (Vector2::new(x.x / x.z, x.y / x.z), x.z)
    }

    /// Plane coordinates and depth of ideal pixel `p`, if it falls inside the face.
    fn hit(&self, p: [f64; 2]) -> Option<(Vector2<f64>, f64)> {
        let (q, _) = self.plane_point(p);
        let n = self.face.outline.len();
        for i in 0..n {
            let (a, b) = (self.face.outline[i], self.face.outline[(i + 1) % n]);
            if (b - a).perp(&(q - a)) < 0.0 {
                return None;
            }
        }
        Some((q, self.depth.dot(&Vector3::new(q.x, q.y, 1.0))))
    }

    /// Texture pixels per ideal pixel near `p` (the larger column of the map's Jacobian).
    fn scale(&self, p: [f64; 2]) -> f64 {
        let h = self.face.to_texture * self.from_image;
        let t = |u: f64, v: f64| {
            let x = h * Vector3::new(u, v, 1.0);
            Vector2::new(x.x / x.z, x.y / x.z)
        };
        let c = t(p[0], p[1]);
        (t(p[0] + 1.0, p[1]) - c).norm().max((t(p[0], p[1] + 1.0) - c).norm())
    }

    /// The texture's grey level at plane point `q`: bilinear between the four texels around
    /// it, clamped to the edge texels.
    fn grey(&self, q: Vector2<f64>) -> f64 {
        let x = self.face.to_texture * Vector3::new(q.x, q.y, 1.0);
        let tex = &self.face.texture;
        let (w, h) = (tex.width() as usize, tex.height() as usize);
        // Clamped first, then floored by truncation (non-negative): no libm call per sample.
        let u = (x.x / x.z).clamp(0.0, (w - 1) as f64);
        let v = (x.y / x.z).clamp(0.0, (h - 1) as f64);
        let (i, j) = (u as usize, v as usize);
        let (fu, fv) = (u - i as f64, v - j as f64);
        let (di, dj) = (usize::from(i + 1 < w), if j + 1 < h { w } else { 0 });
        let texels: &[u8] = tex.as_raw();
        let at = |k: usize| f64::from(texels[k]);
        let k = j * w + i;
        let top = at(k) + fu * (at(k + di) - at(k));
        let bottom = at(k + dj) + fu * (at(k + dj + di) - at(k + dj));
        top + fv * (bottom - top)
    }
}

/// Paints textured faces (culled, nearest first per sample, area-averaged, blurred and
/// noised) over the image; per face, whether it is drawn (seen from its front, in front of
/// the camera, and its image meets the image).
pub(super) fn paint_faces(
    image: &mut GreyImage,
    faces: &[TexturedFace],
    view: (&Isometry3<f64>, &Intrinsics),
    warp: &Warp,
    paint: &Paint<'_>,
) -> Vec<bool> {
    let (w, h) = (i64::from(image.width()), i64::from(image.height()));
    let inside = |b: &[f64; 4]| b[2] >= -0.5 && b[3] >= -0.5 && b[0] <= w as f64 - 0.5 && b[1] <= h as f64 - 0.5;
    let seen: Vec<Option<SeenFace>> = faces.iter().map(|f| SeenFace::of(f, view.0, view.1, warp)).collect();
    let drawn: Vec<bool> = seen.iter().map(|s| s.as_ref().is_some_and(|s| inside(&s.bbox))).collect();
    let seen: Vec<SeenFace> = seen.into_iter().flatten().collect();
    if !drawn.contains(&true) {
        return drawn;
    }
    let bbox = seen.iter().fold([f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY], |b, s| {
        [b[0].min(s.bbox[0]), b[1].min(s.bbox[1]), b[2].max(s.bbox[2]), b[3].max(s.bbox[3])]
    });
    let margin = (paint.kernel.len() / 2) as i64 + 1;
    let (u0, v0) = ((bbox[0].floor() as i64 - margin).max(0), (bbox[1].floor() as i64 - margin).max(0));
    let (u1, v1) = ((bbox[2].ceil() as i64 + margin).min(w - 1), (bbox[3].ceil() as i64 + margin).min(h - 1));
    let patch = Patch { u0, v0, w: (u1 - u0 + 1) as usize, h: (v1 - v0 + 1) as usize };
    let bg = f64::from(paint.background);
    let (mut value, mut coverage) = (vec![0.0f32; patch.w * patch.h], vec![0.0f32; patch.w * patch.h]);
    let mut near: Vec<&SeenFace> = Vec::with_capacity(seen.len());
    for (index, (u, v)) in patch.pixels().enumerate() {
        // The faces whose image may meet this pixel's footprint (its square, one pixel of margin).
        near.clear();
        near.extend(
            seen.iter().filter(|s| {
                u + 1.0 >= s.bbox[0] && v + 1.0 >= s.bbox[1] && u - 1.0 <= s.bbox[2] && v - 1.0 <= s.bbox[3]
            }),
        );
        if near.is_empty() {
            continue;
        }
        let Some(local) = warp.local(u, v) else { continue };
        let (c, g) = pixel_samples(&near, &local);
        coverage[index] = c as f32;
        value[index] = (bg * (1.0 - c) + g) as f32;
    }
    blur(&mut value, &patch, paint.kernel);
    blur(&mut coverage, &patch, paint.kernel);
    let width = image.width() as usize;
    let data: &mut [u8] = image;
    for (j, (row, covered)) in value.chunks_exact(patch.w).zip(coverage.chunks_exact(patch.w)).enumerate() {
        let start = (patch.v0 as usize + j) * width + patch.u0 as usize;
        for (i, noise) in (0..row.len()).zip(paint.noise.span(start, row.len())) {
            if covered[i] > 0.0 {
                data[start + i] = super::noise::quantise(f64::from(row[i]) + noise);
            }
        }
    }
    drawn
}

/// The share of a pixel's samples on a face and the sum of their grey levels divided by the
/// number of samples; `seen`: the faces that may meet the pixel, whose scales set the samples.
fn pixel_samples(seen: &[&SeenFace], local: &super::lens::Local) -> (f64, f64) {
    let scale = seen.iter().map(|s| s.scale(local.ideal)).fold(0.0, f64::max)
        * local.jacobian.column(0).norm().max(local.jacobian.column(1).norm());
    let n = ((4.0 * scale).ceil() as usize).clamp(MIN_SAMPLES, MAX_SAMPLES);
    match sole_face(seen, local) {
        // Every sample on that face, nearest: the same sums without the other faces' tests.
        Some(face) => {
            let sum = samples(local, n).map(|p| face.grey(face.plane_point(p).0)).sum::<f64>();
            (1.0, sum / (n * n) as f64)
        }
        None => each_sample(seen, local, n),
    }
}

/// The `n x n` samples of the pixel (ideal pixels), row by row.
fn samples(local: &super::lens::Local, n: usize) -> impl Iterator<Item = [f64; 2]> + '_ {
    (0..n * n).map(move |k| {
        let d = Vector2::new(((k % n) as f64 + 0.5) / n as f64 - 0.5, ((k / n) as f64 + 0.5) / n as f64 - 0.5);
        let p = Vector2::from(local.ideal) + local.jacobian * d;
        [p.x, p.y]
    })
}

/// [`pixel_samples`] with each sample on its nearest face, every face tested.
fn each_sample(seen: &[&SeenFace], local: &super::lens::Local, n: usize) -> (f64, f64) {
    let (mut hits, mut sum) = (0usize, 0.0);
    for p in samples(local, n) {
        let nearest = seen.iter().filter_map(|s| s.hit(p).map(|(q, z)| (s, q, z))).min_by(|x, y| x.2.total_cmp(&y.2));
        if let Some((s, q, _)) = nearest {
            hits += 1;
            sum += s.grey(q);
        }
    }
    let total = (n * n) as f64;
    (hits as f64 / total, sum / total)
}

/// The face every sample of the pixel falls on, in front of every other face there: the
/// pixel's square (through the lens's local map) inside it, and each other face that may meet
/// the pixel either missing the whole square or behind the face over all of it. `None` when
/// that is not certain (by margins far above the rounding), and the samples are tested face by
/// face.
///
/// A face's outline is convex and the square's image in its plane too (a projective map in
/// front of the camera), so four corners inside an outline put every sample inside, and four
/// corners beyond one of its edges put every sample beyond; the inverse depth of a plane is
/// affine in the image, so a face's depths over the square lie between those at its corners.
fn sole_face<'a>(seen: &[&'a SeenFace<'_>], local: &super::lens::Local) -> Option<&'a SeenFace<'a>> {
    let corners = [[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]].map(|[du, dv]| {
        let p = Vector2::from(local.ideal) + local.jacobian * Vector2::new(du, dv);
        [p.x, p.y]
    });
    // Per face: its corners' plane points and depths, or None (a corner beyond the horizon).
    let mapped = |s: &SeenFace| -> Option<[(Vector2<f64>, f64); 4]> {
        let points = corners.map(|c| s.plane_point(c));
        points
            .iter()
            .all(|(q, w)| *w > 0.0 && q.x.is_finite() && q.y.is_finite())
            .then(|| points.map(|(q, _)| (q, s.depth.dot(&Vector3::new(q.x, q.y, 1.0)))))
    };
    // How far inside edge i of a face a plane point is, and the margin of that test.
    let side = |s: &SeenFace, i: usize, q: Vector2<f64>| {
        let n = s.face.outline.len();
        let (a, b) = (s.face.outline[i], s.face.outline[(i + 1) % n]);
        ((b - a).perp(&(q - a)), 1e-7 * (b - a).norm() * (q.norm() + a.norm() + 1.0))
    };
    // One pass over the faces, each mapped once: the nearest of those that hold the whole
    // square (a tile over its box face: the tile), and the two nearest depths among those
    // that do not miss it (the front face's own among them).
    let mut front: Option<(usize, f64)> = None;
    let mut nearest = [(f64::INFINITY, usize::MAX); 2];
    for (k, s) in seen.iter().enumerate() {
        let points = mapped(s)?;
        let (far, near) =
            points.iter().fold((f64::NEG_INFINITY, f64::INFINITY), |(f, n), &(_, z)| (f.max(z), n.min(z)));
        if !(far.is_finite() && near.is_finite()) {
            return None;
        }
        let edges = 0..s.face.outline.len();
        let beyond = |i: usize, sign: f64| points.iter().all(|&(q, _)| sign * side(s, i, q).0 > side(s, i, q).1);
        if edges.clone().all(|i| beyond(i, 1.0)) && front.is_none_or(|(_, f)| far < f) {
            front = Some((k, far));
        }
        if !edges.into_iter().any(|i| beyond(i, -1.0)) {
            if near < nearest[0].0 {
                nearest = [(near, k), nearest[0]];
            } else if near < nearest[1].0 {
                nearest[1] = (near, k);
            }
        }
    }
    let (index, farthest) = front?;
    let others = if nearest[0].1 == index { nearest[1].0 } else { nearest[0].0 };
    (others > farthest + 1e-9 * (farthest.abs() + 1.0)).then(|| seen[index])
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::super::noise::{Noise, quantised_pool};
    use super::*;

    /// A cube of half side 0.05 m at the origin with a textured tile 1 mm out on each face
    /// (as the markerless tests' box): the faces, each counter-clockwise about its outward
    /// normal.
    fn tiled_cube() -> Vec<TexturedFace> {
        let tex = texture(37, 29);
        let mut faces = Vec::new();
        for k in 0..6 {
            let mut n = [0.0; 3];
            n[k % 3] = if k < 3 { 1.0 } else { -1.0 };
            let n = Vector3::from(n);
            let a = if k % 3 == 0 { Vector3::y() } else { Vector3::x() } * n.sum();
            let b = n.cross(&a);
            for (h, out) in [(0.05, 0.0), (0.04, 0.001)] {
                let c = n * (0.05 + out);
                let vertices = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                    .map(|(x, y)| (c + a * (h * x) + b * (h * y)).into())
                    .to_vec();
                let uv = vec![[-0.5, 28.5], [36.5, 28.5], [36.5, -0.5], [-0.5, -0.5]];
                faces.push(TexturedFace::new(vertices, uv, tex.clone()).unwrap());
            }
        }
        faces
    }

    /// A pixel wholly on one face, nearest, takes that face's samples alone: the same share
    /// and sum as every sample tested on every face, bit for bit, over random views of the
    /// tiled cube (the tiles' edges, the cube's edges and its silhouette among them).
    #[test]
    fn a_pixel_on_one_face_gives_what_testing_every_face_gives() {
        let faces = tiled_cube();
        let k = Intrinsics::new(120.0, 120.0, 32.0, 32.0, std::f64::consts::FRAC_PI_2).unwrap();
        let mut state = 5u64;
        let mut uniform = || (super::super::noise::splitmix64(&mut state) >> 11) as f64 / (1u64 << 53) as f64;
        let (mut sole, mut pixels) = (0, 0);
        for _ in 0..40 {
            let direction = Vector3::new(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5).normalize();
            let eye = Point3::from(direction * (0.15 + 0.2 * uniform()));
            let target = Point3::new(0.02 * (uniform() - 0.5), 0.02 * (uniform() - 0.5), 0.0);
            let pose = Isometry3::face_towards(&eye, &target, &Vector3::new(uniform() - 0.5, 1.0, 0.3));
            let seen: Vec<SeenFace> = faces.iter().filter_map(|f| SeenFace::of(f, &pose, &k, &Warp::Pinhole)).collect();
            let near: Vec<&SeenFace> = seen.iter().collect();
            for v in 0..64 {
                for u in 0..64 {
                    let local = Warp::Pinhole.local(f64::from(u), f64::from(v)).unwrap();
                    for n in [MIN_SAMPLES, 7, MAX_SAMPLES] {
                        let want = each_sample(&near, &local, n);
                        if let Some(face) = sole_face(&near, &local) {
                            let sum = samples(&local, n).map(|p| face.grey(face.plane_point(p).0)).sum::<f64>();
                            assert_eq!((1.0, sum / (n * n) as f64), want, "pixel ({u}, {v}), {n} x {n} samples");
                            sole += 1;
                        }
                        pixels += usize::from(want.0 > 0.0);
                    }
                    assert_eq!(
                        pixel_samples(&near, &local),
                        {
                            let scale = near.iter().map(|s| s.scale(local.ideal)).fold(0.0, f64::max);
                            each_sample(&near, &local, ((4.0 * scale).ceil() as usize).clamp(MIN_SAMPLES, MAX_SAMPLES))
                        },
                        "pixel ({u}, {v})"
                    );
                }
            }
        }
        // Many pixels of the cube are wholly on one face (the others are tested face by face).
        assert!(sole > pixels / 3 && sole < pixels, "{sole} of {pixels}");
    }

    fn texture(w: u32, h: u32) -> Arc<GreyImage> {
        Arc::new(GreyImage::from_fn(w, h, |i, j| [((i * 37 + j * 91) % 251) as u8].into()))
    }

    /// Renders faces without blur or noise on a 0 background, camera at the origin of F*.
    fn render(faces: &[TexturedFace], pose: Isometry3<f64>, f: f64, size: u32) -> (GreyImage, Vec<bool>) {
        let k =
            Intrinsics::new(f, f, f64::from(size) / 2.0, f64::from(size) / 2.0, std::f64::consts::FRAC_PI_2).unwrap();
        let pool = quantised_pool(0, 0.0);
        let noise = Noise { pool: &pool, background: 0, sigma: 0.0, seed: 0 };
        let paint = Paint { kernel: &[1.0], background: 0, foreground: 255, noise };
        let mut image = GreyImage::new(size, size);
        let drawn = paint_faces(&mut image, faces, (&pose, &k), &Warp::Pinhole, &paint);
        (image, drawn)
    }

    /// A square face at depth `z` facing the camera whose texels are `f / z` metres wide...
    /// scaled so that one texel is one pixel at focal `f`.
    fn fronto(tex: &Arc<GreyImage>, z: f64, f: f64, shift: [f64; 2]) -> TexturedFace {
        let (w, h) = (f64::from(tex.width()), f64::from(tex.height()));
        let m = z / f; // metres per pixel at depth z
        let corner = |i: f64, j: f64| [(i + shift[0]) * m, (j + shift[1]) * m, z];
        // Counter-clockwise seen from the camera (front normal towards -z).
        let vertices = vec![corner(-0.5, -0.5), corner(-0.5, h - 0.5), corner(w - 0.5, h - 0.5), corner(w - 0.5, -0.5)];
        let uv = vec![[-0.5, -0.5], [-0.5, h - 0.5], [w - 0.5, h - 0.5], [w - 0.5, -0.5]];
        TexturedFace::new(vertices, uv, tex.clone()).unwrap()
    }

    /// The pixel centred on texel `(i, j)` at one texel a pixel, in closed form: the mean of the
    /// bilinear surface over `[i - 1/2, i + 1/2]` weighs texels `i - 1, i, i + 1` by
    /// `1/8, 3/4, 1/8` per axis (edge texels clamped).
    fn filtered(tex: &GreyImage, i: u32, j: u32) -> f64 {
        const WEIGHTS: [(i64, f64); 3] = [(-1, 0.125), (0, 0.75), (1, 0.125)];
        let clamp = |x: i64, n: u32| x.clamp(0, i64::from(n) - 1) as u32;
        let mut sum = 0.0;
        for (dj, wj) in WEIGHTS {
            for (di, wi) in WEIGHTS {
                let texel =
                    tex.get_pixel(clamp(i64::from(i) + di, tex.width()), clamp(i64::from(j) + dj, tex.height()));
                sum += wi * wj * f64::from(texel.0[0]);
            }
        }
        sum
    }

    /// Pixel `(u, v)` of `image` is the closed form [`filtered`] of texel `(i, j)`, up to the
    /// renderer's rounding.
    fn assert_filtered(image: &GreyImage, (u, v): (u32, u32), tex: &GreyImage, (i, j): (u32, u32)) {
        let (got, expected) = (f64::from(image.get_pixel(u, v).0[0]), filtered(tex, i, j));
        assert!((got - expected).abs() <= 0.5 + 1e-9, "texel {i} {j}: pixel {got}, closed form {expected}");
    }

    #[test]
    fn a_fronto_parallel_face_at_one_to_one_is_the_bilinear_texture_averaged_over_each_pixel() {
        let tex = texture(20, 16);
        // Texel (i, j) at pixel (i + 10, j + 12) of a 48 x 48 image with centre 24.
        let face = fronto(&tex, 2.0, 300.0, [-14.0, -12.0]);
        let (image, drawn) = render(&[face], Isometry3::identity(), 300.0, 48);
        assert_eq!(drawn, vec![true]);
        for j in 0..16 {
            for i in 0..20 {
                assert_filtered(&image, (i + 10, j + 12), &tex, (i, j));
            }
        }
        assert_eq!(image.get_pixel(9, 12).0[0], 0);
        assert_eq!(image.get_pixel(30, 12).0[0], 0);
    }

    /// The 20 x 16 texture's face of [`fronto`] with its vertices in the other order: seen
    /// from its back.
    fn back_of(face: &TexturedFace, tex: &Arc<GreyImage>) -> TexturedFace {
        let mut reversed = face.vertices().iter().map(|p| [p.x, p.y, p.z]).collect::<Vec<_>>();
        reversed.reverse();
        let uv = vec![[19.5, -0.5], [19.5, 15.5], [-0.5, 15.5], [-0.5, -0.5]];
        TexturedFace::new(reversed, uv, tex.clone()).unwrap()
    }

    #[test]
    fn a_face_turned_away_is_culled_and_the_nearer_face_hides_the_farther() {
        let tex = texture(20, 16);
        let face = fronto(&tex, 2.0, 300.0, [-14.0, -12.0]);
        let back = back_of(&face, &tex);
        assert_eq!(render(&[back], Isometry3::identity(), 300.0, 48).1, vec![false]);
        let flat = Arc::new(GreyImage::from_pixel(4, 4, [200].into()));
        let near = fronto(&flat, 1.0, 300.0, [-2.0, -2.0]);
        for order in [[face.clone(), near.clone()], [near, face]] {
            let (image, _) = render(&order, Isometry3::identity(), 300.0, 48);
            assert_eq!(image.get_pixel(23, 23).0[0], 200);
            assert_filtered(&image, (12, 14), &tex, (2, 2));
        }
    }

    #[test]
    fn the_renderer_draws_textured_faces_with_one_flag_per_face() {
        use crate::core::distortion::Distortion;
        use crate::vision::render::{CameraView, RenderConfig, Renderer};
        let tex = texture(20, 16);
        let face = fronto(&tex, 2.0, 300.0, [-14.0, -12.0]);
        let back = back_of(&face, &tex);
        let faces = TexturedFaces(vec![face, back]);
        let config = RenderConfig { blur_sigma: 0.0, noise_sigma: 0.0, background: 7, ..RenderConfig::default() };
        let renderer = Renderer::new(config).unwrap();
        let k = Intrinsics::pinhole(300.0, 300.0, 24.0, 24.0).unwrap();
        let (pose, none) = (Isometry3::identity(), Distortion::none());
        let view = CameraView { pose: &pose, intrinsics: &k, distortion: &none, size: (48, 48) };
        let out = renderer.render(&faces, None, &view, 0).unwrap();
        assert_eq!(out.drawn, vec![true, false]);
        assert_eq!(out.image.get_pixel(9, 12).0[0], 7);
        for (i, j) in [(0, 0), (19, 0), (7, 9), (19, 15)] {
            assert_filtered(&out.image, (i + 10, j + 12), &tex, (i, j));
        }
        let hidden = renderer.render(&faces, Some(&[false, true]), &view, 0).unwrap();
        assert_eq!(hidden.drawn, vec![false, false]);
        assert!(hidden.image.iter().all(|g| *g == 7));
    }

    #[test]
    fn a_minified_checkerboard_averages_to_grey() {
        // Texels of 0 and 255 alternating; at 2 texels per pixel every pixel covers 2 x 2.
        let board = Arc::new(GreyImage::from_fn(40, 40, |i, j| [if (i + j) % 2 == 0 { 0 } else { 255 }].into()));
        let face = fronto(&board, 4.0, 300.0, [-20.0, -20.0]);
        let (image, _) = render(&[face], Isometry3::identity(), 150.0, 48);
        for j in 16..32 {
            for i in 16..32 {
                let g = i32::from(image.get_pixel(i, j).0[0]);
                assert!((g - 128).abs() <= 1, "pixel {i} {j}: {g}");
            }
        }
    }

    #[test]
    fn bad_faces_are_refused_by_name() {
        let tex = texture(4, 4);
        let square = vec![[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [1.0, 1.0, 1.0], [0.0, 1.0, 1.0]];
        let uv = vec![[0.0, 0.0], [3.0, 0.0], [3.0, 3.0], [0.0, 3.0]];
        let err =
            |v: Vec<[f64; 3]>, t: Vec<[f64; 2]>, x: Arc<GreyImage>| TexturedFace::new(v, t, x).unwrap_err().to_string();
        assert!(TexturedFace::new(square.clone(), uv.clone(), tex.clone()).is_ok());
        let mut nan = square.clone();
        nan[2][1] = f64::NAN;
        assert!(err(nan, uv.clone(), tex.clone()).contains("face vertices"));
        let mut bent = square.clone();
        bent[2][2] = 1.1;
        assert!(err(bent, uv.clone(), tex.clone()).contains("not planar"));
        let line = vec![[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [2.0, 0.0, 1.0]];
        assert!(err(line, uv[..3].to_vec(), tex.clone()).contains("degenerate"));
        // A bow tie has no net area (Newell): refused as degenerate; a dart as not convex.
        let bow = vec![square[0], square[2], square[1], square[3]];
        assert!(err(bow, uv.clone(), tex.clone()).contains("degenerate"));
        let dart = vec![[0.0, 0.0, 1.0], [2.0, 0.0, 1.0], [0.5, 0.5, 1.0], [0.0, 2.0, 1.0]];
        assert!(err(dart, uv.clone(), tex.clone()).contains("convex"));
        assert!(err(square.clone(), uv[..3].to_vec(), tex.clone()).contains("face"));
        let mut folded = uv.clone();
        folded[2] = [0.0, 0.0];
        assert!(err(square.clone(), folded, tex.clone()).contains("texture coordinates"));
        assert!(err(square, uv, Arc::new(GreyImage::new(0, 3))).contains("texture"));
    }
}
