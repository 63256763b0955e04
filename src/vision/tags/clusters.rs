//! The gradient clusters of a labelled level ([`Clusters::find`]): the border pixels between
//! each pair of adjacent black and white regions, from which the quad fit reads each
//! candidate's outline (Wang & Olson, "AprilTag 2", IROS 2016, section III-C: "a cluster per
//! pair of regions").
//!
//! The points are those of the AprilTag detector (and of `kornia-apriltag`, whose quad fit
//! reads them): for each pixel of a kept region and each of its neighbours to the right,
//! below, below-left and below-right in another kept region of the other colour, the point
//! half-way between them (in half-pixel units), with the direction from black to white; the
//! below-left neighbour is skipped when the pixel before had its below-right one. They are
//! listed in raster order, the order the quad fit's sort breaks its ties by.

use kornia_apriltag::segmentation::GradientInfo;
use kornia_apriltag::utils::{Pixel, Point2d};
use rustc_hash::FxHashMap;

use super::components::{Components, NO_REGION, word};

/// A cluster's key: the two regions it lies between, the smaller first.
type Key = (usize, usize);

/// The clusters of one level, keyed by their two regions, with their buffers kept from call
/// to call.
#[derive(Default)]
pub(super) struct Clusters {
    /// The clusters found by the last [`Clusters::find`].
    pub map: FxHashMap<Key, Vec<GradientInfo>>,
    /// While gathering: each key's place in `lists`, and the lists in the order found.
    index: FxHashMap<Key, u32>,
    lists: Vec<(Key, Vec<GradientInfo>)>,
    /// Emptied lists of earlier calls, whose buffers the next ones reuse (a photograph's level
    /// has hundreds of clusters: each a buffer allocated, grown and freed a frame otherwise).
    spare: Vec<Vec<GradientInfo>>,
    /// The region of each pixel of the two rows read.
    above: Vec<u32>,
    below: Vec<u32>,
    /// The two rows' pixels as bytes, skipped outside the kept regions.
    bytes_above: Vec<u8>,
    bytes_below: Vec<u8>,
}

/// The clusters being gathered: each key's list, found through the last key (the same pair
/// of regions runs along an edge) or the index.
struct Gathering<'a> {
    index: &'a mut FxHashMap<Key, u32>,
    lists: &'a mut Vec<(Key, Vec<GradientInfo>)>,
    spare: &'a mut Vec<Vec<GradientInfo>>,
    /// The last key and its list.
    last: Option<(Key, usize)>,
}

impl Gathering<'_> {
    fn push(&mut self, key: Key, point: GradientInfo) {
        let i = match self.last {
            Some((k, i)) if k == key => i,
            _ => {
                let next = self.lists.len();
                let i = *self.index.entry(key).or_insert(next as u32) as usize;
                if i == next {
                    let list = self.spare.pop().unwrap_or_else(|| Vec::with_capacity(64));
                    self.lists.push((key, list));
                }
                self.last = Some((key, i));
                i
            }
        };
        if let Some((_, list)) = self.lists.get_mut(i) {
            list.push(point);
        }
    }
}

impl Clusters {
    /// The clusters of `binary` (rows of `width`), whose regions `components` labelled, that
    /// hold a number of points in `sizes` (the others are left out).
    pub(super) fn find(
        &mut self,
        binary: &[Pixel],
        width: usize,
        components: &Components,
        sizes: std::ops::RangeInclusive<usize>,
    ) {
        let Self { map, index, lists, spare, above, below, bytes_above, bytes_below } = self;
        spare.extend(map.drain().map(|(_, mut list)| {
            list.clear();
            list
        }));
        let height = binary.len() / width.max(1);
        if width < 3 || height < 3 {
            return;
        }
        regions_of_row(components, 1, width, above, bytes_above);
        index.clear();
        lists.clear();
        let mut gathering = Gathering { index, lists, spare, last: None };
        for y in 1..height - 1 {
            regions_of_row(components, y + 1, width, below, bytes_below);
            let rows = Rows {
                a: &binary[y * width..(y + 1) * width],
                b: &binary[(y + 1) * width..(y + 2) * width],
                bytes_a: bytes_above,
                bytes_b: bytes_below,
                above,
                below,
                y,
            };
            rows.gather(&mut gathering);
            std::mem::swap(above, below);
            std::mem::swap(bytes_above, bytes_below);
        }
        for (key, mut points) in lists.drain(..) {
            if sizes.contains(&points.len()) {
                map.insert(key, points);
            } else {
                points.clear();
                spare.push(points);
            }
        }
    }
}

/// The region of each pixel of row `y` into `regions` ([`NO_REGION`] outside the kept ones),
/// and its colour into `bytes`, as a skipped pixel outside them (so that the pixels of regions
/// too small to keep are quiet in [`Rows::gather`]'s eight-pixel test).
fn regions_of_row(components: &Components, y: usize, width: usize, regions: &mut Vec<u32>, bytes: &mut Vec<u8>) {
    regions.clear();
    regions.resize(width, NO_REGION);
    bytes.clear();
    bytes.resize(width, Pixel::Skip as u8);
    for (run, region) in components.row(y) {
        if region != NO_REGION {
            let span = run.start as usize..run.end as usize;
            regions[span.clone()].fill(region);
            bytes[span].fill(run.colour as u8);
        }
    }
}

/// The bytes of `xor` (of two words of pixels) that are black against white: the pixels are
/// black 0, white 255 and skipped 127, so a byte is 255 for black against white, 128 or 127
/// for a skipped pixel against another, 0 for the same; its top bit and its lowest bit are
/// both set only for 255 (`xor << 7` brings each byte's lowest bit to its top bit).
#[inline(always)]
fn black_white(xor: u64) -> u64 {
    xor & (xor << 7) & 0x8080_8080_8080_8080
}

/// Row `y` (`a`) and the row below it (`b`), with their pixels' regions.
struct Rows<'a> {
    a: &'a [Pixel],
    b: &'a [Pixel],
    bytes_a: &'a [u8],
    bytes_b: &'a [u8],
    above: &'a [u32],
    below: &'a [u32],
    y: usize,
}

impl Rows<'_> {
    /// The points of row `y`'s interior pixels, in order. Eight pixels at a time where none
    /// is black with a white neighbour of the four read or white with a black one, both in kept
    /// regions (a zero byte of `differs`): those add no point.
    fn gather(&self, gathering: &mut Gathering) {
        let width = self.a.len();
        let (a, b) = (self.bytes_a, self.bytes_b);
        let mut connected_last = false;
        let mut x = 1;
        while x < width - 1 {
            if x + 9 <= width {
                let here = word(a, x);
                let differs = black_white(here ^ word(a, x + 1))
                    | black_white(here ^ word(b, x))
                    | black_white(here ^ word(b, x - 1))
                    | black_white(here ^ word(b, x + 1));
                if differs == 0 {
                    connected_last = false;
                    x += 8;
                    continue;
                }
                let quiet = differs.trailing_zeros() as usize / 8;
                if quiet > 0 {
                    connected_last = false;
                    x += quiet;
                }
            }
            connected_last = self.pixel(x, connected_last, gathering);
            x += 1;
        }
    }

    /// The points of pixel `x` (right, below, below-left unless `connected_last`,
    /// below-right), and whether it had its below-right one.
    #[inline(always)]
    fn pixel(&self, x: usize, connected_last: bool, gathering: &mut Gathering) -> bool {
        let here = (self.above[x], self.a[x]);
        if here.0 == NO_REGION {
            return false;
        }
        let at = (x, self.y);
        self.add(gathering, here, at, (self.above[x + 1], self.a[x + 1]), (1, 0));
        self.add(gathering, here, at, (self.below[x], self.b[x]), (0, 1));
        if !connected_last {
            self.add(gathering, here, at, (self.below[x - 1], self.b[x - 1]), (-1, 1));
        }
        self.add(gathering, here, at, (self.below[x + 1], self.b[x + 1]), (1, 1))
    }

    /// The point between pixel `at` (its region and colour `here`) and its neighbour at
    /// `at + (dx, dy)` (`there`), when they are in two kept regions of different colours;
    /// whether there is one.
    #[inline(always)]
    fn add(
        &self,
        gathering: &mut Gathering,
        (region, colour): (u32, Pixel),
        (x, y): (usize, usize),
        (other, other_colour): (u32, Pixel),
        (dx, dy): (i32, i32),
    ) -> bool {
        if other == NO_REGION || other == region || other_colour == colour {
            return false;
        }
        let key = if region < other { (region as usize, other as usize) } else { (other as usize, region as usize) };
        let delta = other_colour.gradient_to(colour);
        let pos = Point2d { x: (2 * x as i64 + i64::from(dx)) as u32, y: (2 * y as i64 + i64::from(dy)) as u32 };
        gathering.push(key, GradientInfo { pos, gx: delta * dx as isize, gy: delta * dy as isize, slope: 0.0 });
        true
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::vision::tags::synthetic::Rng;

    /// The points of the detector's rule read one pixel at a time (no skipping), as pairs of
    /// a key and a point (position and gradient), in order.
    fn reference(binary: &[Pixel], width: usize, components: &Components) -> Vec<(Key, (u32, u32, i16, i16))> {
        let height = binary.len() / width;
        let mut regions = vec![NO_REGION; binary.len()];
        for y in 0..height {
            for (run, region) in components.row(y) {
                regions[y * width + run.start as usize..y * width + run.end as usize].fill(region);
            }
        }
        let mut points = Vec::new();
        for y in 1..height.saturating_sub(1) {
            let mut connected_last = false;
            for x in 1..width - 1 {
                let i = y * width + x;
                if regions[i] == NO_REGION {
                    connected_last = false;
                    continue;
                }
                let mut point = |j: usize, dx: i32, dy: i32| {
                    let (r, s) = (regions[i], regions[j]);
                    if s == NO_REGION || s == r || binary[j] == binary[i] {
                        return false;
                    }
                    // kornia's sign: -255 when the pixel is the white one.
                    let towards = if binary[i] == Pixel::White { -255 } else { 255 };
                    let pos = ((2 * x as i32 + dx) as u32, (2 * y as i32 + dy) as u32);
                    points.push((
                        (r.min(s) as usize, r.max(s) as usize),
                        (pos.0, pos.1, (towards * dx) as i16, (towards * dy) as i16),
                    ));
                    true
                };
                point(i + 1, 1, 0);
                point(i + width, 0, 1);
                if !connected_last {
                    point(i + width - 1, -1, 1);
                }
                connected_last = point(i + width + 1, 1, 1);
            }
        }
        points
    }

    #[test]
    fn clusters_hold_the_detectors_points_in_raster_order() {
        let mut rng = Rng(5);
        let colours = [Pixel::Black, Pixel::White, Pixel::Skip];
        for (width, height) in [(3, 3), (9, 4), (10, 10), (17, 33), (64, 40), (131, 77)] {
            for block in [1, 3, 9] {
                // Blocks of each colour, larger ones so that regions reach the least size.
                let pixels: Vec<Pixel> = (0..width * height)
                    .map(|i| {
                        let (x, y) = (i % width / block, i / width / block);
                        colours[(x * 7 + y * 3 + usize::from(rng.below(9) == 0)) % 3]
                    })
                    .collect();
                let mut components = Components::default();
                components.label(&pixels, width);
                let mut clusters = Clusters::default();
                clusters.find(&pixels, width, &components, 0..=usize::MAX);
                let mut expected: FxHashMap<Key, Vec<(u32, u32, i16, i16)>> = FxHashMap::default();
                for (key, point) in reference(&pixels, width, &components) {
                    expected.entry(key).or_default().push(point);
                }
                let found: FxHashMap<Key, Vec<(u32, u32, i16, i16)>> = clusters
                    .map
                    .iter()
                    .map(|(k, v)| (*k, v.iter().map(|g| (g.pos.x, g.pos.y, g.gx as i16, g.gy as i16)).collect()))
                    .collect();
                assert_eq!(found, expected, "{width} x {height}, blocks of {block}");
            }
        }
    }
}
