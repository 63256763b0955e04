//! A match's pixel refined to a fraction of a pixel: SIFT places a keypoint at its own scale,
//! so across two lenses (a focal ratio of 2) the same scene point is found up to 2 px apart,
//! and the invariant law, which needs the same points in both images, settles off the goal.
//! The reference's patch around the keypoint, warped into the frame by the local affine map
//! of the neighbouring matches (at the reference's pyramid level nearest that map's scale, the
//! reference first blurred as the frames are: [`blur`](super::blur)), is aligned with the frame by Gauss-Newton
//! with a gain and an offset for the exposure (Lucas-Kanade on a warped template, inverse
//! compositional). [`Precision::Fast`] moves the translation of a small patch (every point,
//! every frame); [`Precision::Fine`] moves the whole affine warp of a larger patch (the few
//! points the invariant law leans on most, its basis, whose errors enter every invariant
//! coordinate). A refinement that does not converge, moves more than [`MAX_SHIFT`], deforms
//! the local map by more than [`MAX_DEFORM`] or leaves the patches unlike (normalised
//! correlation below [`MIN_CORRELATION`]) drops the match.

use kornia_image::Image;
use nalgebra::{Matrix2, Matrix6, Vector2, Vector6};

/// The patch's half side of [`Precision::Fast`], frame pixels.
pub const HALF: i32 = 7;
/// The patch's half side of [`Precision::Fine`], frame pixels.
pub const FINE_HALF: i32 = 11;
/// The largest move of a refinement, pixels.
pub const MAX_SHIFT: f64 = 3.0;
/// The least normalised correlation of the aligned patches.
pub const MIN_CORRELATION: f64 = 0.85;
/// The largest change of any entry of the affine warp's linear part from the local map's
/// ([`Precision::Fine`]; the local map is then more than that far off: a wrong match).
pub const MAX_DEFORM: f64 = 0.25;

/// How carefully a point is aligned.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Precision {
    /// A patch of side `2 HALF + 1`, its translation alone: the local map is taken as it is.
    Fast,
    /// A patch of side `2 FINE_HALF + 1`, the whole affine warp: the local map corrected. The
    /// neighbours' map is a few per cent off (a neighbour on another face, the perspective
    /// across the patch), and the translation alone then settles a tenth of a pixel off.
    Fine,
}

/// The value of `image` at `(u, v)` (bilinear), None outside.
pub fn sample(image: &Image<f32, 1>, u: f64, v: f64) -> Option<f64> {
    let (w, h) = (image.width(), image.height());
    if !(u >= 0.0 && v >= 0.0 && u <= (w - 1) as f64 && v <= (h - 1) as f64) {
        return None;
    }
    Some(bilinear(image.as_slice(), w, h, u, v))
}

/// [`sample`] at a point known to be inside the `w x h` image `px`.
#[inline]
fn bilinear(px: &[f32], w: usize, h: usize, u: f64, v: f64) -> f64 {
    let (u0, v0) = (u.floor() as usize, v.floor() as usize);
    let (u1, v1) = ((u0 + 1).min(w - 1), (v0 + 1).min(h - 1));
    let (a, b) = (u - u0 as f64, v - v0 as f64);
    let at = |x: usize, y: usize| f64::from(px[y * w + x]);
    (1.0 - b) * ((1.0 - a) * at(u0, v0) + a * at(u1, v0)) + b * ((1.0 - a) * at(u0, v1) + a * at(u1, v1))
}

/// The patch sides and sample counts of the two precisions (`N` samples in a patch, `G` in
/// the grid sampled for its template: the patch and a ring for its gradients).
const SIDE: usize = 2 * HALF as usize + 1;
const FINE_SIDE: usize = 2 * FINE_HALF as usize + 1;
const N_FAST: usize = SIDE * SIDE;
const G_FAST: usize = (SIDE + 2) * (SIDE + 2);
const N_FINE: usize = FINE_SIDE * FINE_SIDE;
const G_FINE: usize = (FINE_SIDE + 2) * (FINE_SIDE + 2);
/// The alignment's largest number of iterations.
const ITERATIONS: usize = 20;
/// The step below which the alignment has converged, pixels.
const CONVERGED: f64 = 1e-3;

/// What the alignment moves.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Model {
    Translation,
    Affine,
}

impl Model {
    /// The warp's parameters: `(p_u, p_v)`, then `(D_11, D_12, D_21, D_22)` for the affine.
    fn parameters(self) -> usize {
        match self {
            Model::Translation => 2,
            Model::Affine => 6,
        }
    }
}

/// The pyramid level (of `levels`) whose pixels are the nearest to a frame pixel in size, for
/// the local map `inverse` from the frame to the reference.
fn level_for(inverse: &Matrix2<f64>, levels: usize) -> Option<usize> {
    let scale = inverse.determinant().abs().sqrt();
    Some((scale.log2().round().max(0.0) as usize).min(levels.checked_sub(1)?))
}

/// The pixel in `frame` of the reference point `at` (pixels of level 0 of `pyramid`, the
/// reference image halved at each level), starting from `start`, where `map` is the local
/// linear map from the reference to the frame ([`Precision::Fast`]). None: dropped (see the
/// module documentation).
pub fn refine(
    pyramid: &[Image<f32, 1>],
    frame: &Image<f32, 1>,
    at: [f64; 2],
    map: &Matrix2<f64>,
    start: [f64; 2],
) -> Option<[f64; 2]> {
    refine_with(pyramid, frame, at, map, start, Precision::Fast).map(|(pixel, _)| pixel)
}

/// [`refine`] at the given precision, with the normalised correlation of the aligned patches
/// (how alike the reference's patch and the frame's are once aligned: [`blur`](super::blur)
/// reads it).
pub fn refine_with(
    pyramid: &[Image<f32, 1>],
    frame: &Image<f32, 1>,
    at: [f64; 2],
    map: &Matrix2<f64>,
    start: [f64; 2],
    precision: Precision,
) -> Option<([f64; 2], f64)> {
    match precision {
        Precision::Fast => refine_patch::<N_FAST, G_FAST>(pyramid, frame, at, map, start, Model::Translation),
        Precision::Fine => refine_patch::<N_FINE, G_FINE>(pyramid, frame, at, map, start, Model::Affine),
    }
}

/// [`refine`] with a patch of `N` samples (a square), moving what `model` says; `G` is the
/// sample count of the patch and a ring.
fn refine_patch<const N: usize, const G: usize>(
    pyramid: &[Image<f32, 1>],
    frame: &Image<f32, 1>,
    at: [f64; 2],
    map: &Matrix2<f64>,
    start: [f64; 2],
    model: Model,
) -> Option<([f64; 2], f64)> {
    let inverse = map.try_inverse()?;
    let level = level_for(&inverse, pyramid.len())?;
    let image = pyramid.get(level)?;
    // Level l's pixel (u, v) is level 0's (2^l u, 2^l v): the pyramid's kernel is centred on
    // every other pixel (OpenCV's pyrDown).
    let shrink = f64::from(1u32 << level);
    let (centre, inverse) = (Vector2::new(at[0], at[1]) / shrink, inverse / shrink);
    let mut grid = [0.0; G];
    let reach = half_of(N) + 1;
    for (row, dv) in grid.chunks_exact_mut(G.isqrt()).zip(-reach..=reach) {
        for (value, du) in row.iter_mut().zip(-reach..=reach) {
            let p = centre + inverse * Vector2::new(f64::from(du), f64::from(dv));
            *value = sample(image, p.x, p.y)?;
        }
    }
    align(&Template::<N>::new(&grid, model)?, frame, start, model)
}

/// The half side of a square patch of `n` samples.
const fn half_of(n: usize) -> i32 {
    (n.isqrt() / 2) as i32
}

/// The sample offsets `(du, dv)` of a patch of half side `half`, frame pixels from its
/// centre, row by row.
fn offsets(half: i32) -> impl Iterator<Item = (f64, f64)> {
    (-half..=half).flat_map(move |dv| (-half..=half).map(move |du| (f64::from(du), f64::from(dv))))
}

/// The reference's patch warped into the frame, as the alignment uses it (Baker and Matthews,
/// "Lucas-Kanade 20 years on", IJCV 2004, sec. 3.2 and 3.4: the inverse compositional
/// algorithm, the exposure "projected out"): its values, and its steepest-descent images
/// `grad T dW/dp` of the warp at the identity (eq. 38-39; for the affine warp
/// `W(x) = p + (I + D) x`), less their least-squares fit by the patch and a constant (the
/// exposure's directions, which the gain and offset absorb), with the inverse of their Gram
/// matrix (the Gauss-Newton matrix, fixed).
struct Template<const N: usize> {
    values: [f64; N],
    mean: f64,
    /// The sum of the squared deviations from the mean.
    spread: f64,
    /// The steepest-descent images of the model's parameters (the first ones used).
    descent: [[f64; N]; 6],
    /// The inverse of the Gram matrix of the model's parameters (its top-left block used).
    inverse: Matrix6<f64>,
}

impl<const N: usize> Template<N> {
    /// The template of the grid `grid` (the patch and a ring) for `model`; None for a flat
    /// patch.
    fn new<const G: usize>(grid: &[f64; G], model: Model) -> Option<Self> {
        let (side, half, k) = (N.isqrt(), half_of(N), model.parameters());
        let g = side + 2;
        let mut values = [0.0; N];
        let mut descent = [[0.0; N]; 6];
        for j in 0..side {
            let (above, row, below) = (&grid[j * g..], &grid[(j + 1) * g..], &grid[(j + 2) * g..]);
            for i in 0..side {
                let (gu, gv) = (0.5 * (row[i + 2] - row[i]), 0.5 * (below[i + 1] - above[i + 1]));
                let (du, dv) = (f64::from(i as i32 - half), f64::from(j as i32 - half));
                let s = j * side + i;
                values[s] = row[i + 1];
                for (image, d) in descent.iter_mut().zip([gu, gv, gu * du, gu * dv, gv * du, gv * dv]).take(k) {
                    image[s] = d;
                }
            }
        }
        let n = N as f64;
        let mean = values.iter().sum::<f64>() / n;
        let spread: f64 = values.iter().map(|t| (t - mean) * (t - mean)).sum();
        if !(spread > 1e-9) {
            return None;
        }
        for g in descent.iter_mut().take(k) {
            let g_mean = g.iter().sum::<f64>() / n;
            let along = g.iter().zip(&values).map(|(g, t)| (g - g_mean) * (t - mean)).sum::<f64>() / spread;
            for (g, t) in g.iter_mut().zip(&values) {
                *g -= g_mean + along * (t - mean);
            }
        }
        let inverse = match model {
            Model::Translation => {
                let gram = Matrix2::from_fn(|r, c| dot(&descent[r], &descent[c]));
                let mut inverse = Matrix6::zeros();
                inverse.fixed_view_mut::<2, 2>(0, 0).copy_from(&gram.try_inverse()?);
                inverse
            }
            Model::Affine => Matrix6::from_fn(|r, c| dot(&descent[r], &descent[c])).try_inverse()?,
        };
        Some(Self { values, mean, spread, descent, inverse })
    }

    /// The gain taking the template to `values` (least squares, with an offset) and their
    /// normalised correlation; None for a flat `values`.
    fn exposure(&self, values: &[f64; N]) -> Option<(f64, f64)> {
        let n = N as f64;
        let mv = values.iter().sum::<f64>() / n;
        let (mut svv, mut stv) = (0.0, 0.0);
        for (t, v) in self.values.iter().zip(values) {
            svv += (v - mv) * (v - mv);
            stv += (t - self.mean) * (v - mv);
        }
        if !(svv > 1e-9) {
            return None;
        }
        Some((stv / self.spread, stv / (self.spread * svv).sqrt()))
    }

    /// The inverse-compositional increment `(dp, dD)` for the frame's patch `values`: the frame
    /// is `gain T(W_delta(x)) + offset`, linearised `gain (T + SD delta) + offset`, whose
    /// least-squares `delta` with the gain and offset free is `(SD'^T SD')^-1 SD'^T f / gain`
    /// (eq. 36, `SD'` the steepest-descent images with the exposure's directions projected out).
    fn increment(&self, values: &[f64; N], gain: f64, model: Model) -> (Vector2<f64>, Matrix2<f64>) {
        match model {
            Model::Translation => {
                let b = Vector2::new(dot(&self.descent[0], values), dot(&self.descent[1], values));
                (self.inverse.fixed_view::<2, 2>(0, 0) * b / gain, Matrix2::zeros())
            }
            Model::Affine => {
                let d = self.inverse * Vector6::from_fn(|r, _| dot(&self.descent[r], values)) / gain;
                (Vector2::new(d[0], d[1]), Matrix2::new(d[2], d[3], d[4], d[5]))
            }
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}

/// Gauss-Newton on the warp `W(x) = p + A x` of the frame's patch onto `template` (`A = I`:
/// the local map; only `p` moves for the translation), with a gain and an offset, inverse
/// compositional: each step's increment `W_delta` ([`Template::increment`]) is composed
/// inverted, `W <- W o W_delta^-1` (Baker and Matthews 2004, eq. 32): `A <- A (I + dD)^-1`,
/// `p <- p - A dp`. Dropped: not converged in [`ITERATIONS`], moved more than [`MAX_SHIFT`],
/// `A` more than [`MAX_DEFORM`] from `I`, a patch leaving the frame, or a correlation below
/// [`MIN_CORRELATION`]. Returns the pixel and the correlation.
fn align<const N: usize>(
    template: &Template<N>,
    frame: &Image<f32, 1>,
    start: [f64; 2],
    model: Model,
) -> Option<([f64; 2], f64)> {
    let start = Vector2::new(start[0], start[1]);
    let (mut p, mut a) = (start, Matrix2::identity());
    let mut values = [0.0; N];
    let half = f64::from(half_of(N));
    for _ in 0..ITERATIONS {
        match model {
            Model::Translation => window(frame, p, &mut values)?,
            Model::Affine => warped(frame, p, &a, &mut values)?,
        }
        let (gain, correlation) = template.exposure(&values)?;
        let (dp, dd) = template.increment(&values, gain, model);
        // Converged: no sample of the patch moves by a thousandth of a pixel.
        let moved = match model {
            Model::Translation => {
                p -= dp;
                dp.norm()
            }
            Model::Affine => {
                a *= (Matrix2::identity() + dd).try_inverse()?;
                p -= a * dp;
                (dp.abs() + dd.abs() * Vector2::repeat(half)).amax()
            }
        };
        if !((p - start).norm() <= MAX_SHIFT && (a - Matrix2::identity()).amax() <= MAX_DEFORM) {
            return None;
        }
        if moved < CONVERGED {
            return (correlation >= MIN_CORRELATION).then_some(([p.x, p.y], correlation));
        }
    }
    None
}

/// The bilinear samples of `frame` at `p + (du, dv)` for the integer offsets of a square patch
/// of `N` samples: one fractional offset, so one stencil of four weights over the integer
/// window. None when the window (by half a pixel) is not inside the frame.
fn window<const N: usize>(frame: &Image<f32, 1>, p: Vector2<f64>, out: &mut [f64; N]) -> Option<()> {
    let (w, h, px) = (frame.width(), frame.height(), frame.as_slice());
    let (side, half) = (N.isqrt(), half_of(N));
    let (left, top) = (p.x - f64::from(half) - 0.5, p.y - f64::from(half) - 0.5);
    let (right, bottom) = (p.x + f64::from(half) + 0.5, p.y + f64::from(half) + 0.5);
    if !(left >= 0.0 && top >= 0.0 && right <= (w - 1) as f64 && bottom <= (h - 1) as f64) {
        return None;
    }
    let (u0, v0) = (p.x.floor(), p.y.floor());
    let (a, b) = (p.x - u0, p.y - v0);
    let (left, top) = (u0 as usize - half as usize, v0 as usize - half as usize);
    for (j, row) in out.chunks_exact_mut(side).enumerate() {
        let start = (top + j) * w + left;
        let (upper, lower) = (&px[start..start + side + 1], &px[start + w..start + w + side + 1]);
        for (i, value) in row.iter_mut().enumerate() {
            let (p00, p10) = (f64::from(upper[i]), f64::from(upper[i + 1]));
            let (p01, p11) = (f64::from(lower[i]), f64::from(lower[i + 1]));
            *value = (1.0 - b) * ((1.0 - a) * p00 + a * p10) + b * ((1.0 - a) * p01 + a * p11);
        }
    }
    Some(())
}

/// The bilinear samples of `frame` at `p + a (du, dv)` for the offsets of a square patch of
/// `N` samples; None when a corner of the warped patch (by half a pixel) is not inside the
/// frame.
fn warped<const N: usize>(frame: &Image<f32, 1>, p: Vector2<f64>, a: &Matrix2<f64>, out: &mut [f64; N]) -> Option<()> {
    let (w, h, px) = (frame.width(), frame.height(), frame.as_slice());
    let half = half_of(N);
    let reach = f64::from(half);
    for (su, sv) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
        let c = p + a * Vector2::new(su * reach, sv * reach);
        if !(c.x >= 0.5 && c.y >= 0.5 && c.x + 0.5 <= (w - 1) as f64 && c.y + 0.5 <= (h - 1) as f64) {
            return None;
        }
    }
    for (value, (du, dv)) in out.iter_mut().zip(offsets(half)) {
        let q = p + a * Vector2::new(du, dv);
        *value = bilinear(px, w, h, q.x, q.y);
    }
    Some(())
}

/// The reference image halved `levels` times (kornia's Gaussian pyramid), level 0 first.
pub fn pyramid(image: &Image<f32, 1>, levels: usize) -> crate::vision::error::Result<Vec<Image<f32, 1>>> {
    let mut out = vec![image.clone()];
    for _ in 0..levels {
        let Some(last) = out.last() else { break };
        let size = kornia_image::ImageSize { width: last.width().div_ceil(2), height: last.height().div_ceil(2) };
        if size.width < 2 * HALF as usize + 3 || size.height < 2 * HALF as usize + 3 {
            break;
        }
        let mut down = Image::from_size_val(size, 0.0f32).map_err(pyramid_error)?;
        kornia_imgproc::pyramid::pyrdown_f32(last, &mut down).map_err(pyramid_error)?;
        out.push(down);
    }
    Ok(out)
}

fn pyramid_error(e: kornia_image::ImageError) -> crate::vision::error::VisionError {
    crate::vision::error::VisionError::InvalidImage { what: "reference_image".into(), reason: e.to_string() }
}

/// The matches `(first[i], second[i])` refined in `frame` (see [`refine`]), the local map of
/// each fitted to its neighbours; None where dropped.
pub fn refine_matches(
    pyramid: &[Image<f32, 1>],
    frame: &Image<f32, 1>,
    first: &[[f64; 2]],
    second: &[[f64; 2]],
) -> Vec<Option<[f64; 2]>> {
    (0..first.len().min(second.len()))
        .map(|i| {
            let map = crate::vision::features::matching::local_map(first, second, i)?;
            refine(pyramid, frame, first[i], &map, second[i])
        })
        .collect()
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use kornia_image::ImageSize;

    use super::*;

    fn plane(w: usize, h: usize, f: &dyn Fn(f64, f64) -> f64) -> Image<f32, 1> {
        let data =
            (0..h).flat_map(|v| (0..w).map(move |u| (u, v))).map(|(u, v)| f(u as f64, v as f64) as f32).collect();
        Image::new(ImageSize { width: w, height: h }, data).unwrap()
    }

    /// The tests' random draws (xorshift64).
    struct Draw(u64);

    impl Draw {
        fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            lo + (hi - lo) * (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// A random view of a texture: the local map (a scale in `[lo, hi]`, a rotation and a
    /// shear), the reference point `r0` it puts at the frame's `c`, and the 100 x 90 frame (a
    /// gain and an offset drawn, plus `noise` grey levels of a hashed noise).
    struct Case {
        map: Matrix2<f64>,
        r0: Vector2<f64>,
        c: Vector2<f64>,
        frame: Image<f32, 1>,
    }

    impl Case {
        fn draw(draw: &mut Draw, lo: f64, hi: f64, texture: &dyn Fn(f64, f64) -> f64, noise: f64) -> Self {
            let (scale, angle, shear) = (draw.uniform(lo, hi), draw.uniform(-0.4, 0.4), draw.uniform(-0.1, 0.1));
            let rotation = Matrix2::new(angle.cos(), -angle.sin(), angle.sin(), angle.cos());
            let map = scale * rotation * Matrix2::new(1.0, shear, 0.0, 1.0);
            let inverse = map.try_inverse().unwrap();
            let r0 = Vector2::new(draw.uniform(100.0, 140.0), draw.uniform(80.0, 120.0));
            let c = Vector2::new(draw.uniform(40.0, 60.0), draw.uniform(35.0, 55.0));
            let (gain, offset) = (draw.uniform(0.6, 1.3), draw.uniform(-20.0, 20.0));
            let frame = plane(100, 90, &|u, v| {
                let r = inverse * (Vector2::new(u, v) - c) + r0;
                let hashed = ((u * 12.9898 + v * 78.233).sin() * 43758.5453).fract();
                gain * texture(r.x, r.y) + offset + noise * hashed
            });
            Self { map, r0, c, frame }
        }
    }

    /// A smooth texture seen through a known affine map: the refinement lands on the true pixel
    /// from 1.5 px off, through a change of exposure.
    #[test]
    fn a_warped_patch_is_found_to_a_hundredth_of_a_pixel() {
        let texture = |x: f64, y: f64| {
            120.0 + 50.0 * (0.21 * x + 0.05 * y).sin() * (0.17 * y - 0.03 * x).cos() + 20.0 * (0.11 * x * 0.7).cos()
        };
        let reference = plane(120, 100, &texture);
        // The frame: frame pixel q sees reference point r = A^-1 (q - c) + r0, exposure 0.8 x + 10.
        let map = Matrix2::new(0.95, 0.12, -0.08, 1.05);
        let inverse = map.try_inverse().unwrap();
        let (r0, c) = (Vector2::new(60.0, 50.0), Vector2::new(52.3, 47.6));
        let frame = plane(110, 95, &|u, v| {
            let r = inverse * (Vector2::new(u, v) - c) + r0;
            0.8 * texture(r.x, r.y) + 10.0
        });
        let found = refine(&[reference], &frame, [r0.x, r0.y], &map, [c.x + 1.2, c.y - 0.9]).unwrap();
        assert!((found[0] - c.x).abs() < 0.01 && (found[1] - c.y).abs() < 0.01, "{found:?}");
        // Another patch of the frame is not the reference's: dropped.
        let flat = plane(110, 95, &|_, _| 90.0);
        assert!(refine(&[plane(120, 100, &texture)], &flat, [r0.x, r0.y], &map, [c.x, c.y]).is_none());
    }

    /// The forward-additive formulation (Baker and Matthews 2004, sec. 2), the reference of the
    /// inverse-compositional alignment: each iteration samples the frame at the warped samples
    /// `p + (I + d) x` of a patch of half side `half` with its gradients there (half-pixel
    /// differences of the bilinear interpolant), fits the gain and offset, and solves the
    /// Gauss-Newton system of the frame's steepest-descent images, of the translation alone
    /// (`d` stays 0; 20 iterations, converged below 1e-3 px) or of the whole affine warp (60
    /// iterations, below 1e-6); `p` and `d` move additively.
    fn forward(
        pyramid: &[Image<f32, 1>],
        frame: &Image<f32, 1>,
        (at, map, start): ([f64; 2], &Matrix2<f64>, [f64; 2]),
        half: i32,
        affine: bool,
    ) -> Option<[f64; 2]> {
        let inverse = map.try_inverse()?;
        let level = level_for(&inverse, pyramid.len())?;
        let shrink = f64::from(1u32 << level);
        let template: Vec<f64> = offsets(half)
            .map(|(du, dv)| {
                let p = (Vector2::new(at[0], at[1]) + inverse * Vector2::new(du, dv)) / shrink;
                sample(&pyramid[level], p.x, p.y)
            })
            .collect::<Option<_>>()?;
        let (iterations, converged) = if affine { (60, 1e-6) } else { (ITERATIONS, CONVERGED) };
        let origin = Vector2::new(start[0], start[1]);
        let (mut p, mut d) = (origin, Matrix2::zeros());
        for _ in 0..iterations {
            let (mut values, mut grads) = (Vec::new(), Vec::new());
            for (du, dv) in offsets(half) {
                let q = p + (Matrix2::identity() + d) * Vector2::new(du, dv);
                values.push(sample(frame, q.x, q.y)?);
                let gu = sample(frame, q.x + 0.5, q.y)? - sample(frame, q.x - 0.5, q.y)?;
                let gv = sample(frame, q.x, q.y + 0.5)? - sample(frame, q.x, q.y - 0.5)?;
                grads.push(Vector2::new(gu, gv));
            }
            let n = template.len() as f64;
            let (mt, mv) = (template.iter().sum::<f64>() / n, values.iter().sum::<f64>() / n);
            let stt: f64 = template.iter().map(|t| (t - mt) * (t - mt)).sum();
            let svv: f64 = values.iter().map(|v| (v - mv) * (v - mv)).sum();
            let stv: f64 = template.iter().zip(&values).map(|(t, v)| (t - mt) * (v - mv)).sum();
            let (gain, correlation) = (stv / stt, stv / (stt * svv).sqrt());
            let offset = mv - gain * mt;
            let (mut h, mut b) = (Matrix6::zeros(), Vector6::zeros());
            for (((t, f), g), (du, dv)) in template.iter().zip(&values).zip(&grads).zip(offsets(half)) {
                let j = Vector6::new(g.x, g.y, g.x * du, g.x * dv, g.y * du, g.y * dv);
                h += j * j.transpose();
                b += j * (gain * t + offset - f);
            }
            let step = if affine {
                h.cholesky()?.solve(&b)
            } else {
                let shift = h.fixed_view::<2, 2>(0, 0).into_owned().try_inverse()? * b.fixed_rows::<2>(0);
                Vector6::new(shift.x, shift.y, 0.0, 0.0, 0.0, 0.0)
            };
            p += Vector2::new(step[0], step[1]);
            d += Matrix2::new(step[2], step[3], step[4], step[5]);
            if (p - origin).norm() > MAX_SHIFT || d.amax() > MAX_DEFORM {
                return None;
            }
            if step.norm() < converged {
                return (correlation >= MIN_CORRELATION).then_some([p.x, p.y]);
            }
        }
        None
    }

    /// Random affine maps (scales from 0.35 to 1.4: levels 0 to 2), exposures and starts up to
    /// 1.4 px off, twelve without noise and twelve with a pixel noise of up to 2 grey levels.
    /// Without noise the two formulations land within 0.01 px of each other (where the forward
    /// one converges); with it, the inverse-compositional one (whose gradients are the
    /// template's, free of the frame's noise) stays within 0.05 px of the truth, the forward
    /// one within 0.15 px. Both refuse a flat frame.
    #[test]
    fn the_alignment_agrees_with_the_forward_formulation() {
        let mut draw = Draw(0x2545_f491_4f6c_dd1d);
        let texture = |x: f64, y: f64| {
            120.0
                + 45.0 * (0.23 * x + 0.07 * y).sin() * (0.19 * y - 0.04 * x).cos()
                + 25.0 * (0.09 * x - 0.13 * y).cos()
                + 15.0 * (0.31 * x + 0.27 * y).sin()
        };
        let reference = pyramid(&plane(240, 200, &texture), 2).unwrap();
        let (mut apart, mut new_off, mut old_off) = (0.0f64, 0.0f64, 0.0f64);
        for case in 0..24 {
            let amplitude = if case < 12 { 0.0 } else { 2.0 };
            let Case { map, r0, c, frame } = Case::draw(&mut draw, 0.35, 1.4, &texture, amplitude);
            let start = [c.x + draw.uniform(-1.0, 1.0), c.y + draw.uniform(-1.0, 1.0)];
            let off = |p: [f64; 2]| (p[0] - c.x).hypot(p[1] - c.y);
            let new = refine(&reference, &frame, [r0.x, r0.y], &map, start).unwrap();
            new_off = new_off.max(off(new));
            // The forward formulation does not always converge in its 20 iterations.
            if let Some(old) = forward(&reference, &frame, ([r0.x, r0.y], &map, start), HALF, false) {
                old_off = old_off.max(off(old));
                if amplitude == 0.0 {
                    apart = apart.max((new[0] - old[0]).hypot(new[1] - old[1]));
                }
            }
        }
        assert!(apart < 0.01 && new_off < 0.05 && old_off < 0.15, "apart {apart}, off {new_off} (forward {old_off})");
        let flat = plane(100, 90, &|_, _| 90.0);
        let (at, map) = ([120.0, 100.0], Matrix2::identity());
        assert!(refine(&reference, &flat, at, &map, [50.0, 45.0]).is_none());
        assert!(forward(&reference, &flat, (at, &map, [50.0, 45.0]), HALF, false).is_none());
    }

    /// A textured patch like a photograph's (sinusoids of many frequencies and directions,
    /// edges from a clipped one): grey levels.
    fn photograph(x: f64, y: f64) -> f64 {
        let mut value = 110.0 + 40.0 * (0.5 * x - 0.3 * y).sin().clamp(-0.6, 0.6);
        for k in 1..9 {
            let (f, a) = (0.07 * f64::from(k), 1.7 * f64::from(k));
            value += 60.0 / f64::from(k) * (f * (x * a.cos() + y * a.sin()) + f64::from(k)).sin();
        }
        value
    }

    /// The local map a few per cent off (a neighbour on another face), on random affine warps of
    /// a photograph-like texture, exposures and starts 1 px off: the fine (inverse-compositional
    /// affine) alignment lands within 0.01 px of the forward-additive one and within 0.05 px of
    /// the truth (the frame is drawn unblurred, the template comes from the blurred pyramid),
    /// where the fast one (the translation alone) is ten times as far off at its worst; a map
    /// 40 % off is dropped.
    #[test]
    fn the_affine_alignment_corrects_a_wrong_local_map() {
        let mut draw = Draw(0x9e37_79b9_7f4a_7c15);
        let reference = pyramid(&plane(240, 200, &photograph), 2).unwrap();
        let (mut apart, mut affine_off, mut shift_off, mut compared) = (0.0f64, 0.0f64, 0.0f64, 0);
        for _ in 0..16 {
            let Case { map, r0, c, frame } = Case::draw(&mut draw, 0.45, 1.3, &photograph, 0.0);
            // The neighbours' map: 3-5 % off in each entry.
            let wrong = map.component_mul(&Matrix2::from_fn(|_, _| {
                1.0 + draw.uniform(0.03, 0.05) * draw.uniform(-1.0, 1.0).signum()
            }));
            let start = [c.x + draw.uniform(-0.7, 0.7), c.y + draw.uniform(-0.7, 0.7)];
            let off = |p: [f64; 2]| (p[0] - c.x).hypot(p[1] - c.y);
            let at = [r0.x, r0.y];
            let (affine, _) = refine_with(&reference, &frame, at, &wrong, start, Precision::Fine).unwrap();
            affine_off = affine_off.max(off(affine));
            if let Some((shift, _)) = refine_with(&reference, &frame, at, &wrong, start, Precision::Fast) {
                shift_off = shift_off.max(off(shift));
            }
            if let Some(forward) = forward(&reference, &frame, (at, &wrong, start), FINE_HALF, true) {
                apart = apart.max((affine[0] - forward[0]).hypot(affine[1] - forward[1]));
                compared += 1;
            }
        }
        assert!(
            compared >= 12 && apart < 0.01 && affine_off < 0.05 && shift_off > 10.0 * affine_off,
            "apart {apart} over {compared}, off {affine_off} (translation {shift_off})"
        );
        // A map 40 % off: more than MAX_DEFORM to correct, dropped.
        let c = Vector2::new(50.0, 45.0);
        let frame = plane(100, 90, &|u, v| photograph(u - c.x + 120.0, v - c.y + 100.0));
        let at = [120.0, 100.0];
        assert!(refine_with(&reference, &frame, at, &Matrix2::identity(), [c.x, c.y], Precision::Fine).is_some());
        assert!(
            refine_with(&reference, &frame, at, &(Matrix2::identity() * 1.4), [c.x, c.y], Precision::Fine).is_none()
        );
    }
}
