//! Matches between two images taken by two cameras (any intrinsics): nearest descriptors
//! (Lowe's ratio, both ways), then the fundamental matrix F in RANSAC, which holds between any
//! two pinhole views of a rigid scene whatever their intrinsics (x2' F x1 = 0): a match off its
//! epipolar line by more than the threshold is dropped (a homography instead when it explains
//! nine matches in ten: no parallax, or a plane, where F is not determined); then each match is checked against its
//! neighbours (a locally affine view), which sees a wrong match along its epipolar line.

use kornia_3d::pose::{RansacParams, ransac_fundamental, ransac_homography};
use kornia_algebra::Vec2F64;
use kornia_imgproc::features::sift_match_descriptors;

use crate::vision::error::{Result, VisionError};
use crate::vision::features::keypoints::Keypoints;

/// Lowe's ratio: the nearest descriptor must be nearer than this times the second nearest.
pub const RATIO: f32 = 0.8;

/// The fewest matches the fundamental matrix is estimated from (its 8-point solver, with a
/// margin against a chance consensus).
pub const MIN_MATCHES: usize = 12;

/// A match: keypoint `reference` of the first image, at `pixel` in the second.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Match {
    /// Index in the first image's keypoints.
    pub reference: usize,
    /// Index in the second image's keypoints.
    pub frame: usize,
    /// The pixel in the second image.
    pub pixel: [f64; 2],
}

/// The descriptor matches of `reference` in `frame` (each reference keypoint at most once):
/// mutual nearest neighbours passing Lowe's ratio.
pub fn nearest(reference: &Keypoints, frame: &Keypoints) -> Vec<Match> {
    let pairs =
        sift_match_descriptors(&reference.descriptors, reference.len(), &frame.descriptors, frame.len(), RATIO, true);
    let mut out: Vec<Match> = Vec::new();
    for [r, f] in pairs {
        let (Ok(r), Ok(f)) = (usize::try_from(r), usize::try_from(f)) else { continue };
        let Some(&pixel) = frame.pixels.get(f) else { continue };
        if r < reference.len() && !out.iter().any(|m| m.reference == r || m.frame == f) {
            out.push(Match { reference: r, frame: f, pixel });
        }
    }
    out
}

/// Which pairs `(first[i], second[i])` agree with one fundamental matrix, within `threshold`
/// pixels (RANSAC, seeded: the same answer for the same points). Fewer than [`MIN_MATCHES`]
/// pairs, or no consensus of that many, is an error naming `what`.
pub fn epipolar_inliers(what: &str, first: &[[f64; 2]], second: &[[f64; 2]], threshold: f64) -> Result<Vec<bool>> {
    let few = |reason: String| VisionError::InvalidImage { what: what.into(), reason };
    if first.len() != second.len() || first.len() < MIN_MATCHES {
        return Err(few(format!(
            "{} matches with the reference image, fewer than the {MIN_MATCHES} the epipolar check needs",
            first.len().min(second.len())
        )));
    }
    let to = |p: &[[f64; 2]]| p.iter().map(|&[u, v]| Vec2F64::new(u, v)).collect::<Vec<_>>();
    let params =
        RansacParams { max_iterations: 4000, threshold, min_inliers: MIN_MATCHES, random_seed: Some(32), refit: true };
    let (a, b) = (to(first), to(second));
    // No parallax (the two cameras at one centre, as at the servo's goal with another lens)
    // or a plane: a homography holds and the fundamental matrix is not determined; the
    // homography is then the check.
    let plane = crate::parallel::install(|| ransac_homography(&a, &b, &params))?.ok();
    if let Some(h) = &plane
        && h.inlier_count * 10 >= first.len() * 9
    {
        return Ok(h.inliers.clone());
    }
    match crate::parallel::install(|| ransac_fundamental(&a, &b, &params))? {
        Ok(found) => Ok(found.inliers),
        Err(_) if plane.as_ref().is_some_and(|h| h.inlier_count >= MIN_MATCHES) => {
            Ok(plane.map(|h| h.inliers).unwrap_or_default())
        }
        Err(e) => Err(few(format!("no fundamental matrix agrees with {MIN_MATCHES} of the matches: {e}"))),
    }
}

/// How far (pixels) a match may be from where its neighbours' affine map puts it.
pub const LOCAL_TOLERANCE: f64 = 3.0;

/// The matches of `reference` in `frame` that pass the epipolar check (`threshold` pixels)
/// and then agree with their neighbours ([`locally_consistent`]).
pub fn checked(what: &str, reference: &Keypoints, frame: &Keypoints, threshold: f64) -> Result<Vec<Match>> {
    let matches = nearest(reference, frame);
    let first: Vec<[f64; 2]> = matches.iter().map(|m| reference.pixels[m.reference]).collect();
    let second: Vec<[f64; 2]> = matches.iter().map(|m| m.pixel).collect();
    let inliers = epipolar_inliers(what, &first, &second, threshold)?;
    let kept: Vec<Match> = matches.into_iter().zip(inliers).filter(|(_, ok)| *ok).map(|(m, _)| m).collect();
    let first: Vec<[f64; 2]> = kept.iter().map(|m| reference.pixels[m.reference]).collect();
    let second: Vec<[f64; 2]> = kept.iter().map(|m| m.pixel).collect();
    let local = locally_consistent(&first, &second, LOCAL_TOLERANCE);
    Ok(kept.into_iter().zip(local).filter(|(_, ok)| *ok).map(|(m, _)| m).collect())
}

/// The neighbours a match is checked against by [`locally_consistent`].
pub const NEIGHBOURS: usize = 8;

/// Which matches `(first[i], second[i])` their neighbours agree with: the affine map fitted
/// (least squares) to the [`NEIGHBOURS`] matches nearest to `first[i]` in the first image puts
/// `first[i]` within `tolerance` pixels of `second[i]` (a surface is locally planar and a view
/// locally affine). The fundamental matrix cannot see a wrong match along its epipolar line;
/// its neighbours can. A match with too few neighbours, or whose neighbours do not fix an
/// affine map (collinear), is not kept: not visible rather than wrong.
pub fn locally_consistent(first: &[[f64; 2]], second: &[[f64; 2]], tolerance: f64) -> Vec<bool> {
    (0..first.len().min(second.len()))
        .map(|i| {
            let ids = neighbours(first, first[i], Some(i));
            if ids.len() < NEIGHBOURS {
                return false;
            }
            affine_prediction(first, second, &ids, first[i])
                .is_some_and(|p| (p[0] - second[i][0]).hypot(p[1] - second[i][1]) <= tolerance)
        })
        .collect()
}

/// The indices of the (at most) [`NEIGHBOURS`] points of `points` nearest to `at`, but
/// `skip`, nearest first (equal distances by index): the [`NEIGHBOURS`] smallest are chosen
/// in linear time, then only they are sorted.
fn neighbours(points: &[[f64; 2]], at: [f64; 2], skip: Option<usize>) -> Vec<usize> {
    let mut near: Vec<(f64, usize)> = (0..points.len())
        .filter(|&j| Some(j) != skip)
        .map(|j| ((points[j][0] - at[0]).hypot(points[j][1] - at[1]), j))
        .collect();
    let order = |a: &(f64, usize), b: &(f64, usize)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
    if near.len() > NEIGHBOURS {
        near.select_nth_unstable_by(NEIGHBOURS, order);
        near.truncate(NEIGHBOURS);
    }
    near.sort_unstable_by(order);
    near.into_iter().map(|(_, j)| j).collect()
}

/// The affine map fitted to the pairs `ids` (least squares, centred on `at`), applied to `at`.
fn affine_prediction(first: &[[f64; 2]], second: &[[f64; 2]], ids: &[usize], at: [f64; 2]) -> Option<[f64; 2]> {
    affine_fit(first, second, ids, at).map(|(_, p)| p)
}

/// The affine map fitted to the pairs `ids` (least squares) as its linear part and its value
/// at `at`; None when the first image's points do not fix it (collinear).
fn affine_fit(
    first: &[[f64; 2]],
    second: &[[f64; 2]],
    ids: &[usize],
    at: [f64; 2],
) -> Option<(nalgebra::Matrix2<f64>, [f64; 2])> {
    // Rows [du, dv, 1] of the first image's offsets from `at`; the map's value at `at` is the
    // constant term of each coordinate's least-squares fit.
    let mut ata = nalgebra::Matrix3::<f64>::zeros();
    let mut atb = nalgebra::Matrix3x2::<f64>::zeros();
    for &j in ids {
        let row = nalgebra::Vector3::new(first[j][0] - at[0], first[j][1] - at[1], 1.0);
        ata += row * row.transpose();
        atb += row * nalgebra::RowVector2::new(second[j][0], second[j][1]);
    }
    // Collinear neighbours leave the map free across their line.
    let eig = ata.fixed_view::<2, 2>(0, 0).into_owned().symmetric_eigenvalues();
    let spread = eig.min() / ids.len() as f64;
    if !(spread > 1.0) {
        return None;
    }
    let x = ata.cholesky()?.solve(&atb);
    let linear = nalgebra::Matrix2::new(x[(0, 0)], x[(1, 0)], x[(0, 1)], x[(1, 1)]);
    Some((linear, [x[(2, 0)], x[(2, 1)]]))
}

/// The affine map (first image to second) fitted to the [`NEIGHBOURS`] matches nearest to
/// `at` in the first image: its linear part and its value at `at` (where the second image
/// should show the first image's `at`); None with fewer matches or collinear ones.
pub fn map_at(first: &[[f64; 2]], second: &[[f64; 2]], at: [f64; 2]) -> Option<(nalgebra::Matrix2<f64>, [f64; 2])> {
    let ids = neighbours(&first[..first.len().min(second.len())], at, None);
    (ids.len() == NEIGHBOURS).then(|| affine_fit(first, second, &ids, at)).flatten()
}

/// The local linear map (first image to second) at match `i`, fitted to its
/// [`NEIGHBOURS`] nearest matches.
pub fn local_map(first: &[[f64; 2]], second: &[[f64; 2]], i: usize) -> Option<nalgebra::Matrix2<f64>> {
    let ids = neighbours(&first[..first.len().min(second.len())], first[i], Some(i));
    (ids.len() == NEIGHBOURS).then(|| affine_fit(first, second, &ids, first[i]).map(|(m, _)| m)).flatten()
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    /// The linear-time choice of neighbours is the full sort's (distance, then index), with
    /// ties (a grid) and fewer points than neighbours.
    #[test]
    fn neighbours_are_the_sorted_prefix() {
        let mut state = 7u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 40) % 64) as f64 / 4.0
        };
        for n in [0, 1, 5, NEIGHBOURS, NEIGHBOURS + 1, 40, 150] {
            let points: Vec<[f64; 2]> = (0..n).map(|_| [next(), next()]).collect();
            for (at, skip) in [([3.0, 4.0], None), ([8.0, 8.0], Some(n / 2)), ([0.0, 0.0], Some(0))] {
                let mut all: Vec<(f64, usize)> = (0..n)
                    .filter(|&j| Some(j) != skip)
                    .map(|j| ((points[j][0] - at[0]).hypot(points[j][1] - at[1]), j))
                    .collect();
                all.sort_by(|a, b| a.0.total_cmp(&b.0));
                let expected: Vec<usize> = all.iter().take(NEIGHBOURS).map(|&(_, j)| j).collect();
                assert_eq!(neighbours(&points, at, skip), expected, "n = {n}, at {at:?}, skip {skip:?}");
            }
        }
    }

    /// A grid of points, its image under a homography (a plane seen by another camera), one
    /// match moved 6 px: only that one is refused by its neighbours; the fundamental matrix of
    /// two views of a non-planar grid keeps the true pairs.
    #[test]
    fn neighbours_refuse_a_wrong_match_the_others_pass() {
        let h = nalgebra::Matrix3::new(0.9, 0.1, 20.0, -0.05, 1.1, 5.0, 1e-4, -2e-4, 1.0);
        let mut first = Vec::new();
        for i in 0..10 {
            for j in 0..8 {
                first.push([30.0 + 40.0 * f64::from(i) + 3.0 * f64::from(j % 3), 25.0 + 45.0 * f64::from(j)]);
            }
        }
        let map = |p: [f64; 2]| {
            let x = h * nalgebra::Vector3::new(p[0], p[1], 1.0);
            [x[0] / x[2], x[1] / x[2]]
        };
        let mut second: Vec<[f64; 2]> = first.iter().map(|&p| map(p)).collect();
        second[33][0] += 6.0;
        let ok = locally_consistent(&first, &second, LOCAL_TOLERANCE);
        assert!(!ok[33]);
        // The wrong one spoils its neighbours' fits a little, never beyond the tolerance here.
        assert_eq!(ok.iter().filter(|&&k| !k).count(), 1, "{ok:?}");
        // Collinear neighbours fix no affine map: not kept.
        let line: Vec<[f64; 2]> = (0..12).map(|i| [f64::from(i) * 10.0, 5.0]).collect();
        assert!(locally_consistent(&line, &line, 3.0).iter().all(|&k| !k));
        // Too few pairs for the epipolar check: an error naming the image.
        let err = epipolar_inliers("frame", &first[..5], &second[..5], 1.0).unwrap_err();
        assert!(err.to_string().starts_with("frame: 5 matches"), "{err}");
    }

    /// Two views of a non-planar set by two cameras of different focal lengths: every true
    /// pair is an epipolar inlier, and a pair moved off its epipolar line is not.
    #[test]
    fn the_epipolar_check_needs_no_intrinsics() {
        let mut points = Vec::new();
        for i in 0..40 {
            let t = f64::from(i);
            points.push(nalgebra::Vector3::new(
                (t * 0.37).sin() * 0.2,
                (t * 0.91).cos() * 0.15,
                1.0 + 0.1 * (t * 0.53).sin(),
            ));
        }
        let project = |f: f64, c: [f64; 2], r: nalgebra::Rotation3<f64>, t: nalgebra::Vector3<f64>| {
            points
                .iter()
                .map(|p| {
                    let q = r * p + t;
                    [f * q.x / q.z + c[0], f * q.y / q.z + c[1]]
                })
                .collect::<Vec<_>>()
        };
        let first = project(1200.0, [320.0, 240.0], nalgebra::Rotation3::identity(), nalgebra::Vector3::zeros());
        let r = nalgebra::Rotation3::from_euler_angles(0.05, -0.1, 0.02);
        let mut second = project(600.0, [300.0, 250.0], r, nalgebra::Vector3::new(0.1, -0.03, 0.05));
        second[7][1] += 8.0;
        let inliers = epipolar_inliers("image", &first, &second, 1.0).unwrap();
        assert!(!inliers[7]);
        assert_eq!(inliers.iter().filter(|&&k| k).count(), 39);
    }
}
