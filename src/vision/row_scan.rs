//! The horizontal runs of dot pixels of rows of an image: the pixels whose level (the grey
//! level, or `255 - g` for dark dots) is above their tile's threshold, as `[u0, u1)` column
//! ranges, and the darkest and brightest grey level met on the way (the detector's check for a
//! uniform image, without a pass of its own).
//!
//! Speed: each tile's [`TILE`] pixels of a row become a 32-bit mask (bit `i`: pixel `u0 + i`
//! is a dot pixel) and the runs are read off the mask's transitions (`mask ^ (mask << 1 |
//! carry)`, one `trailing_zeros` per run end): the work per pixel is a fraction of an
//! instruction and a row of background costs one test per tile. On a processor with AVX2 a
//! whole tile's mask is a compare and a `movemask` of 32 bytes, through `pulp`'s safe wrappers
//! of the intrinsics (`pulp::x86::V3`, detected at run time, no `unsafe` here): explicit
//! instructions, since the compiler does not turn a per-byte compare into a lane mask (it
//! widens the bytes to 32-bit lanes: measured). Tiles cut by the image's right edge, and every
//! tile on other processors, build the mask byte by byte; both give the same runs (tested).

use crate::vision::background::TileThresholds;
use crate::vision::tile_levels::TILE;

/// A horizontal run of dot pixels: row `v`, columns `u0..u1` (`u1` excluded).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Run {
    /// Row.
    pub v: u32,
    /// First column.
    pub u0: u32,
    /// One past the last column.
    pub u1: u32,
}

/// The runs of rows `rows` of a `width`-pixel-wide image `data`, appended to `out` in raster
/// order; returns the smallest and largest grey level of those rows.
pub fn scan_rows(
    data: &[u8],
    width: usize,
    rows: std::ops::Range<usize>,
    thresholds: &TileThresholds,
    dark: bool,
    out: &mut Vec<Run>,
) -> [u8; 2] {
    let flip = if dark { 255u8 } else { 0 };
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = pulp::x86::V3::try_new() {
        return simd.vectorize(avx2::Scan { simd, data, width, rows, thresholds, flip, out });
    }
    let mut range = [u8::MAX, 0];
    for v in rows {
        let line = &data[v * width..(v + 1) * width];
        let mut runs = Runs::new(v as u32);
        for (tile, (segment, &level)) in line.chunks(TILE as usize).zip(thresholds.row(v as u32)).enumerate() {
            range = [range[0].min(segment.iter().copied().min().unwrap_or(u8::MAX)), range[1].max(byte_max(segment))];
            runs.segment(byte_mask(segment, flip, level), segment.len() as u32, tile as u32 * TILE, out);
        }
        runs.finish(width as u32, out);
    }
    range
}

fn byte_max(segment: &[u8]) -> u8 {
    segment.iter().copied().max().unwrap_or(0)
}

/// The mask of a segment of at most 32 pixels, byte by byte.
#[inline(always)]
fn byte_mask(segment: &[u8], flip: u8, level: u8) -> u32 {
    segment.iter().enumerate().fold(0u32, |m, (i, &g)| m | (u32::from((g ^ flip) > level) << i))
}

/// The runs of one row, from its segments' masks left to right.
struct Runs {
    v: u32,
    inside: bool,
    start: u32,
}

impl Runs {
    fn new(v: u32) -> Self {
        Self { v, inside: false, start: 0 }
    }

    /// The segment of `len` pixels at column `u0` with mask `mask` (no bit at `len` or above).
    #[inline(always)]
    fn segment(&mut self, mask: u32, len: u32, u0: u32, out: &mut Vec<Run>) {
        let mut edges = mask ^ ((mask << 1) | u32::from(self.inside));
        if len < 32 {
            edges &= (1u32 << len) - 1;
        }
        while edges != 0 {
            let u = u0 + edges.trailing_zeros();
            if self.inside {
                out.push(Run { v: self.v, u0: self.start, u1: u });
            } else {
                self.start = u;
            }
            self.inside = !self.inside;
            edges &= edges - 1;
        }
    }

    /// Closes a run that reaches the end of the row.
    fn finish(self, width: u32, out: &mut Vec<Run>) {
        if self.inside {
            out.push(Run { v: self.v, u0: self.start, u1: width });
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use core::arch::x86_64::__m256i;

    use pulp::bytemuck::cast;
    use pulp::x86::V3;

    use super::{Run, Runs, TILE, TileThresholds, byte_mask, byte_max};

    /// [`scan_rows`](super::scan_rows) compiled for AVX2.
    pub(super) struct Scan<'a> {
        pub simd: V3,
        pub data: &'a [u8],
        pub width: usize,
        pub rows: std::ops::Range<usize>,
        pub thresholds: &'a TileThresholds,
        pub flip: u8,
        pub out: &'a mut Vec<Run>,
    }

    impl pulp::NullaryFnOnce for Scan<'_> {
        type Output = [u8; 2];

        #[inline(always)]
        fn call(self) -> [u8; 2] {
            let simd = self.simd;
            // (g ^ flip) > level as a signed compare: both sides offset by 128.
            let flip = simd.avx._mm256_set1_epi8((self.flip ^ 0x80) as i8);
            let mut low = simd.avx._mm256_set1_epi8(-1);
            let mut high = simd.avx._mm256_setzero_si256();
            let mut range = [u8::MAX, 0u8];
            for v in self.rows {
                let line = &self.data[v * self.width..(v + 1) * self.width];
                let mut runs = Runs::new(v as u32);
                let (whole, cut) = line.as_chunks::<32>();
                let levels = self.thresholds.row(v as u32);
                for (tile, (bytes, &level)) in whole.iter().zip(levels).enumerate() {
                    let x: __m256i = cast(*bytes);
                    low = simd.avx2._mm256_min_epu8(low, x);
                    high = simd.avx2._mm256_max_epu8(high, x);
                    let above = simd.avx2._mm256_cmpgt_epi8(
                        simd.avx2._mm256_xor_si256(x, flip),
                        simd.avx._mm256_set1_epi8((level ^ 0x80) as i8),
                    );
                    let mask = simd.avx2._mm256_movemask_epi8(above) as u32;
                    runs.segment(mask, TILE, tile as u32 * TILE, self.out);
                }
                if !cut.is_empty() {
                    let level = levels.get(whole.len()).copied().unwrap_or(u8::MAX);
                    range = [range[0].min(cut.iter().copied().min().unwrap_or(u8::MAX)), range[1].max(byte_max(cut))];
                    let u0 = (whole.len() * 32) as u32;
                    runs.segment(byte_mask(cut, self.flip, level), cut.len() as u32, u0, self.out);
                }
                runs.finish(self.width as u32, self.out);
            }
            let (low, high): ([u8; 32], [u8; 32]) = (cast(low), cast(high));
            let low = low.into_iter().min().unwrap_or(u8::MAX);
            let high = high.into_iter().max().unwrap_or(0);
            [range[0].min(low), range[1].max(high)]
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::vision::image::GreyImage;

    /// The runs of a row pixel by pixel: the definition.
    fn reference(image: &GreyImage, t: &TileThresholds, dark: bool) -> Vec<Run> {
        let mut out = Vec::new();
        for v in 0..image.height() {
            let mut start = None;
            for u in 0..=image.width() {
                let inside = u < image.width() && (image.get_pixel(u, v)[0] ^ if dark { 255 } else { 0 }) > t.at(u, v);
                match (inside, start) {
                    (true, None) => start = Some(u),
                    (false, Some(s)) => {
                        out.push(Run { v, u0: s, u1: u });
                        start = None;
                    }
                    _ => {}
                }
            }
        }
        out
    }

    #[test]
    fn runs_and_range_match_the_pixels() {
        // Widths with and without a cut tile, runs across tile borders and to the row's end,
        // local and uniform thresholds, both polarities.
        let mut state = 5u64;
        for (w, h) in [(64u32, 40u32), (97, 33), (20, 5), (160, 70)] {
            let image = GreyImage::from_fn(w, h, |u, v| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                let blob = ((u / 7 + v / 5) % 3 == 0) as u8;
                image::Luma([((state >> 40) % 90) as u8 + 120 * blob + 20])
            });
            let range = [*image.as_raw().iter().min().unwrap(), *image.as_raw().iter().max().unwrap()];
            for dark in [false, true] {
                for t in [TileThresholds::local(&image, dark, 20), TileThresholds::uniform(&image, 100)] {
                    let mut runs = Vec::new();
                    let got = scan_rows(image.as_raw(), w as usize, 0..h as usize, &t, dark, &mut runs);
                    assert_eq!(runs, reference(&image, &t, dark), "{w}x{h} dark {dark}");
                    assert!(!runs.is_empty());
                    assert_eq!(got, range);
                }
            }
        }
    }
}
