//! The keypoint target on real images: no markers, no clicks (see [`crate::vision::features`]).
//! Its points are a spread of the reference image's SIFT keypoints, point `i` under identity
//! `i`; the frames are matched to them by descriptors and tracked ([`FeatureTracking`]).
//! It has no [`Target`](crate::vision::Target) to draw: vsinv's renderer draws no textures,
//! so simulated scenes never show it (MuJoCo renders textured objects, `vsinv.mujoco`).

use crate::error::Error;
use crate::vision::detector::features::{FeatureReference, FeatureReferenceDetector, FeatureSettings, FeatureTracking};
use crate::vision::detector::{Detection, Detector};
use crate::vision::error::Result;
use crate::vision::features::matching::MIN_MATCHES;
use crate::vision::image::GreyView;
use crate::vision::image_servo::ImageTargetKind;

/// The most points the target may hold.
pub const MAX_FEATURE_POINTS: u32 = 1000;

/// Layers of convex hull the keypoint target's basis choice sets aside
/// ([`ServoConfig::basis_inset`](crate::servo::ServoConfig::basis_inset)).
pub const FEATURE_BASIS_INSET: usize = 1;

/// The keypoint target's settings (its entry's arguments).
#[derive(Debug, Clone, PartialEq)]
pub struct FeatureTarget {
    /// The detector's settings.
    pub settings: FeatureSettings,
    /// The points to servo on, by identity (None: all of the reference image's spread).
    pub ids: Option<Vec<u32>>,
}

impl ImageTargetKind for FeatureTarget {
    fn detector(&self, _frames: bool) -> Result<Box<dyn Detector>> {
        Ok(Box::new(FeatureReferenceDetector { max_points: self.settings.max_points }))
    }

    /// The frames' detector: the reference's keypoints again (SIFT is deterministic), each
    /// kept point at its pixel.
    fn frames_detector(&self, reference: &GreyView<'_>, kept: &[Detection]) -> Result<Box<dyn Detector>> {
        let found = FeatureReference::new("reference_image", reference, self.settings.max_points)?;
        let all = found.detections();
        let same = kept.iter().all(|k| all.iter().any(|d| d.id == k.id && d.pixel == k.pixel));
        if !same {
            let reason = "the reference image's keypoints differ between two reads".into();
            return Err(Error::InvalidParameter { name: "reference_image", reason }.into());
        }
        let ids: Vec<u32> = kept.iter().map(|d| d.id).collect();
        Ok(Box::new(FeatureTracking::new(found, self.settings, Some(&ids))?))
    }

    /// The points `ids` (each must be one of the reference image's), or all.
    fn select(&self, found: Vec<Detection>) -> Result<Vec<Detection>> {
        let Some(ids) = &self.ids else { return Ok(found) };
        if let Some(missing) = ids.iter().find(|&&id| !found.iter().any(|d| d.id == id)) {
            let reason = format!("no point {missing}: the reference image holds points 0..{}", found.len());
            return Err(Error::InvalidParameter { name: "point_ids", reason }.into());
        }
        Ok(found.into_iter().filter(|d| ids.contains(&d.id)).collect())
    }

    /// One layer: the spread's outermost keypoints (at the object's silhouette, the most
    /// foreshortened, measured with the largest errors) are left out of the basis.
    fn basis_inset(&self) -> usize {
        FEATURE_BASIS_INSET
    }

    fn validate(&self) -> Result<()> {
        let s = &self.settings;
        if s.max_points < MIN_MATCHES || s.max_points > MAX_FEATURE_POINTS as usize {
            let reason = format!("must be in {MIN_MATCHES}..={MAX_FEATURE_POINTS}, got {}", s.max_points);
            return Err(Error::InvalidParameter { name: "max_points", reason }.into());
        }
        if self.ids.as_ref().is_some_and(Vec::is_empty) {
            let reason = "empty (None: every point of the reference image)".into();
            return Err(Error::InvalidParameter { name: "point_ids", reason }.into());
        }
        if s.min_tracked < MIN_MATCHES || s.min_tracked > s.max_points {
            let reason = format!("must be in {MIN_MATCHES}..=max_points ({}), got {}", s.max_points, s.min_tracked);
            return Err(Error::InvalidParameter { name: "min_tracked", reason }.into());
        }
        Ok(())
    }
}
