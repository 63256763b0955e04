//! The printed face of a tag, read from the family data the decoder uses (kornia-apriltag's
//! copy of AprilTag 3's family files: `total_width`, `width_at_border`, `reversed_border`,
//! `bit_x`, `bit_y` and the codes), as the AprilTag library's `apriltag_to_image` draws it:
//! a grid of `total_width` x `total_width` cells, dark except
//!
//! - a one-cell white ring of side `width_at_border + 2` (the quiet zone of the classic
//!   families, around their black border) or `width_at_border` (AprilTag 3's families: the
//!   white square inside a black ring, data cells inside it and outside the ring),
//! - each data cell whose code bit is set: bit `i` (most significant first) is cell
//!   `(bit_x[i] + b, bit_y[i] + b)` with `b = (total_width - width_at_border) / 2`.
//!
//! A family whose corner cells are neither data nor white (tagCircle21h7, tagCircle49h12: the
//! layout's `x` cells) is round: its face is the disc inscribed in the grid.
//!
//! Coordinates are the library's layout: `x` right, `y` down, unit one cell, `(0, 0)` the
//! grid's top-left corner.

use std::sync::OnceLock;

use kornia_apriltag::family::TagFamily as Layout;

use super::TagFamily;
use crate::error::Error;
use crate::vision::error::Result;

/// The family data of each [`TagFamily`], built once (and repaired: [`repaired`]). The
/// decoder reads this same data (`TagDecoder`), so the faces drawn are the codes it decodes.
pub(super) fn layout(family: TagFamily) -> Result<&'static Layout> {
    static LAYOUTS: [OnceLock<std::result::Result<Layout, String>>; TagFamily::ALL.len()] =
        [const { OnceLock::new() }; TagFamily::ALL.len()];
    let index = TagFamily::ALL.iter().position(|f| *f == family).unwrap_or(0);
    let cached =
        LAYOUTS[index].get_or_init(|| Layout::try_from(&family.kind()).map_err(|e| e.to_string()).and_then(repaired));
    Ok(cached
        .as_ref()
        .map_err(|e| Error::InvalidParameter { name: "family", reason: format!("{}: {e}", family.name()) })?)
}

/// A layout whose bit positions are those of an AprilTag layout: `nbits` of each, and turned
/// into themselves by a quarter turn (apriltag-generation's `ImageLayout`: bit `i + nbits / 4`
/// is bit `i` turned, for the first three quarters). kornia-apriltag 0.2's tagCircle49h12 has
/// one `bit_x` too many (50 for 49 bits, a `-2` repeated, which moves every later bit and
/// breaks both its drawing and its decoding): the one entry whose removal restores the
/// symmetry is removed. Any other mismatch is an error.
fn repaired(mut l: Layout) -> std::result::Result<Layout, String> {
    let fits = |xs: &[i8], ys: &[i8]| quarter_turns_close(&l, xs, ys);
    if fits(&l.bit_x, &l.bit_y) {
        return Ok(l);
    }
    let without =
        |v: &[i8], k: usize| -> Vec<i8> { v.iter().enumerate().filter(|&(i, _)| i != k).map(|(_, &c)| c).collect() };
    if l.bit_x.len() == l.nbits + 1
        && let Some(xs) = (0..l.bit_x.len()).map(|k| without(&l.bit_x, k)).find(|xs| fits(xs, &l.bit_y))
    {
        l.bit_x = xs;
        return Ok(l);
    }
    if l.bit_y.len() == l.nbits + 1
        && let Some(ys) = (0..l.bit_y.len()).map(|k| without(&l.bit_y, k)).find(|ys| fits(&l.bit_x, ys))
    {
        l.bit_y = ys;
        return Ok(l);
    }
    Err(format!("the layout's {} bit positions are not those of {} bits", l.bit_x.len().max(l.bit_y.len()), l.nbits))
}

/// Whether `xs`, `ys` are `nbits` positions in the grid, each quarter the previous one turned.
fn quarter_turns_close(l: &Layout, xs: &[i8], ys: &[i8]) -> bool {
    let (n, t) = (l.nbits, l.total_width as i64);
    let b = (t - l.width_at_border as i64) / 2;
    if xs.len() != n || ys.len() != n {
        return false;
    }
    let g = |c: i8| i64::from(c) + b;
    let step = n / 4;
    let inside = xs.iter().chain(ys).all(|&c| (0..t).contains(&g(c)));
    inside && (0..3 * step).all(|i| g(xs[i + step]) == t - 1 - g(ys[i]) && g(ys[i + step]) == g(xs[i]))
}

/// A tag's face: which cells of its grid are white, and whether it is cut to a disc.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TagFace {
    /// Cells across the grid (the family's `total_width`).
    pub total: usize,
    /// Cells across the square whose corners are reported (`width_at_border`).
    pub border: usize,
    /// `white[y][x]`: cell `(x, y)` of the grid, in the library's layout.
    pub white: Vec<Vec<bool>>,
    /// The face is the disc of diameter `total` centred on the grid (the circle families).
    pub round: bool,
}

impl TagFace {
    /// The face of tag `id` of `family`; an id beyond the family is an error naming `id`.
    pub fn new(family: TagFamily, id: u32) -> Result<Self> {
        let l = layout(family)?;
        let Some(&code) = l.code_data.get(id as usize) else {
            let reason = format!("a {} id is in 0..{}, got {id}", family.name(), l.code_data.len());
            return Err(Error::InvalidParameter { name: "id", reason }.into());
        };
        let (total, border) = (l.total_width, l.width_at_border);
        let mut white = vec![vec![false; total]; total];
        let ring = if l.reversed_border { border } else { border + 2 };
        let start = (total - ring.min(total)) / 2;
        for (y, row) in white.iter_mut().enumerate() {
            for (x, cell) in row.iter_mut().enumerate() {
                let on = |c: usize| c == start || c + 1 == start + ring;
                let inside = |c: usize| (start..start + ring).contains(&c);
                *cell = inside(x) && inside(y) && (on(x) || on(y));
            }
        }
        for (i, (x, y)) in data_cells(l).enumerate() {
            white[y][x] = (code >> (l.nbits - 1 - i)) & 1 == 1;
        }
        let corner_is_data = data_cells(l).any(|c| c == (0, 0));
        Ok(Self { total, border, round: !corner_is_data && !white[0][0], white })
    }

    /// The number of ids of `family`.
    pub fn count(family: TagFamily) -> Result<u32> {
        Ok(u32::try_from(layout(family)?.code_data.len()).unwrap_or(u32::MAX))
    }
}

/// The grid cells of the family's data bits, in bit order (most significant first).
pub(crate) fn data_cells(l: &Layout) -> impl Iterator<Item = (usize, usize)> + '_ {
    let b = (l.total_width - l.width_at_border) as i64 / 2;
    let cell = move |c: i8| usize::try_from(i64::from(c) + b).unwrap_or(usize::MAX);
    l.bit_x.iter().zip(&l.bit_y).map(move |(&x, &y)| (cell(x), cell(y)))
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    fn families() -> impl Iterator<Item = TagFamily> {
        TagFamily::ALL.into_iter()
    }

    /// Each family reads kornia's family of its own name (`tagStandard41h12`: `tagstandard41_h12`).
    #[test]
    fn each_family_reads_the_layout_of_its_name() {
        for family in families() {
            let l = layout(family).unwrap();
            assert_eq!(l.name.replace('_', ""), family.name().to_lowercase(), "{family:?}");
        }
        assert_eq!(TagFamily::ALL.map(TagFamily::name), TagFamily::NAMES);
    }

    /// Every layout has its bits' positions, turned into themselves by a quarter turn (after
    /// the repair of tagCircle49h12's, whose raw data has a position too many).
    #[test]
    fn every_layout_is_closed_under_quarter_turns() {
        for family in families() {
            let l = layout(family).unwrap();
            assert!(quarter_turns_close(l, &l.bit_x, &l.bit_y), "{family:?}");
        }
        let raw = Layout::try_from(&TagFamily::TagCircle49h12.kind()).unwrap();
        assert_eq!((raw.nbits, raw.bit_x.len(), raw.bit_y.len()), (49, 50, 49), "kornia fixed it: drop the repair");
        let fixed = layout(TagFamily::TagCircle49h12).unwrap();
        // The middle cell is the last bit, as in every layout with nbits = 1 mod 4.
        assert_eq!((fixed.bit_x[48], fixed.bit_y[48]), (2, 2));
        let mut broken = raw.clone();
        broken.bit_y.truncate(40);
        assert!(repaired(broken).is_err());
    }

    #[test]
    fn every_data_cell_is_in_the_grid_and_none_twice() {
        for family in families() {
            let l = layout(family).unwrap();
            let cells: Vec<_> = data_cells(l).collect();
            assert_eq!(cells.len(), l.nbits, "{family:?}");
            assert!(cells.iter().all(|&(x, y)| x < l.total_width && y < l.total_width), "{family:?}");
            let mut sorted = cells.clone();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(sorted.len(), cells.len(), "{family:?}");
        }
    }

    /// The classic families: a white quiet zone, a black border, data inside it. AprilTag 3's:
    /// a black ring around a white ring (the square whose corners are reported).
    #[test]
    fn the_border_rings_are_the_layouts() {
        for family in families() {
            let face = TagFace::new(family, 0).unwrap();
            let (t, w) = (face.total, face.border);
            let ring = |d: usize| -> Vec<(usize, usize)> {
                (d..t - d).flat_map(|i| [(i, d), (i, t - 1 - d), (d, i), (t - 1 - d, i)]).collect()
            };
            let b = (t - w) / 2;
            let l = layout(family).unwrap();
            let data: Vec<_> = data_cells(l).collect();
            if family.reversed_border() {
                assert!(ring(b).iter().all(|&(x, y)| face.white[y][x]), "{family:?}: white ring");
                assert!(ring(b - 1).iter().all(|&(x, y)| !face.white[y][x]), "{family:?}: black ring");
                assert!(ring(b - 1).iter().all(|c| !data.contains(c)), "{family:?}");
            } else {
                assert_eq!(b, 1, "{family:?}");
                assert!(ring(0).iter().all(|&(x, y)| face.white[y][x]), "{family:?}: quiet zone");
                assert!(ring(1).iter().all(|&(x, y)| !face.white[y][x]), "{family:?}: black border");
            }
            assert_eq!(w as u32, family.border_cells(), "{family:?}");
        }
    }

    #[test]
    fn the_circle_families_are_round_and_their_data_in_the_disc() {
        for family in families() {
            let face = TagFace::new(family, 1).unwrap();
            assert_eq!(face.round, family.name().starts_with("tagCircle"), "{family:?}");
            if !face.round {
                continue;
            }
            let r = face.total as f64 / 2.0;
            let l = layout(family).unwrap();
            for (x, y) in data_cells(l) {
                let d = (x as f64 + 0.5 - r).hypot(y as f64 + 0.5 - r);
                assert!(d < r - 0.35, "{family:?}: data cell ({x}, {y}) at {d} of {r}");
            }
            // The white ring (the reported square) is whole inside the disc.
            let b = (face.total - face.border) as f64 / 2.0;
            assert!((r - b) * std::f64::consts::SQRT_2 < r, "{family:?}");
        }
    }

    #[test]
    fn the_first_tag36h11_code_is_the_librarys() {
        // AprilTag 3's tag36h11 code 0 is 0xd7e00984b; its bit 35 (the most significant) is at
        // bit_x = 1, bit_y = 1 (grid cell (2, 2)), bit 0 (set) at (3, 4), bit 2 (clear) at (2, 4).
        let face = TagFace::new(TagFamily::Tag36h11, 0).unwrap();
        assert_eq!((face.total, face.border, face.round), (10, 8, false));
        assert!(face.white[2][2] && face.white[5][4] && !face.white[5][3]);
        let data = face.white[2..8].iter().flat_map(|r| &r[2..8]).filter(|&&w| w).count();
        assert_eq!(data, 0xd7e00984b_u64.count_ones() as usize);
        assert_eq!(TagFace::count(TagFamily::Tag36h11).unwrap(), 587);
        let err = TagFace::new(TagFamily::Tag36h11, 587).unwrap_err().to_string();
        assert!(err.contains("id") && err.contains("0..587"), "{err}");
    }
}
