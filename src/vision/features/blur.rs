//! The reference blurred as the frame is. A point is aligned on the reference's patch warped
//! into the frame ([`refine`](super::refine)), taken from the reference's pyramid level
//! nearest the frame's scale. That patch carries the reference lens's blur and the pyramid's;
//! the frame carries its own lens's. Where the two differ, the alignment of a patch that is not
//! symmetric (a corner, the end of an edge) settles off the point along its asymmetry: on the
//! project's renderer's textured box (reference at f = 1200 px, frames at 600 px, both with a
//! PSF of 0.8 of their own pixels), a basis corner of the invariant law was 0.106 px off and
//! the pose ended 3.3 mm from the goal, where the same run fed the true pixels ends at 0.001
//! mm.
//!
//! So the blur that makes the two alike is measured once, on the first frame's matches
//! ([`matched_blur`]): the reference is blurred by each sigma of [`BLUR_STEP`] steps up to
//! [`MAX_BLUR`] (a Gaussian, reference pixels, before its pyramid is built), the matches are
//! aligned on each, and the sigma whose aligned patches correlate best (the mean normalised
//! correlation of the matches aligned unblurred, a match that fails counted at the least
//! accepted, its peak refined by a parabola through its neighbours) is kept. A frame sharper than the reference's patches keeps sigma 0: a blur
//! is not undone.

use kornia_image::Image;

use super::matching::local_map;
use super::refine::{MIN_CORRELATION, Precision, pyramid, refine_with};
use crate::vision::error::Result;

/// The step between two blurs tried, reference pixels.
pub const BLUR_STEP: f64 = 0.5;
/// The largest blur tried, reference pixels.
pub const MAX_BLUR: f64 = 4.0;
/// The fewest matches aligned on the unblurred reference for a measure.
pub const MIN_BLUR_MATCHES: usize = 12;

/// The reference plane `image` blurred by a Gaussian of `sigma` pixels (itself for 0).
pub fn blurred(image: &Image<f32, 1>, sigma: f64) -> Result<Image<f32, 1>> {
    if !(sigma > 0.0) {
        return Ok(image.clone());
    }
    let (w, h) = (image.width(), image.height());
    let buffer = imageproc::image::ImageBuffer::<imageproc::image::Luma<f32>, Vec<f32>>::from_raw(
        u32::try_from(w).map_err(|_| too_large())?,
        u32::try_from(h).map_err(|_| too_large())?,
        image.as_slice().to_vec(),
    )
    .ok_or_else(too_large)?;
    let out = imageproc::filter::gaussian_blur_f32(&buffer, sigma as f32);
    Image::new(image.size(), out.into_raw()).map_err(|e| invalid(e.to_string()))
}

fn too_large() -> crate::vision::error::VisionError {
    invalid("too large to blur".into())
}

fn invalid(reason: String) -> crate::vision::error::VisionError {
    crate::vision::error::VisionError::InvalidImage { what: "reference_image".into(), reason }
}

/// The blur (reference pixels) that makes the reference's patches most like the frame's, and
/// the reference's pyramid of `levels` levels above it built with that blur: `sharp` is the
/// reference plane unblurred, `(first[i], second[i])` the matches (reference, frame pixels).
/// None with fewer than [`MIN_BLUR_MATCHES`] matches aligned on the unblurred reference.
pub fn matched_blur(
    sharp: &Image<f32, 1>,
    levels: usize,
    frame: &Image<f32, 1>,
    first: &[[f64; 2]],
    second: &[[f64; 2]],
) -> Result<Option<(f64, Vec<Image<f32, 1>>)>> {
    let maps: Vec<_> = (0..first.len().min(second.len())).map(|i| local_map(first, second, i)).collect();
    let correlations = |levels: &[Image<f32, 1>], i: usize| {
        let map = maps[i].as_ref()?;
        refine_with(levels, frame, first[i], map, second[i], Precision::Fast).map(|(_, c)| c)
    };
    let sharp_levels = pyramid(sharp, levels)?;
    let aligned: Vec<(usize, f64)> =
        (0..maps.len()).filter_map(|i| correlations(&sharp_levels, i).map(|c| (i, c))).collect();
    if aligned.len() < MIN_BLUR_MATCHES {
        return Ok(None);
    }
    // The mean correlation of the matches aligned unblurred, one that fails counted at the
    // least accepted; the blurs tried until two steps past the best.
    let mut means = vec![aligned.iter().map(|(_, c)| c).sum::<f64>() / aligned.len() as f64];
    let steps = (MAX_BLUR / BLUR_STEP).round() as usize;
    for k in 1..=steps {
        let blurred_levels = pyramid(&blurred(sharp, k as f64 * BLUR_STEP)?, levels)?;
        let sum: f64 = aligned.iter().map(|&(i, _)| correlations(&blurred_levels, i).unwrap_or(MIN_CORRELATION)).sum();
        means.push(sum / aligned.len() as f64);
        if k >= peak(&means).round() as usize + 2 {
            break;
        }
    }
    let sigma = BLUR_STEP * peak(&means);
    Ok(Some((sigma, pyramid(&blurred(sharp, sigma)?, levels)?)))
}

/// The place of the largest of `values` (sampled at 0, 1, 2, ...), refined by the parabola
/// through it and its two neighbours; an end stays at the end.
fn peak(values: &[f64]) -> f64 {
    let best = (1..values.len()).fold(0, |best, k| if values[k] > values[best] { k } else { best });
    if best == 0 || best + 1 >= values.len() {
        return best as f64;
    }
    let (l, c, r) = (values[best - 1], values[best], values[best + 1]);
    let curvature = l - 2.0 * c + r;
    if !(curvature < 0.0) {
        return best as f64;
    }
    best as f64 + (0.5 * (l - r) / curvature).clamp(-0.5, 0.5)
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use kornia_image::ImageSize;
    use nalgebra::{Matrix2, Vector2};

    use super::*;
    use crate::vision::features::refine::refine;

    /// Gaussian blobs `(x, y, radius, weight)` on a grey level of 110, blurred by a Gaussian of
    /// `sigma` in closed form (a blob of radius `b` becomes one of variance `b^2 + sigma^2`,
    /// its peak scaled by `b^2 / (b^2 + sigma^2)`).
    fn blobs(x: f64, y: f64, blobs: &[[f64; 4]], sigma: f64) -> f64 {
        let mut v = 110.0;
        for [bx, by, b, weight] in blobs {
            let var = b * b + sigma * sigma;
            v += weight * (b * b / var) * (-((x - bx).powi(2) + (y - by).powi(2)) / (2.0 * var)).exp();
        }
        v
    }

    fn plane(w: usize, h: usize, f: &dyn Fn(f64, f64) -> f64) -> Image<f32, 1> {
        let data =
            (0..h).flat_map(|v| (0..w).map(move |u| (u, v))).map(|(u, v)| f(u as f64, v as f64) as f32).collect();
        Image::new(ImageSize { width: w, height: h }, data).unwrap()
    }

    /// Blobs of radius 1-3 px (small, asymmetric clusters: corners and ends) over 240 x 200
    /// reference pixels, seeded.
    fn scene() -> Vec<[f64; 4]> {
        let mut state = 7u64;
        let mut draw = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..700)
            .map(|_| [draw() * 240.0, draw() * 200.0, 1.0 + 2.0 * draw(), if draw() < 0.5 { 70.0 } else { -70.0 }])
            .collect()
    }

    /// The reference (blur `reference_sigma`, its pixels) and the frame seeing it at half size
    /// through `map` about `c` (blur `frame_sigma`, frame pixels; `frame_sigma` frame pixels
    /// are `2 frame_sigma` reference pixels); the matches on a grid, the frame's 0.4 px off.
    struct Pair {
        reference: Image<f32, 1>,
        frame: Image<f32, 1>,
        first: Vec<[f64; 2]>,
        second: Vec<[f64; 2]>,
        truth: Vec<[f64; 2]>,
    }

    fn pair(reference_sigma: f64, frame_sigma: f64) -> Pair {
        let scene = scene();
        let map = Matrix2::new(0.5, 0.03, -0.02, 0.48);
        let inverse = map.try_inverse().unwrap();
        let c = Vector2::new(8.0, 6.0);
        let reference = plane(240, 200, &|x, y| blobs(x, y, &scene, reference_sigma));
        // Frame pixel q sees reference point inverse (q - c); its blur, reference pixels.
        let frame = plane(140, 110, &|u, v| {
            let r = inverse * (Vector2::new(u, v) - c);
            blobs(r.x, r.y, &scene, 2.0 * frame_sigma)
        });
        let (mut first, mut second, mut truth) = (vec![], vec![], vec![]);
        for j in 0..8 {
            for i in 0..9 {
                let r = Vector2::new(30.0 + 22.0 * f64::from(i), 30.0 + 20.0 * f64::from(j));
                let q = map * r + c;
                first.push([r.x, r.y]);
                truth.push([q.x, q.y]);
                second.push([q.x + 0.4, q.y - 0.3]);
            }
        }
        Pair { reference, frame, first, second, truth }
    }

    /// The pyramid's level 1 holds the reference blurred by its own sigma and the pyramid's
    /// kernel (OpenCV's 5-tap binomial: a variance of 1 level-0 pixel squared), so a frame
    /// blurred by `s` frame pixels (`2 s` reference pixels) needs a blur of
    /// `sqrt(4 s^2 - sigma_r^2 - 1)` reference pixels more: measured within 0.3 px. A frame
    /// sharper than that keeps 0. With the blur matched, the points land nearer their truth
    /// (their median error less than 0.6 times that without, for a blur of more than 1 px).
    #[test]
    fn the_measured_blur_makes_the_reference_as_blurred_as_the_frame() {
        for (reference_sigma, frame_sigma) in [(0.5, 1.0), (0.8, 0.8), (0.3, 1.4), (1.2, 0.3)] {
            let p = pair(reference_sigma, frame_sigma);
            let expected =
                (4.0 * frame_sigma * frame_sigma - reference_sigma * reference_sigma - 1.0f64).max(0.0).sqrt();
            let sharp = pyramid(&p.reference, 2).unwrap();
            let (sigma, levels) = matched_blur(&p.reference, 2, &p.frame, &p.first, &p.second).unwrap().unwrap();
            assert!((sigma - expected).abs() < 0.3, "{reference_sigma} {frame_sigma}: {sigma} against {expected}");
            let errors = |levels: &[Image<f32, 1>]| {
                let mut e: Vec<f64> = (0..p.first.len())
                    .filter_map(|i| {
                        let map = local_map(&p.first, &p.second, i)?;
                        let q = refine(levels, &p.frame, p.first[i], &map, p.second[i])?;
                        Some(((q[0] - p.truth[i][0]).powi(2) + (q[1] - p.truth[i][1]).powi(2)).sqrt())
                    })
                    .collect();
                e.sort_by(f64::total_cmp);
                (e[e.len() / 2], e.len())
            };
            let ((before, n0), (after, n1)) = (errors(&sharp), errors(&levels));
            eprintln!(
                "{reference_sigma} {frame_sigma}: sigma {sigma:.3} (expected {expected:.3}), median error {before:.4} -> {after:.4} px, {n0} -> {n1} aligned"
            );
            assert!(n1 + 2 >= n0, "{n0} -> {n1}");
            if expected > 1.0 {
                assert!(after < 0.6 * before, "{before} -> {after}");
            } else {
                assert!(after <= before + 0.002, "{before} -> {after}");
            }
        }
    }

    #[test]
    fn too_few_matches_give_no_measure_and_the_peak_is_refined() {
        let p = pair(0.5, 1.0);
        let few = MIN_BLUR_MATCHES - 1;
        assert!(matched_blur(&p.reference, 2, &p.frame, &p.first[..few], &p.second[..few]).unwrap().is_none());
        // A parabola's samples: its vertex; an end stays an end.
        let parabola: Vec<f64> = (0..9).map(|k| -(f64::from(k) - 3.3).powi(2)).collect();
        assert!((peak(&parabola) - 3.3).abs() < 1e-9);
        assert_eq!(peak(&[3.0, 2.0, 1.0]), 0.0);
        assert_eq!(peak(&[1.0, 2.0, 3.0]), 2.0);
        assert!(blurred(&p.reference, 0.0).unwrap().as_slice() == p.reference.as_slice());
    }
}
