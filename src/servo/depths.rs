//! Where a servo session's depths come from.

use crate::core::depth_estimator::DepthEstimator;
use crate::error::{Error, Result, check_positive};

/// Per-point depths given to the control law.
pub enum ServoDepths {
    /// The depths measured at the reference pose, zeta* (sec. 5.2): the reference's depths.
    Reference,
    /// One depth for every point, metres (the invariant law needs a non-planar object then;
    /// see `Error::DegenerateStructure`).
    Constant(f64),
    /// An estimator run every step on the current pixels (appendix A, or your own).
    Estimated(Box<dyn DepthEstimator>),
    /// Depths passed to each step (from a depth camera, a model, or a simulator).
    PerStep,
}

impl std::fmt::Debug for ServoDepths {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ServoDepths::Reference => f.write_str("Reference"),
            ServoDepths::Constant(z) => write!(f, "Constant({z})"),
            ServoDepths::Estimated(_) => f.write_str("Estimated"),
            ServoDepths::PerStep => f.write_str("PerStep"),
        }
    }
}

impl ServoDepths {
    /// The depths the law starts with: zeta*, the constant, or zeros until the estimator (or
    /// the caller) gives some.
    pub(crate) fn initial(&self, n: usize, reference_depths: Option<&[f64]>) -> Result<Vec<f64>> {
        match self {
            ServoDepths::Reference => reference_depths.map(<[f64]>::to_vec).ok_or_else(|| Error::InvalidParameter {
                name: "depths",
                reason: "the reference depth source needs the reference image's depths".into(),
            }),
            ServoDepths::Constant(z) => {
                check_positive("depths", *z)?;
                Ok(vec![*z; n])
            }
            ServoDepths::Estimated(_) | ServoDepths::PerStep => Ok(vec![0.0; n]),
        }
    }
}
