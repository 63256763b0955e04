//! `vsinv.vision.TagTracker`: AprilTags through a sequence of frames (the `vision` layer's
//! `TagDetector`), each searched near its last corners first; the work runs with the GIL
//! released.

use pyo3::prelude::*;

use super::errors::invalid_argument;
use super::image_arg::image_arg;
use super::shared::Shared;
use super::tags::{PyTags, decimation_arg, family_arg, tags_out};
use crate::vision::detector::tags::{DEFAULT_REFRESH, TagDetector};
use crate::vision::tags::TagDecoder;

// The signature's default, written as a literal for Python's introspection.
const _: () = assert!(DEFAULT_REFRESH == 15);

/// AprilTags of `family` through a sequence of frames: after a frame, each tag is followed from its last corners
/// (its edges measured again near them, its bits read there, accepted only as the same id: no quad search), else
/// searched in a crop around its last corners (a margin of a quarter of its side plus twice its last motion), and
/// the whole frame is read when one is not found there, when the size changes, and every `refresh` frames (0: only
/// then) to pick up tags coming into view. A tracked frame gives the corners `detect_tags` gives on it (within
/// 0.02 px), for the tags tracked; `reads` says how each was read. `follow=False` skips the following (the quad
/// search in each crop every frame). `decimation` (1..=8, None: the detector's default) is `detect_tags`'s.
///
/// Works from several threads: their calls take turns (each waits with the GIL released).
#[pyclass(name = "TagTracker", module = "vsinv._core", frozen)]
pub(super) struct PyTagTracker {
    inner: Shared<TagDetector>,
}

#[pymethods]
impl PyTagTracker {
    #[new]
    #[pyo3(signature = (family = "tag36h11", decimation = None, refresh = 15, follow = true))]
    fn new(family: &str, decimation: Option<i64>, refresh: i64, follow: bool) -> PyResult<Self> {
        let family = family_arg(family)?;
        let detector = match decimation_arg(decimation)? {
            Some(d) => TagDetector::with_decoder(TagDecoder::with_decimation(family, d)?),
            None => TagDetector::new(family),
        };
        let refresh = u32::try_from(refresh).map_err(|_| {
            invalid_argument("refresh", format!("refresh: expected a whole number of frames >= 0, got {refresh}"))
        })?;
        Ok(Self { inner: Shared::new(detector.with_refresh(refresh).with_following(follow), "TagTracker") })
    }

    /// The tags in the next frame (an image: grey, or BGR/BGRA converted), sorted by id; their `stopped_early` says
    /// whether a quad search of this frame (whole or in a crop) stopped early, as `detect_tags`'s.
    fn track(&self, py: Python<'_>, image: &Bound<'_, PyAny>) -> PyResult<PyTags> {
        let image = image_arg(image, "image")?;
        let buffer = image.buffer("image")?;
        let (tags, family, early) = self
            .inner
            .detached(py, |detector| (detector.track(&buffer), detector.family(), detector.stopped_early()))?;
        tags_out(py, &tags?, family, early)
    }

    /// Forgets the last frame: the next one is read whole.
    fn reset(&self, py: Python<'_>) -> PyResult<()> {
        self.inner.lock(py)?.reset();
        Ok(())
    }

    /// Whether the last frame was read whole (not tracked in crops).
    #[getter]
    fn read_whole(&self, py: Python<'_>) -> PyResult<bool> {
        Ok(self.inner.lock(py)?.read_whole())
    }

    /// How each tag of the last frame was read, in the order of its ids: "edges" (followed from its last corners,
    /// its edges measured again and its bits read there, no quad search), "crop" (the quad search in a crop around
    /// them) or "whole" (the quad search in the whole frame).
    #[getter]
    fn reads(&self, py: Python<'_>) -> PyResult<Vec<&'static str>> {
        Ok(self.inner.lock(py)?.reads().iter().map(|r| r.name()).collect())
    }
}

/// Adds the tag tracker.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyTagTracker>()?;
    Ok(())
}
