//! Natural keypoints as a [`Detector`] (see [`crate::vision::features`]): the reference
//! image's points are a spread of its SIFT keypoints, point `i` under identity `i`. The
//! first frame (from any camera) is matched to the reference by descriptors, checked by the
//! fundamental matrix; then each frame tracks the points from the last one (pyramidal LK with
//! a forward-backward check) and checks the tracks against the reference by the fundamental
//! matrix again. The matches are refined to a fraction of a pixel first (the reference's patch
//! warped into the frame and aligned, [`refine`](crate::vision::features::refine)), since
//! SIFT's own positions differ by up to 2 px across two lenses.
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
use crate::vision::features::flow::{FlowConfig, FramePyramid, plane, track_pyramids};
use crate::vision::features::keypoints::{Keypoints, sift};
use crate::vision::features::matching::{MIN_MATCHES, checked, epipolar_inliers, map_at};
use crate::vision::features::refine::{pyramid, refine, refine_matches};
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
            matched: 0,
            since_match: 0,
            matches: 0,
        })
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
        let refined = refine_matches(&self.reference.pyramid, frame, &first, &second);
        for (i, p) in which.into_iter().zip(refined) {
            self.last[i] = p;
        }
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
                self.last[i] = refine(&self.reference.pyramid, frame, at, &map, guess);
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
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::vision::image::view;

    /// A textured frame (blobs on waves), a `hidden` box of it flat grey.
    fn frame(hidden: Option<(usize, usize, usize, usize)>) -> Vec<u8> {
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
            let (x, y) = ((i % w) as f64, (i / w) as f64);
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
}
