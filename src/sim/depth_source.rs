//! Where the control law's depths come from in a run: the true depths, the reference depths
//! zeta* (sec. 5.2), or an estimator running inside the loop (appendix A).

use nalgebra::{Isometry3, Vector3};

use crate::core::camera::Intrinsics;
use crate::core::depth::{ResectionDepths, depths_from_translation};
pub use crate::core::depth_estimator::DepthEstimator;
use crate::error::Error;
use crate::sim::error::Result;
use crate::sim::scene::{Observation, Scene};

/// Builds a fresh [`DepthEstimator`] for each run, from the scene and the reference image.
pub trait DepthEstimatorFactory: Send + Sync {
    /// The estimator for one run.
    fn start(&self, scene: &Scene, reference_pixels: &[[f64; 2]]) -> Result<Box<dyn DepthEstimator>>;
}

/// Appendix A in the simulator: two images of the object taken by `camera` (unknown to the
/// controller) at `first_pose` and after a pure translation `translation` (F*, metres) give
/// the depths up to scale; every iteration then resects the current camera.
#[derive(Debug, Clone, PartialEq)]
pub struct TranslationPairDepths {
    /// The camera of the pair.
    pub camera: Intrinsics,
    /// Its pose for the first image (camera frame in F*).
    pub first_pose: Isometry3<f64>,
    /// The translation of its centre to the second image, in F*.
    pub translation: Vector3<f64>,
    /// The mean depth the estimates give the reference image (see [`ResectionDepths::new`]).
    pub reference_mean_depth: f64,
}

impl DepthEstimatorFactory for TranslationPairDepths {
    fn start(&self, scene: &Scene, reference_pixels: &[[f64; 2]]) -> Result<Box<dyn DepthEstimator>> {
        let second_pose = nalgebra::Translation3::from(self.translation) * self.first_pose;
        let mut images = [Observation::default(), Observation::default()];
        for (obs, pose) in images.iter_mut().zip([self.first_pose, second_pose]) {
            scene.observe(&pose, &self.camera, None, obs);
            if let Some(i) = obs.visible.iter().position(|v| !v) {
                return Err(Error::InvalidParameter {
                    name: "depth_estimation",
                    reason: format!("point {i} is not seen by the translation pair (behind the camera or occluded)"),
                }
                .into());
            }
        }
        let in_pair = |e: Error| Error::InvalidParameter {
            name: "depth_estimation",
            reason: format!("the translation pair gives no depths: {e}"),
        };
        let first = depths_from_translation(&images[0].pixels, &images[1].pixels).map_err(in_pair)?;
        let resection =
            ResectionDepths::new(&images[0].pixels, &first.depths, reference_pixels, self.reference_mean_depth)
                .map_err(in_pair)?;
        Ok(Box::new(resection))
    }
}

/// Per-point depths given to the control law.
#[derive(Clone)]
pub enum DepthSource {
    /// The true current depths.
    True,
    /// The depths measured at the reference pose, zeta* (sec. 5.2).
    Reference,
    /// Depths from an estimator (appendix A).
    Estimated(std::sync::Arc<dyn DepthEstimatorFactory>),
}

impl std::fmt::Debug for DepthSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            DepthSource::True => "True",
            DepthSource::Reference => "Reference",
            DepthSource::Estimated(_) => "Estimated",
        })
    }
}
