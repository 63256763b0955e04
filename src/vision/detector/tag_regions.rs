//! Where [`TagDetector`](super::tags::TagDetector) searches a tag in the next frame: a
//! rectangle around its last corners, grown by a margin proportional to its size plus its
//! last motion, its sides on a grid of `align` pixels (so that the decoder's decimated image
//! and threshold tiles of the crop are those of the whole frame), clipped to the image;
//! rectangles that overlap are merged, so a tag is read in one crop only.

use crate::vision::tags::Tag;

/// A crop of the image: columns `x0..x1`, rows `y0..y1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Region {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

/// The margin around a tag's last corners, in tag sides: a quarter of a side covers its quiet
/// zone (one cell, an eighth of a side for tag36h11) with room for the threshold's tiles.
const MARGIN_SIDES: f64 = 0.25;
/// The margin's motion term: this many times the largest corner move since the frame before.
const MARGIN_MOTIONS: f64 = 2.0;
/// The least margin, pixels.
const MIN_MARGIN: f64 = 16.0;
/// A crop's sides are whole multiples of this many grid steps, so that its size (and the
/// decoder kept for it) comes back from frame to frame while the tag moves.
const SIZE_STEPS: u32 = 4;

impl Region {
    /// The region to search a tag seen at `tag`'s corners that last moved by `motion` pixels,
    /// in a `width` x `height` image; `None` when its corners are not finite.
    pub fn around(tag: &Tag, motion: f64, width: u32, height: u32, align: u32) -> Option<Self> {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for c in &tag.corners {
            for k in 0..2 {
                lo[k] = lo[k].min(c[k]);
                hi[k] = hi[k].max(c[k]);
            }
        }
        let side = (0..4).map(|i| dist(tag.corners[i], tag.corners[(i + 1) % 4])).fold(0.0, f64::max);
        let margin = (MARGIN_SIDES * side + MARGIN_MOTIONS * motion).max(MIN_MARGIN);
        if !(lo.iter().chain(&hi).all(|x| x.is_finite()) && margin.is_finite()) {
            return None;
        }
        let step = align.max(1);
        let grid = f64::from(step);
        let low = |x: f64, size: u32| clamp(((x - margin) / grid).floor() * grid, size);
        let high = |x: f64, size: u32| clamp(((x + margin + 1.0) / grid).ceil() * grid, size);
        let (x0, x1) = sized(low(lo[0], width), high(hi[0], width), width, step);
        let (y0, y1) = sized(low(lo[1], height), high(hi[1], height), height, step);
        let r = Self { x0, y0, x1, y1 };
        (r.x0 < r.x1 && r.y0 < r.y1).then_some(r)
    }

    /// Its pixels.
    pub fn area(&self) -> u64 {
        u64::from(self.x1 - self.x0) * u64::from(self.y1 - self.y0)
    }

    /// Whether `p` is inside, at least `guard` pixels from a side that is not the image's.
    pub fn holds(&self, p: [f64; 2], guard: f64, width: u32, height: u32) -> bool {
        let inside = |x: f64, a: u32, b: u32, size: u32| {
            let low = if a == 0 { -0.5 } else { f64::from(a) + guard };
            let high = if b == size { f64::from(b) - 0.5 } else { f64::from(b) - 1.0 - guard };
            x >= low && x <= high
        };
        inside(p[0], self.x0, self.x1, width) && inside(p[1], self.y0, self.y1, height)
    }

    fn overlaps(&self, o: &Self) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }

    fn union(&self, o: &Self) -> Self {
        Self { x0: self.x0.min(o.x0), y0: self.y0.min(o.y0), x1: self.x1.max(o.x1), y1: self.y1.max(o.y1) }
    }
}

/// The regions merged until none overlaps another.
pub(crate) fn merged(mut regions: Vec<Region>) -> Vec<Region> {
    let mut i = 0;
    while i < regions.len() {
        match (i + 1..regions.len()).find(|&j| regions[i].overlaps(&regions[j])) {
            Some(j) => {
                let other = regions.swap_remove(j);
                regions[i] = regions[i].union(&other);
                i = 0;
            }
            None => i += 1,
        }
    }
    regions
}

/// `a..b` grown to a whole multiple of `SIZE_STEPS * step` (at its far end, or at its near end
/// on the grid where the image ends), within `0..size`.
fn sized(a: u32, b: u32, size: u32, step: u32) -> (u32, u32) {
    let quantum = SIZE_STEPS * step;
    let want = (b - a).div_ceil(quantum) * quantum;
    let b = a.saturating_add(want).min(size);
    let a = if b - a < want { (b.saturating_sub(want) / step) * step } else { a };
    (a, b)
}

fn clamp(x: f64, size: u32) -> u32 {
    // `x` is finite here; the cast saturates at 0 and is bounded by `size`.
    (x.max(0.0) as u32).min(size)
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn square(u: f64, v: f64, side: f64) -> Tag {
        Tag { id: 0, corners: [[u, v], [u + side, v], [u + side, v + side], [u, v + side]] }
    }

    #[test]
    fn a_region_holds_the_tag_and_its_margin_on_the_grid() {
        let r = Region::around(&square(100.3, 50.2, 40.0), 3.0, 640, 480, 8).unwrap();
        // margin = 0.25 * 40 + 2 * 3 = 16 px each side, out to the 8 px grid (80..160 and
        // 32..112), then 80 px grown to a multiple of 4 steps (96 px).
        assert_eq!(r, Region { x0: 80, y0: 32, x1: 176, y1: 128 });
        assert!([r.x0, r.y0, r.x1, r.y1].iter().all(|x| x % 8 == 0));
        // A small tag still gets the least margin; at an edge of the image the crop grows
        // inwards: 0..28 -> 0..32, and 452..480 -> 448..480.
        let small = Region::around(&square(2.0, 470.0, 6.0), 0.0, 640, 480, 4).unwrap();
        assert_eq!(small, Region { x0: 0, y0: 448, x1: 32, y1: 480 });
        // An image smaller than the quantum is taken whole.
        assert_eq!(sized(4, 12, 10, 4), (0, 10));
        assert_eq!(Region::around(&square(f64::NAN, 0.0, 6.0), 0.0, 640, 480, 4), None);
        assert_eq!(Region::around(&square(700.0, 10.0, 6.0), 0.0, 640, 480, 4), None);
    }

    #[test]
    fn overlapping_regions_merge_into_one() {
        let a = Region { x0: 0, y0: 0, x1: 10, y1: 10 };
        let b = Region { x0: 30, y0: 0, x1: 40, y1: 10 };
        let c = Region { x0: 8, y0: 8, x1: 32, y1: 12 };
        assert_eq!(merged(vec![a, b]), [a, b]);
        assert_eq!(merged(vec![a, b, c]), [Region { x0: 0, y0: 0, x1: 40, y1: 12 }]);
        assert_eq!(a.area(), 100);
    }

    #[test]
    fn a_point_near_a_cut_side_is_not_held() {
        let r = Region { x0: 8, y0: 0, x1: 40, y1: 20 };
        assert!(r.holds([20.0, 0.0], 2.0, 100, 20), "the image's own edges need no guard");
        assert!(!r.holds([9.0, 10.0], 2.0, 100, 20));
        assert!(r.holds([10.0, 10.0], 2.0, 100, 20));
        assert!(!r.holds([38.0, 10.0], 2.0, 100, 20));
        assert!(r.holds([37.0, 10.0], 2.0, 100, 20));
    }
}
