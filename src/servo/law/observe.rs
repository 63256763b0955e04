//! No control: the camera stays still and the session only measures (sec. 5.1, a
//! stationary zooming camera).

use nalgebra::Vector6;

use crate::core::jacobian::MIN_POINTS;
use crate::core::uncertainty::{ImageNoise, Measurement, PoseUncertainty, pixel_pose_uncertainty};
use crate::error::Result;
use crate::servo::law::ServoLaw;
use crate::servo::stop::StopRule;

/// The law that sends a zero twist and never stops on an image rule.
pub struct ObserveLaw;

impl ServoLaw for ObserveLaw {
    fn name(&self) -> &'static str {
        "none"
    }
    fn min_points(&self) -> usize {
        MIN_POINTS
    }
    fn needs_basis(&self) -> bool {
        false
    }
    fn default_stop_rule(&self) -> StopRule {
        StopRule::Invariant
    }
    fn moves(&self) -> bool {
        false
    }
    fn watches_rz_trap(&self) -> bool {
        false
    }
    fn gain(&self) -> f64 {
        1.0
    }
    fn twist(&mut self, _pixels: &[[f64; 2]], _depths: &[f64], _visible: &[bool]) -> Result<Vector6<f64>> {
        Ok(Vector6::zeros())
    }
    fn eps_and_tracking(&self) -> ([f64; 5], f64) {
        ([f64::NAN; 5], f64::NAN)
    }
    fn pose_uncertainty(&self, m: &Measurement<'_>, _basis: [usize; 3], noise: ImageNoise) -> Result<PoseUncertainty> {
        pixel_pose_uncertainty(m, noise)
    }
}
