//! The control laws a servo session runs. Each law is a type implementing [`ServoLaw`]: it
//! owns its behaviour (the points it needs, its default stop rule, its telemetry, the pose
//! uncertainty of its measurements). [`Law`] is the configuration that names a law and its
//! tuning; adding a law is one new type here and one arm in [`Law::build`] and
//! [`Law::from_options`]. The laws' options (gains, tasks, speed limits) are declared once, in
//! [`options`], which says which files adding one touches.

mod ibvs;
mod invariant;
mod observe;
pub mod options;

use nalgebra::Vector6;

use crate::core::adaptive_gain::AdaptiveGain;
use crate::core::camera::Intrinsics;
use crate::core::control::{InvariantController, InvariantControllerConfig};
use crate::core::ibvs::Interaction;
use crate::core::saturation::TwistLimits;
use crate::core::uncertainty::{ImageNoise, Measurement, PoseUncertainty};
use crate::error::{Error, Result};
use crate::servo::stop::StopRule;

use self::options::{FEEDFORWARD, GAIN, GAIN_RZ, INTERACTION, LawOptions, MIN_STRUCTURE_RATIO, RZ_TASK};

pub use self::ibvs::IbvsLaw;
pub use self::invariant::InvariantLaw;
pub use self::observe::ObserveLaw;

/// The control law of a servo session, with its tuning.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Law {
    /// The invariant law of sec. 4.
    Invariant(InvariantControllerConfig),
    /// No control: the camera stays still (sec. 5.1, a stationary zooming camera).
    Observe,
    /// Classic pixel-space IBVS.
    Ibvs {
        /// lambda.
        gain: f64,
        /// Where the interaction matrix is evaluated.
        interaction: Interaction,
        /// A gain that depends on the pixel error norm, replacing `gain`.
        adaptive_gain: Option<AdaptiveGain>,
        /// Largest linear and angular speeds.
        twist_limits: Option<TwistLimits>,
    },
}

impl Law {
    /// The law named `law` (`"invariant"`, `"ibvs"` or `"none"`, [`options::LAWS`]) with the
    /// options given, the others at their defaults; an option `law` does not read is refused
    /// by name. The invariant law: lambda and eta of eqs. (17) and (24); IBVS: lambda of
    /// `v = -lambda L_hat^+ (p - p*)`.
    pub fn from_options(law: &str, o: &LawOptions) -> Result<Law> {
        o.check_law(law)?;
        let (adaptive_gain, twist_limits) = (o.adaptive_gain(), o.twist_limits()?);
        match law {
            "invariant" => Ok(Law::Invariant(InvariantControllerConfig {
                gain: o.number(&GAIN),
                gain_rz: o.number(&GAIN_RZ),
                feedforward: o.flag(&FEEDFORWARD),
                min_structure_ratio: o.number(&MIN_STRUCTURE_RATIO),
                rz_task: o.choice(&RZ_TASK).parse()?,
                adaptive_gain,
                twist_limits,
            })),
            "ibvs" => Ok(Law::Ibvs {
                gain: o.number(&GAIN),
                interaction: o.choice(&INTERACTION).parse()?,
                adaptive_gain,
                twist_limits,
            }),
            "none" => Ok(Law::Observe),
            other => Err(Error::InvalidParameter {
                name: "law",
                reason: format!("expected \"invariant\", \"ibvs\" or \"none\", got {other:?}"),
            }),
        }
    }

    /// The law's controller for a reference image (pinhole pixels of K*, basis, and the
    /// reference depths zeta* where the law reads them) and the intrinsics it believes, K_hat.
    pub fn build(
        &self,
        reference_pixels: &[[f64; 2]],
        basis: [usize; 3],
        reference_depths: Option<&[f64]>,
        k_hat: Intrinsics,
    ) -> Result<Box<dyn ServoLaw>> {
        Ok(match *self {
            Law::Invariant(config) => Box::new(InvariantLaw::new(reference_pixels, basis, k_hat, config)?),
            Law::Ibvs { gain, interaction, adaptive_gain, twist_limits } => Box::new(IbvsLaw::new(
                reference_pixels,
                k_hat,
                gain,
                interaction,
                reference_depths,
                adaptive_gain,
                twist_limits,
            )?),
            Law::Observe => Box::new(ObserveLaw),
        })
    }
}

/// A control law as a servo session runs it.
pub trait ServoLaw: Send + Sync {
    /// Its name in scenarios and summaries (`invariant`, `ibvs`, `none`).
    fn name(&self) -> &'static str;
    /// The fewest points in view it can servo on.
    fn min_points(&self) -> usize;
    /// Whether it needs the three basis points in view.
    fn needs_basis(&self) -> bool;
    /// The stop rule it is judged by unless the session is told otherwise.
    fn default_stop_rule(&self) -> StopRule;
    /// Whether it moves the camera at all (a law that does not never meets an image rule and
    /// ends `observed` at the iteration limit).
    fn moves(&self) -> bool;
    /// Whether it can settle at the rz = pi equilibrium of eq. (24) (see `Status::RzTrap`).
    fn watches_rz_trap(&self) -> bool;
    /// lambda, the gain Prop. 3 reads.
    fn gain(&self) -> f64;
    /// One control step on the points flagged visible.
    fn twist(&mut self, pixels: &[[f64; 2]], depths: &[f64], visible: &[bool]) -> Result<Vector6<f64>>;
    /// The task function eps and the tracking error `||s - s*(t)||` of the last step (NaN
    /// where the law has none).
    fn eps_and_tracking(&self) -> ([f64; 5], f64);
    /// The pose uncertainty its measurements leave (where the loop settles is the law's
    /// business: the invariant law matches s and tau_21, IBVS the pixels).
    fn pose_uncertainty(&self, m: &Measurement<'_>, basis: [usize; 3], noise: ImageNoise) -> Result<PoseUncertainty>;
    /// The invariant controller, for a law that is one (path following, Prop. 3).
    fn invariant(&self) -> Option<&InvariantController> {
        None
    }
    /// The same, mutable.
    fn invariant_mut(&mut self) -> Option<&mut InvariantController> {
        None
    }
}
