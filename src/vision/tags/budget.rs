//! The work [`TagDecoder`](super::TagDecoder) does on one frame, bounded: a cluttered frame
//! (thousands of small dark squares, a random checkerboard, a wall of tags) is searched only
//! as far as the bound allows, and the answer says it stopped early ([`TagReport`]).
//!
//! Where the time goes (1920 x 1080, a wall of 8,000 small tag16h5 tags, 0.9 s before this
//! bound): `kornia-apriltag`'s gradient clusters, quad fit and decoding (0.58 s, inside one
//! call that cannot be interrupted; its threshold and connected components take 4%), then
//! the corners measured again on the edges (`edges.rs`, 0.3 s for 6,767 decoded candidates
//! of 30 ids, about 45 us each). Both grow with the regions of the thresholded image, not
//! with its pixels. So:
//!
//! - before a level is searched, its regions are counted ([`RegionCounter::regions`]: the black and white
//!   regions of the detector's own threshold large enough to start a quad, one pass over the
//!   searched pixels and a union-find over their runs), and a level that would take the frame past [`MAX_SEARCHED_REGIONS`] is not
//!   searched (the coarser levels still are: their regions are fewer);
//! - the decoded candidates are measured best first (fewest bit errors, then the best
//!   decoding margin), an id already measured is not measured again, and at most
//!   [`MAX_MEASURED_CANDIDATES`] are measured.

use kornia_apriltag::threshold::{TileMinMax, adaptive_threshold_with_split};
use kornia_apriltag::utils::Pixel;
use kornia_image::{Image, ImageSize};

use super::{Candidate, Tag};

/// The most regions (of the detector's threshold, counted by `regions`) a frame's quad
/// searches read, over all its levels: the detector takes some 15 to 50 us a region (noise
/// the least, small squares and tags the most), so a frame's quad searches take at most some
/// 0.2 s. Ordinary frames hold fewer: ViSP's AprilTag images at most 950 at the default
/// decimation, 3,854 for the photograph enlarged to 1920 x 1080 and searched at decimation 1;
/// a wall of 8,000 small tags or 4,500 dark squares at 1920 x 1080 some 4,500 to 11,000 on
/// its finest level.
pub const MAX_SEARCHED_REGIONS: u64 = 4096;

/// The most decoded candidates whose corners are measured on the edges in one frame (some
/// 45 us each): one per id unless the best is refused, so only a wall of hundreds of
/// distinct tags reaches it.
pub const MAX_MEASURED_CANDIDATES: usize = 512;

/// The tags of one frame and whether the search stopped early (a level not searched, or
/// candidates not measured, because the frame was too cluttered: see the module docs).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TagReport {
    /// The tags found, sorted by id (as [`detect_tags`](super::detect_tags) returns them).
    pub tags: Vec<Tag>,
    /// Whether some of the frame was not searched or some candidates not measured.
    pub stopped_early: bool,
}

/// What is left of one frame's budget.
#[derive(Debug)]
pub(super) struct Budget {
    regions_left: u64,
    pub(super) stopped_early: bool,
}

impl Budget {
    pub(super) fn new() -> Self {
        Self { regions_left: MAX_SEARCHED_REGIONS, stopped_early: false }
    }

    /// Whether a level whose quad search reads `searched_pixels` is searched: it holds at most
    /// one region per [`MIN_REGION_PIXELS`] pixels, and when that many fit in what is left
    /// they are taken from the budget without counting; otherwise its regions are counted
    /// (`count`, [`RegionCounter::regions`]) and taken as [`Self::admit`] takes them. On an ordinary frame
    /// only the finest level is counted.
    pub(super) fn admit_level(&mut self, searched_pixels: u64, count: impl FnOnce() -> Option<u64>) -> bool {
        let most = searched_pixels / u64::from(MIN_REGION_PIXELS);
        let regions = if most <= self.regions_left { most } else { count().unwrap_or(0) };
        self.admit(regions)
    }

    /// Whether a level of `regions` regions is searched (taking them from the budget); a
    /// level refused marks the frame as stopped early.
    pub(super) fn admit(&mut self, regions: u64) -> bool {
        if regions <= self.regions_left {
            self.regions_left -= regions;
            return true;
        }
        self.stopped_early = true;
        false
    }
}

/// Counts the regions the detector would decode quads from ([`Self::regions`]), its buffers
/// (the decimated level, its threshold, the runs and their union-find) kept from call to call.
#[derive(Default)]
pub(super) struct RegionCounter {
    decimated: Vec<u8>,
    binary: Option<Image<Pixel, 1>>,
    tiles: Option<(ImageSize, TileMinMax)>,
    runs: Runs,
}

impl RegionCounter {
    /// The regions the detector would decode quads from in `source` decimated by `decimation`
    /// (one pixel of `decimation x decimation`, as the detector decimates): the image is
    /// thresholded as the detector thresholds it (`adaptive_threshold_with_split`, 4 x 4
    /// tiles), and the 4-connected regions of black or white pixels of at least
    /// [`MIN_REGION_PIXELS`] are counted (the detector leaves smaller ones out). `None` when the
    /// image is smaller than a tile.
    pub(super) fn regions(
        &mut self,
        source: &Image<u8, 1>,
        decimation: u32,
        min_difference: u8,
        split: f32,
    ) -> Option<u64> {
        let d = decimation.max(1) as usize;
        let decimated = if d == 1 {
            None
        } else {
            let (width, height) = (source.width(), source.height());
            let size = ImageSize { width: 1 + width.saturating_sub(1) / d, height: 1 + height.saturating_sub(1) / d };
            let mut pixels = std::mem::take(&mut self.decimated);
            pixels.clear();
            for row in source.as_slice().chunks_exact(width).step_by(d) {
                pixels.extend(row.iter().step_by(d));
            }
            Some(Image::<u8, 1>::new(size, pixels).ok()?)
        };
        let searched = decimated.as_ref().unwrap_or(source);
        let size = searched.size();
        let binary = match self.binary.take() {
            Some(b) if b.size() == size => b,
            _ => Image::<Pixel, 1>::from_size_val(size, Pixel::Skip).ok()?,
        };
        let binary = self.binary.insert(binary);
        let tiles = match self.tiles.take() {
            Some((s, t)) if s == size => t,
            _ => TileMinMax::new(size, 4),
        };
        let (_, tiles) = self.tiles.insert((size, tiles));
        // kornia's threshold runs with rayon: on vsinv's pool, never rayon's global one, which a
        // forked child would inherit without its threads (see `parallel`).
        let threshold = || adaptive_threshold_with_split(searched, &mut *binary, &mut *tiles, min_difference, split);
        let thresholded = crate::parallel::install(threshold).ok().and_then(Result::ok);
        let count = thresholded.map(|()| self.runs.count_regions(binary.as_slice(), size.width));
        if let Some(image) = decimated {
            self.decimated = image.into_vec();
        }
        count
    }
}

/// The detector's smallest connected component (pixels): smaller ones start no quad.
pub const MIN_REGION_PIXELS: u32 = 25;

/// A run: its first and one-past-last columns, its colour and its index in `parent`.
type Run = (usize, usize, Pixel, u32);

/// The buffers of [`Runs::count_regions`], kept from call to call.
#[derive(Default)]
struct Runs {
    parent: Vec<u32>,
    area: Vec<u32>,
    above: Vec<Run>,
    here: Vec<Run>,
    ends: Vec<usize>,
}

/// The ends (one past the last pixel) of the runs of equal pixels of `row`, in order, into
/// `ends` (the last is the row's length). Eight pixels and the one after them at a time: a
/// byte of `word ^ next` (the eight and the eight from the next pixel on) is not zero where a
/// pixel differs from the one after it, so a row of long runs costs one test per eight pixels
/// (each pixel is still read as a byte of its own: the detector's pixel type allows no wider
/// safe load, and the count gained a tenth).
fn run_ends(row: &[Pixel], ends: &mut Vec<usize>) {
    ends.clear();
    let mut i = 0;
    while let Some(nine) = row.get(i..i + 9) {
        let byte = |k: usize| nine[k] as u8;
        let word = u64::from_le_bytes(std::array::from_fn(byte));
        let next = u64::from_le_bytes(std::array::from_fn(|k| byte(k + 1)));
        let mut differs = word ^ next;
        while differs != 0 {
            let k = differs.trailing_zeros() as usize / 8;
            ends.push(i + k + 1);
            differs &= !(0xff << (8 * k));
        }
        i += 8;
    }
    for j in i..row.len().saturating_sub(1) {
        if row[j] != row[j + 1] {
            ends.push(j + 1);
        }
    }
    if !row.is_empty() {
        ends.push(row.len());
    }
}

impl Runs {
    /// The 4-connected regions of black or white pixels (rows of `width`) of at least
    /// [`MIN_REGION_PIXELS`]: the runs of each row are joined to the overlapping runs of the
    /// same colour in the row above (union-find over runs, their areas summed at the roots).
    fn count_regions(&mut self, pixels: &[Pixel], width: usize) -> u64 {
        let Self { parent, area, above, here, ends } = self;
        parent.clear();
        area.clear();
        above.clear();
        for row in pixels.chunks_exact(width) {
            here.clear();
            run_ends(row, ends);
            let mut start = 0;
            for &end in ends.iter() {
                let colour = row[start];
                if colour != Pixel::Skip {
                    let id = parent.len() as u32;
                    parent.push(id);
                    area.push((end - start) as u32);
                    here.push((start, end, colour, id));
                }
                start = end;
            }
            // Two pointers over the runs of the two rows, both sorted by their start.
            let mut j = 0;
            for &(x0, x1, colour, id) in here.iter() {
                while j < above.len() && above[j].1 <= x0 {
                    j += 1;
                }
                let mut k = j;
                while k < above.len() && above[k].0 < x1 {
                    if above[k].2 == colour {
                        union(parent, area, id, above[k].3);
                    }
                    k += 1;
                }
            }
            std::mem::swap(above, here);
        }
        (0..parent.len()).filter(|&i| parent[i] as usize == i && area[i] >= MIN_REGION_PIXELS).count() as u64
    }
}

fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let up = parent[parent[i as usize] as usize];
        parent[i as usize] = up;
        i = up;
    }
    i
}

/// Joins the regions of `a` and `b`, the larger area keeping its root.
fn union(parent: &mut [u32], area: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra == rb {
        return;
    }
    let (big, small) = if area[ra as usize] >= area[rb as usize] { (ra, rb) } else { (rb, ra) };
    parent[small as usize] = big;
    area[big as usize] = area[big as usize].saturating_add(area[small as usize]);
}

/// The candidates to measure, best first (fewest bit errors, then the best decoding margin;
/// ties in the detector's order), and whether some were left out by the budget: an id is
/// measured again only when its better candidates were all refused by `measure`.
pub(super) fn measure_best_first(
    mut candidates: Vec<Candidate>,
    mut measure: impl FnMut(&[[f64; 2]; 4]) -> Option<[[f64; 2]; 4]>,
) -> (Vec<Tag>, bool) {
    candidates.sort_by(|a, b| a.0.0.cmp(&b.0.0).then(b.0.1.total_cmp(&a.0.1)));
    let mut tags: Vec<Tag> = Vec::new();
    let mut done = std::collections::HashSet::new();
    let mut measured = 0;
    let mut stopped_early = false;
    for (_, id, corners) in candidates {
        if done.contains(&id) {
            continue;
        }
        if measured == MAX_MEASURED_CANDIDATES {
            stopped_early = true;
            break;
        }
        measured += 1;
        if let Some(corners) = measure(&corners) {
            done.insert(id);
            tags.push(Tag { id, corners });
        }
    }
    tags.sort_by_key(|t| t.id);
    (tags, stopped_early)
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use imageproc::region_labelling::{Connectivity, connected_components};

    use super::*;
    use crate::vision::image::GreyImage;
    use crate::vision::tags::synthetic::{Placement, draw};
    use crate::vision::tags::{TagDecoder, TagFamily, detect_tags};

    /// A small deterministic generator (xorshift64*), so that the test needs no crate.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
        }
        fn below(&mut self, n: usize) -> usize {
            (self.next() % n as u64) as usize
        }
        fn unit(&mut self) -> f64 {
            (self.next() >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// The regions of `colour` of at least [`MIN_REGION_PIXELS`], by imageproc's labelling.
    fn reference_count(pixels: &[Pixel], width: u32, colour: Pixel) -> u64 {
        let height = pixels.len() as u32 / width;
        let mask = GreyImage::from_fn(width, height, |u, v| {
            ::image::Luma([u8::from(pixels[(v * width + u) as usize] == colour)])
        });
        let labels = connected_components(&mask, Connectivity::Four, ::image::Luma([0u8]));
        let mut areas = std::collections::HashMap::new();
        for p in labels.pixels().filter(|p| p[0] != 0) {
            *areas.entry(p[0]).or_insert(0u32) += 1;
        }
        areas.values().filter(|&&a| a >= MIN_REGION_PIXELS).count() as u64
    }

    fn count_regions(pixels: &[Pixel], width: usize) -> u64 {
        Runs::default().count_regions(pixels, width)
    }

    #[test]
    fn regions_are_counted_as_a_labelling_counts_them() {
        let mut rng = Rng(7);
        for (width, height, fill) in
            [(1, 40, 0.5), (40, 1, 0.5), (37, 29, 0.3), (64, 48, 0.5), (120, 80, 0.45), (97, 61, 0.6)]
        {
            // Random blocks of black, white and skipped pixels: regions of every shape and size.
            let mut pixels = vec![Pixel::Skip; width * height];
            for _ in 0..(width * height / 6) {
                let (u, v) = (rng.below(width), rng.below(height));
                let (w, h) = (1 + rng.below(8), 1 + rng.below(8));
                let colour = if rng.unit() < fill { Pixel::Black } else { Pixel::White };
                for y in v..(v + h).min(height) {
                    for x in u..(u + w).min(width) {
                        pixels[y * width + x] = colour;
                    }
                }
            }
            let expected = reference_count(&pixels, width as u32, Pixel::Black)
                + reference_count(&pixels, width as u32, Pixel::White);
            assert_eq!(count_regions(&pixels, width), expected, "{width} x {height}");
        }
        assert_eq!(count_regions(&[Pixel::Skip; 100], 10), 0);
        assert_eq!(count_regions(&[Pixel::Black; 100], 10), 1);
        assert_eq!(count_regions(&[Pixel::Black; 24], 6), 0);
    }

    #[test]
    fn run_ends_are_where_a_pixel_differs_from_the_next() {
        let mut rng = Rng(11);
        let colours = [Pixel::Black, Pixel::White, Pixel::Skip];
        let mut ends = Vec::new();
        for length in [0, 1, 2, 8, 9, 16, 17, 40, 131] {
            for run in [1, 3, 8, 20] {
                let row: Vec<Pixel> = (0..length).map(|i| colours[(i / run + rng.below(2)) % 3]).collect();
                run_ends(&row, &mut ends);
                let mut expected: Vec<usize> = (1..length).filter(|&j| row[j] != row[j - 1]).collect();
                expected.extend((length > 0).then_some(length));
                assert_eq!(ends, expected, "length {length}, runs of {run}");
            }
        }
    }

    /// The old rule: every candidate measured, then per id the fewest bit errors and the best
    /// margin among those measured.
    fn measure_all(candidates: &[Candidate], measure: impl Fn(&[[f64; 2]; 4]) -> Option<[[f64; 2]; 4]>) -> Vec<Tag> {
        let mut tags: Vec<((u8, f32), Tag)> =
            candidates.iter().filter_map(|(m, id, c)| Some((*m, Tag { id: *id, corners: measure(c)? }))).collect();
        tags.sort_by(|a, b| a.1.id.cmp(&b.1.id).then(a.0.0.cmp(&b.0.0)).then(b.0.1.total_cmp(&a.0.1)));
        tags.dedup_by_key(|t| t.1.id);
        tags.into_iter().map(|(_, t)| t).collect()
    }

    #[test]
    fn best_first_measuring_keeps_what_measuring_all_kept() {
        let mut rng = Rng(3);
        // Refused when the first coordinate's fraction is below 0.3; moved otherwise.
        let measure = |c: &[[f64; 2]; 4]| (c[0][0].fract() >= 0.3).then(|| c.map(|[u, v]| [u + 0.25, v]));
        for n in [0, 1, 5, 40, 300] {
            let candidates: Vec<Candidate> = (0..n)
                .map(|k| {
                    let margin = rng.below(4) as f32 * 10.0; // ties on purpose
                    let corner = [f64::from(k) + rng.unit(), 0.0];
                    ((rng.below(3) as u8, margin), rng.below(12) as u32, [corner; 4])
                })
                .collect();
            let (tags, stopped) = measure_best_first(candidates.clone(), measure);
            assert_eq!(tags, measure_all(&candidates, measure), "{n}");
            assert!(!stopped);
        }
        // More distinct ids than the budget: the best ones are measured, and it says so.
        let many: Vec<Candidate> =
            (0..3000u32).map(|id| ((u8::from(id % 2 == 1), id as f32), id, [[0.5, 0.0]; 4])).collect();
        let mut calls = 0;
        let (tags, stopped) = measure_best_first(many, |c| {
            calls += 1;
            Some(*c)
        });
        assert!(stopped && calls == MAX_MEASURED_CANDIDATES && tags.len() == MAX_MEASURED_CANDIDATES);
        // Even ids (no bit error) first, the best margin (the largest id) first.
        assert!(tags.iter().all(|t| t.id % 2 == 0 && t.id >= 3000 - 2 * MAX_MEASURED_CANDIDATES as u32));
    }

    /// A wall of small tags (tag16h5, 30 ids, 2 px a cell): the search stops early, within
    /// its bound, and what it finds is right.
    #[test]
    fn a_cluttered_frame_is_searched_within_the_bound_and_says_so() {
        let (width, height, step) = (1280u32, 720u32, 16.0);
        let mut placed = Vec::new();
        let mut v = 10.0;
        while v + step < f64::from(height) {
            let mut u = 10.0;
            while u + step < f64::from(width) {
                placed.push(Placement { id: placed.len() % 30, centre: [u, v], cell: 2.0, quarter_turns: 0 });
                u += step;
            }
            v += step;
        }
        let image = draw(TagFamily::Tag16h5, width, height, &placed);
        let mut decoder = TagDecoder::new(TagFamily::Tag16h5);
        let report = decoder.detect_report(&image).unwrap();
        assert!(report.stopped_early, "{} tags drawn", placed.len());
        // Each tag found is one drawn there (an id at a drawn centre).
        for tag in &report.tags {
            let centre = [0, 1].map(|k| tag.corners.iter().map(|c| c[k]).sum::<f64>() / 4.0);
            let near = |p: &&Placement| (p.centre[0] - centre[0]).hypot(p.centre[1] - centre[1]) < 1.0;
            assert!(placed.iter().filter(near).any(|p| p.id as u32 == tag.id), "{tag:?}");
        }
        // An ordinary frame: a few tags, searched whole.
        let few = [(3, [200.0, 150.0]), (7, [600.0, 400.0]), (11, [1000.0, 300.0])].map(|(id, centre)| Placement {
            id,
            centre,
            cell: 8.0,
            quarter_turns: 1,
        });
        let report = decoder.detect_report(&draw(TagFamily::Tag16h5, width, height, &few)).unwrap();
        assert!(!report.stopped_early);
        assert_eq!(report.tags.iter().map(|t| t.id).collect::<Vec<_>>(), [3, 7, 11]);
        assert_eq!(
            report.tags,
            detect_tags(&draw(TagFamily::Tag16h5, width, height, &few), TagFamily::Tag16h5).unwrap()
        );
    }

    #[test]
    fn the_budget_admits_levels_while_they_fit() {
        let mut budget = Budget::new();
        assert!(budget.admit(MAX_SEARCHED_REGIONS - 10) && !budget.stopped_early);
        assert!(!budget.admit(11) && budget.stopped_early);
        assert!(budget.admit(10));
        let tiny = Image::<u8, 1>::from_size_val(ImageSize { width: 3, height: 3 }, 0).unwrap();
        assert!(RegionCounter::default().regions(&tiny, 1, 5, 0.5).is_none());
        // A level that cannot hold more regions than are left is admitted without counting.
        let mut budget = Budget::new();
        assert!(budget.admit_level(25 * 100, || panic!("counted")));
        assert!(budget.admit_level(25 * (MAX_SEARCHED_REGIONS - 100), || panic!("counted")));
        assert!(!budget.admit_level(25 * 100 + 25, || Some(1000)) && budget.stopped_early);
        assert!(budget.admit_level(25 * 100 + 25, || Some(0)));
    }
}
