//! What the images say about the pose when the loop stops: the measured pixel noise
//! propagated to the pose (first-order, [`crate::core::uncertainty`]).

use crate::core::noise_meter::PixelNoiseMeter;
use crate::core::uncertainty::{DEFAULT_SIGMAS, ImageNoise, Measurement};
use crate::servo::law::ServoLaw;
use crate::servo::stop::StopRules;

/// The pose uncertainty the final images allow.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Certainty {
    /// Pixel noise measured on the servo camera's last images, pixels per coordinate.
    pub pixel_sigma: f64,
    /// The reference image's noise assumed, pixels.
    pub reference_pixel_sigma: f64,
    /// RMS translation and rotation (metres, radians) the noise leaves.
    pub sigma: (f64, f64),
    /// 3 sigma plus the offset the mean error implies: how far from the goal the camera may
    /// be (metres, radians); with the stall rule on, the sigma includes the disagreement floor.
    pub bound: (f64, f64),
    /// The disagreement floor between the reference and the current detections: the
    /// per-coordinate pixel RMS of the systematic error that explains what the pose cannot
    /// remove ([`crate::core::uncertainty`]); None when the stall rule is off (not counted).
    pub floor_pixel_sigma: Option<f64>,
}

impl Certainty {
    /// Whether the bound is within the stop rules' tolerance.
    pub fn within(&self, stop: &StopRules) -> bool {
        let (t, r) = self.bound;
        t <= stop.max_translation_uncertainty && r <= stop.max_rotation_uncertainty_deg.to_radians()
    }

    /// The pose uncertainty of `m.pixels` (the average of `averaged` images) under the law's
    /// measurements; `None` when it cannot be computed (fewer than three images to measure the
    /// noise, too few points in view).
    pub(crate) fn of(
        law: &dyn ServoLaw,
        meter: &PixelNoiseMeter,
        stop: &StopRules,
        m: &Measurement<'_>,
        basis: [usize; 3],
        averaged: usize,
    ) -> Option<Self> {
        let pixel_sigma = meter.sigma()?;
        let reference_pixel_sigma = stop.reference_pixel_sigma.unwrap_or(pixel_sigma);
        let noise = ImageNoise { current: pixel_sigma, reference: reference_pixel_sigma, averaged_images: averaged };
        let u = law.pose_uncertainty(m, basis, noise).ok()?;
        let sigma = (u.translation_sigma(), u.rotation_sigma());
        let (bound, floor_pixel_sigma) = match stop.stall {
            true => {
                let b = (u.translation_bound_with_floor(DEFAULT_SIGMAS), u.rotation_bound_with_floor(DEFAULT_SIGMAS));
                (b, Some(u.floor_pixel_sigma))
            }
            false => ((u.translation_bound(DEFAULT_SIGMAS), u.rotation_bound(DEFAULT_SIGMAS)), None),
        };
        Some(Certainty { pixel_sigma, reference_pixel_sigma, sigma, bound, floor_pixel_sigma })
    }

    /// The reason a met image rule (`rule`: what was met) ends as `settled`.
    pub(crate) fn settled_reason(&self, stop: &StopRules, rule: &str) -> String {
        let (t, r) = self.bound;
        let floor = self.floor_pixel_sigma.map_or(String::new(), |f| format!(", disagreement floor {f:.3} px"));
        format!(
            "{rule}, but the images allow {:.3} mm and {:.3} deg from the goal (tolerance {:.3} mm, {:.3} deg; \
             pixel noise {:.3} px measured, reference {:.3} px{floor})",
            t * 1e3,
            r.to_degrees(),
            stop.max_translation_uncertainty * 1e3,
            stop.max_rotation_uncertainty_deg,
            self.pixel_sigma,
            self.reference_pixel_sigma,
        )
    }
}
