//! Classic image-based visual servoing in pixels (Espiau, Chaumette, Rives 1992):
//! `v = -lambda L_hat^+ (p - p*)`. The baseline that ends at a wrong pose when the lens
//! changes between the reference image and the servo, since `p = p*` then no longer means
//! `F = F*`.

use nalgebra::{Matrix6, Vector6};

use crate::core::adaptive_gain::AdaptiveGain;
use crate::core::camera::{Intrinsics, pixel_interaction_unchecked};
use crate::core::control::check_point_total;
use crate::core::saturation::TwistLimits;
use crate::core::uncertainty::{ImageNoise, Measurement, PoseUncertainty, pixel_pose_uncertainty};
use crate::error::{
    Error, Result, check_depths, check_finite_points, check_overflow, check_positive, check_step_inputs,
};

/// Where the interaction matrix is evaluated (`"current"`, `"desired"` or `"mean"` in
/// scenario files and Python).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "lowercase"))]
pub enum Interaction {
    /// At the current pixels and depths.
    #[default]
    Current,
    /// At the reference pixels and reference depths (constant).
    Desired,
    /// The mean of the two.
    Mean,
}

impl std::str::FromStr for Interaction {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "current" => Ok(Self::Current),
            "desired" => Ok(Self::Desired),
            "mean" => Ok(Self::Mean),
            _ => Err(Error::InvalidParameter {
                name: "interaction",
                reason: format!("expected \"current\", \"desired\" or \"mean\", got {s:?}"),
            }),
        }
    }
}

/// Minimum number of points for a six-dof pixel-space law.
pub const IBVS_MIN_POINTS: usize = 4;

impl crate::core::control::Controller for IbvsController {
    fn step(&mut self, pixels: &[[f64; 2]], depths: &[f64]) -> Result<Vector6<f64>> {
        self.step_masked(pixels, depths, None)
    }
    fn step_visible(&mut self, pixels: &[[f64; 2]], depths: &[f64], visible: &[bool]) -> Result<Vector6<f64>> {
        self.step_masked(pixels, depths, Some(visible))
    }
}

/// Pixel-space IBVS controller.
#[derive(Debug, Clone)]
pub struct IbvsController {
    reference: Vec<[f64; 2]>,
    reference_depths: Option<Vec<f64>>,
    k_hat: Intrinsics,
    k: nalgebra::Matrix3<f64>,
    k_inv: nalgebra::Matrix3<f64>,
    gain: f64,
    interaction: Interaction,
    adaptive_gain: Option<AdaptiveGain>,
    twist_limits: Option<TwistLimits>,
    last_error: Option<f64>,
    last_command: Option<(f64, f64)>,
}

impl IbvsController {
    /// `reference_depths` are required for [`Interaction::Desired`] and [`Interaction::Mean`].
    pub fn new(
        reference_pixels: &[[f64; 2]],
        k_hat: Intrinsics,
        gain: f64,
        interaction: Interaction,
        reference_depths: Option<&[f64]>,
    ) -> Result<Self> {
        check_finite_points("reference_pixels", reference_pixels)?;
        let n = reference_pixels.len();
        if n < IBVS_MIN_POINTS {
            return Err(Error::TooFewPoints { needed: IBVS_MIN_POINTS, got: n, why: "six dof from pixel errors" });
        }
        check_positive("gain", gain)?;
        if let Some(z) = reference_depths {
            check_depths(z, n)?;
        } else if interaction != Interaction::Current {
            return Err(Error::InvalidParameter {
                name: "reference_depths",
                reason: "required when the interaction matrix uses the desired points".into(),
            });
        }
        let k = k_hat.matrix();
        let k_inv = k.try_inverse().ok_or_else(|| Error::InvalidIntrinsics { reason: "K_hat is singular".into() })?;
        Ok(Self {
            reference: reference_pixels.to_vec(),
            reference_depths: reference_depths.map(<[f64]>::to_vec),
            k_hat,
            k,
            k_inv,
            gain,
            interaction,
            adaptive_gain: None,
            twist_limits: None,
            last_error: None,
            last_command: None,
        })
    }

    /// A gain that depends on the pixel error `x = ||p - p*||` (pixels, all used points):
    /// lambda is `lambda(x)` instead of the constant gain; `None` goes back to it.
    pub fn set_adaptive_gain(&mut self, gain: Option<AdaptiveGain>) -> Result<()> {
        if let Some(g) = &gain {
            g.validate()?;
        }
        self.adaptive_gain = gain;
        Ok(())
    }

    /// Largest linear and angular speeds: the twist is scaled as a whole to meet them.
    pub fn set_twist_limits(&mut self, limits: Option<TwistLimits>) -> Result<()> {
        if let Some(l) = &limits {
            l.validate()?;
        }
        self.twist_limits = limits;
        Ok(())
    }

    /// The reference image.
    pub fn reference_pixels(&self) -> &[[f64; 2]] {
        &self.reference
    }
    /// The reference depths, if given.
    pub fn reference_depths(&self) -> Option<&[f64]> {
        self.reference_depths.as_deref()
    }
    /// The estimated intrinsics used in the interaction matrices.
    pub fn k_hat(&self) -> &Intrinsics {
        &self.k_hat
    }
    /// The constant gain lambda (used when there is no adaptive gain).
    pub fn gain(&self) -> f64 {
        self.gain
    }
    /// Where the interaction matrix is evaluated.
    pub fn interaction(&self) -> Interaction {
        self.interaction
    }
    /// The adaptive gain, if set.
    pub fn adaptive_gain(&self) -> Option<AdaptiveGain> {
        self.adaptive_gain
    }
    /// The speed limits, if set.
    pub fn twist_limits(&self) -> Option<TwistLimits> {
        self.twist_limits
    }

    /// The lambda used and the factor the twist limits scaled the twist by, at the last step.
    pub fn last_command(&self) -> Option<(f64, f64)> {
        self.last_command
    }

    /// Root-mean-square pixel error `sqrt(mean ||p_k - p_k*||^2)` at the last step.
    pub fn last_pixel_error(&self) -> Option<f64> {
        self.last_error
    }

    /// One control step: `v = -lambda L_hat^+ (p - p*)`.
    pub fn step(&mut self, pixels: &[[f64; 2]], depths: &[f64]) -> Result<Vector6<f64>> {
        self.step_masked(pixels, depths, None)
    }

    /// A step with only the visible points (at least [`IBVS_MIN_POINTS`]).
    pub fn step_visible(&mut self, pixels: &[[f64; 2]], depths: &[f64], visible: &[bool]) -> Result<Vector6<f64>> {
        self.step_masked(pixels, depths, Some(visible))
    }

    /// The pose uncertainty that pixel noise leaves at `pixels` (the current image, or the
    /// average of `noise.averaged_images` images) under the pixel stop rule, with this
    /// controller's reference image and K_hat ([`crate::core::uncertainty`]; it assumes that
    /// the reference image was taken with the servo camera).
    pub fn pose_uncertainty(
        &self,
        pixels: &[[f64; 2]],
        depths: &[f64],
        visible: Option<&[bool]>,
        noise: ImageNoise,
    ) -> Result<PoseUncertainty> {
        check_point_total(pixels.len(), self.reference.len())?;
        let m = Measurement { pixels, depths, reference_pixels: &self.reference, visible, k_hat: &self.k_hat };
        pixel_pose_uncertainty(&m, noise)
    }

    fn step_masked(&mut self, pixels: &[[f64; 2]], depths: &[f64], visible: Option<&[bool]>) -> Result<Vector6<f64>> {
        let n = self.reference.len();
        check_point_total(pixels.len(), n)?;
        check_step_inputs(pixels, depths, visible)?;
        let used = visible.map_or(n, |v| v.iter().filter(|&&x| x).count());
        if used < IBVS_MIN_POINTS {
            return Err(Error::TooFewPoints { needed: IBVS_MIN_POINTS, got: used, why: "six dof from pixel errors" });
        }
        let mut ltl = Matrix6::zeros();
        let mut lte = Vector6::zeros();
        let mut err2 = 0.0;
        for i in (0..n).filter(|&i| visible.is_none_or(|v| v[i])) {
            let e = nalgebra::Vector2::new(pixels[i][0] - self.reference[i][0], pixels[i][1] - self.reference[i][1]);
            err2 += e.norm_squared();
            let desired = || {
                let z = self.reference_depths.as_ref().map_or(1.0, |z| z[i]);
                pixel_interaction_unchecked(&self.k, &self.k_inv, self.reference[i], z)
            };
            let l = match self.interaction {
                Interaction::Current => pixel_interaction_unchecked(&self.k, &self.k_inv, pixels[i], depths[i]),
                Interaction::Desired => desired(),
                Interaction::Mean => {
                    (pixel_interaction_unchecked(&self.k, &self.k_inv, pixels[i], depths[i]) + desired()) * 0.5
                }
            };
            ltl += l.tr_mul(&l);
            lte += l.tr_mul(&e);
        }
        let chol = ltl.cholesky().ok_or(Error::DegenerateStructure { ratio: 0.0, threshold: 0.0 })?;
        let gain = self.adaptive_gain.map_or(self.gain, |g| g.value(err2.sqrt()));
        let mut twist = chol.solve(&lte) * -gain;
        let saturation = self.twist_limits.map_or(1.0, |l| l.apply(&mut twist));
        check_overflow("pixels, depths", "twist and pixel error", &[twist.as_slice(), &[err2, gain]])?;
        self.last_error = Some((err2 / used as f64).sqrt());
        self.last_command = Some((gain, saturation));
        Ok(twist)
    }
}
