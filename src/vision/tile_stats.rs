//! The statistics of each tile of [`TILE`] x [`TILE`] pixels that the local threshold
//! ([`background`](super::background)) is built from, in the dots' domain (the grey level, or
//! `255 - g` for dark dots): the median of the tile's 2 x 2 subsample (its even rows and
//! columns) and its largest level.
//!
//! Speed: one read of each pixel. A whole tile on a processor with AVX2 is read 32 bytes at a
//! time through `pulp`'s safe wrappers of the intrinsics (`pulp::x86::V3`, detected at run
//! time: no `unsafe` here): the largest level is a byte-wise maximum, the subsample is packed
//! into 8 vectors of 32 bytes (the low byte of each 16-bit lane is an even column), and its
//! median is found bit by bit, from the highest, by counting the subsample values below each
//! candidate (a compare, a mask of the lanes and a population count per vector: 8 rounds of
//! 8 vectors, where a histogram costs an increment and a store per value and a scan of 256
//! bins). Explicit instructions rather than an auto-vectorised loop: the compiler does not turn
//! a per-byte compare into a lane mask (measured: it widens the bytes to 32-bit lanes). The
//! tiles cut by the image's right or bottom edge, and every tile on other processors, take
//! the histogram; both give the same median (the smallest level with at least half the
//! subsample at or below it), which the tests check tile by tile.

use rayon::prelude::*;

use crate::vision::image::{GreyBuffer, Pixels};
use crate::vision::tile_levels::TILE;

/// The statistics of every tile, row-major.
#[derive(Debug, Clone, Default)]
pub struct TileStats {
    /// The median of each tile's 2 x 2 subsample.
    pub medians: Vec<u8>,
    /// The largest level of each tile.
    pub peaks: Vec<u8>,
}

/// The statistics of the `columns` x `rows` tiles of an image; the rows of tiles in parallel
/// (rayon).
pub fn tile_statistics<C: Pixels>(image: &GreyBuffer<C>, dark: bool, columns: usize, rows: usize) -> TileStats {
    let mut medians = vec![0u8; columns * rows];
    let mut peaks = vec![0u8; columns * rows];
    let flip = if dark { 255u8 } else { 0 };
    let (width, height) = (image.width() as usize, image.height() as usize);
    let data: &[u8] = image.as_raw();
    medians.par_chunks_mut(columns).zip(peaks.par_chunks_mut(columns)).enumerate().for_each(
        |(row, (medians, peaks))| {
            let v0 = row * TILE as usize;
            let band = &data[v0 * width..((v0 + TILE as usize).min(height)) * width];
            tile_row(band, width, flip, medians, peaks);
        },
    );
    TileStats { medians, peaks }
}

/// The tiles of one row of tiles: `band` holds its rows of `width` pixels.
fn tile_row(band: &[u8], width: usize, flip: u8, medians: &mut [u8], peaks: &mut [u8]) {
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = pulp::x86::V3::try_new() {
        return simd.vectorize(avx2::TileRow { simd, band, width, flip, medians, peaks });
    }
    for (column, (median, peak)) in medians.iter_mut().zip(peaks.iter_mut()).enumerate() {
        (*median, *peak) = histogram_tile(band, width, column, flip);
    }
}

/// The median and largest level of tile `column` of `band`, by a histogram (any tile).
fn histogram_tile(band: &[u8], width: usize, column: usize, flip: u8) -> (u8, u8) {
    let (u0, u1) = (column * TILE as usize, ((column + 1) * TILE as usize).min(width));
    let mut histogram = [0u16; 256];
    let mut peak = 0u8;
    let mut counted = 0u32;
    for (i, line) in band.chunks_exact(width).enumerate() {
        let line = &line[u0..u1];
        peak = peak.max(line.iter().map(|&g| g ^ flip).max().unwrap_or(0));
        if i % 2 == 0 {
            for &g in line.iter().step_by(2) {
                histogram[usize::from(g ^ flip)] += 1;
                counted += 1;
            }
        }
    }
    (histogram_median(&histogram, counted), peak)
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

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use core::arch::x86_64::__m256i;

    use pulp::bytemuck::cast;
    use pulp::x86::V3;

    use super::{TILE, histogram_tile};

    /// The tiles of one row of tiles, compiled for AVX2 (see the module's documentation).
    pub(super) struct TileRow<'a> {
        pub simd: V3,
        pub band: &'a [u8],
        pub width: usize,
        pub flip: u8,
        pub medians: &'a mut [u8],
        pub peaks: &'a mut [u8],
    }

    impl pulp::NullaryFnOnce for TileRow<'_> {
        type Output = ();

        #[inline(always)]
        fn call(self) {
            let whole_rows = self.band.len() == TILE as usize * self.width;
            for (column, (median, peak)) in self.medians.iter_mut().zip(self.peaks.iter_mut()).enumerate() {
                let whole = whole_rows && (column + 1) * TILE as usize <= self.width;
                let stats = if whole { whole_tile(self.simd, self.band, self.width, column, self.flip) } else { None };
                (*median, *peak) = stats.unwrap_or_else(|| histogram_tile(self.band, self.width, column, self.flip));
            }
        }
    }

    /// Row `v` of tile `column` as a vector (None past the band).
    #[inline(always)]
    fn load(band: &[u8], width: usize, column: usize, v: usize) -> Option<__m256i> {
        let start = v * width + column * TILE as usize;
        band.get(start..)?.first_chunk::<32>().map(|bytes| cast::<[u8; 32], __m256i>(*bytes))
    }

    /// The median of the 2 x 2 subsample and the largest level of a whole tile.
    #[inline(always)]
    fn whole_tile(simd: V3, band: &[u8], width: usize, column: usize, flip: u8) -> Option<(u8, u8)> {
        let flip = simd.avx._mm256_set1_epi8(flip as i8);
        let even = simd.avx._mm256_set1_epi16(0x00ff);
        let mut peak = simd.avx._mm256_setzero_si256();
        let mut sample = [peak; 8];
        for (q, packed) in sample.iter_mut().enumerate() {
            let rows = [0, 1, 2, 3].map(|i| load(band, width, column, 4 * q + i));
            let [Some(r0), Some(r1), Some(r2), Some(r3)] = rows else { return None };
            let [r0, r1, r2, r3] = [r0, r1, r2, r3].map(|r| simd.avx2._mm256_xor_si256(r, flip));
            let high = simd.avx2._mm256_max_epu8(simd.avx2._mm256_max_epu8(r0, r1), simd.avx2._mm256_max_epu8(r2, r3));
            peak = simd.avx2._mm256_max_epu8(peak, high);
            // Even columns of the even rows 4q and 4q + 2 (lane order is irrelevant to a median).
            let (e0, e2) = (simd.avx2._mm256_and_si256(r0, even), simd.avx2._mm256_and_si256(r2, even));
            *packed = simd.avx2._mm256_packus_epi16(e0, e2);
        }
        Some((median(simd, &sample), horizontal_max(peak)))
    }

    /// The smallest level with at least half of the 256 values at or below it: the largest
    /// `m` with fewer than half below it, built from its highest bit down.
    #[inline(always)]
    fn median(simd: V3, sample: &[__m256i; 8]) -> u8 {
        // Unsigned order as signed order: both sides offset by 128.
        let bias = simd.avx._mm256_set1_epi8(i8::MIN);
        let sample = sample.map(|s| simd.avx2._mm256_xor_si256(s, bias));
        let mut m = 0u8;
        for bit in (0..8).rev() {
            let candidate = m | (1 << bit);
            let c = simd.avx._mm256_set1_epi8((candidate ^ 0x80) as i8);
            let below: u32 = sample
                .iter()
                .map(|&s| (simd.avx2._mm256_movemask_epi8(simd.avx2._mm256_cmpgt_epi8(c, s)) as u32).count_ones())
                .sum();
            if below < 128 {
                m = candidate;
            }
        }
        m
    }

    /// The largest byte of a vector.
    #[inline(always)]
    fn horizontal_max(x: __m256i) -> u8 {
        let bytes: [u8; 32] = cast(x);
        bytes.into_iter().max().unwrap_or(0)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::vision::image::GreyImage;

    #[test]
    fn every_tile_matches_its_histogram() {
        // Random levels with runs of equal values (ties at the median), whole and cut tiles
        // (70 x 45: the last column and row of tiles are cut), both polarities; each tile
        // against the histogram of its own pixels.
        let mut state = 7u64;
        for (w, h, spread) in [(70u32, 45u32, 256u64), (96, 64, 3), (64, 33, 40), (33, 96, 256)] {
            let image = GreyImage::from_fn(w, h, |u, _| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                image::Luma([((state >> 33) % spread) as u8 + (u % 7) as u8 * u8::from(spread < 256)])
            });
            let (columns, rows) = (w.div_ceil(TILE) as usize, h.div_ceil(TILE) as usize);
            for dark in [false, true] {
                let stats = tile_statistics(&image, dark, columns, rows);
                let flip = if dark { 255 } else { 0 };
                for row in 0..rows {
                    for column in 0..columns {
                        let mut sample = Vec::new();
                        let mut peak = 0u8;
                        for v in row * 32..((row + 1) * 32).min(h as usize) {
                            for u in column * 32..((column + 1) * 32).min(w as usize) {
                                let g = image.get_pixel(u as u32, v as u32)[0] ^ flip;
                                peak = peak.max(g);
                                if u % 2 == 0 && v % 2 == 0 {
                                    sample.push(g);
                                }
                            }
                        }
                        sample.sort_unstable();
                        let i = row * columns + column;
                        let at = (w, h, dark, row, column);
                        assert_eq!(stats.medians[i], sample[(sample.len() - 1) / 2], "{at:?}");
                        assert_eq!(stats.peaks[i], peak, "{at:?}");
                    }
                }
            }
        }
    }
}
