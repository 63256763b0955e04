//! The control core: the paper's mathematics, with no dependency beyond nalgebra and
//! thiserror. This is what a controller embeds.
//!
//! | paper | module |
//! |---|---|
//! | camera model, eq. (4), point interaction matrix | [`camera`] |
//! | projective invariant transform, sec. 2.3, eq. (21) | [`invariant`] |
//! | invariant Jacobian, sec. 4.1, eqs. (11)-(13), (23) | [`jacobian`] |
//! | control laws, eqs. (14), (17), (24) | [`control`] |
//! | the rz task: eq. (24) and the general case of any start angle | [`rz_task`] |
//! | classic IBVS baseline | [`ibvs`] |
//! | a gain that depends on the error (ViSP's adaptive gain) | [`adaptive_gain`] |
//! | twist saturation keeping the twist's direction | [`saturation`] |
//! | Props. 1-3, appendix B | [`stability`] |
//! | plane + parallax (eq. 9), the invariant-space path (eq. 10), sec. 3 | [`planning`] |
//! | depths up to scale: pure translation (eq. 26), resection, appendix A | [`depth`] |
//! | eq. (26) from tracked keypoints: a consensus on the epipole, unusable depths flagged | [`robust_depth`] |
//! | the reference depths of a photo from any camera, from the object's model (not in the paper) | [`reference_depths`] |
//! | the depth estimator a servo session runs each step (appendix A's resection, or yours) | [`depth_estimator`] |
//! | rigid motions, exact twist integration | [`se3`] |
//! | lens distortion (OpenCV's plumb_bob and rational models), not in the paper | [`distortion`] |
//! | OpenCV's fisheye lens (Kannala-Brandt, ROS's `equidistant`), not in the paper | [`fisheye`] |
//! | pixel noise measured from an image stream, not in the paper | [`noise_meter`] |
//! | pose uncertainty left by pixel noise (first-order propagation), not in the paper | [`uncertainty`] |
//! | the widest triangle (basis choice, sec. 5.1) in `O(n log n)` | [`widest_triangle`] |

pub mod adaptive_gain;
mod boundary_points;
pub mod camera;
pub mod control;
pub(crate) mod convex_hull;
pub mod depth;
pub mod depth_estimator;
pub mod distortion;
pub mod fisheye;
pub mod ibvs;
pub mod invariant;
pub mod jacobian;
pub mod noise_meter;
pub mod planning;
pub mod reference_depths;
pub mod robust_depth;
pub mod rz_task;
pub mod saturation;
pub mod se3;
pub mod stability;
pub mod uncertainty;
pub mod widest_triangle;
