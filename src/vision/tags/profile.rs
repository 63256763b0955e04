//! A grey profile across an edge: bilinear samples at half-pixel steps along a ray
//! ([`edges`](super::edges) reads one per crossing, about 9,400 in a 640 x 480 photograph of 12
//! tags).
//!
//! [`read_profile`] is the definition: each sample as [`sample`](super::edges) reads it, four
//! samples at a time. On a processor with AVX2, [`Avx2Profile`] does the same operations in the
//! same order on four `f64` lanes, with the whole-pixel coordinates converted in one
//! instruction and each pixel's four neighbours widened together, so the two give the same
//! bits (tested).

use crate::vision::image::{GreyBuffer, Pixels};

/// The most samples a profile reads (a reach of 6 px is 25 half-pixel steps).
pub(super) const PROFILE_SAMPLES: usize = 32;

/// Half-pixel steps across the edge.
pub(super) const STEP: f64 = 0.5;

/// A profile's samples: `samples` points `p + (start + STEP k) out`, read as `255 - g` when
/// `reversed`.
#[derive(Clone, Copy)]
pub(super) struct Ray {
    pub p: [f64; 2],
    pub out: [f64; 2],
    pub start: f64,
    pub samples: usize,
    pub reversed: bool,
}

impl Ray {
    /// The profile through `p` along `out` reaching `reach` on each side, in half-pixel steps.
    pub fn across(p: [f64; 2], out: [f64; 2], reach: f64, reversed: bool) -> Self {
        let steps = (2.0 * reach / STEP).round() as usize;
        Self { p, out, start: -(steps as f64) * STEP / 2.0, samples: steps + 1, reversed }
    }
}

/// Where a ray's samples are read: the image's bytes, its row stride, the last column and row
/// a sample's square starts at, and the last byte offset one may start at.
struct Grid<'a> {
    pixels: &'a [u8],
    stride: usize,
    last_u: f64,
    last_v: f64,
    last: usize,
}

impl<'a> Grid<'a> {
    fn of<C: Pixels>(image: &'a GreyBuffer<C>) -> Option<Self> {
        let stride = image.width() as usize;
        let pixels: &[u8] = image.as_raw();
        Some(Self {
            pixels,
            stride,
            last_u: f64::from(image.width().saturating_sub(2)),
            last_v: f64::from(image.height().saturating_sub(2)),
            last: pixels.len().checked_sub(stride + 2)?,
        })
    }

    /// The four pixels of the square whose top left pixel is at byte `first`:
    /// `[top left, top right, bottom left, bottom right]`.
    #[inline(always)]
    fn square(&self, first: usize) -> Option<[u8; 4]> {
        let top = self.pixels.get(first..first + 2)?;
        let bottom = self.pixels.get(first + self.stride..first + self.stride + 2)?;
        Some([top[0], top[1], bottom[0], bottom[1]])
    }
}

/// `x` held in `[0, last]`: 0 below it, `last` at or above `last` (comparisons, not
/// `f64::clamp`, whose NaN rule keeps it out of the vector lanes: the coordinates are finite).
#[inline(always)]
fn clamp(x: f64, last: f64) -> f64 {
    if x < 0.0 {
        0.0
    } else if x < last {
        x
    } else {
        last
    }
}

/// The grey levels of the ray's samples, each bilinear as [`sample`](super::edges) reads it
/// (the same operations in the same order, so the same bits), all of them known to be inside
/// the image: the coordinates and weights of four samples at a time, then their pixels, then
/// their levels.
#[inline(always)]
pub(super) fn read_profile<C: Pixels>(
    image: &GreyBuffer<C>,
    ray: Ray,
    profile: &mut [f64; PROFILE_SAMPLES],
) -> Option<()> {
    let grid = Grid::of(image)?;
    for (c, chunk) in profile.chunks_exact_mut(4).enumerate().take(ray.samples.div_ceil(4)) {
        let (mut fu, mut fv, mut first) = ([0.0; 4], [0.0; 4], [0usize; 4]);
        for l in 0..4 {
            let o = ray.start + STEP * (4 * c + l) as f64;
            let (u, v) = (ray.p[0] + ray.out[0] * o, ray.p[1] + ray.out[1] * o);
            // `u, v >= 0` inside the image: truncation is the floor, and the last column (row)
            // is read between the one before it and itself, as in `sample`. A lane past the
            // profile's end may be outside the image: held inside it, its level is never read.
            let (u0, v0) = (clamp(u, grid.last_u).trunc(), clamp(v, grid.last_v).trunc());
            (fu[l], fv[l]) = (u - u0, v - v0);
            first[l] = (v0 as usize * grid.stride + u0 as usize).min(grid.last);
        }
        for l in 0..4 {
            let [a, b, c, d] = grid.square(first[l])?.map(f64::from);
            let g = (a * (1.0 - fu[l]) + b * fu[l]) * (1.0 - fv[l]) + (c * (1.0 - fu[l]) + d * fu[l]) * fv[l];
            chunk[l] = if ray.reversed { 255.0 - g } else { g };
        }
    }
    Some(())
}

/// [`read_profile`] in AVX2 lanes, run by `pulp` (`simd.vectorize`).
#[cfg(target_arch = "x86_64")]
pub(super) struct Avx2Profile<'a, C: Pixels> {
    pub simd: pulp::x86::V3,
    pub image: &'a GreyBuffer<C>,
    pub ray: Ray,
    pub profile: &'a mut [f64; PROFILE_SAMPLES],
}

#[cfg(target_arch = "x86_64")]
impl<C: Pixels> pulp::NullaryFnOnce for Avx2Profile<'_, C> {
    type Output = Option<()>;

    #[inline(always)]
    fn call(self) -> Option<()> {
        use core::arch::x86_64::{__m256d, _MM_FROUND_NO_EXC, _MM_FROUND_TO_ZERO};
        use pulp::bytemuck::cast;

        let Self { simd, image, ray, profile } = self;
        let (avx, sse2, sse41) = (simd.avx, simd.sse2, simd.sse4_1);
        let grid = Grid::of(image)?;
        let splat = |x: f64| avx._mm256_set1_pd(x);
        let (zero, one, step) = (avx._mm256_setzero_pd(), splat(1.0), splat(STEP));
        let (start, last_u, last_v) = (splat(ray.start), splat(grid.last_u), splat(grid.last_v));
        let (pu, pv, ou, ov) = (splat(ray.p[0]), splat(ray.p[1]), splat(ray.out[0]), splat(ray.out[1]));
        // `max(0, min(x, last))` is `clamp(x, last)` bit for bit (a -0 stays -0).
        let held = |x: __m256d, last: __m256d| avx._mm256_max_pd(zero, avx._mm256_min_pd(x, last));
        let trunc = |x: __m256d| avx._mm256_round_pd::<{ _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC }>(x);
        // Each lane's level from one byte of a 32-bit word (levels of four lanes a word).
        let widen = |word: i32| avx._mm256_cvtepi32_pd(sse41._mm_cvtepu8_epi32(sse2._mm_cvtsi32_si128(word)));
        let mut ks: __m256d = cast([0.0, 1.0, 2.0, 3.0]);
        for chunk in profile.chunks_exact_mut(4).take(ray.samples.div_ceil(4)) {
            let o = avx._mm256_add_pd(start, avx._mm256_mul_pd(step, ks));
            let u = avx._mm256_add_pd(pu, avx._mm256_mul_pd(ou, o));
            let v = avx._mm256_add_pd(pv, avx._mm256_mul_pd(ov, o));
            let (u0, v0) = (trunc(held(u, last_u)), trunc(held(v, last_v)));
            let (fu, fv) = (avx._mm256_sub_pd(u, u0), avx._mm256_sub_pd(v, v0));
            let (cu, cv): ([i32; 4], [i32; 4]) = (cast(avx._mm256_cvttpd_epi32(u0)), cast(avx._mm256_cvttpd_epi32(v0)));
            // The squares' pixels by corner: byte `l` of word `k` is corner `k` of lane `l`.
            let mut words = [0u32; 4];
            for l in 0..4 {
                let first = (cv[l] as usize * grid.stride + cu[l] as usize).min(grid.last);
                for (word, level) in words.iter_mut().zip(grid.square(first)?) {
                    *word |= u32::from(level) << (8 * l);
                }
            }
            let [a, b, c, d] = words.map(|w| widen(w as i32));
            let (gu, fu1, fv1) = (fu, avx._mm256_sub_pd(one, fu), avx._mm256_sub_pd(one, fv));
            let top = avx._mm256_add_pd(avx._mm256_mul_pd(a, fu1), avx._mm256_mul_pd(b, gu));
            let bottom = avx._mm256_add_pd(avx._mm256_mul_pd(c, fu1), avx._mm256_mul_pd(d, gu));
            let mut g = avx._mm256_add_pd(avx._mm256_mul_pd(top, fv1), avx._mm256_mul_pd(bottom, fv));
            if ray.reversed {
                g = avx._mm256_sub_pd(splat(255.0), g);
            }
            let levels: [f64; 4] = cast(g);
            chunk.copy_from_slice(&levels);
            ks = avx._mm256_add_pd(ks, splat(4.0));
        }
        Some(())
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::vision::image::GreyImage;
    use crate::vision::tags::edges::{inside, sample};

    #[test]
    fn a_profile_is_read_as_its_samples_one_by_one_bit_for_bit() {
        // The four-lane reading, and the AVX2 one where the processor has it, against `sample`
        // at each point, on rays in every direction that end on the image's last row and
        // column too, and on rays through the first row and column (coordinates of 0 and -0).
        let image = GreyImage::from_fn(37, 29, |u, v| ::image::Luma([((u * 71 + v * 113 + u * v * 7) % 256) as u8]));
        let mut checked = 0;
        for k in 0..800 {
            let angle = f64::from(k) * 0.731;
            let out = if k % 4 == 3 {
                [[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]][k as usize / 4 % 4]
            } else {
                [angle.cos(), angle.sin()]
            };
            let p = if k % 8 == 7 {
                [f64::from(k % 33), f64::from(k % 5) * -0.0]
            } else {
                [2.0 + f64::from(k % 33) * 1.03, 2.0 + f64::from(k % 25) * 1.01]
            };
            let steps = 6 + k as usize % 20;
            let start = -(steps as f64) * STEP / 2.0;
            let at = |k: usize| [p[0] + out[0] * (start + STEP * k as f64), p[1] + out[1] * (start + STEP * k as f64)];
            if !inside(&image, at(0)) || !inside(&image, at(steps)) {
                continue;
            }
            for reversed in [false, true] {
                let ray = Ray { p, out, start, samples: steps + 1, reversed };
                let mut profile = [0.0; PROFILE_SAMPLES];
                read_profile(&image, ray, &mut profile).unwrap();
                let mut readings = vec![profile];
                #[cfg(target_arch = "x86_64")]
                if let Some(simd) = pulp::x86::V3::try_new() {
                    let mut profile = [0.0; PROFILE_SAMPLES];
                    simd.vectorize(Avx2Profile { simd, image: &image, ray, profile: &mut profile }).unwrap();
                    readings.push(profile);
                }
                for (k, value) in readings.iter().flat_map(|r| r.iter().enumerate().take(steps + 1)) {
                    let [u, v] = at(k);
                    let g = sample(&image, u, v).unwrap();
                    let expected = if reversed { 255.0 - g } else { g };
                    assert_eq!(value.to_bits(), expected.to_bits(), "ray {p:?} {out:?}, sample {k}");
                }
            }
            checked += 1;
        }
        assert!(checked > 200, "{checked} rays inside the image");
    }
}
