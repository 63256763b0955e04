//! The local threshold of dot detection: a background model on tiles, so that a dot is a
//! pixel that stands out of the background *around it*, under a lighting gradient and in
//! front of a cluttered scene alike (a global level, Otsu's say, is pulled by the clutter and
//! cut by the gradient).
//!
//! The image is cut into square tiles of [`TILE`] pixels. Per tile: the median of a 2 x 2
//! subsample and the largest level ([`tile_stats`](super::tile_stats)). Per tile again, over
//! its neighbourhood:
//! - the background `b`: the lower quartile of the tile medians of the 5 x 5 tiles around it
//!   (a dot, or a cluster of dots, may fill most of a tile and some of its neighbours: the
//!   lower quartile of the neighbourhood still falls on the background, as long as a quarter
//!   of it is background);
//! - the peak `p`: the largest level of the 3 x 3 tiles around it;
//! - the threshold `b + max(min_contrast, (p - b) / 2)`: half way between the background and
//!   the brightest dot nearby (the full width at half maximum of a blurred dot), never closer
//!   to the background than `min_contrast` grey levels (noise and texture);
//! - inside a dot wider than that neighbourhood, the threshold of a coarser level
//!   ([`coarse`](super::coarse)).
//!
//! All levels are in the dots' domain: the grey level for light dots, `255 - g` for dark ones.

use crate::vision::coarse::{Pyramid, Tile};
use crate::vision::image::{GreyBuffer, Pixels};
use crate::vision::tile_levels::{BACKGROUND_REACH, TILE, flat, largest, threshold};
use crate::vision::tile_stats::{TileStats, tile_statistics};

/// One threshold (and background level) per tile, in the dots' domain.
#[derive(Debug, Clone, PartialEq)]
pub struct TileThresholds {
    columns: usize,
    /// Row-major per tile: a pixel is a dot pixel when its level is above this.
    levels: Vec<u8>,
    /// Row-major per tile: the background level.
    background: Vec<u8>,
}

impl TileThresholds {
    /// The same threshold everywhere (the explicit `threshold=`); the background is unknown
    /// (0).
    pub fn uniform<C: Pixels>(image: &GreyBuffer<C>, threshold: u8) -> Self {
        let (columns, rows) = grid(image);
        Self { columns, levels: vec![threshold; columns * rows], background: vec![0; columns * rows] }
    }

    /// The local thresholds of an image (see the module's documentation).
    pub fn local<C: Pixels>(image: &GreyBuffer<C>, dark: bool, min_contrast: u8) -> Self {
        let (columns, rows) = grid(image);
        let TileStats { medians, peaks } = tile_statistics(image, dark, columns, rows);
        let coarse = Pyramid::new(&medians, &peaks, columns, rows);
        let mut levels = Vec::with_capacity(columns * rows);
        let mut background = Vec::with_capacity(columns * rows);
        let mut quartiles = Vec::with_capacity(columns);
        for row in 0..rows {
            lower_quartiles_of_row(&medians, columns, rows, row, &mut quartiles);
            for (column, &b) in quartiles.iter().enumerate() {
                let p = largest(&peaks, columns, rows, row, column);
                let fine = (threshold(b, p, min_contrast), b);
                let tile = Tile { row, column, flat: flat(b, p, min_contrast) };
                let (level, b) = coarse.inside_large_dot(tile, fine, min_contrast);
                levels.push(level);
                background.push(b);
            }
        }
        Self { columns, levels, background }
    }

    /// The thresholds of the tiles of row `v` of the image, one per tile column.
    pub fn row(&self, v: u32) -> &[u8] {
        let start = (v / TILE) as usize * self.columns;
        &self.levels[start..start + self.columns]
    }

    /// The threshold at pixel `(u, v)`.
    pub fn at(&self, u: u32, v: u32) -> u8 {
        self.row(v)[(u / TILE) as usize]
    }

    /// The background level of the tile of pixel `(u, v)`.
    pub fn background_at(&self, u: u32, v: u32) -> u8 {
        self.background[(v / TILE) as usize * self.columns + (u / TILE) as usize]
    }
}

fn grid<C: Pixels>(image: &GreyBuffer<C>) -> (usize, usize) {
    (image.width().div_ceil(TILE) as usize, image.height().div_ceil(TILE) as usize)
}

/// [`lower_quartile`] of every tile of row `row`, left to right, into `out`: a histogram of
/// the neighbourhood slid along the row (Huang's running median: 2 x 5 updates a tile), the
/// quartile moved from the last tile's (a step or two where the background changes slowly).
fn lower_quartiles_of_row(medians: &[u8], columns: usize, rows: usize, row: usize, out: &mut Vec<u8>) {
    out.clear();
    let (r0, r1) = (row.saturating_sub(BACKGROUND_REACH), (row + BACKGROUND_REACH).min(rows - 1));
    let mut window = Window { histogram: [0; 256], m: 0, below: 0, count: 0 };
    let column_of = |c: usize| (r0..=r1).map(move |r| medians[r * columns + c]);
    for column in 0..BACKGROUND_REACH.min(columns) {
        column_of(column).for_each(|x| window.add(x));
    }
    for column in 0..columns {
        if column + BACKGROUND_REACH < columns {
            column_of(column + BACKGROUND_REACH).for_each(|x| window.add(x));
        }
        if column > BACKGROUND_REACH {
            column_of(column - BACKGROUND_REACH - 1).for_each(|x| window.remove(x));
        }
        out.push(window.order_statistic((window.count - 1) / 4));
    }
}

/// A histogram of levels and a level `m` with the count of the values below it.
struct Window {
    histogram: [u32; 256],
    m: usize,
    below: usize,
    count: usize,
}

impl Window {
    fn add(&mut self, x: u8) {
        self.histogram[usize::from(x)] += 1;
        self.count += 1;
        self.below += usize::from(usize::from(x) < self.m);
    }

    fn remove(&mut self, x: u8) {
        self.histogram[usize::from(x)] -= 1;
        self.count -= 1;
        self.below -= usize::from(usize::from(x) < self.m);
    }

    /// The `k`-th smallest value (`k < count`): the level with `below <= k < below + its
    /// count`, `m` moved there.
    fn order_statistic(&mut self, k: usize) -> u8 {
        while self.below > k {
            self.m -= 1;
            self.below -= self.histogram[self.m] as usize;
        }
        while self.below + self.histogram[self.m] as usize <= k {
            self.below += self.histogram[self.m] as usize;
            self.m += 1;
        }
        self.m as u8
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::vision::image::GreyImage;
    use crate::vision::tile_levels::lower_quartile;

    #[test]
    fn sliding_quartiles_are_each_tiles_own() {
        // Grids of random medians (ties, narrow and wide spreads, one row or column, smaller
        // than the neighbourhood): each row's slid quartiles against the tile-by-tile ones.
        let mut state = 11u64;
        for (columns, rows, spread) in [(9usize, 7usize, 256u64), (1, 5, 9), (6, 1, 256), (40, 12, 3), (3, 3, 50)] {
            let medians: Vec<u8> = (0..columns * rows)
                .map(|_| {
                    state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                    ((state >> 33) % spread) as u8
                })
                .collect();
            let mut row_out = Vec::new();
            for row in 0..rows {
                lower_quartiles_of_row(&medians, columns, rows, row, &mut row_out);
                let each: Vec<u8> = (0..columns).map(|c| lower_quartile(&medians, columns, rows, row, c)).collect();
                assert_eq!(row_out, each, "{columns} x {rows}, row {row}");
            }
        }
    }

    #[test]
    fn a_gradient_background_gets_thresholds_that_follow_it() {
        // A ramp from 20 to 220 across 256 columns: each tile's threshold is its own
        // background plus min_contrast, within the ramp's rise over the neighbourhood.
        let image = GreyImage::from_fn(256, 64, |u, _| image::Luma([20 + (u * 200 / 255) as u8]));
        let t = TileThresholds::local(&image, false, 20);
        for column in 0..8u32 {
            let u = column * TILE + TILE / 2;
            let here = f64::from(image.get_pixel(u, 10)[0]);
            let level = f64::from(t.at(u, 10));
            assert!(level > here - 60.0 && level < here + 60.0, "tile {column}: {level} vs {here}");
            assert!(f64::from(t.background_at(u, 10)) < here, "tile {column}");
        }
    }

    #[test]
    fn a_dot_sets_the_threshold_half_way() {
        let mut image = GreyImage::from_pixel(128, 128, image::Luma([40]));
        for v in 56..72 {
            for u in 56..72 {
                image.put_pixel(u, v, image::Luma([240]));
            }
        }
        let t = TileThresholds::local(&image, false, 20);
        assert_eq!(t.at(64, 64), 140);
        assert_eq!(t.background_at(64, 64), 40);
        // Dark dots: the negative's levels.
        let negative = GreyImage::from_fn(128, 128, |u, v| image::Luma([255 - image.get_pixel(u, v)[0]]));
        assert_eq!(TileThresholds::local(&negative, true, 20), t);
        // Far from the dot: the background plus min_contrast.
        let flat = GreyImage::from_pixel(300, 300, image::Luma([40]));
        assert_eq!(TileThresholds::local(&flat, false, 20).at(150, 150), 60);
        assert_eq!(TileThresholds::uniform(&flat, 99).at(299, 299), 99);
    }
}
