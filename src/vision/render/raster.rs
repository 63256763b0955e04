//! Rasterising a shape of the ideal image: the area fraction of each pixel it covers (exact
//! inside and outside, supersampled 8 x 8 near the boundary, through the lens), an optional
//! Gaussian blur (the optical PSF), the sensor noise, clipping and quantisation to 8 bits,
//! composed over the image with `max` (overlapping shapes do not add up).

use nalgebra::Vector2;

use super::lens::{Local, Warp};
use super::noise::{Noise, quantise};
use crate::vision::image::GreyImage;

/// Supersampling per axis on boundary pixels.
const SUBSAMPLES: usize = 8;

/// A region of the ideal pinhole image, `value <= 0` inside.
pub(super) trait Shape {
    /// `[u_min, v_min, u_max, v_max]` of its pixels in the rendered image.
    fn bbox(&self) -> [f64; 4];
    /// The implicit function at ideal pixel `(u, v)`: `<= 0` inside.
    fn value(&self, u: f64, v: f64) -> f64;
    /// Its gradient at `(u, v)`.
    fn gradient(&self, u: f64, v: f64) -> Vector2<f64>;

    /// For a shape whose implicit function is a quadratic polynomial, the bound
    /// `sum |coefficient x monomial|` of its terms at `(u, v)` (None: not a quadratic): with
    /// [`Shape::second_order`] it lets the supersampling skip pixels whose samples all lie on
    /// one side.
    fn quadratic_scale(&self, _u: f64, _v: f64) -> Option<f64> {
        None
    }

    /// The second-order part `[a, b, c]` of a quadratic implicit function,
    /// `value(p + d) = value(p) + gradient(p) . d + a dx^2 + 2 b dx dy + c dy^2`.
    fn second_order(&self) -> [f64; 3] {
        [0.0; 3]
    }

    /// Whether every point of the shape lies within [`Shape::bbox`] (its tangent lines, to
    /// rounding): then, without a lens, the pixels more than one pixel beyond the box are
    /// known to be uncovered without evaluating them. False by default.
    fn bbox_holds_shape(&self) -> bool {
        false
    }

    /// The area fraction of each pixel of the patch inside the shape (pixel `(u, v)` covers
    /// `[u - 0.5, u + 0.5] x [v - 0.5, v + 0.5]`), row-major: by default exact inside and
    /// outside and supersampled near the boundary; a shape that knows its exact areas (a
    /// polygon) gives them.
    fn coverage(&self, patch: &Patch, warp: &Warp) -> Vec<f32>
    where
        Self: Sized,
    {
        let mut out = vec![0.0f32; patch.w * patch.h];
        // Without a lens, a pixel more than one pixel beyond the box has all its samples at
        // least half a pixel outside the shape: 0, what the far test or the count gives.
        let reach = match warp {
            Warp::Pinhole if self.bbox_holds_shape() => {
                let [u0, v0, u1, v1] = self.bbox();
                Some([u0 - 1.0, v0 - 1.0, u1 + 1.0, v1 + 1.0])
            }
            _ => None,
        };
        for (index, (u, v)) in patch.pixels().enumerate() {
            if let Some([u0, v0, u1, v1]) = reach
                && !(u >= u0 && u <= u1 && v >= v0 && v <= v1)
            {
                continue;
            }
            out[index] = match warp {
                // Without a lens the pixel is its ideal point: no Jacobian to build per pixel.
                Warp::Pinhole => pixel_coverage(self, [u, v], None),
                Warp::Lens { .. } => {
                    warp.local(u, v).map_or(0.0, |local| pixel_coverage(self, local.ideal, Some(&local)))
                }
            };
        }
        out
    }
}

/// How a shape is painted.
pub(super) struct Paint<'a> {
    /// The blur kernel (normalised, odd length; `[1]`: none).
    pub(super) kernel: &'a [f32],
    /// Grey level of the background.
    pub(super) background: u8,
    /// Grey level of the shape.
    pub(super) foreground: u8,
    /// The frame's noise.
    pub(super) noise: Noise<'a>,
}

/// A rectangle of pixels: the top-left pixel and the size.
pub(super) struct Patch {
    pub(super) u0: i64,
    pub(super) v0: i64,
    pub(super) w: usize,
    pub(super) h: usize,
}

impl Patch {
    /// The pixels `(u, v)`, row-major.
    pub(super) fn pixels(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        (0..self.h)
            .flat_map(move |j| (0..self.w).map(move |i| ((self.u0 + i as i64) as f64, (self.v0 + j as i64) as f64)))
    }
}

/// Paints one shape (coverage, blur, noise, quantisation) over the image; false when it
/// falls entirely outside the image.
pub(super) fn paint(image: &mut GreyImage, shape: &impl Shape, warp: &Warp, paint: &Paint<'_>) -> bool {
    let margin = (paint.kernel.len() / 2) as i64 + 1;
    let (w, h) = (i64::from(image.width()), i64::from(image.height()));
    let [u0, v0, u1, v1] = shape.bbox();
    let (u0, v0) = ((u0.floor() as i64 - margin).max(0), (v0.floor() as i64 - margin).max(0));
    let (u1, v1) = ((u1.ceil() as i64 + margin).min(w - 1), (v1.ceil() as i64 + margin).min(h - 1));
    if u0 > u1 || v0 > v1 {
        return false;
    }
    let patch = Patch { u0, v0, w: (u1 - u0 + 1) as usize, h: (v1 - v0 + 1) as usize };
    let mut coverage = shape.coverage(&patch, warp);
    blur(&mut coverage, &patch, paint.kernel);
    let (bg, fg) = (f64::from(paint.background), f64::from(paint.foreground));
    let width = image.width() as usize;
    let data: &mut [u8] = image;
    paint.noise.warm((0..patch.h).map(|j| ((patch.v0 as usize + j) * width + patch.u0 as usize, patch.w)));
    let mut noise = paint.noise.reader();
    for (j, row) in coverage.chunks_exact(patch.w).enumerate() {
        let start = (patch.v0 as usize + j) * width + patch.u0 as usize;
        for (i, &c) in row.iter().enumerate() {
            // Uncovered: the value would be the noisy background the pixel already holds (or
            // less than what another shape drew there); its noise is not read.
            if c == 0.0 {
                continue;
            }
            let index = start + i;
            let value = quantise(bg + (fg - bg) * f64::from(c) + noise(index));
            // max: two overlapping shapes do not add up.
            data[index] = data[index].max(value);
        }
    }
    true
}

/// Exact inside and outside (first-order distance to the boundary beyond 1.5 pixels),
/// supersampled near the boundary.
///
/// The distance `value / |gradient|` is compared with 1.5 as `value^2 > 2.25 |gradient|^2`
/// with the value's sign, without the square root and the division that every pixel of the
/// patch would otherwise wait for (the patch's whole time, at the renderer's sizes).
/// `local`: the pixel's place in the ideal image, None for the identity (no lens) at `ideal`.
fn pixel_coverage(shape: &impl Shape, ideal: [f64; 2], local: Option<&Local>) -> f32 {
    let [u, v] = ideal;
    let gradient = match local {
        Some(local) => local.jacobian.transpose() * shape.gradient(u, v),
        None => shape.gradient(u, v),
    };
    let value = shape.value(u, v);
    let far = value * value > 2.25 * gradient.norm_squared();
    if far && value < 0.0 {
        1.0
    } else if far && value > 0.0 {
        0.0
    } else {
        let identity = Local { ideal, jacobian: nalgebra::Matrix2::identity() };
        counted_from(shape, local.unwrap_or(&identity), value, [gradient.x, gradient.y])
    }
}

/// The share of the pixel's `SUBSAMPLES x SUBSAMPLES` samples inside the shape: the count of
/// every sample evaluated. A quadratic shape counts them from its expansion about the pixel
/// ([`SampleQuadratic`]); a sample it cannot decide, or another shape, evaluates every one.
#[cfg(test)]
fn counted(shape: &impl Shape, local: &Local) -> f32 {
    let [u, v] = local.ideal;
    let g = local.jacobian.transpose() * shape.gradient(u, v);
    counted_from(shape, local, shape.value(u, v), [g.x, g.y])
}

/// [`counted`] given the shape's value at the pixel and its gradient in sample offsets
/// (`J^T gradient`), as the far test computed them.
fn counted_from(shape: &impl Shape, local: &Local, value: f64, gradient: [f64; 2]) -> f32 {
    let inside = SampleQuadratic::of(shape, local, value, gradient)
        .and_then(|q| q.one_side().or_else(|| q.count()))
        .unwrap_or_else(|| every_sample(shape, local));
    inside as f32 / (SUBSAMPLES * SUBSAMPLES) as f32
}

/// The offset of sample `k` from the pixel's centre along one axis, pixels.
fn sample_offset(k: usize) -> f64 {
    (k as f64 + 0.5) / SUBSAMPLES as f64 - 0.5
}

/// The samples of the pixel inside the shape, each evaluated: sample `(s, t)` is at
/// `p + J (s, t)`.
fn every_sample(shape: &impl Shape, local: &Local) -> usize {
    let (j, [u, v]) = (&local.jacobian, local.ideal);
    let inside =
        |s: f64, t: f64| shape.value(u + j[(0, 0)] * s + j[(0, 1)] * t, v + j[(1, 0)] * s + j[(1, 1)] * t) <= 0.0;
    (0..SUBSAMPLES)
        .flat_map(|a| (0..SUBSAMPLES).map(move |b| (sample_offset(b), sample_offset(a))))
        .filter(|&(s, t)| inside(s, t))
        .count()
}

/// A quadratic shape over the samples of one pixel: exactly,
/// `value(p + J (s, t)) = value(p) + g_s s + g_t t + a s^2 + 2 b s t + c t^2`, with
/// `(g_s, g_t) = J^T gradient(p)` and `[a, b; b, c] = J^T A J` (`A` of
/// [`Shape::second_order`]). Evaluated in floating point, each sample's value is off by a few
/// 1e-16 of the size of the terms ([`Shape::quadratic_scale`]); `margin`, 1e-9 of it (as in
/// [`Shape::quadratic_scale`] at the pixel's farthest sample), decides every sample farther
/// than that from the boundary as its own evaluation does. All 64 in straight-line
/// arithmetic, without a branch a sample.
struct SampleQuadratic {
    value: f64,
    gradient: [f64; 2],
    /// `[a, b, c]` in sample offsets.
    second: [f64; 3],
    margin: f64,
}

impl SampleQuadratic {
    /// From the shape's `value` at the pixel and its `gradient` in sample offsets; None for a
    /// shape that is not a quadratic.
    fn of(shape: &impl Shape, local: &Local, value: f64, gradient: [f64; 2]) -> Option<Self> {
        let (j, [u, v]) = (&local.jacobian, local.ideal);
        let (du, dv) = (0.5 * (j[(0, 0)].abs() + j[(0, 1)].abs()), 0.5 * (j[(1, 0)].abs() + j[(1, 1)].abs()));
        let margin = 1e-9 * shape.quadratic_scale(u.abs() + du + 1.0, v.abs() + dv + 1.0)?;
        let [a, b, c] = shape.second_order();
        let (s, t) = ([j[(0, 0)], j[(1, 0)]], [j[(0, 1)], j[(1, 1)]]);
        let form = |x: [f64; 2], y: [f64; 2]| a * x[0] * y[0] + b * (x[0] * y[1] + x[1] * y[0]) + c * x[1] * y[1];
        Some(Self { value, gradient, second: [form(s, s), form(s, t), form(t, t)], margin })
    }

    /// All the samples (or none) when every one is certainly inside (outside): the expansion's
    /// terms bounded over the pixel's samples (`|s|, |t| <= 7/16`) keep the value from zero.
    /// None otherwise (then [`SampleQuadratic::count`]).
    fn one_side(&self) -> Option<usize> {
        let ([gs, gt], [a, b, c], m) = (self.gradient, self.second, self.margin);
        let h = sample_offset(SUBSAMPLES - 1);
        let spread = (gs.abs() + gt.abs()) * h + (a.abs() + 2.0 * b.abs() + c.abs()) * h * h;
        if !(self.value.is_finite() && spread.is_finite() && m.is_finite()) {
            None
        } else if self.value - spread > m {
            Some(0)
        } else if self.value + spread < -m {
            Some(SUBSAMPLES * SUBSAMPLES)
        } else {
            None
        }
    }

    /// The samples inside, or None when one lies within the margin of the boundary (or a
    /// value is not finite): those are evaluated one by one.
    fn count(&self) -> Option<usize> {
        let ([gs, gt], [a, b, c], m) = (self.gradient, self.second, self.margin);
        let offsets: [f64; SUBSAMPLES] = std::array::from_fn(sample_offset);
        let (mut inside, mut unsure) = (0usize, false);
        for &t in &offsets {
            let (row, slope) = (self.value + t * (gt + c * t), gs + 2.0 * b * t);
            for &s in &offsets {
                let q = row + s * (slope + a * s);
                inside += usize::from(q < -m);
                unsure |= !(q < -m || q > m);
            }
        }
        (!unsure && m.is_finite()).then_some(inside)
    }
}

/// A normalised Gaussian kernel of standard deviation `sigma` (3 sigma each side); `[1]`
/// when sigma is 0.
pub(super) fn gaussian_kernel(sigma: f64) -> Vec<f32> {
    if sigma <= 0.0 {
        return vec![1.0];
    }
    let radius = (3.0 * sigma).ceil() as i64;
    let taps: Vec<f64> = (-radius..=radius).map(|x| (-(x * x) as f64 / (2.0 * sigma * sigma)).exp()).collect();
    let sum: f64 = taps.iter().sum();
    taps.iter().map(|t| (t / sum) as f32).collect()
}

/// Separable convolution of a row-major patch with a symmetric kernel (zero outside): each
/// output is the sum of `kernel[y + r - x] * input[y]` over the taps inside, in increasing `y`.
pub(super) fn blur(values: &mut [f32], patch: &Patch, kernel: &[f32]) {
    if kernel.len() == 1 {
        return;
    }
    let r = kernel.len() / 2;
    let (w, h) = (patch.w, patch.h);
    let mut tmp = vec![0.0f32; values.len()];
    // The taps of output x of a line of n: the kernel slice and the input range they meet.
    let taps = |x: usize, n: usize| {
        let (lo, hi) = (x.saturating_sub(r), (x + r).min(n - 1));
        (&kernel[lo + r - x..=hi + r - x], lo..=hi)
    };
    for (row, out) in values.chunks_exact(w).zip(tmp.chunks_exact_mut(w)) {
        // A row of zeros (beyond a shape) blurs to zeros, already there.
        if row.iter().all(|&c| c == 0.0) {
            continue;
        }
        for (x, o) in out.iter_mut().enumerate().filter(|(x, _)| *x < r || *x + r >= w) {
            let (k, range) = taps(x, w);
            *o = k.iter().zip(&row[range]).map(|(a, b)| a * b).sum();
        }
        // Every tap inside the row: tap by tap over the outputs (vectorised), each output
        // summing its taps in the same order as above.
        if w > 2 * r {
            accumulate(&mut out[r..w - r], kernel, |t| &row[t..t + w - 2 * r]);
        }
    }
    for j in 0..h {
        let (k, range) = taps(j, h);
        let lo = *range.start();
        accumulate(&mut values[j * w..(j + 1) * w], k, |t| &tmp[(lo + t) * w..(lo + t + 1) * w]);
    }
}

/// `out[i] = sum over t of kernel[t] * input(t)[i]`, the terms added in the order of `t`
/// (the kernel and the grey levels are not negative, so the sum starts at the first term).
fn accumulate<'a>(out: &mut [f32], kernel: &[f32], input: impl Fn(usize) -> &'a [f32]) {
    for (t, &k) in kernel.iter().enumerate() {
        let line = input(t);
        if t == 0 {
            out.iter_mut().zip(line).for_each(|(o, &b)| *o = k * b);
        } else {
            out.iter_mut().zip(line).for_each(|(o, &b)| *o += k * b);
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    /// The half-plane `u <= 10.25`, seen over rows 0..4.
    struct HalfPlane;

    impl Shape for HalfPlane {
        fn bbox(&self) -> [f64; 4] {
            [0.0, 0.0, 10.25, 3.0]
        }
        fn value(&self, u: f64, _: f64) -> f64 {
            u - 10.25
        }
        fn gradient(&self, _: f64, _: f64) -> Vector2<f64> {
            Vector2::new(1.0, 0.0)
        }
    }

    #[test]
    fn any_shape_is_rasterised_by_its_coverage() {
        let mut image = GreyImage::new(16, 4);
        let noise = Noise { pool: &[], background: 0, sigma: 0.0, seed: 0 };
        let paint = Paint { kernel: &[1.0], background: 0, foreground: 200, noise };
        assert!(paint_shape(&mut image, &paint));
        let row: Vec<u8> = (0..16).map(|u| image.get_pixel(u, 1)[0]).collect();
        // Pixel 10 covers [9.5, 10.5]: three quarters inside.
        assert_eq!(&row[..12], &[200, 200, 200, 200, 200, 200, 200, 200, 200, 200, 150, 0]);
    }

    fn paint_shape(image: &mut GreyImage, paint: &Paint<'_>) -> bool {
        super::paint(image, &HalfPlane, &Warp::Pinhole, paint)
    }

    /// The share of the pixel's samples inside the shape, each evaluated.
    fn every_sample(shape: &impl Shape, local: &Local) -> f32 {
        let (j, [u, v], n) = (&local.jacobian, local.ideal, SUBSAMPLES);
        let offset = |k: usize| (k as f64 + 0.5) / n as f64 - 0.5;
        let inside: usize = (0..n * n)
            .map(|k| (offset(k % n), offset(k / n)))
            .map(|(du, dv)| (u + j[(0, 0)] * du + j[(0, 1)] * dv, v + j[(1, 0)] * du + j[(1, 1)] * dv))
            .map(|(uu, vv)| usize::from(shape.value(uu, vv) <= 0.0))
            .sum();
        inside as f32 / (n * n) as f32
    }

    /// The expansion about the pixel gives the count of every sample evaluated, exactly, on
    /// ellipses of any size, scale and orientation.
    #[test]
    fn the_expansion_gives_the_count_of_the_samples() {
        use crate::vision::render::conic::ImageEllipse;
        use nalgebra::{Matrix2, Matrix3};
        let mut state = 17u64;
        let mut uniform = || (super::super::noise::splitmix64(&mut state) >> 11) as f64 / (1u64 << 53) as f64;
        let (mut shortcuts, mut pixels) = (0, 0);
        for _ in 0..300 {
            // An ellipse of semi-axes 0.5-20 px, any orientation, anywhere in a 2000 px image,
            // its conic scaled by up to 1e+-6; a Jacobian up to 30 % from the identity.
            let (cx, cy, t) = (2000.0 * uniform(), 2000.0 * uniform(), std::f64::consts::PI * uniform());
            let (ra, rb) = (0.5 + 19.5 * uniform(), 0.5 + 19.5 * uniform());
            let scale = 10f64.powf(12.0 * uniform() - 6.0);
            let (c, s) = (t.cos(), t.sin());
            let r = Matrix3::new(c, s, -(c * cx + s * cy), -s, c, s * cx - c * cy, 0.0, 0.0, 1.0);
            let d = Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0 / (ra * ra), 1.0 / (rb * rb), -1.0));
            let conic = r.transpose() * d * r * scale;
            let ellipse = ImageEllipse { conic, bbox: [0.0; 4] };
            let jacobian = Matrix2::new(
                1.0 + 0.3 * (uniform() - 0.5),
                0.3 * (uniform() - 0.5),
                0.3 * (uniform() - 0.5),
                1.0 + 0.3 * (uniform() - 0.5),
            );
            let reach = ra.max(rb) + 3.0;
            for _ in 0..200 {
                let ideal = [cx + reach * (2.0 * uniform() - 1.0), cy + reach * (2.0 * uniform() - 1.0)];
                let local = Local { ideal, jacobian };
                let full = every_sample(&ellipse, &local);
                assert_eq!(counted(&ellipse, &local), full, "{ideal:?}");
                pixels += 1;
                let [u, v] = ideal;
                let g = jacobian.transpose() * ellipse.gradient(u, v);
                let expansion = SampleQuadratic::of(&ellipse, &local, ellipse.value(u, v), [g.x, g.y]).unwrap();
                assert!(expansion.one_side().is_none_or(|side| side == expansion.count().unwrap()), "{ideal:?}");
                shortcuts += usize::from(expansion.count().is_some());
            }
        }
        // The expansion decides (it is what saves the time): every pixel but those with a
        // sample within 1e-9 of the boundary.
        assert!(shortcuts > pixels * 99 / 100, "{shortcuts} of {pixels}");
    }

    /// Samples exactly on the boundary (a circle through samples of the pixel) are inside, as
    /// when each sample is evaluated: the expansion leaves them to the exact evaluation.
    #[test]
    fn samples_on_the_boundary_are_counted_as_each_sample_evaluated() {
        use crate::vision::render::conic::ImageEllipse;
        use nalgebra::{Matrix2, Matrix3};
        // (u - 10)^2 + (v - 10)^2 = 10 / 256: through the samples at (+-3/16, +-1/16) and
        // (+-1/16, +-3/16) of pixel (10, 10).
        let conic = Matrix3::new(1.0, 0.0, -10.0, 0.0, 1.0, -10.0, -10.0, -10.0, 200.0 - 10.0 / 256.0);
        let ellipse = ImageEllipse { conic, bbox: [0.0; 4] };
        let local = Local { ideal: [10.0, 10.0], jacobian: Matrix2::identity() };
        assert_eq!(counted(&ellipse, &local), every_sample(&ellipse, &local));
        // The 4 samples at (+-1/16, +-1/16) and the 8 on the boundary.
        assert_eq!(counted(&ellipse, &local), 12.0 / 64.0);
    }

    /// Without a lens, skipping the pixels beyond an ellipse's box changes no pixel's
    /// coverage (discs of 0.3 to 40 px, any tilt).
    #[test]
    fn pixels_beyond_an_ellipses_box_are_the_ones_evaluated_to_zero() {
        use crate::core::camera::Intrinsics;
        use crate::vision::render::Disc;
        use crate::vision::render::conic::ImageEllipse;
        let mut state = 29u64;
        let mut uniform = || (super::super::noise::splitmix64(&mut state) >> 11) as f64 / (1u64 << 53) as f64;
        let k = Intrinsics::pinhole(600.0, 600.0, 416.0, 312.0).unwrap();
        let (mut skipped, mut ellipses) = (0, 0);
        for _ in 0..300 {
            let center = [0.3 * (uniform() - 0.5), 0.2 * (uniform() - 0.5), 0.3 + 0.6 * uniform()];
            let normal = [2.0 * (uniform() - 0.5), 2.0 * (uniform() - 0.5), -1.0];
            let disc = Disc::new(center, normal, 0.0004 + 0.02 * uniform()).unwrap();
            let Some(ellipse) = ImageEllipse::of(&disc, &nalgebra::Isometry3::identity(), &k, &Warp::Pinhole) else {
                continue;
            };
            let [u0, v0, u1, v1] = ellipse.bbox();
            let (pu, pv) = (u0.floor() as i64 - 4, v0.floor() as i64 - 4);
            let patch = Patch {
                u0: pu,
                v0: pv,
                w: (u1.ceil() as i64 + 5 - pu) as usize,
                h: (v1.ceil() as i64 + 5 - pv) as usize,
            };
            let every: Vec<f32> = patch.pixels().map(|(u, v)| pixel_coverage(&ellipse, [u, v], None)).collect();
            assert_eq!(ellipse.coverage(&patch, &Warp::Pinhole), every, "{disc:?}");
            skipped += patch.pixels().filter(|&(u, v)| u < u0 - 1.0 || v > v1 + 1.0).count();
            ellipses += 1;
        }
        assert!(ellipses > 250 && skipped > 0, "{ellipses} {skipped}");
    }

    #[test]
    fn kernel_is_normalised() {
        assert_eq!(gaussian_kernel(0.0), vec![1.0]);
        let k = gaussian_kernel(1.2);
        assert_eq!(k.len(), 2 * 4 + 1);
        assert!((k.iter().sum::<f32>() - 1.0).abs() < 1e-6);
    }
}
