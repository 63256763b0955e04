//! Natural keypoints as a [`Detector`] (see [`crate::vision::features`]): the reference
//! image's points are a spread of its SIFT keypoints, point `i` under identity `i`. The
//! first frame (from any camera) is matched to the reference by descriptors, checked by the
//! fundamental matrix; then each frame tracks the points from the last one (pyramidal LK with
//! a forward-backward check) and checks the tracks against the reference by the fundamental
//! matrix again. The matches are refined to a fraction of a pixel first (the reference's patch
//! warped into the frame and aligned, [`refine`](crate::vision::features::refine)), since
//! SIFT's own positions differ by up to 2 px across two lenses. The reference is blurred
//! as the frames are, by a blur measured on the first frame's matches
//! ([`blur`](crate::vision::features::blur)).
//! A point not found (SIFT matches a third to a half of them across a focal ratio of 2; tracks
//! lose some) is looked for again each frame where its found neighbours put it, aligned on
//! its reference patch ([`FeatureTracking::reacquire`]): the law then measures every point in
//! view, and its basis is switched less often (each switch restarts the controller).
//! A point failing a check is reported not found, never at a wrong place; when
//! fewer than [`FeatureSettings::min_tracked`] remain, the frame is matched afresh
//! (re-detection). The expected pixels are ignored.

use kornia_image::Image;

use crate::vision::detector::{Detection, Detector, Expected};
use crate::vision::error::{Result, VisionError};
use crate::vision::features::blur::matched_blur;
use crate::vision::features::flow::{FlowConfig, FramePyramid, plane, track_pyramids};
use crate::vision::features::keypoints::{Keypoints, sift};
use crate::vision::features::matching::{MIN_MATCHES, checked, epipolar_inliers, local_map, map_at};
use crate::vision::features::refine::{Precision, pyramid, refine, refine_matches, refine_with};
use crate::vision::features::spread::spread;
use crate::vision::image::GreyView;

/// The reference pyramid's levels above the image (focal ratios up to 16 between the lenses).
pub const REFINE_LEVELS: usize = 4;

/// [`FeatureSettings::max_points`] when not given (the target's argument reads it too).
pub const DEFAULT_MAX_POINTS: usize = 150;
/// [`FeatureSettings::min_tracked`] when not given (the target's argument reads it too).
pub const DEFAULT_MIN_TRACKED: usize = 24;

/// The settings of the keypoint target.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FeatureSettings {
    /// How many points of the reference image the target holds (a spread of its keypoints).
    pub max_points: usize,
    /// Fewer points tracked than this (or than half of those matched in the last match)
    /// and the frame is matched afresh.
    pub min_tracked: usize,
    /// The epipolar check's bound at a match by descriptors, pixels.
    pub match_threshold: f64,
    /// The epipolar check's bound on the tracks of each frame, pixels.
    pub track_threshold: f64,
    /// The frame-to-frame tracker's settings.
    pub flow: FlowConfig,
    /// Frames at least between two re-detections (each costs a SIFT of the frame).
    pub redetect_every: u32,
}

impl Default for FeatureSettings {
    fn default() -> Self {
        Self {
            max_points: DEFAULT_MAX_POINTS,
            min_tracked: DEFAULT_MIN_TRACKED,
            match_threshold: 1.5,
            track_threshold: 2.0,
            flow: FlowConfig::default(),
            redetect_every: 5,
        }
    }
}

/// The reference image's keypoints (all of them, for the matcher's ratio test) and the
/// target's points among them (a spread of [`FeatureSettings::max_points`]), point `i`
/// being keypoint `points[i]`.
#[derive(Clone)]
pub struct FeatureReference {
    /// Every keypoint of the reference image.
    pub keypoints: Keypoints,
    /// The target's points: indices in `keypoints`.
    pub points: Vec<usize>,
    /// The reference image's pyramid, for the refinement of the matches ([`refine`](crate::vision::features::refine)).
    pub pyramid: Vec<Image<f32, 1>>,
}

impl std::fmt::Debug for FeatureReference {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FeatureReference")
            .field("keypoints", &self.keypoints.len())
            .field("points", &self.points)
            .field("levels", &self.pyramid.len())
            .finish()
    }
}

impl FeatureReference {
    /// The keypoints of `image` and a spread of `max_points` of them; too few keypoints for
    /// the epipolar check is an error naming `what`.
    pub fn new(what: &str, image: &GreyView<'_>, max_points: usize) -> Result<Self> {
        let keypoints = sift(what, image)?;
        let points = spread(&keypoints.pixels, &keypoints.responses, image.width(), image.height(), max_points);
        if points.len() < MIN_MATCHES {
            return Err(VisionError::InvalidImage {
                what: what.into(),
                reason: format!(
                    "{} keypoints (too little texture), the keypoint target needs at least {MIN_MATCHES}",
                    points.len()
                ),
            });
        }
        let pyramid = pyramid(&plane(what, image)?, REFINE_LEVELS)?;
        Ok(Self { keypoints, points, pyramid })
    }

    /// The target's points as detections (identity `i` for point `i`).
    pub fn detections(&self) -> Vec<Detection> {
        (0u32..)
            .zip(&self.points)
            .map(|(id, &k)| Detection { id, pixel: self.keypoints.pixels[k], found: true })
            .collect()
    }
}

/// The reference image's detector: its points, every time (see [`FeatureReference`]).
#[derive(Debug, Clone, Copy)]
pub struct FeatureReferenceDetector {
    /// How many points.
    pub max_points: usize,
}

impl Detector for FeatureReferenceDetector {
    fn start(&mut self, image: &GreyView<'_>, _expected: &[Expected]) -> Result<Vec<Detection>> {
        self.detect(image)
    }

    fn detect(&mut self, image: &GreyView<'_>) -> Result<Vec<Detection>> {
        Ok(FeatureReference::new("reference_image", image, self.max_points)?.detections())
    }
}

/// The most frames a lost point waits between two tries to find it again
/// ([`FeatureTracking::reacquire`]).
pub const MAX_SKIPPED: u8 = 7;

/// The frames' detector. See the module documentation.
pub struct FeatureTracking {
    settings: FeatureSettings,
    reference: FeatureReference,
    /// The identity of each point tracked, and its keypoint (index in the reference's).
    ids: Vec<u32>,
    keypoints: Vec<usize>,
    /// The last frame's pyramid (kept: it is the next track's start).
    previous: Option<FramePyramid>,
    /// The pyramid before it, done with: its buffers hold the next frame's.
    spare: Option<FramePyramid>,
    last: Vec<Option<[f64; 2]>>,
    /// Each lost point's failed reacquisitions in a row ([`FeatureTracking::reacquire`]) and
    /// the frames left before its next try.
    misses: Vec<(u8, u8)>,
    /// The points aligned with [`Precision::Fine`] ([`Detector::favour`]): indices in `ids`.
    favoured: Vec<usize>,
    /// The blur of the reference's patches, measured on the first frame's matches
    /// ([`matched_blur`]); None until measured.
    blur: Option<f64>,
    matched: usize,
    since_match: u32,
    matches: u32,
}

impl std::fmt::Debug for FeatureTracking {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FeatureTracking").field("points", &self.last.len()).field("matches", &self.matches).finish()
    }
}

impl FeatureTracking {
    /// The detector of the frames, for the points `ids` of `reference` (None: all); an
    /// identity the reference does not hold is an error naming `point_ids`.
    pub fn new(reference: FeatureReference, settings: FeatureSettings, ids: Option<&[u32]>) -> Result<Self> {
        let all: Vec<u32> = (0u32..).take(reference.points.len()).collect();
        let ids = ids.map_or(all, <[u32]>::to_vec);
        let mut keypoints = Vec::with_capacity(ids.len());
        for &id in &ids {
            let k = usize::try_from(id).ok().and_then(|i| reference.points.get(i)).ok_or_else(|| {
                let reason = format!("no point {id}: the reference image holds points 0..{}", reference.points.len());
                crate::error::Error::InvalidParameter { name: "point_ids", reason }
            })?;
            keypoints.push(*k);
        }
        let n = ids.len();
        Ok(Self {
            settings,
            reference,
            ids,
            keypoints,
            previous: None,
            spare: None,
            last: vec![None; n],
            misses: vec![(0, 0); n],
            favoured: Vec::new(),
            blur: None,
            matched: 0,
            since_match: 0,
            matches: 0,
        })
    }

    /// The blur (a Gaussian's sigma, reference pixels) added to the reference so that its
    /// patches are as blurred as the frames' ([`matched_blur`]), measured on the first frame
    /// whose matches allowed it; None before.
    pub fn reference_blur(&self) -> Option<f64> {
        self.blur
    }

    /// How many times a frame was matched by descriptors (the first frame and each
    /// re-detection).
    pub fn matches(&self) -> u32 {
        self.matches
    }

    /// Matches `image` to the reference by descriptors (checked by the fundamental matrix)
    /// and takes the positions of the points not tracked. A frame with too few matches
    /// leaves the points as they are.
    fn rematch(&mut self, image: &GreyView<'_>, plane: &Image<f32, 1>) -> Result<()> {
        self.matches += 1;
        self.since_match = 0;
        let frame = sift("image", image)?;
        let Ok(found) = checked("image", &self.reference.keypoints, &frame, self.settings.match_threshold) else {
            return Ok(());
        };
        let first: Vec<[f64; 2]> = found.iter().map(|m| self.reference.keypoints.pixels[m.reference]).collect();
        let second: Vec<[f64; 2]> = found.iter().map(|m| m.pixel).collect();
        if self.blur.is_none()
            && let Some(sharp) = self.reference.pyramid.first()
        {
            let levels = self.reference.pyramid.len() - 1;
            if let Some((sigma, pyramid)) = matched_blur(sharp, levels, plane, &first, &second)? {
                self.reference.pyramid = pyramid;
                self.blur = Some(sigma);
            }
        }
        let refined = refine_matches(&self.reference.pyramid, plane, &first, &second);
        for (m, pixel) in found.iter().zip(refined) {
            if let Some(i) = self.keypoints.iter().position(|&k| k == m.reference)
                && self.last[i].is_none()
            {
                self.last[i] = pixel;
            }
        }
        self.matched = self.last.iter().flatten().count();
        self.misses.fill((0, 0));
        Ok(())
    }

    /// Aligns each tracked point on the reference's patch warped into the frame ([`refine`]),
    /// from where the tracker put it: frame-to-frame tracks drift (a few tenths of a pixel
    /// over a hundred frames), the reference's patch does not. A point that does not align is
    /// lost.
    ///
    /// [`refine`]: crate::vision::features::refine
    fn anchor(&mut self, frame: &Image<f32, 1>) {
        let which: Vec<usize> = (0..self.last.len()).filter(|&i| self.last[i].is_some()).collect();
        let first: Vec<[f64; 2]> = which.iter().map(|&i| self.reference.keypoints.pixels[self.keypoints[i]]).collect();
        let second: Vec<[f64; 2]> = which.iter().filter_map(|&i| self.last[i]).collect();
        for (k, &i) in which.iter().enumerate() {
            self.last[i] =
                local_map(&first, &second, k).and_then(|map| self.align(frame, i, first[k], &map, second[k]));
        }
    }

    /// Point `i` (the reference's `at`) aligned in `frame` from `start` with the local map `map`
    /// ([`refine`]); a favoured point is then aligned again from there with
    /// [`Precision::Fine`], the first result kept where that fails.
    fn align(
        &self,
        frame: &Image<f32, 1>,
        i: usize,
        at: [f64; 2],
        map: &nalgebra::Matrix2<f64>,
        start: [f64; 2],
    ) -> Option<[f64; 2]> {
        let fast = refine(&self.reference.pyramid, frame, at, map, start)?;
        if !self.favoured.contains(&i) {
            return Some(fast);
        }
        refine_with(&self.reference.pyramid, frame, at, map, fast, Precision::Fine)
            .map_or(Some(fast), |(fine, _)| Some(fine))
    }

    /// Finds the points not found again without descriptors: each one's pixel predicted by the
    /// affine map of its nearest found neighbours (reference to frame), then aligned on the
    /// reference's patch as the matches are ([`refine`]). SIFT matches a third to a half of
    /// the points across a focal ratio of 2, and tracks lose some on the way; with the others
    /// back, the law measures every point in view (its bound shrinks with their number and
    /// spread) and its basis is switched less often. The epipolar check follows.
    ///
    /// A point that fails skips 1, then 3, then [`MAX_SKIPPED`] frames before each next try
    /// (until found, or a match of the frame): most lost points stay lost for many frames,
    /// behind the object or off its visible faces (87 % of the tries failed on ViSP's
    /// `mbt/cube` frames, each a whole alignment).
    pub fn reacquire(&mut self, frame: &Image<f32, 1>) {
        let found: Vec<usize> = (0..self.last.len()).filter(|&i| self.last[i].is_some()).collect();
        if found.len() == self.last.len() {
            return;
        }
        let first: Vec<[f64; 2]> = found.iter().map(|&i| self.reference.keypoints.pixels[self.keypoints[i]]).collect();
        let second: Vec<[f64; 2]> = found.iter().filter_map(|&i| self.last[i]).collect();
        for i in 0..self.last.len() {
            if self.last[i].is_some() {
                continue;
            }
            let (missed, wait) = self.misses[i];
            if wait > 0 {
                self.misses[i].1 = wait - 1;
                continue;
            }
            let at = self.reference.keypoints.pixels[self.keypoints[i]];
            if let Some((map, guess)) = map_at(&first, &second, at) {
                self.last[i] = self.align(frame, i, at, &map, guess);
            }
            self.misses[i] = match self.last[i] {
                Some(_) => (0, 0),
                None => (missed.saturating_add(1), ((2u8 << missed.min(2)) - 1).min(MAX_SKIPPED)),
            };
        }
    }

    /// Drops the points off the epipolar geometry of the others with the reference: all of
    /// them when too few are left for the check.
    fn check_epipolar(&mut self) {
        let (mut first, mut second, mut which) = (Vec::new(), Vec::new(), Vec::new());
        for (i, p) in self.last.iter().enumerate() {
            if let Some(p) = p {
                first.push(self.reference.keypoints.pixels[self.keypoints[i]]);
                second.push(*p);
                which.push(i);
            }
        }
        match epipolar_inliers("image", &first, &second, self.settings.track_threshold) {
            Ok(inliers) => {
                for (i, ok) in which.into_iter().zip(inliers) {
                    if !ok {
                        self.last[i] = None;
                    }
                }
            }
            Err(_) => self.last.fill(None),
        }
    }

    /// The points found (those not found are not reported).
    fn report(&self) -> Vec<Detection> {
        self.ids
            .iter()
            .zip(&self.last)
            .filter_map(|(&id, p)| p.map(|pixel| Detection { id, pixel, found: true }))
            .collect()
    }

    fn too_few(&self) -> bool {
        let visible = self.last.iter().flatten().count();
        visible < self.settings.min_tracked.max(self.matched / 2)
    }
}

impl Detector for FeatureTracking {
    /// Matches the first frame to the reference (the hints are ignored).
    fn start(&mut self, image: &GreyView<'_>, _expected: &[Expected]) -> Result<Vec<Detection>> {
        self.last.fill(None);
        self.misses.fill((0, 0));
        let next = FramePyramid::of(plane("image", image)?, self.settings.flow.levels, self.spare.take())?;
        self.rematch(image, next.image())?;
        self.check_epipolar();
        self.reacquire(next.image());
        self.spare = self.previous.replace(next);
        self.check_epipolar();
        Ok(self.report())
    }

    /// Tracks the points from the last frame, checks them, and matches the frame afresh
    /// when too few remain.
    fn detect(&mut self, image: &GreyView<'_>) -> Result<Vec<Detection>> {
        let mut next = FramePyramid::of(plane("image", image)?, self.settings.flow.levels, self.spare.take())?;
        let same_size = self.previous.as_ref().is_some_and(|p| p.image().size() == next.image().size());
        if same_size && let Some(previous) = &mut self.previous {
            let which: Vec<usize> = (0..self.last.len()).filter(|&i| self.last[i].is_some()).collect();
            let points: Vec<[f64; 2]> = which.iter().filter_map(|&i| self.last[i]).collect();
            let tracked = track_pyramids(previous, &mut next, &points, &self.settings.flow)?;
            for (i, p) in which.into_iter().zip(tracked) {
                self.last[i] = p;
            }
            self.anchor(next.image());
        } else {
            self.last.fill(None);
        }
        self.since_match = self.since_match.saturating_add(1);
        if self.too_few() && (self.since_match >= self.settings.redetect_every || !same_size) {
            self.rematch(image, next.image())?;
        }
        self.reacquire(next.image());
        self.spare = self.previous.replace(next);
        self.check_epipolar();
        Ok(self.report())
    }

    /// The favoured points are aligned with [`Precision::Fine`] (the others with
    /// [`Precision::Fast`]): the law's basis, three points, a small cost a frame.
    fn favour(&mut self, ids: &[u32]) {
        self.favoured = ids.iter().filter_map(|id| self.ids.iter().position(|i| i == id)).collect();
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::vision::image::view;

    /// A textured frame (blobs on waves), a `hidden` box of it flat grey.
    fn frame(hidden: Option<(usize, usize, usize, usize)>) -> Vec<u8> {
        seen_through(&|x, y| [x, y], hidden)
    }

    /// The textured frame of [`frame`] seen through `to_texture` (frame pixel to texture point).
    fn seen_through(
        to_texture: &dyn Fn(f64, f64) -> [f64; 2],
        hidden: Option<(usize, usize, usize, usize)>,
    ) -> Vec<u8> {
        let (w, h) = (320usize, 240usize);
        let mut state = 11u64;
        let blobs: Vec<[f64; 3]> = (0..90)
            .map(|_| {
                let mut draw = || {
                    state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                    (state >> 33) as f64 / f64::from(1u32 << 31)
                };
                [draw() * w as f64, draw() * h as f64, 2.0 + 5.0 * draw()]
            })
            .collect();
        let mut out = vec![0u8; w * h];
        for (i, px) in out.iter_mut().enumerate() {
            let [x, y] = to_texture((i % w) as f64, (i / w) as f64);
            let mut v = 120.0 + 25.0 * (0.11 * x).sin() * (0.07 * y).cos();
            for (k, b) in blobs.iter().enumerate() {
                let d2 = ((x - b[0]).powi(2) + (y - b[1]).powi(2)) / (b[2] * b[2]);
                v += if k % 2 == 0 { 90.0 } else { -90.0 } * (-d2).exp();
            }
            *px = v.clamp(0.0, 255.0) as u8;
        }
        if let Some((x0, y0, x1, y1)) = hidden {
            for y in y0..y1 {
                out[y * w + x0..y * w + x1].fill(128);
            }
        }
        out
    }

    /// Points hidden by a box are lost; each is tried again after skipping 1, 3, then
    /// `MAX_SKIPPED` frames; once the box is gone, every one is found again within
    /// `MAX_SKIPPED + 1` frames, where it was.
    #[test]
    fn a_lost_point_is_tried_less_often_and_found_again() {
        let clear = frame(None);
        let reference = FeatureReference::new("reference_image", &view("r", 320, 240, &clear).unwrap(), 150).unwrap();
        let mut tracking = FeatureTracking::new(reference, FeatureSettings::default(), None).unwrap();
        let first = tracking.start(&view("image", 320, 240, &clear).unwrap(), &[]).unwrap();
        let box_ = (200, 20, 300, 120);
        let inside = |p: [f64; 2]| p[0] > 215.0 && p[0] < 285.0 && p[1] > 35.0 && p[1] < 105.0;
        let hidden: Vec<u32> = first.iter().filter(|d| inside(d.pixel)).map(|d| d.id).collect();
        assert!(hidden.len() >= 3, "{} points in the box", hidden.len());
        let covered = frame(Some(box_));
        let mut tries: Vec<Vec<usize>> = vec![Vec::new(); tracking.ids.len()];
        for k in 1..=16 {
            let before: Vec<u8> = tracking.misses.iter().map(|m| m.0).collect();
            let found = tracking.detect(&view("image", 320, 240, &covered).unwrap()).unwrap();
            assert_eq!(tracking.matches(), 1, "no match of a frame again");
            for &id in &hidden {
                let i = id as usize;
                assert!(found.iter().all(|d| d.id != id), "point {id} seen through the box");
                if tracking.misses[i].0 != before[i] {
                    tries[i].push(k);
                }
            }
        }
        for &id in &hidden {
            assert_eq!(tries[id as usize], [1, 3, 7, 15], "point {id}'s tries");
        }
        let mut back = Vec::new();
        for _ in 0..=MAX_SKIPPED {
            back = tracking.detect(&view("image", 320, 240, &clear).unwrap()).unwrap();
        }
        for d in &first {
            let again = back.iter().find(|b| b.id == d.id).expect("found again");
            assert!((again.pixel[0] - d.pixel[0]).hypot(again.pixel[1] - d.pixel[1]) < 0.05, "point {}", d.id);
        }
    }

    /// Frames blurred by a Gaussian of 1.5 px that the reference does not have, at the same
    /// scale (so the reference's level 0 is aligned, unblurred): the blur measured on the first
    /// frame's matches is 1.5 px within 0.3 (None before a frame), and the points are found at
    /// their reference pixels (the median error under 0.03 px).
    #[test]
    fn the_reference_is_blurred_as_the_frames_are() {
        let clear = frame(None);
        let sharp = crate::vision::image::GreyImage::from_raw(320, 240, clear.clone()).unwrap();
        let blurred = imageproc::filter::gaussian_blur_f32(&sharp, 1.5).into_raw();
        let reference = FeatureReference::new("reference_image", &view("r", 320, 240, &clear).unwrap(), 150).unwrap();
        let mut tracking = FeatureTracking::new(reference.clone(), FeatureSettings::default(), None).unwrap();
        assert_eq!(tracking.reference_blur(), None);
        let found = tracking.start(&view("image", 320, 240, &blurred).unwrap(), &[]).unwrap();
        let sigma = tracking.reference_blur().expect("measured");
        assert!((sigma - 1.5).abs() < 0.3, "{sigma}");
        let mut errors: Vec<f64> = found
            .iter()
            .map(|d| {
                let r = reference.keypoints.pixels[reference.points[d.id as usize]];
                (d.pixel[0] - r[0]).hypot(d.pixel[1] - r[1])
            })
            .collect();
        errors.sort_by(f64::total_cmp);
        assert!(errors.len() >= 60 && errors[errors.len() / 2] < 0.03, "{} found, {errors:?}", errors.len());
        eprintln!("blur {sigma:.3}, {} found, median error {:.4} px", errors.len(), errors[errors.len() / 2]);
    }

    /// The reference folded along the line `x = 160` (two planes, as the faces of a box) and
    /// seen through a perspective with a smaller lens: the neighbours' affine map is off at the
    /// points near the fold, whose neighbours lie on the other face. Each point's true pixel known:
    /// the points favoured ([`Detector::favour`], here all of them) are aligned with
    /// [`Precision::Fine`], and those within 25 px of the fold land nearer their true pixels
    /// than the fast alignment puts them (the median error down by 30 % or more; a patch
    /// across the fold fits neither alignment's warp); a favour naming no tracked point changes
    /// nothing.
    #[test]
    fn favoured_points_land_nearer_their_true_pixels() {
        let h = nalgebra::Matrix3::new(0.62, 0.06, 50.0, -0.05, 0.66, 38.0, 4e-4, 3e-4, 1.0);
        // The second face: `x = 160` kept in place, the rest stretched and sheared.
        let fold = nalgebra::Matrix3::new(1.3, 0.0, -48.0, 0.12, 1.0, -19.2, 0.0, 0.0, 1.0);
        let (inverse, unfold) = (h.try_inverse().unwrap(), fold.try_inverse().unwrap());
        let project = |m: &nalgebra::Matrix3<f64>, p: [f64; 2]| {
            let q = m * nalgebra::Vector3::new(p[0], p[1], 1.0);
            [q.x / q.z, q.y / q.z]
        };
        // Each frame pixel the mean of 3 x 3 samples of the texture (as a lens and a sensor
        // blur it).
        let layers: Vec<Vec<u8>> = (0..9)
            .map(|k| {
                let (du, dv) = (f64::from(k % 3 - 1) / 3.0, f64::from(k / 3 - 1) / 3.0);
                seen_through(
                    &|u, v| {
                        let r = project(&inverse, [u + du, v + dv]);
                        if r[0] < 160.0 { r } else { project(&unfold, r) }
                    },
                    None,
                )
            })
            .collect();
        let warped: Vec<u8> =
            (0..320 * 240).map(|i| (layers.iter().map(|l| f64::from(l[i])).sum::<f64>() / 9.0).round() as u8).collect();
        let clear = frame(None);
        let reference = FeatureReference::new("reference_image", &view("r", 320, 240, &clear).unwrap(), 150).unwrap();
        let truth = |id: u32| {
            let r = reference.keypoints.pixels[reference.points[id as usize]];
            if r[0] < 160.0 { project(&h, r) } else { project(&(h * fold), r) }
        };
        let track = |favour: &[u32]| {
            let mut tracking = FeatureTracking::new(reference.clone(), FeatureSettings::default(), None).unwrap();
            tracking.favour(favour);
            tracking.start(&view("image", 320, 240, &warped).unwrap(), &[]).unwrap();
            tracking.detect(&view("image", 320, 240, &warped).unwrap()).unwrap()
        };
        let near = |id: u32| (reference.keypoints.pixels[reference.points[id as usize]][0] - 160.0).abs() < 25.0;
        let errors = |found: &[Detection]| {
            let mut e: Vec<f64> = found
                .iter()
                .filter(|d| near(d.id))
                .map(|d| (d.pixel[0] - truth(d.id)[0]).hypot(d.pixel[1] - truth(d.id)[1]))
                .collect();
            e.sort_by(f64::total_cmp);
            (e.len(), e[e.len() / 2])
        };
        let all: Vec<u32> = (0..150).collect();
        let (fast, fine) = (track(&[]), track(&all));
        let ((n_fast, median_fast), (n_fine, median_fine)) = (errors(&fast), errors(&fine));
        assert!(n_fast >= 10 && n_fine + n_fine / 10 >= n_fast, "{n_fast} fast, {n_fine} fine");
        assert!(median_fine < 0.7 * median_fast, "median {median_fine} (fast {median_fast})");
        let elsewhere = track(&[9999]);
        assert!(elsewhere.iter().zip(&fast).all(|(a, b)| a.id == b.id && a.pixel == b.pixel));
    }
}
