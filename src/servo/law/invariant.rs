//! The invariant law of sec. 4 (eqs. 14, 17, 24) as a servo session runs it.

use nalgebra::Vector6;

use crate::core::camera::Intrinsics;
use crate::core::control::{InvariantController, InvariantControllerConfig};
use crate::core::jacobian::MIN_POINTS;
use crate::core::uncertainty::{ImageNoise, Measurement, PoseUncertainty, invariant_pose_uncertainty};
use crate::error::Result;
use crate::servo::law::ServoLaw;
use crate::servo::stop::StopRule;

/// The invariant law: six points or more, the basis in view, judged in the invariant space.
pub struct InvariantLaw {
    controller: InvariantController,
}

impl InvariantLaw {
    /// The law for a reference image and basis, with K_hat.
    pub fn new(
        reference_pixels: &[[f64; 2]],
        basis: [usize; 3],
        k_hat: Intrinsics,
        config: InvariantControllerConfig,
    ) -> Result<Self> {
        Ok(Self { controller: InvariantController::new(reference_pixels, k_hat, basis, config)? })
    }
}

impl ServoLaw for InvariantLaw {
    fn name(&self) -> &'static str {
        "invariant"
    }
    fn min_points(&self) -> usize {
        MIN_POINTS
    }
    fn needs_basis(&self) -> bool {
        true
    }
    fn default_stop_rule(&self) -> StopRule {
        StopRule::Invariant
    }
    fn moves(&self) -> bool {
        true
    }
    fn watches_rz_trap(&self) -> bool {
        true
    }
    fn gain(&self) -> f64 {
        self.controller.config().gain
    }
    fn twist(&mut self, pixels: &[[f64; 2]], depths: &[f64], visible: &[bool]) -> Result<Vector6<f64>> {
        self.controller.step_visible(pixels, depths, visible)
    }
    fn eps_and_tracking(&self) -> ([f64; 5], f64) {
        self.controller.state().map_or(([f64::NAN; 5], f64::NAN), |s| (s.eps.into(), s.invariant_error))
    }
    fn pose_uncertainty(&self, m: &Measurement<'_>, basis: [usize; 3], noise: ImageNoise) -> Result<PoseUncertainty> {
        invariant_pose_uncertainty(m, basis, noise)
    }
    fn invariant(&self) -> Option<&InvariantController> {
        Some(&self.controller)
    }
    fn invariant_mut(&mut self) -> Option<&mut InvariantController> {
        Some(&mut self.controller)
    }
}
