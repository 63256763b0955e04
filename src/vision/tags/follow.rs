//! A tag followed from its last corners with no quad search ([`TagFollower`]): the four outer
//! edges are measured again on the full-resolution image around where they were (profiles
//! across each edge within a bounded window, a line fitted to their crossings, corners where
//! the lines meet: `edges.rs`, the refinement the whole-frame detection ends with; when the
//! tag moved more than those profiles reach, each edge is first searched along its normal
//! within three quarters of a cell, `edge_search.rs`), then the
//! bits are read through the homography of those corners as the AprilTag decoder reads them
//! (a linear grey model of the border's black and white cells, each bit against the model's
//! midpoint, sharpened by the decoder's Laplacian), and the code must be the tracked tag's,
//! unrotated, within the family's bit errors ([`TagFamily::max_bit_errors`]) and confirmed by
//! the family's own decoding table. Anything else is refused (`None`): the caller searches
//! the tag again, never reports a tag under an identity it did not read.

use kornia_apriltag::family::TagFamily as Layout;
use nalgebra::{Matrix3, Vector3};

use super::edge_search;
use super::edges::{self, Border};
use super::{TAG_CORNERS_IN_LAYOUT, Tag, TagFamily, decoder_error};
use crate::vision::error::Result;
use crate::vision::image::{GreyBuffer, Pixels};

type P = [f64; 2];

/// The decoder's sharpening of the bit values (kornia-apriltag's and the AprilTag library's
/// default `decode_sharpening`).
const SHARPENING: f64 = 0.25;

/// The edges found farther than this from the last corners (pixels) are refined from there.
const MOVED_PX: f64 = 1.0;

/// The largest distance between corresponding corners.
fn largest_move(a: &[P; 4], b: &[P; 4]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1])).fold(0.0, f64::max)
}

/// Follows tags of one family from their last corners (the family's layout and decoding
/// table built once).
pub struct TagFollower {
    family: TagFamily,
    layout: Layout,
}

impl std::fmt::Debug for TagFollower {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TagFollower").field("family", &self.family).finish_non_exhaustive()
    }
}

impl TagFollower {
    /// A follower of `family`'s tags.
    pub fn new(family: TagFamily) -> Result<Self> {
        let layout = Layout::try_from(&family.kind()).map_err(decoder_error)?;
        Ok(Self { family, layout })
    }

    /// Tag `id`, whose corners were near `start` (in [`Tag::corners`]'s order), at its corners
    /// measured on `image`'s edges; `None` when the edges do not support them or the bits
    /// read there are not tag `id`'s in that orientation.
    pub fn follow<C: Pixels>(&self, image: &GreyBuffer<C>, id: u32, start: &[P; 4]) -> Option<Tag> {
        let border = Border { cells: f64::from(self.family.border_cells()), reversed: self.family.reversed_border() };
        // From where the edges were searched when they moved by more than a pixel (the
        // refinement's profiles reach 1.5 px at least), from the last corners otherwise.
        let moved = edge_search::moved_corners(image, start, border).filter(|m| largest_move(m, start) > MOVED_PX);
        let corners = match moved {
            Some(moved) => edges::refine_corners(image, &moved, border),
            None => edges::refine_corners(image, start, border),
        }?;
        let code = self.read_code(image, &corners)?;
        self.is_code_of(code, id).then_some(Tag { id, corners })
    }

    /// Whether `code` (read in the tag's orientation) is tag `id`'s within the family's bit
    /// errors, and the family's decoding table reads it as `id` too.
    fn is_code_of(&self, code: usize, id: u32) -> bool {
        let Some(&truth) = self.layout.code_data.get(id as usize) else { return false };
        let errors = (code ^ truth).count_ones();
        let table = self.layout.quick_decode.decode(code, &self.layout.code_data);
        errors <= u32::from(self.family.max_bit_errors()) && table.is_some_and(|e| u32::from(e.id) == id)
    }

    /// The code read inside the quad `corners` (bit `i` of the layout is bit `nbits - 1 - i`),
    /// as the AprilTag decoder reads it; `None` when the border's grey models cannot be fitted,
    /// have the wrong polarity, or a bit falls outside the image.
    fn read_code<C: Pixels>(&self, image: &GreyBuffer<C>, corners: &[P; 4]) -> Option<usize> {
        let l = &self.layout;
        let w = l.width_at_border as f64;
        let map = SquareMap::onto(corners)?;
        let sample = |x: f64, y: f64| {
            let p = map.apply(x / w, y / w)?;
            edges::bilinear(image, p[0], p[1])
        };
        let (outer, inner) = border_models(l.width_at_border, &sample)?;
        let (ow, iw) = (outer.at(w / 2.0, w / 2.0), inner.at(w / 2.0, w / 2.0));
        if (ow - iw < 0.0) != l.reversed_border {
            return None;
        }
        let size = l.total_width;
        let min = (l.width_at_border as isize - size as isize) / 2;
        let cell = |i: usize| -> Option<usize> {
            let (x, y) = (l.bit_x[i] as isize - min, l.bit_y[i] as isize - min);
            usize::try_from(y * size as isize + x).ok()
        };
        let mut values = vec![0.0f64; size * size];
        for i in 0..l.nbits {
            let (x, y) = (f64::from(l.bit_x[i]) + 0.5, f64::from(l.bit_y[i]) + 0.5);
            let v = sample(x, y)?;
            *values.get_mut(cell(i)?)? = v - (outer.at(x, y) + inner.at(x, y)) / 2.0;
        }
        let values = sharpened(&values, size);
        (0..l.nbits).try_fold(0usize, |code, i| Some((code << 1) | usize::from(*values.get(cell(i)?)? > 0.0)))
    }
}

/// The grey models of the cells just outside the square (the quiet zone, or the dark ring of
/// a reversed family) and just inside it (the black border, or the white one), read at the
/// centres of the `w` cells along each side (the AprilTag decoder's samples).
fn border_models(w: usize, sample: &impl Fn(f64, f64) -> Option<f64>) -> Option<(Plane, Plane)> {
    let (mut outer, mut inner) = (Plane::default(), Plane::default());
    let wf = w as f64;
    for i in 0..w {
        let t = i as f64 + 0.5;
        for (x, y, out) in [
            (-0.5, t, true),
            (0.5, t, false),
            (wf + 0.5, t, true),
            (wf - 0.5, t, false),
            (t, -0.5, true),
            (t, 0.5, false),
            (t, wf + 0.5, true),
            (t, wf - 0.5, false),
        ] {
            if let Some(g) = sample(x, y) {
                if out { outer.add(x, y, g) } else { inner.add(x, y, g) }
            }
        }
    }
    Some((outer.solved()?, inner.solved()?))
}

/// `values` (a `size x size` grid) plus [`SHARPENING`] times their Laplacian (zero outside
/// the grid), as the AprilTag decoder sharpens the bits.
fn sharpened(values: &[f64], size: usize) -> Vec<f64> {
    let at = |x: isize, y: isize| -> f64 {
        if x < 0 || y < 0 || x >= size as isize || y >= size as isize {
            return 0.0;
        }
        values.get(y as usize * size + x as usize).copied().unwrap_or(0.0)
    };
    let mut out = values.to_vec();
    for y in 0..size as isize {
        for x in 0..size as isize {
            let laplacian = 4.0 * at(x, y) - at(x - 1, y) - at(x + 1, y) - at(x, y - 1) - at(x, y + 1);
            if let Some(v) = out.get_mut(y as usize * size + x as usize) {
                *v += SHARPENING * laplacian;
            }
        }
    }
    out
}

/// A grey level linear in the layout's coordinates, fitted by least squares.
#[derive(Debug, Default, Clone, Copy)]
struct Plane {
    normal: Matrix3<f64>,
    right: Vector3<f64>,
    coefficients: Vector3<f64>,
}

impl Plane {
    fn add(&mut self, x: f64, y: f64, g: f64) {
        let q = Vector3::new(x, y, 1.0);
        self.normal += q * q.transpose();
        self.right += q * g;
    }

    fn solved(mut self) -> Option<Self> {
        self.coefficients = self.normal.lu().solve(&self.right)?;
        self.coefficients.iter().all(|c| c.is_finite()).then_some(self)
    }

    fn at(&self, x: f64, y: f64) -> f64 {
        self.coefficients.dot(&Vector3::new(x, y, 1.0))
    }
}

/// The homography of the unit square onto a quadrilateral (Heckbert, "Fundamentals of texture
/// mapping and image warping", 1989, section 2.2.3): `(0, 0), (1, 0), (1, 1), (0, 1)` go to
/// the square's corners in the layout (top-left, top-right, bottom-right, bottom-left).
#[derive(Debug, Clone, Copy)]
struct SquareMap {
    /// `x = (a u + b v + c) / (g u + h v + 1)`, `y = (d u + e v + f) / (g u + h v + 1)`.
    m: [f64; 8],
}

impl SquareMap {
    /// The map onto the quad of `corners` ([`Tag::corners`]'s order: corner `k` is at
    /// [`TAG_CORNERS_IN_LAYOUT`]`[k]` of the unit square); `None` when degenerate.
    fn onto(corners: &[P; 4]) -> Option<Self> {
        let at = |u: f64, v: f64| TAG_CORNERS_IN_LAYOUT.iter().position(|c| *c == [u, v]).map(|k| corners[k]);
        let ([x0, y0], [x1, y1], [x2, y2], [x3, y3]) = (at(0.0, 0.0)?, at(1.0, 0.0)?, at(1.0, 1.0)?, at(0.0, 1.0)?);
        let (sx, sy) = (x0 - x1 + x2 - x3, y0 - y1 + y2 - y3);
        let (dx1, dx2, dy1, dy2) = (x1 - x2, x3 - x2, y1 - y2, y3 - y2);
        let den = dx1 * dy2 - dx2 * dy1;
        if den.abs() < 1e-12 {
            return None;
        }
        let g = (sx * dy2 - dx2 * sy) / den;
        let h = (dx1 * sy - sx * dy1) / den;
        let m = [x1 - x0 + g * x1, x3 - x0 + h * x3, x0, y1 - y0 + g * y1, y3 - y0 + h * y3, y0, g, h];
        m.iter().all(|c| c.is_finite()).then_some(Self { m })
    }

    fn apply(&self, u: f64, v: f64) -> Option<P> {
        let [a, b, c, d, e, f, g, h] = self.m;
        let w = g * u + h * v + 1.0;
        (w.abs() > 1e-12).then(|| [(a * u + b * v + c) / w, (d * u + e * v + f) / w])
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::vision::tags::detect_tags;
    use crate::vision::tags::synthetic::{Placement, corners, draw};

    const FAMILY: TagFamily = TagFamily::Tag36h11;

    fn worst(a: &[P; 4], b: &[P; 4]) -> f64 {
        a.iter().zip(b).map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1])).fold(0.0, f64::max)
    }

    /// The map sends the unit square's corners onto the quad's, and its centre onto the
    /// diagonals' crossing (a projective invariant), computed here independently.
    #[test]
    fn the_square_map_sends_corners_and_centre_where_they_belong() {
        let q = [[120.0, 95.0], [20.0, 80.0], [30.0, 10.0], [100.0, 20.0]];
        let map = SquareMap::onto(&q).unwrap();
        for (k, [u, v]) in TAG_CORNERS_IN_LAYOUT.iter().enumerate() {
            let p = map.apply(*u, *v).unwrap();
            assert!((p[0] - q[k][0]).abs() < 1e-9 && (p[1] - q[k][1]).abs() < 1e-9, "{k}: {p:?}");
        }
        // Diagonals q0-q2 and q1-q3 cross at a + s (c - a), by Cramer's rule.
        let (a, c, b, d) = (q[0], q[2], q[1], q[3]);
        let (r, s2) = ([c[0] - a[0], c[1] - a[1]], [d[0] - b[0], d[1] - b[1]]);
        let det = r[0] * (-s2[1]) + s2[0] * r[1];
        let s = ((b[0] - a[0]) * (-s2[1]) + s2[0] * (b[1] - a[1])) / det;
        let centre = map.apply(0.5, 0.5).unwrap();
        assert!((centre[0] - (a[0] + s * r[0])).abs() < 1e-9 && (centre[1] - (a[1] + s * r[1])).abs() < 1e-9);
        assert!(SquareMap::onto(&[[0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]]).is_none());
    }

    /// A tag that moved by up to four pixels (two thirds of a cell) is followed to the corners the whole-frame
    /// detection finds; the same quad is refused under any other id, and in another
    /// orientation (its corners listed from another one).
    #[test]
    fn follows_a_moved_tag_and_refuses_other_identities() {
        let follower = TagFollower::new(FAMILY).unwrap();
        let before = Placement { id: 42, centre: [90.3, 70.6], cell: 7.2, quarter_turns: 1 };
        let after = Placement { centre: [93.9, 68.4], ..before };
        let image = draw(FAMILY, 180, 140, &[after]);
        let whole = detect_tags(&image, FAMILY).unwrap();
        let start = corners(FAMILY, &before);
        let followed = follower.follow(&image, 42, &start).unwrap();
        assert_eq!(whole.len(), 1);
        assert!(worst(&followed.corners, &whole[0].corners) < 1e-3, "{followed:?} vs {whole:?}");
        assert!(worst(&followed.corners, &corners(FAMILY, &after)) < 0.01);
        for other in [0, 41, 43, 586, 587, u32::MAX] {
            assert!(follower.follow(&image, other, &start).is_none(), "id {other}");
        }
        let turned = [start[1], start[2], start[3], start[0]];
        assert!(follower.follow(&image, 42, &turned).is_none());
        // Another tag at the same place, or none, is not tag 42.
        let replaced = draw(FAMILY, 180, 140, &[Placement { id: 43, ..after }]);
        assert!(follower.follow(&replaced, 42, &start).is_none());
        assert!(follower.follow(&replaced, 43, &start).is_some());
        assert!(follower.follow(&draw(FAMILY, 180, 140, &[]), 42, &start).is_none());
    }

    /// Every family the test drawing knows: the code read is the tag's own, exactly.
    #[test]
    fn reads_the_code_of_every_family() {
        for family in [TagFamily::Tag36h11, TagFamily::Tag36h10, TagFamily::Tag25h9, TagFamily::Tag16h5] {
            let name = family.name();
            let follower = TagFollower::new(family).unwrap();
            let p = Placement { id: 5, centre: [100.0, 90.0], cell: 9.0, quarter_turns: 2 };
            let image = draw(family, 200, 180, &[p]);
            let code = follower.read_code(&image, &corners(family, &p)).unwrap();
            assert_eq!(code, follower.layout.code_data[5], "{name}");
        }
    }
}
