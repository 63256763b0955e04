//! What is found in an image, in the spirit of ViSP's `vpDetectorBase`: a detector takes an
//! image and reports the target's points it finds, by identity, with their pixels and a
//! found flag. A tracker is a detector that is started once on a first image with where each
//! point is expected (the user's clicks, or the projections); a detector that needs no help
//! (a tag detector) ignores those hints. [`DotTracking`](dot_tracking::DotTracking), the dot
//! tracker, and [`TagDetector`](tags::TagDetector), AprilTag corners by identity, are the
//! detectors.

pub mod dot_tracking;
pub mod features;
mod tag_regions;
pub mod tags;

use crate::vision::error::Result;
use crate::vision::image::GreyView;
use crate::vision::image::Window;

/// Where a point is expected in the first image: its identity and a pixel near it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Expected {
    /// The point's identity ([`TargetPoint::id`](crate::vision::target::TargetPoint::id)).
    pub id: u32,
    /// A pixel `(u, v)` near it.
    pub pixel: [f64; 2],
}

/// A point as a detector reports it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Detection {
    /// The point's identity.
    pub id: u32,
    /// Its pixel `(u, v)`: where it was found, or its last known position when not found.
    pub pixel: [f64; 2],
    /// Found in this image.
    pub found: bool,
}

/// Finds a target's points in images.
pub trait Detector: Send + Sync {
    /// Starts on the first image, given where each point is expected; returns the points
    /// found in it. An error when the detector cannot start (a point it needs is not there).
    fn start(&mut self, image: &GreyView<'_>, expected: &[Expected]) -> Result<Vec<Detection>>;

    /// The points in the next image (after [`Detector::start`]); a point may be missing from
    /// the list or reported with `found` false.
    fn detect(&mut self, image: &GreyView<'_>) -> Result<Vec<Detection>>;

    /// Whether the search of the last image stopped at the detector's bound on its work (a
    /// frame too cluttered to be searched whole): a point it did not report may be there.
    /// `false` for a detector without such a bound.
    fn stopped_early(&self) -> bool {
        false
    }

    /// The windows of the next image that [`Detector::detect_within`] reads, when the
    /// detector reads only parts of an image (a tracker's windows around its predictions);
    /// `None` (the default): it reads the whole image. A simulation renders only these.
    fn reads(&self) -> Option<Vec<Window>> {
        None
    }

    /// [`Detector::detect`] on an image right only inside [`Detector::reads`] (its other
    /// pixels may hold anything): the same points, or `None`, the detector unchanged, when it
    /// needs pixels beyond them (then call `detect` on the whole image). `None` by default.
    fn detect_within(&mut self, _image: &GreyView<'_>) -> Result<Option<Vec<Detection>>> {
        Ok(None)
    }

    /// The points, by identity, that the caller leans on most from the next image on (the
    /// invariant law's basis: their errors enter every invariant coordinate `q = Q^-1 p`,
    /// sec. 2.3): a detector may measure them with more care. Ignored by default.
    fn favour(&mut self, _ids: &[u32]) {}
}
