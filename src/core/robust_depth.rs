//! Eq. (26) from tracked keypoints (issue 32): the depths of the first image of a
//! pure-translation pair up to one scale, robust to bad tracks and honest about the points
//! whose depth the pair does not fix.
//!
//! For a pure translation every point's image motion lies on a line through the epipole
//! (eq. 26: `p^I = a p^II + b e`). A consensus over minimal pairs of such lines (MSAC,
//! deterministic) finds the epipole, least squares over its inliers refines it, and each
//! point's depth `~ 1 / b` then comes with two checks against the tracking noise `sigma`
//! (pixels, per coordinate):
//! - its residual, the distance of `p^I` from the line through `p^II` and `e`, has a standard
//!   deviation of `sqrt(2) sigma` for a good track (both images' noise across the line):
//!   beyond [`MAX_RESIDUAL_SIGMAS`] of them the track is wrong;
//! - the noise along the line (also `sqrt(2) sigma`) moves `b`, hence the depth, by
//!   `sqrt(2) sigma / |p^I - p^II|` relatively: a point whose parallax `|p^I - p^II|` leaves
//!   more than [`MAX_RELATIVE_DEPTH_ERROR`] at three standard deviations (the points near the
//!   epipole) has no usable depth.
//!
//! Unusable points get a NaN depth, never a silently wrong one.

use nalgebra::Vector3;

use crate::core::depth::{
    EPIPOLE, TranslationDepths, check_pair, degenerate, epipolar_residual, epipole_least_squares, homog,
};
use crate::error::{Error, Result, check_positive};

/// A track whose residual exceeds this many standard deviations of a good track's residual
/// (`sqrt(2) sigma`) is wrong: a Gaussian good track goes beyond with probability 6e-5.
pub const MAX_RESIDUAL_SIGMAS: f64 = 4.0;

/// The largest relative depth error (three standard deviations of the noise along the
/// epipolar line over the parallax) of a usable depth.
pub const MAX_RELATIVE_DEPTH_ERROR: f64 = 0.1;

/// Minimal samples drawn by the consensus (all pairs when there are fewer).
const SAMPLES: usize = 300;

/// Fewest usable points: the resection of appendix A needs 6.
pub const MIN_USABLE: usize = 6;

/// SplitMix64, a fixed seed: the same pairs on every run.
struct Pairs(u64);

impl Pairs {
    fn next(&mut self, n: usize) -> (usize, usize) {
        let mut draw = |m: usize| {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) % m as u64) as usize
        };
        let i = draw(n);
        let j = draw(n - 1);
        (i, if j >= i { j + 1 } else { j })
    }
}

/// Eq. (26) robust to bad tracks, for keypoints tracked with a noise of `pixel_noise` pixels
/// (standard deviation per coordinate; the features target's tracks: median error 0.1-0.2
/// px, sigma about 0.1-0.15). Depths are scaled to a mean of 1 over the usable points and NaN
/// elsewhere (see the module's doc for the two tests). Fails when the consensus leaves fewer
/// than [`MIN_USABLE`] usable points or the motion is degenerate.
pub fn robust_depths_from_translation(
    first: &[[f64; 2]],
    second: &[[f64; 2]],
    pixel_noise: f64,
) -> Result<TranslationDepths> {
    check_positive("pixel_noise", pixel_noise)?;
    check_pair(first, second, MIN_USABLE)?;
    let n = first.len();
    let sigma = std::f64::consts::SQRT_2 * pixel_noise;
    let max_residual = MAX_RESIDUAL_SIGMAS * sigma;
    let min_parallax = 3.0 * sigma / MAX_RELATIVE_DEPTH_ERROR;
    let residuals =
        |e: &Vector3<f64>| -> Vec<f64> { (0..n).map(|k| epipolar_residual(first[k], second[k], e)).collect() };
    // Least squares over the consensus' inliers, then once more over the refined epipole's.
    let mut e = consensus(first, second, max_residual)?;
    for _ in 0..2 {
        let inliers: Vec<usize> =
            residuals(&e).iter().enumerate().filter(|(_, r)| **r <= max_residual).map(|(k, _)| k).collect();
        if inliers.len() < MIN_USABLE {
            return Err(too_few(
                inliers.len(),
                "tracks on lines through one epipole (the motion is not a translation?)",
            ));
        }
        let pick = |p: &[[f64; 2]]| -> Vec<[f64; 2]> { inliers.iter().map(|&k| p[k]).collect() };
        e = epipole_least_squares(&pick(first), &pick(second))?;
    }
    let residuals = residuals(&e);
    let mut inv_depth = vec![f64::NAN; n];
    for k in 0..n {
        let parallax = (first[k][0] - second[k][0]).hypot(first[k][1] - second[k][1]);
        if residuals[k] <= max_residual && parallax >= min_parallax {
            inv_depth[k] = inverse_depth_along(first[k], second[k], &e);
        }
    }
    let sign = inv_depth.iter().filter(|b| b.is_finite()).sum::<f64>().signum();
    let usable: Vec<bool> = inv_depth.iter().map(|b| b.is_finite() && b * sign > 0.0).collect();
    let count = usable.iter().filter(|u| **u).count();
    if count < MIN_USABLE {
        return Err(too_few(count, "points with a small residual and enough parallax for their depth"));
    }
    let mean = (0..n).filter(|&k| usable[k]).map(|k| 1.0 / (inv_depth[k] * sign)).sum::<f64>() / count as f64;
    let depths = (0..n).map(|k| if usable[k] { 1.0 / (inv_depth[k] * sign) / mean } else { f64::NAN }).collect();
    let rms = ((0..n).filter(|&k| usable[k]).map(|k| residuals[k].powi(2)).sum::<f64>() / count as f64).sqrt();
    Ok(TranslationDepths { depths, epipole: e, residual: rms, residuals, usable })
}

/// Eq. (26) for one point, `p^I = a p^II + b e`, with the third row exact (`a = 1 - b e_z`,
/// both pixels have w = 1): `p^I - p^II = b (e_xy - e_z p^II)`, and `b` from the component
/// of the motion along that direction, in pixels. (A least squares over the three rows
/// weighs the unit third row against pixel rows: with noisy tracks it trades `a`, a scaling
/// about the pixel origin, against `b`, 15 % of depth error from 0.6 px of tracking error.)
fn inverse_depth_along(first: [f64; 2], second: [f64; 2], e: &Vector3<f64>) -> f64 {
    let u = [e.x - e.z * second[0], e.y - e.z * second[1]];
    ((first[0] - second[0]) * u[0] + (first[1] - second[1]) * u[1]) / (u[0] * u[0] + u[1] * u[1])
}

fn too_few(got: usize, why: &'static str) -> Error {
    Error::TooFewPoints { needed: MIN_USABLE, got, why }
}

/// MSAC: the epipole of the pair of motion lines that minimises the sum of the residuals
/// clipped at `max_residual`.
fn consensus(first: &[[f64; 2]], second: &[[f64; 2]], max_residual: f64) -> Result<Vector3<f64>> {
    let n = first.len();
    let lines: Vec<Vector3<f64>> = (0..n).map(|k| homog(first[k]).cross(&homog(second[k]))).collect();
    let candidates: Vec<(usize, usize)> = if n * (n - 1) / 2 <= SAMPLES {
        (0..n).flat_map(|i| (i + 1..n).map(move |j| (i, j))).collect()
    } else {
        let mut pairs = Pairs(0x7ec7_0a5e);
        (0..SAMPLES).map(|_| pairs.next(n)).collect()
    };
    let mut best: Option<(f64, Vector3<f64>)> = None;
    for (i, j) in candidates {
        let e = lines[i].cross(&lines[j]);
        let norm = e.norm();
        if !(norm > 0.0 && norm.is_finite()) {
            continue; // the same line twice, or a point that did not move
        }
        let e = e / norm;
        let cost: f64 = (0..n).map(|k| epipolar_residual(first[k], second[k], &e).min(max_residual).powi(2)).sum();
        if best.is_none_or(|(c, _)| cost < c) {
            best = Some((cost, e));
        }
    }
    best.map(|(_, e)| e).ok_or(degenerate(EPIPOLE, 0.0))
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::core::depth::ResectionDepths;
    use nalgebra::Matrix3;

    /// A skewed camera translated by `t` (its own frame) in front of a non-planar cloud: the
    /// pixels of both views and the true depths of the first, computed directly (`K X`).
    fn pair(t: [f64; 3]) -> (Vec<[f64; 2]>, Vec<[f64; 2]>, Vec<f64>) {
        let k = Matrix3::new(610.0, 2.0, 330.0, 0.0, 590.0, 250.0, 0.0, 0.0, 1.0);
        let (mut a, mut b, mut z) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..40 {
            let f = i as f64;
            let x = Vector3::new((f * 0.37).sin() * 0.2, (f * 0.61).cos() * 0.15, 0.6 + 0.15 * (f * 1.3).sin());
            let (p, q) = (k * x, k * (x - Vector3::from(t)));
            a.push([p.x / p.z, p.y / p.z]);
            b.push([q.x / q.z, q.y / q.z]);
            z.push(x.z);
        }
        (a, b, z)
    }

    #[test]
    fn exact_pixels_give_the_closed_form() {
        let (a, b, z) = pair([0.04, -0.02, 0.01]);
        let d = robust_depths_from_translation(&a, &b, 0.01).unwrap();
        assert!(d.usable.iter().all(|u| *u));
        let kappa = d.depths[0] / z[0];
        for (e, t) in d.depths.iter().zip(&z) {
            assert!((e / t / kappa - 1.0).abs() < 1e-9, "{e} / {t} vs {kappa}");
        }
        assert!(d.residual < 1e-9);
    }

    #[test]
    fn wrong_tracks_are_flagged_and_the_resection_skips_them() {
        let (a, mut b, z) = pair([0.04, -0.02, 0.01]);
        for k in [3, 17, 29] {
            b[k][0] += 7.0; // a track that slid along the texture
        }
        let d = robust_depths_from_translation(&a, &b, 0.1).unwrap();
        for k in 0..a.len() {
            assert_eq!(d.usable[k], ![3, 17, 29].contains(&k), "point {k}: residual {}", d.residuals[k]);
            assert_eq!(d.depths[k].is_nan(), !d.usable[k]);
        }
        let kappa = d.depths[0] / z[0];
        assert!((0..a.len()).filter(|&k| d.usable[k]).all(|k| (d.depths[k] / z[k] / kappa - 1.0).abs() < 1e-9));
        // The plain least squares is pulled by the three.
        let plain = crate::core::depth::depths_from_translation(&a, &b);
        assert!(
            !plain.is_ok_and(|p| (0..a.len()).all(|k| (p.depths[k] / z[k] / (p.depths[0] / z[0]) - 1.0).abs() < 1e-3))
        );
        // The resection built from the usable depths places the three on their rays: the
        // reference image is the first one translated elsewhere.
        let (_, reference, _) = pair([-0.03, 0.05, -0.02]);
        let mut est = ResectionDepths::new(&a, &d.depths, &reference, 1.0).unwrap();
        let mut out = vec![0.0; a.len()];
        est.estimate(&reference, &vec![true; a.len()], &mut out).unwrap();
        let truth: Vec<f64> = z.iter().map(|z| z + 0.02).collect(); // depths in the reference view
        let kappa = out[0] / truth[0];
        assert!(out.iter().zip(&truth).all(|(o, t)| (o / t / kappa - 1.0).abs() < 1e-8), "{out:?}");
    }

    #[test]
    fn bad_noise_no_motion_and_too_few_are_refused() {
        let (a, b, _) = pair([0.04, -0.02, 0.01]);
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let e = robust_depths_from_translation(&a, &b, bad).unwrap_err();
            assert!(matches!(e, Error::InvalidParameter { name: "pixel_noise", .. }), "{e}");
        }
        assert!(matches!(robust_depths_from_translation(&a[..5], &b[..5], 0.1), Err(Error::TooFewPoints { .. })));
        // No motion: no parallax anywhere.
        assert!(matches!(robust_depths_from_translation(&a, &a, 0.1), Err(Error::DegenerateEstimate { .. })));
    }
}
