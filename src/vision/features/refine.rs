//! A match's pixel refined to a fraction of a pixel: SIFT places a keypoint at its own scale,
//! so across two lenses (a focal ratio of 2) the same scene point is found up to 2 px apart,
//! and the invariant law, which needs the same points in both images, settles off the goal.
//! The reference's patch around the keypoint, warped into the frame by the local affine map
//! of the neighbouring matches (at the reference's pyramid level nearest that map's scale, so
//! that it is blurred as the frame's lens blurs it), is aligned with the frame by Gauss-Newton
//! on the translation, with a gain and an offset for the exposure (Lucas-Kanade on a warped
//! template). A refinement that does not converge, moves more than [`MAX_SHIFT`] or leaves the
//! patches unlike (normalised correlation below [`MIN_CORRELATION`]) drops the match.

use kornia_image::Image;
use nalgebra::{Matrix2, Vector2};

/// The patch's half side, frame pixels.
pub const HALF: i32 = 7;
/// The largest move of a refinement, pixels.
pub const MAX_SHIFT: f64 = 3.0;
/// The least normalised correlation of the aligned patches.
pub const MIN_CORRELATION: f64 = 0.85;

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

/// The pixel in `frame` of the reference point `at` (pixels of level 0 of `pyramid`, the
/// reference image halved at each level), starting from `start`, where `map` is the local
/// linear map from the reference to the frame. None: dropped (see the module documentation).
pub fn refine(
    pyramid: &[Image<f32, 1>],
    frame: &Image<f32, 1>,
    at: [f64; 2],
    map: &Matrix2<f64>,
    start: [f64; 2],
) -> Option<[f64; 2]> {
    let inverse = map.try_inverse()?;
    // The level whose pixels are the nearest to a frame pixel in size.
    let scale = inverse.determinant().abs().sqrt();
    let level = (scale.log2().round().max(0.0) as usize).min(pyramid.len().checked_sub(1)?);
    let image = pyramid.get(level)?;
    let shrink = f64::from(1u32 << level);
    // Level l's pixel (u, v) is level 0's (2^l u, 2^l v): the pyramid's kernel is centred on
    // every other pixel (OpenCV's pyrDown).
    let to_level = |p: Vector2<f64>| p / shrink;
    let centre = Vector2::new(at[0], at[1]);
    let mut template = Vec::new();
    for dv in -HALF..=HALF {
        for du in -HALF..=HALF {
            let p = to_level(centre + inverse * Vector2::new(f64::from(du), f64::from(dv)));
            template.push(sample(image, p.x, p.y)?);
        }
    }
    align(&template, frame, start)
}

/// Gauss-Newton on the translation of the frame's patch onto `template` (with a gain and an
/// offset fitted at each step).
fn align(template: &[f64], frame: &Image<f32, 1>, start: [f64; 2]) -> Option<[f64; 2]> {
    let mut p = Vector2::new(start[0], start[1]);
    let (w, h, px) = (frame.width(), frame.height(), frame.as_slice());
    let (mut values, mut grads) = (Vec::with_capacity(template.len()), Vec::with_capacity(template.len()));
    for _ in 0..20 {
        // Every sample below lies within half a pixel of the patch: the patch inside the
        // frame, or the refinement fails (as [`sample`] would at its first sample outside).
        let (left, top) = (p.x + f64::from(-HALF) - 0.5, p.y + f64::from(-HALF) - 0.5);
        let (right, bottom) = (p.x + f64::from(HALF) + 0.5, p.y + f64::from(HALF) + 0.5);
        if !(left >= 0.0 && top >= 0.0 && right <= (w - 1) as f64 && bottom <= (h - 1) as f64) {
            return None;
        }
        let at = |u: f64, v: f64| bilinear(px, w, h, u, v);
        values.clear();
        grads.clear();
        for dv in -HALF..=HALF {
            for du in -HALF..=HALF {
                let (u, v) = (p.x + f64::from(du), p.y + f64::from(dv));
                values.push(at(u, v));
                let gx = (at(u + 0.5, v) - at(u - 0.5, v)) / 1.0;
                let gy = (at(u, v + 0.5) - at(u, v - 0.5)) / 1.0;
                grads.push(Vector2::new(gx, gy));
            }
        }
        let (gain, offset, correlation) = fit_exposure(template, &values)?;
        let (mut h, mut b) = (Matrix2::zeros(), Vector2::zeros());
        for ((t, f), g) in template.iter().zip(&values).zip(&grads) {
            h += g * g.transpose();
            b += g * (gain * t + offset - f);
        }
        let step = h.try_inverse()? * b;
        p += step;
        if (p - Vector2::new(start[0], start[1])).norm() > MAX_SHIFT {
            return None;
        }
        if step.norm() < 1e-3 {
            return (correlation >= MIN_CORRELATION).then_some([p.x, p.y]);
        }
    }
    None
}

/// The gain and offset taking `template` to `values` (least squares) and their normalised
/// correlation; None for a flat patch.
fn fit_exposure(template: &[f64], values: &[f64]) -> Option<(f64, f64, f64)> {
    let n = template.len() as f64;
    let (mt, mv) = (template.iter().sum::<f64>() / n, values.iter().sum::<f64>() / n);
    let (mut stt, mut svv, mut stv) = (0.0, 0.0, 0.0);
    for (t, v) in template.iter().zip(values) {
        stt += (t - mt) * (t - mt);
        svv += (v - mv) * (v - mv);
        stv += (t - mt) * (v - mv);
    }
    if !(stt > 1e-9 && svv > 1e-9) {
        return None;
    }
    let gain = stv / stt;
    Some((gain, mv - gain * mt, stv / (stt * svv).sqrt()))
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

    /// A smooth texture seen through a known affine map: the refinement lands on the true pixel
    /// from 1.5 px off, through a change of exposure.
    #[test]
    fn a_warped_patch_is_found_to_a_hundredth_of_a_pixel() {
        let texture = |x: f64, y: f64| {
            120.0 + 50.0 * (0.21 * x + 0.05 * y).sin() * (0.17 * y - 0.03 * x).cos() + 20.0 * (0.11 * x * 0.7).cos()
        };
        let plane = |w: usize, h: usize, f: &dyn Fn(f64, f64) -> f64| {
            let data =
                (0..h).flat_map(|v| (0..w).map(move |u| (u, v))).map(|(u, v)| f(u as f64, v as f64) as f32).collect();
            Image::new(ImageSize { width: w, height: h }, data).unwrap()
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
}
