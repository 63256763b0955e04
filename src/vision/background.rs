//! The local threshold of dot detection: a background model on tiles, so that a dot is a
//! pixel that stands out of the background *around it*, under a lighting gradient and in
//! front of a cluttered scene alike (a global level, Otsu's say, is pulled by the clutter and
//! cut by the gradient).
//!
//! The image is cut into square tiles of [`TILE`] pixels. Per tile: the median of a 2 x 2
//! subsample (a histogram) and the largest level. Per tile again, over its neighbourhood:
//! - the background `b`: the lower quartile of the tile medians of the 5 x 5 tiles around it
//!   (a dot, or a cluster of dots, may fill most of a tile and some of its neighbours: the
//!   lower quartile of the neighbourhood still falls on the background, as long as a quarter
//!   of it is background);
//! - the peak `p`: the largest level of the 3 x 3 tiles around it;
//! - the threshold `b + max(min_contrast, (p - b) / 2)`: half way between the background and
//!   the brightest dot nearby (the full width at half maximum of a blurred dot), never closer
//!   to the background than `min_contrast` grey levels (noise and texture).
//!
//! All levels are in the dots' domain: the grey level for light dots, `255 - g` for dark ones.

use crate::vision::image::{GreyBuffer, Pixels};

/// Side of a tile, pixels.
pub const TILE: u32 = 32;
/// Tiles on each side of a tile in its background neighbourhood (5 x 5 tiles).
const BACKGROUND_REACH: usize = 2;
/// Tiles on each side of a tile in its peak neighbourhood (3 x 3 tiles).
const PEAK_REACH: usize = 1;

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
        let stats = tile_statistics(image, dark, columns, rows);
        let mut levels = Vec::with_capacity(columns * rows);
        let mut background = Vec::with_capacity(columns * rows);
        for row in 0..rows {
            for column in 0..columns {
                let b = lower_quartile(&stats, columns, rows, row, column);
                let p = neighbourhood(columns, rows, row, column, PEAK_REACH).map(|i| stats[i].peak).max().unwrap_or(b);
                let half = p.saturating_sub(b) / 2;
                levels.push(b.saturating_add(half.max(min_contrast)));
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

/// The indices of the tiles within `reach` tiles of `(row, column)`, clipped to the grid.
fn neighbourhood(columns: usize, rows: usize, row: usize, column: usize, reach: usize) -> impl Iterator<Item = usize> {
    let (r0, r1) = (row.saturating_sub(reach), (row + reach).min(rows - 1));
    let (c0, c1) = (column.saturating_sub(reach), (column + reach).min(columns - 1));
    (r0..=r1).flat_map(move |r| (c0..=c1).map(move |c| r * columns + c))
}

/// The lower quartile of the tile medians around a tile.
fn lower_quartile(stats: &[TileStats], columns: usize, rows: usize, row: usize, column: usize) -> u8 {
    let mut medians = [0u8; (2 * BACKGROUND_REACH + 1) * (2 * BACKGROUND_REACH + 1)];
    let tiles = neighbourhood(columns, rows, row, column, BACKGROUND_REACH);
    let n = medians.iter_mut().zip(tiles).map(|(m, i)| *m = stats[i].median).count();
    let medians = &mut medians[..n];
    medians.sort_unstable();
    medians[(n - 1) / 4]
}

/// A tile's median (of its 2 x 2 subsample) and largest level.
#[derive(Debug, Clone, Copy, Default)]
struct TileStats {
    median: u8,
    peak: u8,
}

/// The statistics of every tile, row-major; the rows of tiles in parallel (rayon).
fn tile_statistics<C: Pixels>(image: &GreyBuffer<C>, dark: bool, columns: usize, rows: usize) -> Vec<TileStats> {
    use rayon::prelude::*;
    let mut stats = vec![TileStats::default(); columns * rows];
    stats.par_chunks_mut(columns).enumerate().for_each(|(row, out)| tile_row(image, dark, row as u32, out));
    stats
}

/// The statistics of the tiles of one row of tiles.
fn tile_row<C: Pixels>(image: &GreyBuffer<C>, dark: bool, row: u32, out: &mut [TileStats]) {
    let (width, height) = (image.width() as usize, image.height());
    let flip = if dark { 255u8 } else { 0 };
    let data: &[u8] = image.as_raw();
    let (v0, v1) = (row * TILE, ((row + 1) * TILE).min(height));
    for (column, tile) in out.iter_mut().enumerate() {
        let (u0, u1) = (column * TILE as usize, ((column + 1) * TILE as usize).min(width));
        let mut histogram = [0u16; 256];
        let mut peak = 0u8;
        let mut counted = 0u32;
        for v in v0..v1 {
            let line = &data[v as usize * width + u0..v as usize * width + u1];
            peak = peak.max(line.iter().map(|&g| g ^ flip).max().unwrap_or(0));
            if (v - v0) % 2 == 0 {
                for &g in line.iter().step_by(2) {
                    histogram[usize::from(g ^ flip)] += 1;
                    counted += 1;
                }
            }
        }
        *tile = TileStats { median: histogram_median(&histogram, counted), peak };
    }
}

fn histogram_median(histogram: &[u16; 256], total: u32) -> u8 {
    let half = total.div_ceil(2);
    let mut seen = 0u32;
    for (level, &count) in histogram.iter().enumerate() {
        seen += u32::from(count);
        if seen >= half {
            return level as u8;
        }
    }
    255
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::vision::image::GreyImage;

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
