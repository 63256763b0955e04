//! Coarser tiles, for dots larger than a tile's neighbourhood.
//!
//! The local threshold ([`background`](super::background)) takes the background of a tile
//! from the 5 x 5 tiles around it (160 px): inside a dot wider than about 120 px (a quarter of
//! that neighbourhood is no longer background) the "background" is the dot itself, the
//! threshold is `min_contrast` above the dot, and the dot falls apart into its rim.
//!
//! A pyramid of coarser tiles answers that: level `k` has tiles of `2^k` x `2^k` tiles, each
//! with the median of its four children's medians (the lower one of an even count) and the
//! largest of their peaks; per coarse tile, the background (the lower quartile of the 5 x 5
//! coarse tiles around it) and the peak (the largest of the 3 x 3), as at level 0. A tile
//! takes the threshold of the finest level that shows contrast (half way between its
//! background and peak) when that is lower than its own and the tile is inside a dot at that
//! level: its own neighbourhood is flat (no contrast beyond `min_contrast`), or its own
//! background is above that threshold (its whole neighbourhood is inside the dot: a dot with
//! marks printed inside, whose neighbourhood is not flat). The inside of a dot of any size is
//! then above its threshold. A tile of a plain background keeps its own threshold (bit for
//! bit): its background is under the coarser threshold, and when flat, a coarser background
//! is no higher there, so the coarser threshold, at least `min_contrast` above it, is not
//! lower.

use crate::vision::tile_levels::{flat, largest, lower_quartile, threshold};

/// The coarse levels, finest first, up to a single tile.
#[derive(Debug, Clone, Default)]
pub struct Pyramid {
    levels: Vec<Level>,
}

/// One level: per coarse tile, its background and peak.
#[derive(Debug, Clone)]
struct Level {
    /// Tiles per coarse tile side: `1 << shift`.
    shift: u32,
    columns: usize,
    background: Vec<u8>,
    peak: Vec<u8>,
}

impl Pyramid {
    /// The levels above the tiles' `medians` and `peaks` (`columns` x `rows`, row-major).
    pub fn new(medians: &[u8], peaks: &[u8], columns: usize, rows: usize) -> Self {
        let (mut medians, mut peaks) = (medians.to_vec(), peaks.to_vec());
        let (mut columns, mut rows) = (columns, rows);
        let mut levels = Vec::new();
        while columns > 1 || rows > 1 {
            (medians, peaks, columns, rows) = halve(&medians, &peaks, columns, rows);
            let index = |i: usize| (i / columns, i % columns);
            let background =
                (0..columns * rows).map(|i| lower_quartile(&medians, columns, rows, index(i).0, index(i).1)).collect();
            let peak = (0..columns * rows).map(|i| largest(&peaks, columns, rows, index(i).0, index(i).1)).collect();
            levels.push(Level { shift: levels.len() as u32 + 1, columns, background, peak });
        }
        Self { levels }
    }

    /// The threshold and background of `tile`, whose own are `fine` (see the module's
    /// documentation): those of the finest level with contrast, when they are lower and the
    /// tile is flat or its own background is above them (its neighbourhood is inside a dot).
    pub fn inside_large_dot(&self, tile: Tile, fine: (u8, u8), min_contrast: u8) -> (u8, u8) {
        for level in &self.levels {
            let i = (tile.row >> level.shift) * level.columns + (tile.column >> level.shift);
            let (b, p) = (level.background[i], level.peak[i]);
            if !flat(b, p, min_contrast) {
                let t = threshold(b, p, min_contrast);
                let inside = tile.flat || fine.1 > t;
                return if t < fine.0 && inside { (t, b) } else { fine };
            }
        }
        fine
    }
}

/// A tile of level 0, as the pyramid sees it.
#[derive(Debug, Clone, Copy)]
pub struct Tile {
    /// Row of tiles.
    pub row: usize,
    /// Column of tiles.
    pub column: usize,
    /// Whether its neighbourhood shows no contrast beyond `min_contrast`.
    pub flat: bool,
}

/// The next level: each coarse tile has the lower median of its (up to four) children's
/// medians and the largest of their peaks.
fn halve(medians: &[u8], peaks: &[u8], columns: usize, rows: usize) -> (Vec<u8>, Vec<u8>, usize, usize) {
    let (c2, r2) = (columns.div_ceil(2), rows.div_ceil(2));
    let (mut m2, mut p2) = (Vec::with_capacity(c2 * r2), Vec::with_capacity(c2 * r2));
    for row in 0..r2 {
        for column in 0..c2 {
            let mut children = [0u8; 4];
            let mut n = 0;
            let mut peak = 0u8;
            for r in 2 * row..(2 * row + 2).min(rows) {
                for c in 2 * column..(2 * column + 2).min(columns) {
                    children[n] = medians[r * columns + c];
                    peak = peak.max(peaks[r * columns + c]);
                    n += 1;
                }
            }
            let children = &mut children[..n];
            children.sort_unstable();
            m2.push(children[(n - 1) / 2]);
            p2.push(peak);
        }
    }
    (m2, p2, c2, r2)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn halving_takes_the_lower_median_and_the_largest_peak() {
        // 3 x 3 tiles: coarse tiles of 4, 2, 2 and 1 children.
        let medians = [9, 3, 7, 5, 1, 8, 6, 2, 4];
        let peaks = [10, 20, 30, 40, 50, 60, 70, 80, 90];
        let (m, p, c, r) = halve(&medians, &peaks, 3, 3);
        assert_eq!((c, r), (2, 2));
        assert_eq!(m, vec![3, 7, 2, 4]);
        assert_eq!(p, vec![50, 60, 80, 90]);
    }

    #[test]
    fn a_dot_wider_than_the_neighbourhood_gets_a_threshold_inside_it() {
        // 16 x 16 tiles of background 40, a square of 10 x 10 tiles at 200 in the middle: the
        // tile at its centre is flat (its 5 x 5 neighbourhood is all dot); a coarser level sees
        // the background and puts the threshold half way.
        let (columns, rows) = (16usize, 16usize);
        let inside = |r: usize, c: usize| (3..13).contains(&r) && (3..13).contains(&c);
        let medians: Vec<u8> = (0..256).map(|i| if inside(i / 16, i % 16) { 200 } else { 40 }).collect();
        let pyramid = Pyramid::new(&medians, &medians, columns, rows);
        let fine = (220, 200);
        let tile = |row, column, flat| Tile { row, column, flat };
        assert_eq!(pyramid.inside_large_dot(tile(8, 8, true), fine, 20), (120, 40));
        // Not flat (a mark inside the dot): the coarse threshold still, its own background being above.
        assert_eq!(pyramid.inside_large_dot(tile(8, 8, false), (180, 150), 20), (120, 40));
        // A tile of the background keeps its own threshold, flat or not.
        assert_eq!(pyramid.inside_large_dot(tile(0, 0, true), (60, 40), 20), (60, 40));
        assert_eq!(pyramid.inside_large_dot(tile(2, 2, false), (140, 40), 20), (140, 40));
    }
}
