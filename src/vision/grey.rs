//! Colour to grey: 8-bit RGB or BGR pixels (a camera's `rgb8`/`bgr8` frames, rows possibly
//! padded) to the 8-bit grey levels the detectors read, by Rec. 601 luma
//! `0.299 R + 0.587 G + 0.114 B` in fixed point with rounding (weights 9798, 19235 and 3735
//! over 2^15: OpenCV's `COLOR_RGB2GRAY` to the bit, the weights [`load_image`] uses).
//!
//! [`load_image`]: crate::vision::load_image

use crate::error::{Error, Result};
use crate::vision::image::{GreyImage, check_dimensions};

/// The order of the three channels of a colour pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChannelOrder {
    /// Red, green, blue (`rgb8`).
    Rgb,
    /// Blue, green, red (`bgr8`, OpenCV's order).
    Bgr,
}

/// The grey image of `height` rows of `width` colour pixels, row `v` starting at byte
/// `v * row_stride` of `data` (`row_stride >= 3 * width`: padded rows are read as such);
/// `what` names the argument in errors (an empty image, a stride shorter than a row, data
/// shorter than the rows).
pub fn colour_to_grey(
    what: &str,
    width: u32,
    height: u32,
    row_stride: usize,
    data: &[u8],
    order: ChannelOrder,
) -> Result<GreyImage> {
    check_dimensions(what, u64::from(width), u64::from(height))?;
    let (w, h) = (width as usize, height as usize);
    let row_bytes = 3 * w;
    if row_stride < row_bytes {
        return Err(invalid(what, format!("rows of {row_stride} bytes are shorter than {width} pixels of 3 bytes")));
    }
    let needed = row_stride * (h - 1) + row_bytes;
    if data.len() < needed {
        return Err(invalid(what, format!("{} bytes for {height} rows of {row_stride} bytes", data.len())));
    }
    let weights = match order {
        ChannelOrder::Rgb => [9798, 19235, 3735],
        ChannelOrder::Bgr => [3735, 19235, 9798],
    };
    // Filled as it is made (no zeroing pass); one thread: the loop runs at memory speed.
    let mut grey = Vec::with_capacity(w * h);
    for row in data.chunks(row_stride).take(h) {
        let (pixels, _) = row[..row_bytes].as_chunks::<3>();
        grey.extend(pixels.iter().map(|&p| luma(p, weights)));
    }
    GreyImage::from_raw(width, height, grey).ok_or_else(|| invalid(what, "inconsistent size".into()))
}

/// One pixel's weighted sum, rounded, over 2^15 (at most 255: the weights sum to 2^15).
fn luma(px: [u8; 3], [a, b, c]: [u32; 3]) -> u8 {
    let l = a * u32::from(px[0]) + b * u32::from(px[1]) + c * u32::from(px[2]);
    ((l + (1 << 14)) >> 15) as u8
}

fn invalid(what: &str, reason: String) -> Error {
    Error::InvalidImage { what: what.to_string(), reason }
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
