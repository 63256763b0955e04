//! A rig of AprilTags of one family (any [`TagFamily`] the detector reads): each tag's four
//! outer corners are the target's points, identity `4 id + c` with `c` in OpenCV aruco's
//! order (0 top-left, 1 top-right, 2 bottom-right, 3 bottom-left of the tag as printed), so a
//! detector matches the reference image and the current one by identity, whatever the two
//! cameras.
//!
//! The tag as printed is its family's face ([`TagFace`]: the grid of `total_width` cells the
//! decoder's family data describes, cut to a disc for the circle families). The tag's *size* is
//! the side of the square whose corners are reported (`width_at_border` cells: tag36h11's
//! black border, 8 cells in a grid of 10 with its white quiet zone; tagStandard41h12's white
//! square inside the black ring, 5 cells in a grid of 9 whose outer data cells lie outside the
//! ring), as AprilTag and OpenCV define it. "As printed" is as OpenCV prints the tag
//! (`cv2.aruco.generateImageMarker` of `DICT_APRILTAG_36h11`), the corner order's reference:
//! the AprilTag library's own layout turned half a turn. The white cells are drawn as polygons
//! on the dark background, which shows through as the black ones.

use nalgebra::{Isometry3, Point3};

use crate::error::{Error, Short};
use crate::vision::error::Result;
use crate::vision::render::{Canvas, Polygon};
use crate::vision::tags::{TagFace, TagFamily};
use crate::vision::target::{Target, TargetPoint, shown};

/// Vertices of the regular polygon (inscribed) that stands for a round face's disc: its
/// sides are at most `r (1 - cos(pi / 256))`, 7.5e-5 of the radius, inside the circle.
const DISC_SIDES: usize = 256;

/// One tag: its id, its size and its pose.
#[derive(Debug, Clone, PartialEq)]
pub struct RigTag {
    /// The id in the rig's family.
    pub id: u32,
    /// Side of the square whose corners are reported (tag36h11's black border), metres.
    pub size: f64,
    /// The tag frame in F*: origin at the tag's centre, x to the right and y up as printed,
    /// z out of the printed face (OpenCV aruco's marker frame); the tag is seen from z > 0.
    pub pose: Isometry3<f64>,
}

impl RigTag {
    /// The four corners in F*, in OpenCV's order (top-left, top-right, bottom-right,
    /// bottom-left as printed).
    pub fn corners(&self) -> [[f64; 3]; 4] {
        let h = self.size / 2.0;
        [[-h, h], [h, h], [h, -h], [-h, -h]].map(|[x, y]| (self.pose * Point3::new(x, y, 0.0)).coords.into())
    }

    /// The white cells of the face as polygons of F*, rows merged into runs, cut to the disc
    /// of a round face.
    fn white_polygons(&self, face: &TagFace) -> Vec<Polygon> {
        let cell = self.size / face.border as f64;
        let half = face.total as f64 / 2.0;
        // Layout point (x, y) (cells, y down) turned half a turn, in the tag frame (y up).
        let plane = |x: f64, y: f64| [(half - x) * cell, (y - half) * cell];
        let disc: Option<Vec<[f64; 2]>> = face.round.then(|| {
            (0..DISC_SIDES)
                .map(|k| {
                    let a = std::f64::consts::TAU * k as f64 / DISC_SIDES as f64;
                    [half * cell * a.cos(), half * cell * a.sin()]
                })
                .collect()
        });
        let mut cells = Vec::new();
        for (y, row) in face.white.iter().enumerate() {
            let mut x = 0;
            while x < face.total {
                if !row[x] {
                    x += 1;
                    continue;
                }
                let start = x;
                while x < face.total && row[x] {
                    x += 1;
                }
                let (x0, x1, y0, y1) = (start as f64, x as f64, y as f64, y as f64 + 1.0);
                let mut run = vec![plane(x0, y0), plane(x1, y0), plane(x1, y1), plane(x0, y1)];
                if let Some(disc) = &disc {
                    run = clip_convex(run, disc);
                }
                if run.len() >= 3 {
                    cells.push(
                        run.iter().map(|&[px, py]| (self.pose * Point3::new(px, py, 0.0)).coords.into()).collect(),
                    );
                }
            }
        }
        // Finite vertices (checked in TagRig::new), three or more: cannot fail.
        cells.into_iter().filter_map(|v| Polygon::new(v).ok()).collect()
    }
}

/// `subject` clipped to the convex polygon `clip` (both convex, vertices in order;
/// Sutherland-Hodgman): empty when they do not overlap.
fn clip_convex(subject: Vec<[f64; 2]>, clip: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let orientation = |p: &[[f64; 2]]| {
        (0..p.len())
            .map(|i| {
                let (a, b) = (p[i], p[(i + 1) % p.len()]);
                a[0] * b[1] - b[0] * a[1]
            })
            .sum::<f64>()
            .signum()
    };
    let sign = orientation(clip);
    let mut out = subject;
    for i in 0..clip.len() {
        let (a, b) = (clip[i], clip[(i + 1) % clip.len()]);
        let side = |p: [f64; 2]| sign * ((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]));
        let input = std::mem::take(&mut out);
        for j in 0..input.len() {
            let (p, q) = (input[j], input[(j + 1) % input.len()]);
            let (sp, sq) = (side(p), side(q));
            if sp >= 0.0 {
                out.push(p);
            }
            if (sp >= 0.0) != (sq >= 0.0) {
                let t = sp / (sp - sq);
                out.push([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]);
            }
        }
        if out.is_empty() {
            break;
        }
    }
    out
}

/// A rig of tags of one family: the target's points are the tags' corners, four per tag in
/// the tags' order.
#[derive(Debug, Clone, PartialEq)]
pub struct TagRig {
    family: TagFamily,
    tags: Vec<RigTag>,
    points: Vec<TargetPoint>,
    cells: Vec<Vec<Polygon>>,
}

impl TagRig {
    /// A rig of `family`'s tags with distinct ids of the family, finite sizes > 0 and finite
    /// poses.
    pub fn new(family: TagFamily, tags: Vec<RigTag>) -> Result<Self> {
        let bad = |i: usize, reason: String| {
            Err(Error::InvalidParameter { name: "tags", reason: format!("tag {i}: {reason}") }.into())
        };
        let mut cells = Vec::with_capacity(tags.len());
        for (i, tag) in tags.iter().enumerate() {
            let face = match TagFace::new(family, tag.id) {
                Ok(face) => face,
                Err(e) => return bad(i, e.to_string()),
            };
            if let Some(j) = tags[..i].iter().position(|t| t.id == tag.id) {
                return bad(i, format!("id {} is also tag {j}'s", tag.id));
            }
            if !(tag.size.is_finite() && tag.size > 0.0) {
                return bad(i, format!("size must be finite and > 0 metres, got {}", Short(tag.size)));
            }
            let pose = &tag.pose;
            if !(pose.translation.vector.iter().chain(pose.rotation.coords.iter()).all(|v| v.is_finite())) {
                return bad(i, "the pose must be finite".into());
            }
            cells.push(tag.white_polygons(&face));
        }
        let points = tags
            .iter()
            .flat_map(|t| (0u32..).zip(t.corners()).map(|(c, position)| TargetPoint { id: 4 * t.id + c, position }))
            .collect();
        Ok(Self { family, tags, points, cells })
    }

    /// The family of the tags.
    pub fn family(&self) -> TagFamily {
        self.family
    }

    /// The tags.
    pub fn tags(&self) -> &[RigTag] {
        &self.tags
    }
}

impl Target for TagRig {
    fn points(&self) -> &[TargetPoint] {
        &self.points
    }

    /// A tag is drawn when one of its corners is shown and the camera sees its printed face
    /// (then its shown corners count as drawn).
    fn draw(&self, canvas: &mut Canvas<'_>, visible: Option<&[bool]>) -> Vec<bool> {
        let eye = Point3::from(canvas.view().pose.translation.vector);
        let mut drawn = Vec::with_capacity(self.points.len());
        for (t, (tag, cells)) in self.tags.iter().zip(&self.cells).enumerate() {
            let any_shown = (4 * t..4 * t + 4).any(|i| shown(visible, i));
            let facing = (tag.pose.inverse() * eye).z > 0.0;
            let done = any_shown && facing && canvas.fill_polygons(cells);
            drawn.extend((4 * t..4 * t + 4).map(|i| done && shown(visible, i)));
        }
        drawn
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use nalgebra::{Translation3, UnitQuaternion, Vector3};

    use super::*;
    use crate::core::camera::Intrinsics;
    use crate::core::distortion::Distortion;
    use crate::vision::render::{CameraView, RenderConfig, Renderer};

    /// A tag facing the camera at F* (x right, y up as printed: image u right, v up).
    fn facing(id: u32, size: f64, center: [f64; 3]) -> RigTag {
        let rotation = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI);
        RigTag { id, size, pose: Isometry3::from_parts(Translation3::new(center[0], center[1], center[2]), rotation) }
    }

    fn render(tags: &TagRig, pose: &Isometry3<f64>, config: RenderConfig) -> crate::vision::render::Rendered {
        let k = Intrinsics::pinhole(1000.0, 1000.0, 200.0, 150.0).unwrap();
        let view = CameraView { pose, intrinsics: &k, distortion: &Distortion::none(), size: (400, 300) };
        Renderer::new(config).unwrap().render(tags, None, &view, 0).unwrap()
    }

    fn sharp() -> RenderConfig {
        RenderConfig { blur_sigma: 0.0, noise_sigma: 0.0, background: 20, foreground: 220, ..Default::default() }
    }

    #[test]
    fn corners_have_opencv_order_and_identities() {
        let tags =
            TagRig::new(TagFamily::Tag36h11, vec![facing(3, 0.08, [0.0, 0.0, 0.5]), facing(10, 0.04, [0.1, 0.0, 0.5])])
                .unwrap();
        let ids: Vec<u32> = tags.points().iter().map(|p| p.id).collect();
        assert_eq!(ids, [12, 13, 14, 15, 40, 41, 42, 43]);
        // Top-left as printed is at image left (x < 0) and top (y < 0 in F*, v down).
        let p = |i: usize| tags.points()[i].position;
        assert!((p(0)[0] + 0.04).abs() < 1e-15 && (p(0)[1] + 0.04).abs() < 1e-15 && (p(0)[2] - 0.5).abs() < 1e-15);
        assert!((p(1)[0] - 0.04).abs() < 1e-15 && (p(1)[1] + 0.04).abs() < 1e-15);
        assert!((p(2)[0] - 0.04).abs() < 1e-15 && (p(2)[1] - 0.04).abs() < 1e-15);
        assert!((p(3)[0] + 0.04).abs() < 1e-15 && (p(3)[1] - 0.04).abs() < 1e-15);
        assert!(TagRig::new(TagFamily::Tag36h11, vec![facing(587, 0.08, [0.0, 0.0, 0.5])]).is_err());
        assert!(
            TagRig::new(TagFamily::Tag36h11, vec![facing(3, 0.08, [0.0, 0.0, 0.5]), facing(3, 0.08, [0.1, 0.0, 0.5])])
                .is_err()
        );
        assert!(TagRig::new(TagFamily::Tag36h11, vec![facing(3, -0.08, [0.0, 0.0, 0.5])]).is_err());
        assert!(TagRig::new(TagFamily::Tag36h11, vec![facing(3, 0.08, [0.0, f64::NAN, 0.5])]).is_err());
    }

    /// tag36h11's data bits as printed (the library's layout turned half a turn):
    /// `[row][column]` of the 6 x 6 data square, true for white.
    fn tag36h11_bits(id: u32) -> [[bool; 6]; 6] {
        let face = TagFace::new(TagFamily::Tag36h11, id).unwrap();
        std::array::from_fn(|r| std::array::from_fn(|c| face.white[7 - r][7 - c]))
    }

    /// Reads a fronto-parallel tag's 10 x 10 cells back at their centres.
    fn read_cells(image: &crate::vision::GreyImage, tag: &RigTag, k: [f64; 4]) -> [[bool; 10]; 10] {
        let cell = tag.size / 8.0;
        let mut out = [[false; 10]; 10];
        for (r, row) in out.iter_mut().enumerate() {
            for (c, white) in row.iter_mut().enumerate() {
                let (x, y) = ((c as f64 + 0.5 - 5.0) * cell, (5.0 - r as f64 - 0.5) * cell);
                let p = tag.pose * Point3::new(x, y, 0.0);
                let (u, v) = (k[0] * p.x / p.z + k[2], k[1] * p.y / p.z + k[3]);
                *white = image.get_pixel(u.round() as u32, v.round() as u32)[0] > 120;
            }
        }
        out
    }

    #[test]
    fn a_rendered_tag_reads_back_its_code() {
        for id in [0, 1, 42, 586] {
            let tag = facing(id, 0.1, [0.01, -0.005, 0.5]);
            let tags = TagRig::new(TagFamily::Tag36h11, vec![tag.clone()]).unwrap();
            let config = RenderConfig { noise_sigma: 3.0, ..Default::default() };
            let out = render(&tags, &Isometry3::identity(), config);
            assert_eq!(out.drawn, [true; 4]);
            let cells = read_cells(&out.image, &tag, [1000.0, 1000.0, 200.0, 150.0]);
            let bits = tag36h11_bits(id);
            for r in 0..10 {
                for c in 0..10 {
                    let expected = match (r, c) {
                        (0 | 9, _) | (_, 0 | 9) => true,
                        (1 | 8, _) | (_, 1 | 8) => false,
                        _ => bits[r - 2][c - 2],
                    };
                    assert_eq!(cells[r][c], expected, "tag {id}, cell ({r}, {c})");
                }
            }
        }
    }

    #[test]
    fn the_white_area_is_the_white_cells_area() {
        let tag = facing(7, 0.08, [0.0, 0.0, 0.5]);
        let out = render(&TagRig::new(TagFamily::Tag36h11, vec![tag]).unwrap(), &Isometry3::identity(), sharp());
        let sum: f64 = out.image.pixels().map(|p| (f64::from(p[0]) - 20.0) / 200.0).sum();
        // A cell is 0.01 m at 0.5 m: 20 px, 400 px^2; the quiet zone has 36 cells.
        let white = 36 + tag36h11_bits(7).iter().flatten().filter(|&&b| b).count();
        let expected = white as f64 * 400.0;
        assert!((sum - expected).abs() < 0.5, "{sum} vs {expected}");
    }

    #[test]
    fn a_tag_seen_from_behind_or_hidden_is_not_drawn() {
        let tags =
            TagRig::new(TagFamily::Tag36h11, vec![facing(1, 0.05, [0.0, 0.0, 0.5]), facing(2, 0.05, [0.0, 0.0, -0.5])])
                .unwrap();
        let out = render(&tags, &Isometry3::identity(), sharp());
        assert_eq!(out.drawn, [true, true, true, true, false, false, false, false]);
        // From behind the first tag (turned round about y, beyond it): its back.
        let behind = Isometry3::from_parts(
            Translation3::new(0.0, 0.0, 1.0),
            UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::PI),
        );
        assert_eq!(render(&tags, &behind, sharp()).drawn[..4], [false; 4]);
        let k = Intrinsics::pinhole(1000.0, 1000.0, 200.0, 150.0).unwrap();
        let view = CameraView {
            pose: &Isometry3::identity(),
            intrinsics: &k,
            distortion: &Distortion::none(),
            size: (400, 300),
        };
        let mut visible = [false; 8];
        visible[2] = true;
        let out = Renderer::new(sharp()).unwrap().render(&tags, Some(&visible), &view, 0).unwrap();
        assert_eq!(out.drawn, [false, false, true, false, false, false, false, false]);
        let none = Renderer::new(sharp()).unwrap().render(&tags, Some(&[false; 8]), &view, 0).unwrap();
        assert!(none.image.pixels().all(|p| p[0] == 20));
    }
}
