//! The image halved again and again (each pixel the mean of the 2 x 2 pixels it covers): the
//! coarser levels on which [`TagDecoder`](super::TagDecoder) looks for the tags too large for
//! its finest search.
//!
//! Why: `kornia-apriltag` fits its quads with running sums in single precision of `w x^2`
//! terms over a cluster of edge pixels (the AprilTag library sums in double precision). The
//! rounding grows with the cluster's length and its coordinates, and the fit of a large tag,
//! or of a tag far from the image's origin, falls apart: at 1920 x 1080 and decimation 1 it
//! loses every tag36h11 tag wider than about 120 px. Halved, a tag is both smaller and nearer
//! the origin; some level has it at a size the quad fit reads, and its corners are then
//! measured again on the full image's edges (`edges.rs`), so the level does not limit their
//! accuracy. The mean of the 2 x 2 pixels (not one pixel of four, as the detector's own
//! decimation) also averages the noise away.

use crate::vision::image::{GreyBuffer, GreyImage, Pixels};

/// The image halved: pixel `(u, v)` is the rounded mean of pixels `2u..2u+2 x 2v..2v+2` (the
/// last row or column of an odd side is dropped), so a point `p` of the half image (pixel
/// centres at `+0.5`, as the AprilTag library counts) is at `2 p` in the image.
pub(super) fn halve<C: Pixels>(image: &GreyBuffer<C>) -> GreyImage {
    let (w, h) = (image.width() / 2, image.height() / 2);
    let stride = image.width() as usize;
    let pixels: &[u8] = image.as_raw();
    let mut out = Vec::with_capacity(w as usize * h as usize);
    // Pairs of rows, read in pairs of pixels (a form the compiler vectorises).
    for rows in pixels.chunks_exact(2 * stride).take(h as usize) {
        let (top, bottom) = rows.split_at(stride);
        let pairs = top.chunks_exact(2).zip(bottom.chunks_exact(2)).take(w as usize);
        out.extend(pairs.map(|(t, b)| {
            let sum = u16::from(t[0]) + u16::from(t[1]) + u16::from(b[0]) + u16::from(b[1]);
            ((sum + 2) / 4) as u8
        }));
    }
    GreyImage::from_raw(w, h, out).unwrap_or_default()
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn each_pixel_is_the_mean_of_the_four_it_covers() {
        // Independent: the mean computed pixel by pixel from get_pixel.
        let image = GreyImage::from_fn(7, 5, |u, v| ::image::Luma([((u * 37 + v * 91 + u * v * 13) % 256) as u8]));
        let half = halve(&image);
        assert_eq!(half.dimensions(), (3, 2));
        for (u, v, p) in half.enumerate_pixels() {
            let sum: u32 = [(0, 0), (1, 0), (0, 1), (1, 1)]
                .iter()
                .map(|(a, b)| u32::from(image.get_pixel(2 * u + a, 2 * v + b)[0]))
                .sum();
            assert!((f64::from(p[0]) - f64::from(sum) / 4.0).abs() <= 0.5, "{u} {v}");
        }
        assert_eq!(halve(&GreyImage::new(1, 9)).dimensions(), (0, 4));
    }
}
