//! The sums of a large dot's pixels for its centroid ([`centroid`](super::centroid)), over one
//! run: per pixel `above = g - b(u, v)` (its level over the background plane) and
//! - of the dot's own pixels ([`own_sums`]), `weight = max(above, 0)`, summed as
//!   `[above, weight, weight u, weight v]`;
//! - of the background ([`background_sums`]), `weight = above` above the noise floor (its
//!   anti-aliased edge), 0 under it, summed as `[weight, weight u, weight v]`;
//!
//! in [`LANES`] interleaved partial sums (pixel `i` of the run into lane `i % LANES`), each lane
//! summed left to right.
//!
//! Speed: on a processor with AVX2 the four lanes are the four `f64` of one 256-bit register,
//! through `pulp`'s safe wrappers of the intrinsics (`pulp::x86::V3`, detected at run time: no
//! `unsafe` here): each lane does the very operations of the scalar loop in the same order
//! (no fused multiply-add), so both give the same sums bit for bit (tested). Elsewhere the
//! scalar loop.

/// Partial sums per [`own_sums`] call.
pub const LANES: usize = 4;

/// The background plane `b(u, v) = a + b_u (u - u_c) + b_v (v - v_c)`.
#[derive(Debug, Clone, Copy)]
pub struct Plane {
    /// `[a, b_u, b_v]`.
    pub coefficients: [f64; 3],
    /// `[u_c, v_c]`.
    pub centre: [f64; 2],
}

impl Plane {
    /// The background at pixel `(u, v)`.
    #[inline(always)]
    pub fn at(&self, u: u32, v: u32) -> f64 {
        let [a, bu, bv] = self.coefficients;
        a + bu * (f64::from(u) - self.centre[0]) + bv * (f64::from(v) - self.centre[1])
    }
}

/// `[own, sum, su, sv]` over a run of the dot's own pixels, `segment` starting at column
/// `u0` of row `v`, levels `g ^ flip` (see the module's documentation).
pub fn own_sums(segment: &[u8], flip: u8, u0: u32, v: u32, plane: &Plane) -> [f64; 4] {
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = pulp::x86::V3::try_new() {
        return simd.vectorize(avx2::LaneSums { simd, segment, flip, u0, v, plane, floor: None });
    }
    reduce(scalar_lanes(segment, flip, u0, v, plane, None))
}

/// `[sum, su, sv]` over a run of background pixels, `segment` starting at column `u0` of row
/// `v`, levels `g ^ flip`, the pixels at most `floor` above the plane weighing nothing (see the
/// module's documentation).
pub fn background_sums(segment: &[u8], flip: u8, u0: u32, v: u32, plane: &Plane, floor: f64) -> [f64; 3] {
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = pulp::x86::V3::try_new() {
        let [_, sum, su, sv] = simd.vectorize(avx2::LaneSums { simd, segment, flip, u0, v, plane, floor: Some(floor) });
        return [sum, su, sv];
    }
    let [_, sum, su, sv] = reduce(scalar_lanes(segment, flip, u0, v, plane, Some(floor)));
    [sum, su, sv]
}

/// The four lanes' sums into one: `(l0 + l1) + (l2 + l3)`.
fn reduce(lanes: [[f64; LANES]; 4]) -> [f64; 4] {
    lanes.map(|l| (l[0] + l[1]) + (l[2] + l[3]))
}

/// The lanes pixel by pixel (the definition): the own pixels' sums, or with a `floor` the
/// background's.
fn scalar_lanes(segment: &[u8], flip: u8, u0: u32, v: u32, plane: &Plane, floor: Option<f64>) -> [[f64; LANES]; 4] {
    let mut lanes = [[0.0f64; LANES]; 4];
    add_pixels(&mut lanes, segment, flip, (u0, v), plane, floor);
    lanes
}

/// The weight of a pixel `above` the plane in a centroid: its positive part for the dot's own
/// pixels (`floor` None), itself above the background's noise `floor` and 0 under it (and for a
/// NaN, as `f64::max`).
#[inline(always)]
pub(crate) fn weight(above: f64, floor: Option<f64>) -> f64 {
    match floor {
        None => above.max(0.0),
        Some(floor) if above > floor => above,
        Some(_) => 0.0,
    }
}

/// Adds pixels `segment` (from column `u0` of row `v`, its first pixel in lane 0) to `lanes`.
#[inline(always)]
fn add_pixels(
    lanes: &mut [[f64; LANES]; 4],
    segment: &[u8],
    flip: u8,
    (u0, v): (u32, u32),
    plane: &Plane,
    floor: Option<f64>,
) {
    let fv = f64::from(v);
    for (i, &g) in segment.iter().enumerate() {
        let (lane, u) = (i % LANES, u0 + i as u32);
        let above = f64::from(g ^ flip) - plane.at(u, v);
        let weight = weight(above, floor);
        lanes[0][lane] += above;
        lanes[1][lane] += weight;
        lanes[2][lane] += weight * f64::from(u);
        lanes[3][lane] += weight * fv;
    }
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use core::arch::x86_64::{__m256d, _CMP_GT_OQ};

    use pulp::bytemuck::cast;
    use pulp::x86::V3;

    use super::{LANES, Plane, add_pixels, reduce};

    /// [`own_sums`](super::own_sums) and [`background_sums`](super::background_sums) compiled for AVX2.
    pub(super) struct LaneSums<'a> {
        pub simd: V3,
        pub segment: &'a [u8],
        pub flip: u8,
        pub u0: u32,
        pub v: u32,
        pub plane: &'a Plane,
        /// `None`: the dot's own pixels; `Some`: the background's, with its noise floor.
        pub floor: Option<f64>,
    }

    impl pulp::NullaryFnOnce for LaneSums<'_> {
        type Output = [f64; 4];

        #[inline(always)]
        fn call(self) -> [f64; 4] {
            let (simd, plane) = (self.simd, self.plane);
            let avx = simd.avx;
            let [a, bu, bv] = plane.coefficients;
            let splat = |x: f64| avx._mm256_set1_pd(x);
            // b(u, v) = (a + b_u (u - u_c)) + b_v (v - v_c), as the scalar loop evaluates it.
            let (a, bu, cu) = (splat(a), splat(bu), splat(plane.centre[0]));
            let row = splat(bv * (f64::from(self.v) - plane.centre[1]));
            let fv = splat(f64::from(self.v));
            let zero = avx._mm256_setzero_pd();
            let floor = self.floor.map(splat);
            let (mut own, mut sum, mut su, mut sv) = (zero, zero, zero, zero);
            let (chunks, tail) = self.segment.as_chunks::<LANES>();
            // Columns as f64 (whole numbers: the steps of 4 are exact); 4 levels widened to
            // 32-bit lanes, then to f64.
            let u = f64::from(self.u0);
            let mut us: __m256d = cast([u, u + 1.0, u + 2.0, u + 3.0]);
            let step = splat(LANES as f64);
            let flip = u32::from_ne_bytes([self.flip; 4]) as i32;
            for chunk in chunks {
                let bytes = simd.sse2._mm_cvtsi32_si128(i32::from_ne_bytes(*chunk) ^ flip);
                let g = avx._mm256_cvtepi32_pd(simd.sse4_1._mm_cvtepu8_epi32(bytes));
                let background =
                    avx._mm256_add_pd(avx._mm256_add_pd(a, avx._mm256_mul_pd(bu, avx._mm256_sub_pd(us, cu))), row);
                let above = avx._mm256_sub_pd(g, background);
                // max(above, 0): 0 for a NaN `above`, as f64::max; above the floor: `above`
                // where the (ordered) comparison holds, 0 elsewhere and for a NaN.
                let weight = match floor {
                    None => avx._mm256_max_pd(above, zero),
                    Some(floor) => avx._mm256_and_pd(above, avx._mm256_cmp_pd::<_CMP_GT_OQ>(above, floor)),
                };
                own = avx._mm256_add_pd(own, above);
                sum = avx._mm256_add_pd(sum, weight);
                su = avx._mm256_add_pd(su, avx._mm256_mul_pd(weight, us));
                sv = avx._mm256_add_pd(sv, avx._mm256_mul_pd(weight, fv));
                us = avx._mm256_add_pd(us, step);
            }
            let mut lanes: [[f64; LANES]; 4] = [cast(own), cast(sum), cast(su), cast(sv)];
            let u = self.u0 + (chunks.len() * LANES) as u32;
            add_pixels(&mut lanes, tail, self.flip, (u, self.v), plane, self.floor);
            reduce(lanes)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_vector_sums_are_the_scalar_ones_bit_for_bit() {
        // Runs of every length to 40 (whole chunks and tails), both polarities, planes with
        // and without slope, at columns and rows far from the centre; levels on both sides of
        // the plane (negative `above`, zero weights).
        let mut state = 21u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            state >> 33
        };
        for len in 0..40usize {
            for flip in [0u8, 255] {
                let segment: Vec<u8> = (0..len).map(|_| (next() % 256) as u8).collect();
                let plane = Plane {
                    coefficients: [
                        (next() % 2000) as f64 / 10.0,
                        (next() % 200) as f64 / 1e3 - 0.1,
                        (next() % 200) as f64 / 1e3 - 0.1,
                    ],
                    centre: [(next() % 4000) as f64 * 0.5, (next() % 3000) as f64 * 0.5],
                };
                let (u0, v) = ((next() % 3000) as u32, (next() % 2000) as u32);
                let scalar = reduce(scalar_lanes(&segment, flip, u0, v, &plane, None));
                let ours = own_sums(&segment, flip, u0, v, &plane);
                assert_eq!(ours.map(f64::to_bits), scalar.map(f64::to_bits), "len {len} flip {flip}");
                for floor in [0.0, 2.5, 40.0] {
                    let [_, sum, su, sv] = reduce(scalar_lanes(&segment, flip, u0, v, &plane, Some(floor)));
                    let ours = background_sums(&segment, flip, u0, v, &plane, floor);
                    assert_eq!(ours.map(f64::to_bits), [sum, su, sv].map(f64::to_bits), "len {len} floor {floor}");
                }
            }
        }
    }

    #[test]
    fn the_sums_are_those_of_the_pixels() {
        // A flat plane at 10: above = g - 10, weight its positive part.
        let segment = [30u8, 5, 10, 12, 200];
        let plane = Plane { coefficients: [10.0, 0.0, 0.0], centre: [0.0, 0.0] };
        let [own, sum, su, sv] = own_sums(&segment, 0, 100, 7, &plane);
        assert_eq!(own, 20.0 - 5.0 + 0.0 + 2.0 + 190.0);
        assert_eq!(sum, 20.0 + 2.0 + 190.0);
        assert_eq!(su, 20.0 * 100.0 + 2.0 * 103.0 + 190.0 * 104.0);
        assert_eq!(sv, 212.0 * 7.0);
        // The background above a floor of 2: only 30 (20) and 200 (190) weigh; 12 (2) does not.
        let [sum, su, sv] = background_sums(&segment, 0, 100, 7, &plane, 2.0);
        assert_eq!(sum, 20.0 + 190.0);
        assert_eq!(su, 20.0 * 100.0 + 190.0 * 104.0);
        assert_eq!(sv, 210.0 * 7.0);
    }
}
