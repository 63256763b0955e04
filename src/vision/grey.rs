//! Colour to grey: 8-bit RGB, BGR, RGBA or BGRA pixels (a camera's `rgb8`/`bgr8`/`rgba8`/
//! `bgra8` frames, rows possibly padded) to the 8-bit grey levels the detectors read, by
//! Rec. 601 luma `0.299 R + 0.587 G + 0.114 B` in fixed point with rounding (weights 9798,
//! 19235 and 3735 over 2^15: OpenCV's `cvtColor` `COLOR_RGB2GRAY`, `COLOR_BGR2GRAY`,
//! `COLOR_RGBA2GRAY` and `COLOR_BGRA2GRAY` to the bit, the weights [`load_image`] uses; alpha
//! is ignored).
//!
//! Speed: integer arithmetic in a plain per-pixel loop that the compiler vectorises; the loop
//! is compiled a second time for AVX2 and that copy is chosen at run time when the processor
//! has it (`pulp`'s dispatch: no `unsafe` here), which is what brings a 1920 x 1080 frame
//! under a millisecond on one core (`benches/grey.py`).
//!
//! [`load_image`]: crate::vision::load_image

use rayon::prelude::*;

use crate::vision::error::{Result, VisionError};
use crate::vision::image::{GreyImage, check_dimensions};

/// The order of the colour channels of a pixel (an alpha channel, if any, comes last).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChannelOrder {
    /// Red, green, blue (`rgb8`, `rgba8`).
    Rgb,
    /// Blue, green, red (`bgr8`, `bgra8`, OpenCV's order).
    Bgr,
}

/// The grey image of `height` rows of `width` colour pixels of 3 bytes (see
/// [`pixels_to_grey`]).
pub fn colour_to_grey(
    what: &str,
    width: u32,
    height: u32,
    row_stride: usize,
    data: &[u8],
    order: ChannelOrder,
) -> Result<GreyImage> {
    pixels_to_grey(what, width, height, 3, row_stride, data, order)
}

/// The grey image of `height` rows of `width` pixels of `channels` bytes (3: colour, 4:
/// colour and alpha, ignored), row `v` starting at byte `v * row_stride` of `data`
/// (`row_stride >= channels * width`: padded rows are read as such); `what` names the
/// argument in errors (an empty image, another channel count, a stride shorter than a row,
/// data shorter than the rows).
pub fn pixels_to_grey(
    what: &str,
    width: u32,
    height: u32,
    channels: usize,
    row_stride: usize,
    data: &[u8],
    order: ChannelOrder,
) -> Result<GreyImage> {
    check_dimensions(what, u64::from(width), u64::from(height))?;
    if channels != 3 && channels != 4 {
        return Err(invalid(what, format!("{channels} channels: expected 3 (colour) or 4 (colour and alpha)")));
    }
    let (w, h) = (width as usize, height as usize);
    let row_bytes = channels * w;
    if row_stride < row_bytes {
        return Err(invalid(
            what,
            format!("rows of {row_stride} bytes are shorter than {width} pixels of {channels} bytes"),
        ));
    }
    let needed = row_stride * (h - 1) + row_bytes;
    if data.len() < needed {
        return Err(invalid(what, format!("{} bytes for {height} rows of {row_stride} bytes", data.len())));
    }
    let weights = match order {
        ChannelOrder::Rgb => [9798, 19235, 3735],
        ChannelOrder::Bgr => [3735, 19235, 9798],
    };
    let rows = Rows { w, row_stride, row_bytes, channels, weights };
    let mut grey = vec![0u8; w * h];
    if w * h < PARALLEL_PIXELS {
        rows.convert(data, &mut grey);
    } else {
        // Bands of rows on vsinv's own pool (never rayon's global one).
        crate::parallel::install(|| {
            let bands = data.par_chunks(row_stride * BAND_ROWS).zip(grey.par_chunks_mut(w * BAND_ROWS));
            bands.for_each(|(band, out)| rows.convert(band, out));
        })?;
    }
    GreyImage::from_raw(width, height, grey).ok_or_else(|| invalid(what, "inconsistent size".into()))
}

/// Images of at least this many pixels are converted on several threads (below it, starting
/// the work on the pool costs about what it saves).
const PARALLEL_PIXELS: usize = 1 << 18;

/// The rows a thread converts at a time.
const BAND_ROWS: usize = 32;

/// The layout of the rows and the weights.
#[derive(Clone, Copy)]
struct Rows {
    w: usize,
    row_stride: usize,
    row_bytes: usize,
    channels: usize,
    weights: [u32; 3],
}

impl Rows {
    /// Converts the rows of `data` into the rows of `out` (as many as both hold), with the
    /// widest vector instructions the processor has.
    fn convert(self, data: &[u8], out: &mut [u8]) {
        let arch = pulp::Arch::new();
        match self.channels {
            3 => arch.dispatch(Band::<3> { rows: self, data, out }),
            _ => arch.dispatch(Band::<4> { rows: self, data, out }),
        }
    }
}

/// Rows of pixels of `N` bytes to convert: a `pulp` operation, whose `with_simd` is
/// compiled once for each instruction set and inlined into the copy for it (a closure here
/// was not inlined, and ran at scalar speed: measured).
struct Band<'a, const N: usize> {
    rows: Rows,
    data: &'a [u8],
    out: &'a mut [u8],
}

impl<const N: usize> pulp::WithSimd for Band<'_, N> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        let r = self.rows;
        for (row, o) in self.data.chunks(r.row_stride).zip(self.out.chunks_exact_mut(r.w)) {
            grey_row::<N>(&row[..r.row_bytes], o, r.weights);
        }
    }
}

/// One row of pixels of `N` bytes: a loop without branches over whole pixels, which the
/// compiler turns into vector code (inlined into the dispatched copy).
#[inline(always)]
fn grey_row<const N: usize>(row: &[u8], out: &mut [u8], weights: [u32; 3]) {
    let (pixels, _) = row.as_chunks::<N>();
    for (p, o) in pixels.iter().zip(out.iter_mut()) {
        *o = luma([p[0], p[1], p[2]], weights);
    }
}

/// One pixel's weighted sum, rounded, over 2^15 (at most 255: the weights sum to 2^15).
#[inline(always)]
fn luma(px: [u8; 3], [a, b, c]: [u32; 3]) -> u8 {
    let l = a * u32::from(px[0]) + b * u32::from(px[1]) + c * u32::from(px[2]);
    ((l + (1 << 14)) >> 15) as u8
}

fn invalid(what: &str, reason: String) -> VisionError {
    VisionError::InvalidImage { what: what.to_string(), reason }
}
#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    /// The luma in floating point, rounded: the closed form the fixed point approximates.
    fn luma(r: u8, g: u8, b: u8) -> f64 {
        0.299 * f64::from(r) + 0.587 * f64::from(g) + 0.114 * f64::from(b)
    }

    #[test]
    fn every_pixel_is_its_rounded_luma_within_one_level() {
        let (w, h, stride) = (37u32, 70u32, 37 * 3 + 5);
        let data: Vec<u8> = (0..stride * 70).map(|i| ((i * 7919) % 251) as u8).collect();
        let rgb = colour_to_grey("image", w, h, stride, &data, ChannelOrder::Rgb).unwrap();
        let bgr = colour_to_grey("image", w, h, stride, &data, ChannelOrder::Bgr).unwrap();
        for v in 0..h as usize {
            for u in 0..w as usize {
                let p = &data[v * stride + 3 * u..][..3];
                let got = f64::from(rgb.get_pixel(u as u32, v as u32).0[0]);
                assert!((got - luma(p[0], p[1], p[2])).abs() <= 0.5 + 1e-3, "rgb at {u},{v}");
                let got = f64::from(bgr.get_pixel(u as u32, v as u32).0[0]);
                assert!((got - luma(p[2], p[1], p[0])).abs() <= 0.5 + 1e-3, "bgr at {u},{v}");
            }
        }
    }

    #[test]
    fn blocks_threads_and_tails_give_each_pixel_its_own_luma() {
        // Widths with and without a tail of fewer than BLOCK pixels, padded rows, and a
        // size above PARALLEL_PIXELS (split over threads); each pixel against `luma` alone.
        for (w, h, pad) in [(16u32, 3u32, 0usize), (37, 5, 4), (643, 481, 7), (1024, 300, 0)] {
            let stride = 3 * w as usize + pad;
            let data: Vec<u8> = (0..stride * h as usize).map(|i| ((i * 7919 + i / 613) % 256) as u8).collect();
            for (order, weights) in [(ChannelOrder::Rgb, [9798, 19235, 3735]), (ChannelOrder::Bgr, [3735, 19235, 9798])]
            {
                let grey = colour_to_grey("image", w, h, stride, &data, order).unwrap();
                for (v, row) in grey.as_raw().chunks(w as usize).enumerate() {
                    for (u, &g) in row.iter().enumerate() {
                        let p = &data[v * stride + 3 * u..][..3];
                        assert_eq!(g, super::luma([p[0], p[1], p[2]], weights), "{w}x{h} at {u},{v}");
                    }
                }
            }
        }
    }

    #[test]
    fn alpha_is_ignored() {
        // RGBA / BGRA rows (padded, odd widths, one above PARALLEL_PIXELS): each pixel the
        // luma of its colour, whatever its alpha.
        for (w, h, pad) in [(37u32, 5u32, 3usize), (643, 481, 5)] {
            let stride = 4 * w as usize + pad;
            let data: Vec<u8> = (0..stride * h as usize).map(|i| ((i * 7919 + i / 613) % 256) as u8).collect();
            for (order, weights) in [(ChannelOrder::Rgb, [9798, 19235, 3735]), (ChannelOrder::Bgr, [3735, 19235, 9798])]
            {
                let grey = pixels_to_grey("image", w, h, 4, stride, &data, order).unwrap();
                for (v, row) in grey.as_raw().chunks(w as usize).enumerate() {
                    for (u, &g) in row.iter().enumerate() {
                        let p = &data[v * stride + 4 * u..][..3];
                        assert_eq!(g, super::luma([p[0], p[1], p[2]], weights), "{w}x{h} at {u},{v}");
                    }
                }
            }
        }
        let two = pixels_to_grey("frame", 2, 1, 2, 4, &[0; 4], ChannelOrder::Rgb).unwrap_err();
        assert!(two.to_string().contains("2 channels"), "{two}");
    }

    #[test]
    fn white_stays_white_and_black_black() {
        let white = colour_to_grey("image", 4, 2, 12, &[255; 24], ChannelOrder::Rgb).unwrap();
        assert!(white.as_raw().iter().all(|&x| x == 255));
        let black = colour_to_grey("image", 4, 2, 12, &[0; 24], ChannelOrder::Bgr).unwrap();
        assert!(black.as_raw().iter().all(|&x| x == 0));
    }

    #[test]
    fn bad_sizes_are_refused_by_name() {
        let short = colour_to_grey("frame", 4, 2, 12, &[0; 23], ChannelOrder::Rgb).unwrap_err();
        assert!(short.to_string().starts_with("frame: 23 bytes"), "{short}");
        let stride = colour_to_grey("frame", 4, 2, 11, &[0; 24], ChannelOrder::Rgb).unwrap_err();
        assert!(stride.to_string().contains("shorter than 4 pixels"), "{stride}");
        assert!(colour_to_grey("frame", 0, 2, 12, &[0; 24], ChannelOrder::Rgb).is_err());
    }
}
