//! A rig of AprilTags (family tag36h11, AprilTag 3's `tag36h11`, OpenCV's
//! `DICT_APRILTAG_36h11`): each tag's four outer corners are the target's points, identity
//! `4 id + c` with `c` in OpenCV aruco's order (0 top-left, 1 top-right, 2 bottom-right,
//! 3 bottom-left of the tag as printed), so a detector matches the reference image and the
//! current one by identity, whatever the two cameras.
//!
//! The tag as printed is a grid of 10 x 10 cells (the family's `total_width`): a white quiet
//! zone one cell wide, the black border (`width_at_border` = 8 cells: the tag's *size* is the
//! side of this square, as AprilTag and OpenCV define it) and 6 x 6 data cells. "As printed"
//! is as OpenCV prints the tag (`cv2.aruco.generateImageMarker` of `DICT_APRILTAG_36h11`),
//! the corner order's reference: that is the AprilTag library's own layout turned half a
//! turn. In the library's layout, bit `i` of the 36-bit code (most significant first) is the
//! cell at column `bit_x[i]`, row `bit_y[i]` of the 8 x 8 square, white when set (the codes
//! and layout are kornia-apriltag's copy of AprilTag 3's `tag36h11.c`). The white cells are
//! drawn as polygons on the dark background, which shows through as the black ones.

use nalgebra::{Isometry3, Point3};

use crate::error::{Error, Result, Short};
use crate::vision::render::{Canvas, Polygon};
use crate::vision::target::{Target, TargetPoint, shown};

/// The number of tag36h11 codes: valid ids are `0..TAG36H11_COUNT`.
pub const TAG36H11_COUNT: u32 = 587;
/// Cells across the tag as printed (quiet zone included).
const TOTAL_CELLS: usize = 10;
/// Cells across the black border's outer square (the tag's size).
const BORDER_CELLS: usize = 8;
/// Data cells across.
const DATA_CELLS: usize = 6;

/// One tag: its id, its size and its pose.
#[derive(Debug, Clone, PartialEq)]
pub struct RigTag {
    /// The tag36h11 id, `0..587`.
    pub id: u32,
    /// Side of the black border's outer square, metres.
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

    /// The white cells (quiet zone and set data bits) as polygons of F*, rows merged into runs.
    fn white_polygons(&self) -> Vec<Polygon> {
        let bits = tag36h11_bits(self.id);
        let cell = self.size / BORDER_CELLS as f64;
        let half = TOTAL_CELLS as f64 / 2.0;
        // Cells [c0, c1) x [r0, r1) of the 10 x 10 grid, row 0 at the top.
        let rect = |c0: usize, c1: usize, r0: usize, r1: usize| {
            let (x0, x1) = ((c0 as f64 - half) * cell, (c1 as f64 - half) * cell);
            let (y0, y1) = ((half - r0 as f64) * cell, (half - r1 as f64) * cell);
            let corners = [[x0, y0], [x1, y0], [x1, y1], [x0, y1]];
            corners.map(|[x, y]| (self.pose * Point3::new(x, y, 0.0)).coords.into()).to_vec()
        };
        let last = TOTAL_CELLS - 1;
        let mut cells = vec![
            rect(0, TOTAL_CELLS, 0, 1),
            rect(0, TOTAL_CELLS, last, TOTAL_CELLS),
            rect(0, 1, 1, last),
            rect(last, TOTAL_CELLS, 1, last),
        ];
        // Data cell (row, column) of the 6 x 6 square is cell (row + 2, column + 2) of the grid.
        for (row, bits) in bits.iter().enumerate() {
            let mut column = 0;
            while column < DATA_CELLS {
                if !bits[column] {
                    column += 1;
                    continue;
                }
                let start = column;
                while column < DATA_CELLS && bits[column] {
                    column += 1;
                }
                cells.push(rect(start + 2, column + 2, row + 2, row + 3));
            }
        }
        // Four finite vertices each (checked in TagRig::new): cannot fail.
        cells.into_iter().filter_map(|v| Polygon::new(v).ok()).collect()
    }
}

/// The data bits of tag36h11 tag `id` as printed (as OpenCV prints it: the library's layout
/// turned half a turn): `[row][column]` of the 6 x 6 data square, true for white. Ids beyond
/// the family give all black.
pub fn tag36h11_bits(id: u32) -> [[bool; 6]; 6] {
    let mut bits = [[false; 6]; 6];
    let Some(&code) = kornia_apriltag::family::tag36h11::CODE_DATA.get(id as usize) else {
        return bits;
    };
    let (bit_x, bit_y) = tag36h11_layout();
    let n = bit_x.len();
    for i in 0..n {
        // Layout coordinates 1..=6 are the data cells 0..=5; half a turn: 5 - x, 5 - y.
        let (x, y) = (DATA_CELLS - bit_x[i] as usize, DATA_CELLS - bit_y[i] as usize);
        bits[y][x] = (code >> (n - 1 - i)) & 1 == 1;
    }
    bits
}

/// The family's bit positions (`bit_x`, `bit_y`: cells of the 8 x 8 black-border square).
fn tag36h11_layout() -> &'static (Vec<i8>, Vec<i8>) {
    static LAYOUT: std::sync::OnceLock<(Vec<i8>, Vec<i8>)> = std::sync::OnceLock::new();
    LAYOUT.get_or_init(|| match kornia_apriltag::family::TagFamily::tag36_h11() {
        Ok(family) => (family.bit_x, family.bit_y),
        Err(_) => (Vec::new(), Vec::new()),
    })
}

/// A rig of tags: the target's points are the tags' corners, four per tag in the tags' order.
#[derive(Debug, Clone, PartialEq)]
pub struct TagRig {
    tags: Vec<RigTag>,
    points: Vec<TargetPoint>,
    cells: Vec<Vec<Polygon>>,
}

impl TagRig {
    /// A rig of tags with distinct ids in `0..587`, finite sizes > 0 and finite poses.
    pub fn new(tags: Vec<RigTag>) -> Result<Self> {
        let bad = |i: usize, reason: String| {
            Err(Error::InvalidParameter { name: "tags", reason: format!("tag {i}: {reason}") })
        };
        for (i, tag) in tags.iter().enumerate() {
            if tag.id >= TAG36H11_COUNT {
                return bad(i, format!("id must be in 0..{TAG36H11_COUNT} (tag36h11), got {}", tag.id));
            }
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
        }
        let points = tags
            .iter()
            .flat_map(|t| (0u32..).zip(t.corners()).map(|(c, position)| TargetPoint { id: 4 * t.id + c, position }))
            .collect();
        let cells = tags.iter().map(RigTag::white_polygons).collect();
        Ok(Self { tags, points, cells })
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
        let tags = TagRig::new(vec![facing(3, 0.08, [0.0, 0.0, 0.5]), facing(10, 0.04, [0.1, 0.0, 0.5])]).unwrap();
        let ids: Vec<u32> = tags.points().iter().map(|p| p.id).collect();
        assert_eq!(ids, [12, 13, 14, 15, 40, 41, 42, 43]);
        // Top-left as printed is at image left (x < 0) and top (y < 0 in F*, v down).
        let p = |i: usize| tags.points()[i].position;
        assert!((p(0)[0] + 0.04).abs() < 1e-15 && (p(0)[1] + 0.04).abs() < 1e-15 && (p(0)[2] - 0.5).abs() < 1e-15);
        assert!((p(1)[0] - 0.04).abs() < 1e-15 && (p(1)[1] + 0.04).abs() < 1e-15);
        assert!((p(2)[0] - 0.04).abs() < 1e-15 && (p(2)[1] - 0.04).abs() < 1e-15);
        assert!((p(3)[0] + 0.04).abs() < 1e-15 && (p(3)[1] - 0.04).abs() < 1e-15);
        assert!(TagRig::new(vec![facing(587, 0.08, [0.0, 0.0, 0.5])]).is_err());
        assert!(TagRig::new(vec![facing(3, 0.08, [0.0, 0.0, 0.5]), facing(3, 0.08, [0.1, 0.0, 0.5])]).is_err());
        assert!(TagRig::new(vec![facing(3, -0.08, [0.0, 0.0, 0.5])]).is_err());
        assert!(TagRig::new(vec![facing(3, 0.08, [0.0, f64::NAN, 0.5])]).is_err());
    }

    #[test]
    fn the_first_code_is_tag36h11s() {
        // AprilTag 3's tag36h11 code 0 is 0xd7e00984b; bit 35 (the most significant) is the
        // cell at bit_x = 1, bit_y = 1 of the library's layout: the bottom-right data cell as
        // OpenCV prints the tag; bit 0 (set) is at bit_x = 3, bit_y = 4 and bit 2 (clear) at
        // bit_x = 2, bit_y = 4.
        let bits = tag36h11_bits(0);
        assert!(bits[5][5] && bits[1][2] && !bits[1][3]);
        let ones: usize = bits.iter().flatten().filter(|&&b| b).count();
        assert_eq!(ones, 0xd7e00984b_u64.count_ones() as usize);
        assert_eq!(tag36h11_bits(600), [[false; 6]; 6]);
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
            let tags = TagRig::new(vec![tag.clone()]).unwrap();
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
        let out = render(&TagRig::new(vec![tag]).unwrap(), &Isometry3::identity(), sharp());
        let sum: f64 = out.image.pixels().map(|p| (f64::from(p[0]) - 20.0) / 200.0).sum();
        // A cell is 0.01 m at 0.5 m: 20 px, 400 px^2; the quiet zone has 36 cells.
        let white = 36 + tag36h11_bits(7).iter().flatten().filter(|&&b| b).count();
        let expected = white as f64 * 400.0;
        assert!((sum - expected).abs() < 0.5, "{sum} vs {expected}");
    }

    #[test]
    fn a_tag_seen_from_behind_or_hidden_is_not_drawn() {
        let tags = TagRig::new(vec![facing(1, 0.05, [0.0, 0.0, 0.5]), facing(2, 0.05, [0.0, 0.0, -0.5])]).unwrap();
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
