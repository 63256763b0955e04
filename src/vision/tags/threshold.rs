//! The AprilTag detector's adaptive threshold ([`Threshold::apply`]), a whole row at a time:
//! the rule of `kornia-apriltag`'s `adaptive_threshold_with_split` (and of the AprilTag
//! library), the same pixels (tested against it).
//!
//! The rule (Olson, "AprilTag: A robust and flexible visual fiducial system", ICRA 2011,
//! section III-A, as kept by AprilTag 2): the image is cut into tiles of [`TILE`] x [`TILE`]
//! pixels; each whole tile's darkest and brightest pixels are taken over it and its eight
//! neighbours (the whole tiles around it); where they differ by less than the least contrast
//! the tile is skipped, elsewhere a pixel is white above `min + (max - min) split` (the
//! product truncated to a level) and black at or below it. The pixels past the last whole tile
//! column (row) take the last whole tile's.
//!
//! Why here: `kornia-apriltag` classifies each tile's row of four pixels in a call of its own,
//! too short for its vector loop; here each tile row's levels are spread over a row of pixels
//! once, every pixel row is classified in one loop over the whole row (which the compiler
//! vectorises), and the skipped tiles' pixels are then filled, a run of skipped tiles at once.

use kornia_apriltag::utils::Pixel;

/// The threshold's tiles (pixels a side), the AprilTag detector's.
pub(super) const TILE: usize = 4;

/// The buffers of the threshold, kept from call to call.
#[derive(Default)]
pub(super) struct Threshold {
    /// Each whole tile's darkest and brightest pixel, then over its neighbourhood.
    min: Vec<u8>,
    max: Vec<u8>,
    near_min: Vec<u8>,
    near_max: Vec<u8>,
    /// One tile row's levels spread over a row of pixels, and its skipped columns (runs).
    levels: Vec<u8>,
    skipped: Vec<std::ops::Range<usize>>,
    /// Scratch rows of extremes: a band of pixel rows' darkest and brightest pixel in each
    /// column ([`Self::tile_extremes`]), then the tiles' extremes across each tile row
    /// ([`Self::neighbourhoods`]).
    work_min: Vec<u8>,
    work_max: Vec<u8>,
}

impl Threshold {
    /// Thresholds `src` (rows of `width`) into `out` (the same size) with the least contrast
    /// `min_contrast` and the split `split` (clamped to `[0, 1]`). An image narrower or lower
    /// than a tile, or an `out` of another size, is left as it is (the caller searches no
    /// such level).
    pub(super) fn apply(&mut self, src: &[u8], width: usize, out: &mut [Pixel], min_contrast: u8, split: f32) {
        let height = src.len() / width.max(1);
        let (tiles_x, tiles_y) = (width / TILE, height / TILE);
        if tiles_x == 0 || tiles_y == 0 || out.len() != src.len() {
            return;
        }
        self.tile_extremes(src, width, tiles_x, tiles_y);
        self.neighbourhoods(tiles_x, tiles_y);
        let split = split.clamp(0.0, 1.0);
        for (rows, (src_rows, out_rows)) in src.chunks(TILE * width).zip(out.chunks_mut(TILE * width)).enumerate() {
            // The rows past the last whole tile row take its levels.
            self.spread(rows.min(tiles_y - 1), width, tiles_x, min_contrast, split);
            for (row, out_row) in src_rows.chunks_exact(width).zip(out_rows.chunks_exact_mut(width)) {
                classify(row, &self.levels, out_row);
                for run in &self.skipped {
                    if let Some(pixels) = out_row.get_mut(run.clone()) {
                        pixels.fill(Pixel::Skip);
                    }
                }
            }
        }
    }

    /// The darkest and brightest pixel of each whole tile.
    fn tile_extremes(&mut self, src: &[u8], width: usize, tiles_x: usize, tiles_y: usize) {
        let Self { min, max, work_min: column_min, work_max: column_max, .. } = self;
        min.clear();
        max.clear();
        for band in src.chunks_exact(TILE * width).take(tiles_y) {
            column_min.clear();
            column_max.clear();
            column_min.resize(width, u8::MAX);
            column_max.resize(width, 0);
            for row in band.chunks_exact(width) {
                let (lows, highs, row) = (&mut column_min[..width], &mut column_max[..width], &row[..width]);
                for x in 0..width {
                    lows[x] = lows[x].min(row[x]);
                    highs[x] = highs[x].max(row[x]);
                }
            }
            let tiles = column_min.chunks_exact(TILE).zip(column_max.chunks_exact(TILE)).take(tiles_x);
            for (lows, highs) in tiles {
                min.push(lows.iter().copied().fold(u8::MAX, u8::min));
                max.push(highs.iter().copied().fold(0, u8::max));
            }
        }
    }

    /// Each whole tile's extremes over it and its neighbouring whole tiles: over the three
    /// tiles across (fewer at the ends) in each tile row, then over three such rows.
    fn neighbourhoods(&mut self, tiles_x: usize, tiles_y: usize) {
        let Self { min, max, near_min, near_max, work_min: across_min, work_max: across_max, .. } = self;
        across(min, tiles_x, across_min, u8::min);
        across(max, tiles_x, across_max, u8::max);
        down(across_min, tiles_x, tiles_y, near_min, u8::min);
        down(across_max, tiles_x, tiles_y, near_max, u8::max);
    }

    /// Tile row `ty`'s levels over a row of `width` pixels and its skipped columns, as runs
    /// (the columns past the last whole tile take its).
    fn spread(&mut self, ty: usize, width: usize, tiles_x: usize, min_contrast: u8, split: f32) {
        self.levels.clear();
        self.skipped.clear();
        for x in 0..width.div_ceil(TILE) {
            let k = ty * tiles_x + x.min(tiles_x - 1);
            let (lo, hi) = (self.near_min[k], self.near_max[k]);
            let level = lo + (f32::from(hi - lo) * split) as u8;
            let columns = x * TILE..(x * TILE + TILE).min(width);
            self.levels.extend(std::iter::repeat_n(level, columns.len()));
            if hi - lo < min_contrast {
                match self.skipped.last_mut() {
                    Some(run) if run.end == columns.start => run.end = columns.end,
                    _ => self.skipped.push(columns),
                }
            }
        }
    }
}

/// `f` of each value of each row of `values` (rows of `n`) and its neighbours in the row, into
/// `out`.
fn across(values: &[u8], n: usize, out: &mut Vec<u8>, f: fn(u8, u8) -> u8) {
    out.clear();
    out.resize(values.len(), 0);
    for (row, out) in values.chunks_exact(n).zip(out.chunks_exact_mut(n)) {
        out.copy_from_slice(row);
        for (o, pair) in out[1..].iter_mut().zip(row.windows(2)) {
            *o = f(*o, pair[0]);
        }
        for (o, pair) in out.iter_mut().zip(row[1..].iter()) {
            *o = f(*o, *pair);
        }
    }
}

/// `f` of each value of `values` (`rows` rows of `n`) and those above and below it, into `out`.
fn down(values: &[u8], n: usize, rows: usize, out: &mut Vec<u8>, f: fn(u8, u8) -> u8) {
    out.clear();
    out.extend_from_slice(values);
    for y in 0..rows {
        let row = &mut out[y * n..(y + 1) * n];
        for neighbour in [y.checked_sub(1), (y + 1 < rows).then_some(y + 1)].into_iter().flatten() {
            let other = &values[neighbour * n..(neighbour + 1) * n];
            for (o, &v) in row.iter_mut().zip(other) {
                *o = f(*o, v);
            }
        }
    }
}

/// One row: white above its column's level, black at or below.
fn classify(row: &[u8], levels: &[u8], out: &mut [Pixel]) {
    let n = row.len().min(levels.len()).min(out.len());
    let (row, levels, out) = (&row[..n], &levels[..n], &mut out[..n]);
    for x in 0..n {
        out[x] = if row[x] > levels[x] { Pixel::White } else { Pixel::Black };
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use kornia_apriltag::threshold::{TileMinMax, adaptive_threshold_with_split};
    use kornia_image::{Image, ImageSize};

    use super::*;
    use crate::vision::tags::synthetic::Rng;

    #[test]
    fn the_threshold_is_kornias_pixel_for_pixel() {
        // Texture, flat patches (skipped tiles), gradients and noise, on sizes with and
        // without a partial tile row and column; splits and least contrasts of the range.
        let mut rng = Rng(3);
        let mut threshold = Threshold::default();
        for (width, height) in [(4, 4), (5, 7), (17, 9), (64, 48), (131, 77), (320, 240), (7, 130)] {
            let src: Vec<u8> = (0..width * height)
                .map(|i| {
                    let (x, y) = (i % width, i / width);
                    let flat = (x / 13 + y / 11) % 3 == 0;
                    let base = (x * 3 + y * 2) % 200;
                    if flat { 90 } else { (base + rng.below(60)).min(255) as u8 }
                })
                .collect();
            for (min_contrast, split) in [(15u8, 0.5f32), (5, 0.33), (40, 0.9), (0, 0.0), (20, 1.0)] {
                let size = ImageSize { width, height };
                let image = Image::<u8, 1>::new(size, src.clone()).unwrap();
                let mut expected = Image::from_size_val(size, Pixel::Skip).unwrap();
                let mut tiles = TileMinMax::new(size, TILE);
                adaptive_threshold_with_split(&image, &mut expected, &mut tiles, min_contrast, split).unwrap();
                let mut ours = vec![Pixel::Black; width * height];
                threshold.apply(&src, width, &mut ours, min_contrast, split);
                assert_eq!(ours.as_slice(), expected.as_slice(), "{width} x {height}, {min_contrast} {split}");
            }
        }
    }
}
