//! When a servo session stops: the thresholds (the `[stop]` table of a scenario) and the two
//! image rules, pixel and invariant.

use crate::error::{Error, Result};

/// When the loop stops (the `[stop]` table of a scenario).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize), serde(deny_unknown_fields, default))]
pub struct StopRules {
    /// Iteration limit.
    pub max_iterations: usize,
    /// Same camera (K = K* throughout) or IBVS: stop when every point is closer than this to
    /// its reference pixel (the paper's 0.5 px).
    pub pixel_error: f64,
    /// Different cameras: stop when `||s - s*||` is below this, with `|tau_21|` below
    /// `tau21` and `tau_11 > 0`, `tau_22 > 0` (correction 8).
    pub invariant_error: f64,
    /// Threshold on `|tau_21|` for the invariant rule.
    pub tau21: f64,
    /// The errors are averaged over this many last iterations before the comparison (1: no
    /// averaging; noisy runs want 10 or so).
    pub window: usize,
    /// A camera farther than this (metres) from the reference pose counts as diverged (read
    /// by the simulator, which knows the pose).
    pub divergence_distance: f64,
    /// When the image rule is met, the run is `converged` only if the pose uncertainty the
    /// images still allow (3 sigma plus the offset the mean error implies, see
    /// [`crate::core::uncertainty`]) is at most this far from the goal, metres; otherwise it is
    /// `settled`. Also the tolerance of the summary's `within_tolerance`.
    pub max_translation_uncertainty: f64,
    /// The same for the rotation, degrees.
    pub max_rotation_uncertainty_deg: f64,
    /// The reference image's pixel noise, pixels; `None`: assumed equal to the noise measured
    /// on the servo camera's images (one image cannot show its own noise).
    pub reference_pixel_sigma: Option<f64>,
    /// The stall rule (issue 27), for real cameras whose detections of one pose disagree
    /// between the reference and the servo lens (the invariant error then settles above
    /// `invariant_error`): the run ends when, over the last `stall_window` images, the error
    /// has stopped decreasing and the mean commanded twist would move the camera by less
    /// than `stall_motion` times the pose tolerance; `converged` if the pose uncertainty,
    /// with the measured disagreement floor, is within the tolerance, else `settled`. Off by
    /// default here (the simulator's exact projections meet the image rules); on by default
    /// in `ImageServo` and the ROS bridge. (The three stall keys are written to a scenario
    /// file only when they differ from their defaults.)
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "is_false"))]
    pub stall: bool,
    /// Images the stall rule looks back over (at least 4).
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "is_default_stall_window"))]
    pub stall_window: usize,
    /// The stall rule's motion threshold, as a fraction of `max_translation_uncertainty` and
    /// `max_rotation_uncertainty_deg`: the motion the mean twist would make over the window.
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "is_default_stall_motion"))]
    pub stall_motion: f64,
}

/// The stall rule's defaults (off, 50 images, a tenth of the tolerance).
const STALL_WINDOW: usize = 50;
const STALL_MOTION: f64 = 0.1;

#[cfg(feature = "serde")]
fn is_false(v: &bool) -> bool {
    !*v
}
#[cfg(feature = "serde")]
fn is_default_stall_window(v: &usize) -> bool {
    *v == STALL_WINDOW
}
#[cfg(feature = "serde")]
fn is_default_stall_motion(v: &f64) -> bool {
    *v == STALL_MOTION
}

impl Default for StopRules {
    fn default() -> Self {
        Self {
            max_iterations: 2000,
            pixel_error: 0.5,
            invariant_error: 1e-4,
            tau21: 1e-4,
            window: 1,
            divergence_distance: 10.0,
            max_translation_uncertainty: 0.005,
            max_rotation_uncertainty_deg: 0.5,
            reference_pixel_sigma: None,
            stall: false,
            stall_window: STALL_WINDOW,
            stall_motion: STALL_MOTION,
        }
    }
}

impl StopRules {
    /// Checks the counts (the thresholds are compared as they are).
    pub fn validate(&self) -> Result<()> {
        if self.window == 0 || self.max_iterations == 0 {
            return Err(Error::InvalidParameter {
                name: "stop",
                reason: "window and max_iterations must be >= 1".into(),
            });
        }
        if self.stall_window < 4 {
            let reason = format!("must be >= 4 images, got {}", self.stall_window);
            return Err(Error::InvalidParameter { name: "stop.stall_window", reason });
        }
        if !(self.stall_motion > 0.0 && self.stall_motion <= 1.0) {
            let reason = format!("a fraction of the pose tolerance in (0, 1], got {}", self.stall_motion);
            return Err(Error::InvalidParameter { name: "stop.stall_motion", reason });
        }
        Ok(())
    }
}

/// Which image rule decides convergence.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize), serde(rename_all = "snake_case"))]
pub enum StopRule {
    /// Image error (same camera, or IBVS).
    Pixel,
    /// Invariant error with tau_21 and the signs of tau_11, tau_22 (different cameras).
    Invariant,
}

impl StopRule {
    /// The name used in summaries and JSON (the serde name).
    pub fn as_str(&self) -> &'static str {
        match self {
            StopRule::Pixel => "pixel",
            StopRule::Invariant => "invariant",
        }
    }
}

/// Whether the window-averaged errors (`mean`, laid out as [`super::measure::measure`] writes
/// its rows) meet the stop rule; `tau` are the current image's tau_11, tau_21, tau_22.
///
/// Points hidden for good must not block the rule forever, so it is judged on the points in
/// view throughout the window (their mean is finite; a point hidden in any image of the
/// window has a NaN mean and is left out), and only when at least `min_points` of them
/// remain (the law's minimum; the basis counts for three under the invariant rule, and the
/// session switches to a visible basis and restarts the window when a basis point leaves).
pub(crate) fn stop_rule_met(
    rule: StopRule,
    stop: &StopRules,
    mean: &[f64],
    n_others: usize,
    tau: [f64; 3],
    min_points: usize,
) -> bool {
    let m_inv = 3 * n_others;
    match rule {
        StopRule::Pixel => {
            let seen: Vec<f64> = mean[1 + m_inv..]
                .chunks_exact(2)
                .filter(|c| c[0].is_finite() && c[1].is_finite())
                .map(|c| (c[0] * c[0] + c[1] * c[1]).sqrt())
                .collect();
            seen.len() >= min_points && seen.iter().fold(0.0, |a: f64, &b| a.max(b)) < stop.pixel_error
        }
        // correction 8: tau_21 near zero alone also admits the rz = pi equilibrium.
        StopRule::Invariant => {
            let blocks = mean[1..1 + m_inv].chunks_exact(3).filter(|c| c.iter().all(|v| v.is_finite()));
            let (count, sum2) = blocks.fold((0, 0.0), |(n, s), c| (n + 1, s + c.iter().map(|v| v * v).sum::<f64>()));
            3 + count >= min_points
                && sum2.sqrt() < stop.invariant_error
                && mean[0].abs() < stop.tau21
                && tau[0] > 0.0
                && tau[2] > 0.0
        }
    }
}
