//! The two image filters of pyramidal Lucas-Kanade, computed as kornia-rs computes them
//! (`kornia_imgproc::pyramid::pyrdown_f32`, `kornia_imgproc::filter::scharr_spatial_gradient_float`:
//! the same kernels, the same borders, the same order of the sums, so the same bits), in
//! loops the compiler can vectorise: kornia's per-pixel loops check the border and index
//! with bounds checks (pyrdown) or run one rayon task a row (Scharr). The tests compare both
//! with kornia's, bit for bit; the gain is measured by `benches/features_tracking.py`.

use kornia_image::{Image, ImageError, ImageSize};

/// OpenCV's `pyrDown` kernel (1 4 6 4 1) / 16, in each direction.
const GAUSS: [f32; 5] = [0.0625, 0.25, 0.375, 0.25, 0.0625];
/// The normalised Scharr kernels (kornia's `normalized_scharr_kernel3`), row by row.
const SCHARR_X: [f32; 9] = [-0.09375, 0.0, 0.09375, -0.3125, 0.0, 0.3125, -0.09375, 0.0, 0.09375];
const SCHARR_Y: [f32; 9] = [-0.09375, -0.3125, -0.09375, 0.0, 0.0, 0.0, 0.09375, 0.3125, 0.09375];

/// OpenCV's `BORDER_REFLECT_101` index (`-1` is `1`, `len` is `len - 2`).
fn reflect_101(p: i64, len: i64) -> usize {
    if len == 1 {
        return 0;
    }
    let period = 2 * (len - 1);
    let p = p.abs() % period;
    (if p >= len { period - p } else { p }) as usize
}

/// A plane of `width x height` grey levels inside a larger row-major buffer: row `r` starts at
/// `offset + r * stride` (a level with a margin around it, or a whole image).
#[derive(Debug, Clone, Copy)]
pub struct Plane {
    /// Pixels a row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// The buffer's pixels a row.
    pub stride: usize,
    /// The first pixel's index in the buffer.
    pub offset: usize,
}

impl Plane {
    /// A whole image's plane.
    pub fn of(image: &Image<f32, 1>) -> Self {
        Self { width: image.width(), height: image.height(), stride: image.width(), offset: 0 }
    }

    /// The plane's row `r` in `buffer`.
    #[inline]
    fn row<'a>(&self, buffer: &'a [f32], r: usize) -> &'a [f32] {
        &buffer[self.offset + r * self.stride..][..self.width]
    }

    #[inline]
    fn row_mut<'a>(&self, buffer: &'a mut [f32], r: usize) -> &'a mut [f32] {
        &mut buffer[self.offset + r * self.stride..][..self.width]
    }
}

/// `src` blurred by the 5 x 5 Gaussian and halved (sizes rounded up), borders reflected
/// (OpenCV's `pyrDown`).
pub fn pyrdown(src: &Image<f32, 1>) -> Result<Image<f32, 1>, ImageError> {
    let (dw, dh) = (src.width().div_ceil(2), src.height().div_ceil(2));
    let mut dst = Image::from_size_val(ImageSize { width: dw, height: dh }, 0.0f32)?;
    let to = Plane { width: dw, height: dh, stride: dw, offset: 0 };
    pyrdown_into(src.as_slice(), Plane::of(src), dst.as_slice_mut(), to);
    Ok(dst)
}

/// [`pyrdown`] of the plane `from` of `s` into the plane `to` of `d` (its size
/// `from`'s halved, rounded up).
pub fn pyrdown_into(s: &[f32], from: Plane, d: &mut [f32], to: Plane) {
    let (dw, dh) = (to.width, to.height);
    let mut weights = [0.0f32; 25];
    for (k, w) in weights.iter_mut().enumerate() {
        *w = GAUSS[k / 5] * GAUSS[k % 5];
    }
    // Interior: every tap inside the source. A source row is split into its even and odd
    // pixels, so that the taps `2x - 2 .. 2x + 2` of the outputs `x` are five contiguous
    // runs (even[x-1], odd[x-1], even[x], odd[x], even[x+1]) and the loop over `x`
    // vectorises; each output's sum keeps kornia's order of taps (rows, then columns).
    let half = from.width.div_ceil(2);
    // Five split rows, source row `r` in slot `r % 5` (each split once, read by up to three
    // output rows).
    let mut parts: [Vec<f32>; 5] = std::array::from_fn(|_| vec![0.0f32; 2 * half]);
    let mut held = [usize::MAX; 5];
    let inner = dw.saturating_sub(2);
    let rows = if inner > 0 { 1..dh.saturating_sub(1) } else { 0..0 };
    for y in rows {
        for r in 2 * y - 2..=2 * y + 2 {
            if held[r % 5] == r {
                continue;
            }
            held[r % 5] = r;
            let (even, odd) = parts[r % 5].split_at_mut(half);
            for (i, pair) in from.row(s, r).chunks(2).enumerate() {
                even[i] = pair[0];
                odd[i] = pair.get(1).copied().unwrap_or(0.0);
            }
        }
        let out = &mut to.row_mut(d, y)[1..1 + inner];
        out.fill(0.0);
        for ky in 0..5 {
            let (even, odd) = parts[(2 * y + ky - 2) % 5].split_at(half);
            let taps = [&even[..inner], &odd[..inner], &even[1..1 + inner], &odd[1..1 + inner], &even[2..2 + inner]];
            for (tap, &weight) in taps.iter().zip(&weights[ky * 5..ky * 5 + 5]) {
                for (o, &t) in out.iter_mut().zip(tap.iter()) {
                    *o += t * weight;
                }
            }
        }
    }
    // The border (first and last rows and columns): indices reflected.
    let (w, h) = (from.width as i64, from.height as i64);
    let border = |y: usize, x: usize| {
        let mut sum = 0.0f32;
        for ky in 0..5 {
            let row = from.row(s, reflect_101(2 * y as i64 + ky as i64 - 2, h));
            for kx in 0..5 {
                sum += row[reflect_101(2 * x as i64 + kx as i64 - 2, w)] * weights[ky * 5 + kx];
            }
        }
        sum
    };
    for y in 0..dh {
        let middle = if y == 0 || y + 1 >= dh { 1..dw.saturating_sub(1) } else { 0..0 };
        for x in std::iter::once(0).chain(middle).chain((dw > 1).then_some(dw - 1)) {
            to.row_mut(d, y)[x] = border(y, x);
        }
    }
}

/// The normalised Scharr gradients of `src` along x and y, borders replicated.
pub fn scharr(src: &Image<f32, 1>) -> Result<(Image<f32, 1>, Image<f32, 1>), ImageError> {
    let mut gx = Image::from_size_val(src.size(), 0.0f32)?;
    let mut gy = Image::from_size_val(src.size(), 0.0f32)?;
    let plane = Plane::of(src);
    scharr_into(src.as_slice(), plane, gx.as_slice_mut(), gy.as_slice_mut(), plane);
    Ok((gx, gy))
}

/// [`scharr`] of the plane `from` of `s` into the planes `to` of `ox` and `oy` (one size).
pub fn scharr_into(s: &[f32], from: Plane, ox: &mut [f32], oy: &mut [f32], to: Plane) {
    let (w, h) = (from.width, from.height);
    // One pixel: the nine taps in kornia's order (rows, then columns).
    let one = |taps: [f32; 9]| {
        let (mut sx, mut sy) = (0.0f32, 0.0f32);
        for ((tap, kx), ky) in taps.iter().zip(&SCHARR_X).zip(&SCHARR_Y) {
            sx += tap * kx;
            sy += tap * ky;
        }
        (sx, sy)
    };
    for r in 0..h {
        let interior_row = h >= 2 && w >= 2 && r > 0 && r + 1 < h;
        let (rx, ry) = (to.row_mut(ox, r), to.row_mut(oy, r));
        if interior_row {
            let (up, mid, down) = (from.row(s, r - 1), from.row(s, r), from.row(s, r + 1));
            for c in 1..w - 1 {
                let taps =
                    [up[c - 1], up[c], up[c + 1], mid[c - 1], mid[c], mid[c + 1], down[c - 1], down[c], down[c + 1]];
                (rx[c], ry[c]) = one(taps);
            }
        }
        // Replicated border: row and column clamped into the image (the first and last
        // columns of an interior row, every column of the others).
        let middle = if interior_row { 0..0 } else { 1..w.saturating_sub(1) };
        for c in std::iter::once(0).chain(middle).chain((w > 1).then_some(w - 1)) {
            let clamp = |i: usize, n: usize| (i.min(n).max(1)) - 1;
            let taps = std::array::from_fn(|k| from.row(s, clamp(r + k / 3, h))[clamp(c + k % 3, w)]);
            (rx[c], ry[c]) = one(taps);
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use kornia_imgproc::filter::scharr_spatial_gradient_float;
    use kornia_imgproc::pyramid::pyrdown_f32;

    use super::*;

    fn noise(w: usize, h: usize, seed: u64) -> Image<f32, 1> {
        let mut state = seed;
        let data = (0..w * h)
            .map(|_| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                ((state >> 33) % 25600) as f32 / 100.0
            })
            .collect();
        Image::new(ImageSize { width: w, height: h }, data).unwrap()
    }

    /// Bit for bit kornia's, on even, odd and tiny sizes.
    #[test]
    fn the_filters_are_kornias_to_the_bit() {
        for (w, h) in [(64, 48), (37, 23), (6, 5), (3, 2), (1, 1), (2, 7), (1, 9), (9, 1), (333, 251), (640, 480)] {
            let src = noise(w, h, (w * 131 + h) as u64);
            let mut down =
                Image::from_size_val(ImageSize { width: w.div_ceil(2), height: h.div_ceil(2) }, 0.0).unwrap();
            pyrdown_f32(&src, &mut down).unwrap();
            assert_eq!(pyrdown(&src).unwrap().as_slice(), down.as_slice(), "pyrdown {w}x{h}");
            let (mut ix, mut iy) =
                (Image::from_size_val(src.size(), 0.0).unwrap(), Image::from_size_val(src.size(), 0.0).unwrap());
            scharr_spatial_gradient_float(&src, &mut ix, &mut iy).unwrap();
            let (gx, gy) = scharr(&src).unwrap();
            assert_eq!(gx.as_slice(), ix.as_slice(), "scharr x {w}x{h}");
            assert_eq!(gy.as_slice(), iy.as_slice(), "scharr y {w}x{h}");
        }
    }
}
