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

use kornia_image::{Image, ImageSize};

use crate::vision::image::{GreyBuffer, Pixels};

/// The image halved: pixel `(u, v)` of `out` is the rounded mean of pixels `2u..2u+2 x
/// 2v..2v+2` of `pixels` (rows of `width`; the last row or column of an odd side is dropped),
/// so a point `p` of the half image (pixel centres at `+0.5`, as the AprilTag library counts)
/// is at `2 p` in the image. `out` has rows of `half_width` (at most `width / 2`), as many as
/// it holds (at most half those of `pixels`).
fn halve_into(pixels: &[u8], width: usize, out: &mut [u8], half_width: usize) {
    if half_width == 0 {
        return;
    }
    for (rows, out) in pixels.chunks_exact(2 * width).zip(out.chunks_exact_mut(half_width)) {
        let (top, bottom) = rows.split_at(width);
        #[cfg(target_arch = "x86_64")]
        if let Some(simd) = pulp::x86::V3::try_new() {
            simd.vectorize(avx2::HalveRows { simd, top, bottom, out });
            continue;
        }
        halve_rows(top, bottom, out);
    }
}

/// One row of the half image from two rows of the image, from its first pixel.
fn halve_rows(top: &[u8], bottom: &[u8], out: &mut [u8]) {
    let pairs = top.chunks_exact(2).zip(bottom.chunks_exact(2));
    for (o, (t, b)) in out.iter_mut().zip(pairs) {
        let sum = u16::from(t[0]) + u16::from(t[1]) + u16::from(b[0]) + u16::from(b[1]);
        *o = ((sum + 2) / 4) as u8;
    }
}

/// [`halve_rows`] on a processor with AVX2, 32 pixels of the half row at a time: the sums of
/// horizontal pairs of each row (`maddubs` with ones, 16-bit lanes), added, rounded and
/// halved twice, packed back to bytes (the packing works within 128-bit halves: a permutation
/// restores the order); the pixels after the last whole 32 as [`halve_rows`] does.
#[cfg(target_arch = "x86_64")]
mod avx2 {
    use core::arch::x86_64::__m256i;

    use pulp::bytemuck::cast;
    use pulp::x86::V3;

    pub(super) struct HalveRows<'a> {
        pub simd: V3,
        pub top: &'a [u8],
        pub bottom: &'a [u8],
        pub out: &'a mut [u8],
    }

    impl pulp::NullaryFnOnce for HalveRows<'_> {
        type Output = ();

        #[inline(always)]
        fn call(self) {
            let (avx, avx2) = (self.simd.avx, self.simd.avx2);
            let ones = avx._mm256_set1_epi8(1);
            let two = avx._mm256_set1_epi16(2);
            let (blocks, _) = self.out.as_chunks_mut::<32>();
            let (tops, _) = self.top.as_chunks::<64>();
            let (bottoms, _) = self.bottom.as_chunks::<64>();
            let mut done = 0;
            for ((out, top), bottom) in blocks.iter_mut().zip(tops).zip(bottoms) {
                let pair_sums = |bytes: &[u8; 64], half: usize| -> __m256i {
                    let mut lanes = [0u8; 32];
                    lanes.copy_from_slice(&bytes[32 * half..32 * half + 32]);
                    avx2._mm256_maddubs_epi16(cast(lanes), ones)
                };
                let mean = |half: usize| {
                    let sum = avx2._mm256_add_epi16(pair_sums(top, half), pair_sums(bottom, half));
                    avx2._mm256_srli_epi16::<2>(avx2._mm256_add_epi16(sum, two))
                };
                let packed = avx2._mm256_packus_epi16(mean(0), mean(1));
                *out = cast(avx2._mm256_permute4x64_epi64::<0b11_01_10_00>(packed));
                done += 32;
            }
            let rest = self.out.get_mut(done..).unwrap_or_default();
            let (top, bottom) =
                (self.top.get(2 * done..).unwrap_or_default(), self.bottom.get(2 * done..).unwrap_or_default());
            super::halve_rows(top, bottom, rest);
        }
    }
}

/// The levels of one image, kept from frame to frame (their buffers are reused while the
/// image size stays the same): level 0 the image itself (in kornia's image type, which the
/// detector reads), level `k` the image halved `k` times ([`halve_into`]).
#[derive(Default)]
pub(super) struct Pyramid {
    levels: Vec<Image<u8, 1>>,
}

impl Pyramid {
    /// Level 0: a copy of `image` (`None` when its buffer is short).
    pub(super) fn set<C: Pixels>(&mut self, image: &GreyBuffer<C>) -> Option<&Image<u8, 1>> {
        let size = ImageSize { width: image.width() as usize, height: image.height() as usize };
        let pixels: &[u8] = image.as_raw();
        let pixels = pixels.get(..size.width * size.height)?;
        self.resize(0, size)?.as_slice_mut().copy_from_slice(pixels);
        self.levels.first()
    }

    /// Level `k` from level `k - 1` (which must be set), `None` when either is missing or
    /// the level would be empty.
    pub(super) fn halve(&mut self, k: usize) -> Option<&Image<u8, 1>> {
        let finer = self.levels.get(k.checked_sub(1)?)?;
        let (width, size) = (finer.width(), ImageSize { width: finer.width() / 2, height: finer.height() / 2 });
        if size.width == 0 || size.height == 0 {
            return None;
        }
        self.resize(k, size)?;
        let (finer, coarser) = self.levels.split_at_mut(k);
        let level = coarser.first_mut()?;
        halve_into(finer.last()?.as_slice(), width, level.as_slice_mut(), size.width);
        self.levels.get(k)
    }

    /// Level `k` (at most one past the last) with `size`, a new buffer when its size changed.
    fn resize(&mut self, k: usize, size: ImageSize) -> Option<&mut Image<u8, 1>> {
        if self.levels.get(k).is_none_or(|l| l.size() != size) {
            let level = Image::from_size_val(size, 0).ok()?;
            match self.levels.get_mut(k) {
                Some(old) => *old = level,
                None => self.levels.push(level),
            }
        }
        self.levels.get_mut(k)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::vision::image::GreyImage;

    fn halve(image: &GreyImage) -> GreyImage {
        let (w, h) = (image.width() / 2, image.height() / 2);
        let mut out = vec![0; w as usize * h as usize];
        halve_into(image.as_raw(), image.width() as usize, &mut out, w as usize);
        GreyImage::from_raw(w, h, out).unwrap()
    }

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

    #[test]
    fn wide_rows_give_the_rounded_mean_of_every_four_pixels() {
        // Rows long enough for the 32-pixel blocks (and their tails, odd widths included):
        // each pixel is the mean of its four rounded half up, computed from get_pixel.
        for width in [64, 65, 127, 131, 200] {
            let image = GreyImage::from_fn(width, 6, |u, v| {
                ::image::Luma([((u * 97 + v * 61 + (u ^ v) * 211 + u * u * v) % 256) as u8])
            });
            let half = halve(&image);
            for (u, v, p) in half.enumerate_pixels() {
                let sum: u32 = [(0, 0), (1, 0), (0, 1), (1, 1)]
                    .iter()
                    .map(|(a, b)| u32::from(image.get_pixel(2 * u + a, 2 * v + b)[0]))
                    .sum();
                assert_eq!(u32::from(p[0]), (sum + 2) / 4, "width {width}, pixel {u} {v}");
            }
        }
        // The brightest image stays at 255 (no lane overflows).
        let white = GreyImage::from_pixel(130, 4, ::image::Luma([255]));
        assert!(halve(&white).pixels().all(|p| p[0] == 255));
    }

    #[test]
    fn the_kept_levels_are_the_image_halved_again_and_again_whatever_came_before() {
        let image = |w, h, seed: u32| {
            GreyImage::from_fn(w, h, |u, v| ::image::Luma([((u * 29 + v * 53 + seed * u * v) % 251) as u8]))
        };
        let mut pyramid = Pyramid::default();
        // Sizes that change from frame to frame, and back: every level is rebuilt or reused.
        for (w, h, seed) in [(67, 45, 1), (64, 48, 2), (67, 45, 3), (9, 3, 4), (67, 45, 5)] {
            let frame = image(w, h, seed);
            let mut expected = frame.clone();
            assert_eq!(pyramid.set(&frame).unwrap().as_slice(), expected.as_raw().as_slice());
            for k in 1.. {
                expected = halve(&expected);
                match pyramid.halve(k) {
                    Some(level) => {
                        assert_eq!((level.width() as u32, level.height() as u32), expected.dimensions());
                        assert_eq!(level.as_slice(), expected.as_raw().as_slice(), "{w} x {h}, level {k}");
                    }
                    None => {
                        assert!(expected.width() == 0 || expected.height() == 0);
                        break;
                    }
                }
            }
        }
    }
}
