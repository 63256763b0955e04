//! Classic pixel-space IBVS as a servo session runs it.

use nalgebra::Vector6;

use crate::core::adaptive_gain::AdaptiveGain;
use crate::core::camera::Intrinsics;
use crate::core::ibvs::{IBVS_MIN_POINTS, IbvsController, Interaction};
use crate::core::saturation::TwistLimits;
use crate::core::uncertainty::{ImageNoise, Measurement, PoseUncertainty, pixel_pose_uncertainty};
use crate::error::Result;
use crate::servo::law::ServoLaw;
use crate::servo::stop::StopRule;

/// IBVS: judged on the pixels, needs no basis.
pub struct IbvsLaw {
    controller: IbvsController,
}

impl IbvsLaw {
    /// The law for a reference image (and its depths, where the interaction reads them).
    pub fn new(
        reference_pixels: &[[f64; 2]],
        k_hat: Intrinsics,
        gain: f64,
        interaction: Interaction,
        reference_depths: Option<&[f64]>,
        adaptive_gain: Option<AdaptiveGain>,
        twist_limits: Option<TwistLimits>,
    ) -> Result<Self> {
        let mut controller = IbvsController::new(reference_pixels, k_hat, gain, interaction, reference_depths)?;
        controller.set_adaptive_gain(adaptive_gain)?;
        controller.set_twist_limits(twist_limits)?;
        Ok(Self { controller })
    }
}

impl ServoLaw for IbvsLaw {
    fn name(&self) -> &'static str {
        "ibvs"
    }
    fn min_points(&self) -> usize {
        IBVS_MIN_POINTS
    }
    fn needs_basis(&self) -> bool {
        false
    }
    fn default_stop_rule(&self) -> StopRule {
        StopRule::Pixel
    }
    fn moves(&self) -> bool {
        true
    }
    fn watches_rz_trap(&self) -> bool {
        false
    }
    fn gain(&self) -> f64 {
        self.controller.gain()
    }
    fn twist(&mut self, pixels: &[[f64; 2]], depths: &[f64], visible: &[bool]) -> Result<Vector6<f64>> {
        self.controller.step_visible(pixels, depths, visible)
    }
    fn eps_and_tracking(&self) -> ([f64; 5], f64) {
        ([f64::NAN; 5], f64::NAN)
    }
    fn pose_uncertainty(&self, m: &Measurement<'_>, _basis: [usize; 3], noise: ImageNoise) -> Result<PoseUncertainty> {
        pixel_pose_uncertainty(m, noise)
    }
}
