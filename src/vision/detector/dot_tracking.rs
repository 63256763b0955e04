//! Today's detector: the [`DotTracker`], started on the expected pixels (its clicks), each
//! dot reported under the identity it was expected with.

use crate::error::Error;
use crate::vision::detector::{Detection, Detector, Expected};
use crate::vision::error::Result;
use crate::vision::image::GreyView;
use crate::vision::image::Window;
use crate::vision::tracker::{DotTracker, TrackResult, TrackerConfig};

/// Dots tracked from image to image.
#[derive(Debug, Clone)]
pub struct DotTracking {
    config: TrackerConfig,
    ids: Vec<u32>,
    tracker: Option<DotTracker>,
    partial: bool,
}

impl DotTracking {
    /// A detector that will track with `config` once started; every expected dot must start.
    pub fn new(config: TrackerConfig) -> Self {
        Self { config, ids: Vec::new(), tracker: None, partial: false }
    }

    /// The same, started on the expected dots that can be started: a hint outside the image,
    /// on a dot cut by the border or on a blob that is not a dot leaves that dot out (not
    /// reported, so not visible); an error only when no dot starts (the first dot's error).
    pub fn partial(config: TrackerConfig) -> Self {
        Self { partial: true, ..Self::new(config) }
    }

    /// The expected dots the tracker can start on, each tried alone (all of them when every
    /// dot must start).
    fn startable<'a>(&self, image: &GreyView<'_>, expected: &'a [Expected]) -> Result<Vec<&'a Expected>> {
        if !self.partial {
            return Ok(expected.iter().collect());
        }
        let mut first_error = None;
        let mut kept = Vec::with_capacity(expected.len());
        for e in expected {
            match DotTracker::new(image, &[e.pixel], self.config) {
                Ok(_) => kept.push(e),
                Err(err) => {
                    first_error.get_or_insert(err);
                }
            }
        }
        match (kept.is_empty(), first_error) {
            (true, Some(err)) => Err(err),
            _ => Ok(kept),
        }
    }

    /// The tracker, once started.
    fn started(&mut self) -> Result<&mut DotTracker> {
        self.tracker
            .as_mut()
            .ok_or_else(|| Error::InvalidParameter { name: "detector", reason: "detect before start".into() }.into())
    }

    fn detections(&self, pixels: &[[f64; 2]], found: impl Fn(usize) -> bool) -> Vec<Detection> {
        self.ids
            .iter()
            .zip(pixels)
            .enumerate()
            .map(|(i, (&id, &pixel))| Detection { id, pixel, found: found(i) })
            .collect()
    }
}

impl Detector for DotTracking {
    /// Finds each dot near its expected pixel (every dot must be there, unless
    /// [`partial`](DotTracking::partial)).
    fn start(&mut self, image: &GreyView<'_>, expected: &[Expected]) -> Result<Vec<Detection>> {
        let expected = self.startable(image, expected)?;
        let clicks: Vec<[f64; 2]> = expected.iter().map(|e| e.pixel).collect();
        let tracker = DotTracker::new(image, &clicks, self.config)?;
        self.ids = expected.iter().map(|e| e.id).collect();
        let out = self.detections(tracker.positions(), |_| true);
        self.tracker = Some(tracker);
        Ok(out)
    }

    fn detect(&mut self, image: &GreyView<'_>) -> Result<Vec<Detection>> {
        let tracked = self.started()?.track(image)?;
        Ok(self.detections(&tracked.pixels, |i| tracked.found[i]))
    }

    /// The tracker's first windows ([`DotTracker::first_windows`]).
    fn reads(&self) -> Option<Vec<Window>> {
        self.tracker.as_ref().map(DotTracker::first_windows)
    }

    fn detect_within(&mut self, image: &GreyView<'_>) -> Result<Option<Vec<Detection>>> {
        let mut tracked = TrackResult::default();
        if !self.started()?.track_in_first_windows(image, &mut tracked)? {
            return Ok(None);
        }
        Ok(Some(self.detections(&tracked.pixels, |i| tracked.found[i])))
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use nalgebra::Isometry3;

    use super::*;
    use crate::core::camera::Intrinsics;
    use crate::core::distortion::Distortion;
    use crate::vision::image::{GreyImage, view_of};
    use crate::vision::render::{CameraView, RenderConfig, Renderer};
    use crate::vision::target::dots::Dots;

    fn image(shift: f64) -> GreyImage {
        let k = Intrinsics::pinhole(1000.0, 1000.0, 60.0, 40.0).unwrap();
        let points = [[-0.02 + shift, 0.0, 0.5], [0.02 + shift, 0.005, 0.5]];
        let dots = Dots::facing_reference(&points, 0.004).unwrap();
        let (pose, none) = (Isometry3::identity(), Distortion::none());
        let view = CameraView { pose: &pose, intrinsics: &k, distortion: &none, size: (120, 80) };
        Renderer::new(RenderConfig::default()).unwrap().render(&dots, None, &view, 0).unwrap().image
    }

    /// Detected within the tracker's first windows (the rest of the image garbage): the
    /// detections of the whole image, or `None` and the detector unchanged when a dot needs a
    /// larger window (a jump of several windows).
    #[test]
    fn detects_within_its_windows_as_in_the_whole_image() {
        let expected = [Expected { id: 9, pixel: [21.0, 40.0] }, Expected { id: 4, pixel: [99.0, 50.0] }];
        let mut windowed = DotTracking::new(TrackerConfig::default());
        let mut whole = DotTracking::new(TrackerConfig::default());
        assert!(windowed.reads().is_none(), "no windows before start");
        let first = image(0.0);
        windowed.start(&view_of(&first).unwrap(), &expected).unwrap();
        whole.start(&view_of(&first).unwrap(), &expected).unwrap();
        let (mut within, mut beyond) = (0, 0);
        for shift in [0.0, 0.001, 0.003, 0.004, 0.02, 0.021, 0.022] {
            let next = image(shift);
            let windows = windowed.reads().unwrap();
            assert_eq!(windows.len(), 2);
            // Every pixel outside the windows spoilt: bright, a dot everywhere.
            let mut spoilt = next.clone();
            for (i, g) in spoilt.iter_mut().enumerate() {
                let (u, v) = (i as u32 % 120, i as u32 / 120);
                if !windows.iter().any(|w| (w.u0..=w.u1).contains(&u) && (w.v0..=w.v1).contains(&v)) {
                    *g = 255;
                }
            }
            let want = whole.detect(&view_of(&next).unwrap()).unwrap();
            match windowed.detect_within(&view_of(&spoilt).unwrap()).unwrap() {
                Some(got) => {
                    within += 1;
                    assert_eq!(got, want, "shift {shift}");
                }
                None => {
                    beyond += 1;
                    assert_eq!(windowed.reads().unwrap(), windows, "unchanged");
                    assert_eq!(windowed.detect(&view_of(&next).unwrap()).unwrap(), want, "shift {shift}");
                }
            }
        }
        assert!(within >= 5 && beyond >= 1, "{within} within, {beyond} beyond");
    }

    #[test]
    fn reports_the_tracker_under_the_expected_identities() {
        let expected = [Expected { id: 9, pixel: [21.0, 40.0] }, Expected { id: 4, pixel: [99.0, 50.0] }];
        let mut detector = DotTracking::new(TrackerConfig::default());
        assert!(detector.detect(&view_of(&image(0.0)).unwrap()).is_err(), "detect before start");
        let first = image(0.0);
        let started = detector.start(&view_of(&first).unwrap(), &expected).unwrap();
        let mut tracker = DotTracker::new(&first, &[[21.0, 40.0], [99.0, 50.0]], TrackerConfig::default()).unwrap();
        assert_eq!(started.iter().map(|d| (d.id, d.found)).collect::<Vec<_>>(), [(9, true), (4, true)]);
        assert_eq!(started.iter().map(|d| d.pixel).collect::<Vec<_>>(), tracker.positions());
        for shift in [0.0, 0.001, 0.002] {
            let next = image(shift);
            let got = detector.detect(&view_of(&next).unwrap()).unwrap();
            let want = tracker.track(&next).unwrap();
            assert_eq!(got.iter().map(|d| d.pixel).collect::<Vec<_>>(), want.pixels);
            assert_eq!(got.iter().map(|d| d.found).collect::<Vec<_>>(), want.found);
            assert_eq!(got.iter().map(|d| d.id).collect::<Vec<_>>(), [9, 4]);
        }
        // A dot not in the first image: the tracker cannot start.
        let missing = [Expected { id: 0, pixel: [60.0, 10.0] }];
        assert!(DotTracking::new(TrackerConfig::default()).start(&view_of(&first).unwrap(), &missing).is_err());
    }
}
