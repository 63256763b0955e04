//! Depths estimated inside the loop: the seam where a depth estimator (appendix A's
//! resection, or a user's own) plugs into a servo session.

use crate::core::depth::ResectionDepths;
use crate::error::Result;

/// A depth estimator running inside the loop: from the current (noisy) pixels, the depths
/// of all points up to one positive scale (`zeta_hat = kappa(t) zeta`, sec. 4.1).
pub trait DepthEstimator: Send + Sync {
    /// Fills `depths` (one per point; entries of hidden points are ignored by the law).
    fn estimate(&mut self, pixels: &[[f64; 2]], visible: &[bool], depths: &mut [f64]) -> Result<()>;
}

/// Appendix A: the camera resected against depths known up to scale.
impl DepthEstimator for ResectionDepths {
    fn estimate(&mut self, pixels: &[[f64; 2]], visible: &[bool], depths: &mut [f64]) -> Result<()> {
        ResectionDepths::estimate(self, pixels, visible, depths)
    }
}
