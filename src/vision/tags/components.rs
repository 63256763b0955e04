//! The connected regions of a thresholded level ([`Components::label`]): the black and white
//! regions the quad search starts from, labelled once and read twice: their count bounds the
//! frame's work (`budget.rs`), and their borders are the gradient clusters (`clusters.rs`).
//!
//! The AprilTag detector's own rules (Olson, "AprilTag: A robust and flexible visual fiducial
//! system", ICRA 2011, section III-B; kept by `kornia-apriltag`): the regions are 4-connected,
//! of one colour, made of the runs of the interior columns (the first and last columns belong
//! to none), and a region of fewer than [`MIN_REGION_PIXELS`] starts no quad.

use kornia_apriltag::utils::Pixel;

/// The detector's smallest region (pixels): smaller ones start no quad.
pub const MIN_REGION_PIXELS: u32 = 25;

/// The region of a run too small to start a quad (or of a pixel in no run).
pub(super) const NO_REGION: u32 = u32::MAX;

/// A run of equal pixels in one row: its first and one-past-last columns, and its colour.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Run {
    pub start: u32,
    pub end: u32,
    pub colour: Pixel,
}

/// The runs of a labelled level and their regions, kept from call to call (their buffers
/// reused).
#[derive(Default)]
pub(super) struct Components {
    runs: Vec<Run>,
    /// The runs of row `y` are `runs[row_start[y]..row_start[y + 1]]`.
    row_start: Vec<u32>,
    /// Union-find over the runs: each run's parent, and the pixels of each root's region.
    parent: Vec<u32>,
    area: Vec<u32>,
    /// Each run's region: its root's index when the region has at least
    /// [`MIN_REGION_PIXELS`], [`NO_REGION`] otherwise.
    region: Vec<u32>,
    ends: Vec<usize>,
    bytes: Vec<u8>,
}

impl Components {
    /// Labels the 4-connected regions of black or white pixels of `pixels` (rows of `width`),
    /// in the detector's interior columns, and returns how many have at least
    /// [`MIN_REGION_PIXELS`]: each row's runs are joined to the overlapping runs of the same
    /// colour in the row above (union by area over runs).
    pub(super) fn label(&mut self, pixels: &[Pixel], width: usize) -> u64 {
        let Self { runs, row_start, parent, area, region, ends, bytes } = self;
        runs.clear();
        row_start.clear();
        parent.clear();
        area.clear();
        let interior = 1..width.saturating_sub(1);
        for row in pixels.chunks_exact(width.max(1)) {
            let above = row_start.last().map_or(0, |&s| s as usize)..runs.len();
            row_start.push(runs.len() as u32);
            let Some(inner) = row.get(interior.clone()) else { continue };
            as_bytes(inner, bytes);
            run_ends(bytes, ends);
            let mut start = 0;
            for &end in ends.iter() {
                let colour = inner[start];
                if colour != Pixel::Skip {
                    let id = runs.len() as u32;
                    runs.push(Run { start: (start + 1) as u32, end: (end + 1) as u32, colour });
                    parent.push(id);
                    area.push((end - start) as u32);
                }
                start = end;
            }
            join_to_row_above(runs, above, parent, area);
        }
        row_start.push(runs.len() as u32);
        region.clear();
        region.extend((0..runs.len() as u32).map(|r| {
            let root = find(parent, r);
            if area[root as usize] >= MIN_REGION_PIXELS { root } else { NO_REGION }
        }));
        (0..parent.len()).filter(|&i| parent[i] as usize == i && area[i] >= MIN_REGION_PIXELS).count() as u64
    }

    /// The runs of row `y` of the last labelled level, each with its region.
    pub(super) fn row(&self, y: usize) -> impl Iterator<Item = (Run, u32)> + '_ {
        let span = match (self.row_start.get(y), self.row_start.get(y + 1)) {
            (Some(&a), Some(&b)) => a as usize..b as usize,
            _ => 0..0,
        };
        self.runs[span.clone()].iter().copied().zip(self.region[span].iter().copied())
    }
}

/// Joins the runs of the last row (from `above.end` on) to the overlapping runs of the same
/// colour in the row before it (`above`): two pointers over the two rows, both sorted by
/// their start.
fn join_to_row_above(runs: &[Run], above: std::ops::Range<usize>, parent: &mut [u32], area: &mut [u32]) {
    let mut j = above.start;
    for (id, here) in runs.iter().enumerate().skip(above.end) {
        while j < above.end && runs[j].end <= here.start {
            j += 1;
        }
        let mut k = j;
        while k < above.end && runs[k].start < here.end {
            if runs[k].colour == here.colour {
                union(parent, area, id as u32, k as u32);
            }
            k += 1;
        }
    }
}

/// The pixels of `row` as bytes (the detector's pixel type is one), into `bytes`: a copy that
/// is then read eight pixels at a time ([`word`]).
pub(super) fn as_bytes(row: &[Pixel], bytes: &mut Vec<u8>) {
    bytes.clear();
    bytes.extend(row.iter().map(|&p| p as u8));
}

/// The eight pixels of `bytes` from `from` on, as one word (the first in the lowest byte); the
/// caller keeps `from + 8` within `bytes`.
#[inline(always)]
pub(super) fn word(bytes: &[u8], from: usize) -> u64 {
    let mut eight = [0u8; 8];
    eight.copy_from_slice(&bytes[from..from + 8]);
    u64::from_le_bytes(eight)
}

/// The ends (one past the last pixel) of the runs of equal pixels of `row` (bytes of pixels,
/// [`as_bytes`]), in order, into `ends` (the last is the row's length). Eight pixels and the
/// one after them at a time: a byte of `word ^ next` (the eight and the eight from the next
/// pixel on) is not zero where a pixel differs from the one after it, so a row of long runs
/// costs one test per eight pixels.
pub(super) fn run_ends(row: &[u8], ends: &mut Vec<usize>) {
    ends.clear();
    let mut i = 0;
    while i + 9 <= row.len() {
        let mut differs = word(row, i) ^ word(row, i + 1);
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

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use imageproc::region_labelling::{Connectivity, connected_components};

    use super::*;
    use crate::vision::image::GreyImage;
    use crate::vision::tags::synthetic::Rng;

    /// The labels of `colour`'s regions in the interior columns, by imageproc's labelling.
    fn reference_labels(
        pixels: &[Pixel],
        width: u32,
        colour: Pixel,
    ) -> ::image::ImageBuffer<::image::Luma<u32>, Vec<u32>> {
        let height = pixels.len() as u32 / width;
        let interior = |u: u32| u > 0 && u + 1 < width;
        let mask = GreyImage::from_fn(width, height, |u, v| {
            ::image::Luma([u8::from(interior(u) && pixels[(v * width + u) as usize] == colour)])
        });
        connected_components(&mask, Connectivity::Four, ::image::Luma([0u8]))
    }

    fn areas(labels: &::image::ImageBuffer<::image::Luma<u32>, Vec<u32>>) -> std::collections::HashMap<u32, u32> {
        let mut areas = std::collections::HashMap::new();
        for p in labels.pixels().filter(|p| p[0] != 0) {
            *areas.entry(p[0]).or_insert(0u32) += 1;
        }
        areas
    }

    fn random_blocks(rng: &mut Rng, width: usize, height: usize, fill: f64) -> Vec<Pixel> {
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
        pixels
    }

    /// The count and every pixel's region as a labelling finds them: two pixels share a
    /// region exactly when the labelling gives them one label, and a region is kept exactly
    /// when its label covers at least [`MIN_REGION_PIXELS`].
    #[test]
    fn regions_are_labelled_as_a_labelling_labels_them() {
        let mut rng = Rng(7);
        for (width, height, fill) in [
            (1, 40, 0.5),
            (2, 30, 0.5),
            (3, 40, 0.5),
            (40, 1, 0.5),
            (37, 29, 0.3),
            (64, 48, 0.5),
            (120, 80, 0.45),
            (97, 61, 0.6),
        ] {
            let pixels = random_blocks(&mut rng, width, height, fill);
            let mut components = Components::default();
            let count = components.label(&pixels, width);
            let mut expected = 0;
            for colour in [Pixel::Black, Pixel::White] {
                let labels = reference_labels(&pixels, width as u32, colour);
                let areas = areas(&labels);
                expected += areas.values().filter(|&&a| a >= MIN_REGION_PIXELS).count() as u64;
                // Each pixel's region, from the runs.
                let mut ours = vec![NO_REGION; width * height];
                for y in 0..height {
                    for (run, region) in components.row(y).filter(|(run, _)| run.colour == colour) {
                        assert!(run.start >= 1 && (run.end as usize) < width);
                        ours[y * width + run.start as usize..y * width + run.end as usize].fill(region);
                    }
                }
                let mut seen = std::collections::HashMap::new();
                for (i, p) in labels.pixels().enumerate() {
                    let kept = p[0] != 0 && areas[&p[0]] >= MIN_REGION_PIXELS;
                    assert_eq!(ours[i] != NO_REGION, kept, "{width} x {height}, pixel {i}");
                    if kept {
                        assert_eq!(*seen.entry(p[0]).or_insert(ours[i]), ours[i], "{width} x {height}, pixel {i}");
                    }
                }
                let distinct: std::collections::HashSet<_> = seen.values().collect();
                assert_eq!(distinct.len(), seen.len(), "{width} x {height}: two labels share a region");
            }
            assert_eq!(count, expected, "{width} x {height}");
        }
        let mut components = Components::default();
        assert_eq!(components.label(&[Pixel::Skip; 100], 10), 0);
        assert_eq!(components.label(&[Pixel::Black; 120], 12), 1);
        // Rows of 5 pixels, 3 of them interior: 8 rows are 24 pixels of a region, 9 are 27.
        assert_eq!(components.label(&[Pixel::Black; 40], 5), 0);
        assert_eq!(components.label(&[Pixel::Black; 45], 5), 1);
        assert_eq!(components.row(99).count(), 0);
    }

    #[test]
    fn run_ends_are_where_a_pixel_differs_from_the_next() {
        let mut rng = Rng(11);
        let colours = [Pixel::Black, Pixel::White, Pixel::Skip];
        let mut ends = Vec::new();
        for length in [0, 1, 2, 8, 9, 16, 17, 40, 131] {
            for run in [1, 3, 8, 20] {
                let row: Vec<Pixel> = (0..length).map(|i| colours[(i / run + rng.below(2)) % 3]).collect();
                let mut bytes = Vec::new();
                as_bytes(&row, &mut bytes);
                run_ends(&bytes, &mut ends);
                let mut expected: Vec<usize> = (1..length).filter(|&j| row[j] != row[j - 1]).collect();
                expected.extend((length > 0).then_some(length));
                assert_eq!(ends, expected, "length {length}, runs of {run}");
            }
        }
    }
}
