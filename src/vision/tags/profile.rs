//! A grey profile across an edge, bilinear samples at half-pixel steps along a ray, and where
//! the edge crosses it ([`edges`](super::edges) reads about 9,400 in a 640 x 480 photograph of
//! 12 tags).
//!
//! [`read_profile`] and [`crossing_in_profile`] are the definition: each sample as
//! [`sample`](super::edges) reads it, and where the edge crosses the profile. On a processor
//! with AVX2, [`crossings_along`] reads four profiles at a time, one in each `f64` lane, by the
//! same operations in the same order, so the two give the same bits (tested); the work of a
//! profile outside its samples (its ends' levels, its integral, the crossing) is then shared
//! by four.

use super::edges::inside;
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

/// Where the edge crosses a profile, as a signed distance from the ray's point, and the edge's
/// width ([`crossing_in_profile`]).
pub(super) type Crossing = Option<(f64, Option<f64>)>;

/// Least contrast between the border and the quiet zone, grey levels.
const MIN_CONTRAST: f64 = 10.0;

/// [`crossing_in_profile`] of the rays through each of `points` along `out` reaching `reach`
/// (levels read as `255 - g` when `reversed`; widths when `want_width`): `found(i, crossing)` for
/// each point in order. With AVX2 four rays at a time, one in each lane ([`Lanes`]), bit for
/// bit the same.
pub(super) fn crossings_along<C: Pixels>(
    image: &GreyBuffer<C>,
    points: &[[f64; 2]],
    out: [f64; 2],
    reach: f64,
    (reversed, want_width): (bool, bool),
    mut found: impl FnMut(usize, Crossing),
) {
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = pulp::x86::V3::try_new() {
        return simd.vectorize(Lanes { simd, image, points, out, reach, reversed, want_width, found });
    }
    for (i, &p) in points.iter().enumerate() {
        let ray = Ray::across(p, out, reach, reversed);
        found(i, crossing_in_profile(image, ray, want_width, |profile| read_profile(image, ray, profile)));
    }
}

/// Where the edge crosses the profile `ray` (from the square outwards), as a signed distance
/// from its point, its samples read by `read`. The profile, scaled from its black end (0) to
/// its white end (1), is a step blurred by the lens and the pixels' area: its integral over
/// the profile is the length on the white side of the edge, exactly so for a pixel-area or a
/// symmetric blur (the level-crossing of a pixel-sampled step is off by up to a tenth of a
/// pixel). With `want_width`, the distance between the profile's first crossings of the levels
/// a quarter and three quarters of the way from black to white on either side of the edge
/// (`None` when one is not inside the profile). `None` when its ends are not both inside the
/// image, without contrast, or when the edge is not inside the profile.
#[inline(always)]
pub(super) fn crossing_in_profile<C: Pixels>(
    image: &GreyBuffer<C>,
    ray: Ray,
    want_width: bool,
    read: impl FnOnce(&mut [f64; PROFILE_SAMPLES]) -> Option<()>,
) -> Crossing {
    if ray.samples > PROFILE_SAMPLES || !ends_inside(image, ray) {
        return None;
    }
    let mut profile = [0.0f64; PROFILE_SAMPLES];
    read(&mut profile)?;
    let steps = ray.samples - 1;
    let (black, white) = ((profile[0] + profile[1]) / 2.0, (profile[steps] + profile[steps - 1]) / 2.0);
    // Trapezoid rule: the integral of the piecewise linear profile.
    let whiteness = |v: f64| (v - black) / (white - black);
    let inner: f64 = profile[1..steps].iter().map(|&v| whiteness(v)).sum();
    let area = STEP * (inner + (whiteness(profile[0]) + whiteness(profile[steps])) / 2.0);
    found_edge(|k| profile[k], ray, want_width, [black, white], -ray.start - area)
}

/// Whether the first and last samples of `ray` are inside the image's pixel centres: each
/// coordinate is monotonic along the ray, so every sample then is, and is read without a check.
#[inline(always)]
fn ends_inside<C: Pixels>(image: &GreyBuffer<C>, ray: Ray) -> bool {
    let at = |k: usize| {
        let o = ray.start + STEP * k as f64;
        [ray.p[0] + ray.out[0] * o, ray.p[1] + ray.out[1] * o]
    };
    inside(image, at(0)) && inside(image, at(ray.samples - 1))
}

/// The crossing `edge` of a read profile (sample `k` at level `profile(k)`) whose ends are at
/// levels `black` and `white`, when it has the contrast and lies inside the profile, with its
/// width when `want_width`.
#[inline(always)]
fn found_edge(
    profile: impl Fn(usize) -> f64,
    ray: Ray,
    want_width: bool,
    [black, white]: [f64; 2],
    edge: f64,
) -> Crossing {
    if white - black < MIN_CONTRAST || edge.abs() > -ray.start - 1.0 {
        return None;
    }
    if !want_width {
        return Some((edge, None));
    }
    // The sample at the edge, then outwards to the first sample past each quartile level.
    let (steps, start) = (ray.samples - 1, ray.start);
    let whiteness = |v: f64| (v - black) / (white - black);
    let at_edge = (((edge - start) / STEP).round() as usize).min(steps);
    let level_at = |level: f64, outwards: bool| -> Option<f64> {
        let (mut k, w) = (at_edge, |k: usize| whiteness(profile(k)));
        loop {
            let next = if outwards { k.checked_add(1).filter(|&n| n <= steps)? } else { k.checked_sub(1)? };
            let (inside, outside) = if outwards { (w(k), w(next)) } else { (w(next), w(k)) };
            if (inside - level) * (outside - level) <= 0.0 && inside != outside {
                let (lo, hi) = if outwards { (k, next) } else { (next, k) };
                let t = (level - w(lo)) / (w(hi) - w(lo));
                return Some(start + STEP * (lo as f64 + t));
            }
            k = next;
        }
    };
    let width = level_at(0.75, true).zip(level_at(0.25, false)).map(|(hi, lo)| hi - lo);
    Some((edge, width))
}

/// [`crossings_along`] in AVX2 lanes, run by `pulp` (`simd.vectorize`): four rays at a time,
/// one in each `f64` lane, their samples read together (the coordinates' whole parts converted
/// in one instruction, each pixel's four neighbours widened together), and their contrast, the
/// profile's integral and the crossing computed in the lanes, each lane by the very operations
/// of [`crossing_in_profile`] in its order (the integral's sum from -0, as `Iterator::sum`).
#[cfg(target_arch = "x86_64")]
struct Lanes<'a, C: Pixels, F: FnMut(usize, Crossing)> {
    simd: pulp::x86::V3,
    image: &'a GreyBuffer<C>,
    points: &'a [[f64; 2]],
    out: [f64; 2],
    reach: f64,
    reversed: bool,
    want_width: bool,
    found: F,
}

#[cfg(target_arch = "x86_64")]
impl<C: Pixels, F: FnMut(usize, Crossing)> pulp::NullaryFnOnce for Lanes<'_, C, F> {
    type Output = ();

    #[inline(always)]
    fn call(self) {
        use core::arch::x86_64::__m256d;
        use pulp::bytemuck::cast;

        let Self { simd, image, points, out, reach, reversed, want_width, mut found } = self;
        let avx = simd.avx;
        let splat = |x: f64| avx._mm256_set1_pd(x);
        let Some(first) = points.first() else { return };
        let ray = Ray::across(*first, out, reach, reversed);
        let Some(grid) = Grid::of(image).filter(|_| ray.samples <= PROFILE_SAMPLES) else {
            return (0..points.len()).for_each(|i| found(i, None));
        };
        let (samples, steps) = (ray.samples, ray.samples - 1);
        let (two, half_step, neg_start) = (splat(2.0), splat(STEP), splat(-ray.start));
        for (c, chunk) in points.chunks(4).enumerate() {
            // The last chunk's missing lanes repeat its last ray (their results are dropped).
            let lane = |l: usize| chunk[l.min(chunk.len() - 1)];
            let (pu, pv): (__m256d, __m256d) =
                (cast([0, 1, 2, 3].map(|l| lane(l)[0])), cast([0, 1, 2, 3].map(|l| lane(l)[1])));
            let mut levels = [avx._mm256_setzero_pd(); PROFILE_SAMPLES];
            for (k, level) in levels.iter_mut().enumerate().take(samples) {
                let o = ray.start + STEP * k as f64;
                let (u, v) = (avx._mm256_add_pd(pu, splat(out[0] * o)), avx._mm256_add_pd(pv, splat(out[1] * o)));
                let Some(g) = bilinear_lanes(simd, &grid, u, v) else {
                    return (c * 4..points.len()).for_each(|i| found(i, None));
                };
                *level = if reversed { avx._mm256_sub_pd(splat(255.0), g) } else { g };
            }
            let black = avx._mm256_div_pd(avx._mm256_add_pd(levels[0], levels[1]), two);
            let white = avx._mm256_div_pd(avx._mm256_add_pd(levels[steps], levels[steps - 1]), two);
            let contrast = avx._mm256_sub_pd(white, black);
            let whiteness = |v: __m256d| avx._mm256_div_pd(avx._mm256_sub_pd(v, black), contrast);
            let inner = levels[1..steps].iter().fold(splat(-0.0), |sum, &v| avx._mm256_add_pd(sum, whiteness(v)));
            let ends = avx._mm256_div_pd(avx._mm256_add_pd(whiteness(levels[0]), whiteness(levels[steps])), two);
            let area = avx._mm256_mul_pd(half_step, avx._mm256_add_pd(inner, ends));
            let edges: [f64; 4] = cast(avx._mm256_sub_pd(neg_start, area));
            let (blacks, whites): ([f64; 4], [f64; 4]) = (cast(black), cast(white));
            let columns: [[f64; 4]; PROFILE_SAMPLES] = cast(levels);
            for (l, &p) in chunk.iter().enumerate() {
                let ray = Ray { p, ..ray };
                let crossing = ends_inside(image, ray)
                    .then(|| found_edge(|k| columns[k][l], ray, want_width, [blacks[l], whites[l]], edges[l]));
                found(4 * c + l, crossing.flatten());
            }
        }
    }
}

/// The bilinear levels at four points `(u, v)` (lanes), each as [`read_profile`] reads one;
/// `None` only if a square were outside the image (never: the coordinates are held inside).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn bilinear_lanes(
    simd: pulp::x86::V3,
    grid: &Grid,
    u: core::arch::x86_64::__m256d,
    v: core::arch::x86_64::__m256d,
) -> Option<core::arch::x86_64::__m256d> {
    use core::arch::x86_64::{__m256d, _MM_FROUND_NO_EXC, _MM_FROUND_TO_ZERO};
    use pulp::bytemuck::cast;

    let (avx, sse2, sse41) = (simd.avx, simd.sse2, simd.sse4_1);
    let zero = avx._mm256_setzero_pd();
    // `max(0, min(x, last))` is `clamp(x, last)` bit for bit (a -0 stays -0).
    let held = |x: __m256d, last: f64| avx._mm256_max_pd(zero, avx._mm256_min_pd(x, avx._mm256_set1_pd(last)));
    let trunc = |x: __m256d| avx._mm256_round_pd::<{ _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC }>(x);
    let (u0, v0) = (trunc(held(u, grid.last_u)), trunc(held(v, grid.last_v)));
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
    let widen = |word: u32| avx._mm256_cvtepi32_pd(sse41._mm_cvtepu8_epi32(sse2._mm_cvtsi32_si128(word as i32)));
    let [a, b, c, d] = [widen(words[0]), widen(words[1]), widen(words[2]), widen(words[3])];
    let one = avx._mm256_set1_pd(1.0);
    let (fu1, fv1) = (avx._mm256_sub_pd(one, fu), avx._mm256_sub_pd(one, fv));
    let top = avx._mm256_add_pd(avx._mm256_mul_pd(a, fu1), avx._mm256_mul_pd(b, fu));
    let bottom = avx._mm256_add_pd(avx._mm256_mul_pd(c, fu1), avx._mm256_mul_pd(d, fu));
    Some(avx._mm256_add_pd(avx._mm256_mul_pd(top, fv1), avx._mm256_mul_pd(bottom, fv)))
}

/// [`crossing_in_profile`] of the one ray through `p` (as [`crossings_along`] finds it).
#[cfg(test)]
pub(super) fn crossing_and_width<C: Pixels>(
    image: &GreyBuffer<C>,
    p: [f64; 2],
    out: [f64; 2],
    reach: f64,
    flags: (bool, bool),
) -> Crossing {
    let mut crossing = None;
    crossings_along(image, &[p], out, reach, flags, |_, found| crossing = found);
    crossing
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::vision::image::GreyImage;
    use crate::vision::tags::edges::sample;
    use crate::vision::tags::synthetic::Rng;

    /// Rays in every direction through points all over a 37 x 29 image, some ending on its last
    /// row and column, some along its first row and column (coordinates of 0 and -0).
    fn rays(count: u32) -> impl Iterator<Item = ([f64; 2], [f64; 2], usize)> {
        (0..count).map(|k| {
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
            (p, out, 6 + k as usize % 20)
        })
    }

    #[test]
    fn a_profile_is_read_as_its_samples_one_by_one_bit_for_bit() {
        let image = GreyImage::from_fn(37, 29, |u, v| ::image::Luma([((u * 71 + v * 113 + u * v * 7) % 256) as u8]));
        let mut checked = 0;
        for (p, out, steps) in rays(800) {
            let start = -(steps as f64) * STEP / 2.0;
            let ray = Ray { p, out, start, samples: steps + 1, reversed: false };
            if !ends_inside(&image, ray) {
                continue;
            }
            for reversed in [false, true] {
                let mut profile = [0.0; PROFILE_SAMPLES];
                read_profile(&image, Ray { reversed, ..ray }, &mut profile).unwrap();
                for (k, value) in profile.iter().enumerate().take(steps + 1) {
                    let o = start + STEP * k as f64;
                    let g = sample(&image, p[0] + out[0] * o, p[1] + out[1] * o).unwrap();
                    let expected = if reversed { 255.0 - g } else { g };
                    assert_eq!(value.to_bits(), expected.to_bits(), "ray {p:?} {out:?}, sample {k}");
                }
            }
            checked += 1;
        }
        assert!(checked > 200, "{checked} rays inside the image");
    }

    #[test]
    fn rays_read_in_lanes_cross_where_each_alone_does_bit_for_bit() {
        // Edges in every direction, blurred, with noise, faint ones (under the least contrast)
        // and rays that leave the image: batches of 1 to 9 rays along one direction (whole
        // groups of four and remainders) against each ray's scalar crossing.
        let mut rng = Rng(17);
        let image = GreyImage::from_fn(61, 47, |u, v| {
            let (x, y) = (f64::from(u) - 30.0, f64::from(v) - 23.0);
            let step = if 0.8 * x + 0.6 * y > 0.0 { 200.0 } else { 40.0 };
            let faint = if x < -20.0 { 0.05 } else { 1.0 };
            ::image::Luma([(40.0 + (step - 40.0) * faint + f64::from((u * 37 + v * 11) % 9)).min(255.0) as u8])
        });
        let (mut found, mut none, mut widths) = (0, 0, 0);
        for k in 0..600u32 {
            // Near the edge (normal (0.8, 0.6) through (30, 23)), across it at up to 0.6 rad
            // from its normal, a tenth of them the other way (from white to black: no crossing).
            let angle = 0.6435 + (rng.unit() - 0.5) * 1.2 + if k % 10 == 9 { std::f64::consts::PI } else { 0.0 };
            let out = [angle.cos(), angle.sin()];
            let along = [-out[1], out[0]];
            let count = 1 + k as usize % 9;
            let (t, off) = ((rng.unit() - 0.5) * 70.0, (rng.unit() - 0.5) * 4.0);
            let first = [30.0 - 0.6 * t + 0.8 * off, 23.0 + 0.8 * t + 0.6 * off];
            let points: Vec<[f64; 2]> = (0..count)
                .map(|i| [first[0] + along[0] * 1.3 * i as f64, first[1] + along[1] * 1.3 * i as f64])
                .collect();
            let reach = 1.5 + rng.unit() * 5.0;
            for flags in [(false, false), (false, true), (true, true)] {
                let mut lanes = vec![None; count];
                crossings_along(&image, &points, out, reach, flags, |i, c| lanes[i] = Some(c));
                for (&p, lane) in points.iter().zip(&lanes) {
                    let ray = Ray::across(p, out, reach, flags.0);
                    let alone = crossing_in_profile(&image, ray, flags.1, |profile| read_profile(&image, ray, profile));
                    let bits = |c: Crossing| c.map(|(e, w)| (e.to_bits(), w.map(f64::to_bits)));
                    assert_eq!(lane.map(bits), Some(bits(alone)), "ray {p:?} {out:?} reach {reach} {flags:?}");
                    match alone {
                        Some((_, w)) => (found, widths) = (found + 1, widths + usize::from(w.is_some())),
                        None => none += 1,
                    }
                }
            }
        }
        assert!(found > 2000 && none > 500 && widths > 1000, "{found} crossings, {none} none, {widths} widths");
    }
}
