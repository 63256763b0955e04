//! What one servo step reports: the twist to send, the verdict, and the figures behind them.

use nalgebra::Vector6;

use crate::servo::verdict::Verdict;

/// The outcome of [`crate::servo::Servo::step`].
#[derive(Debug, Clone, PartialEq)]
pub struct ServoStep {
    /// The camera twist to send, `(vx, vy, vz, wx, wy, wz)` in the camera frame (m/s, rad/s);
    /// zero when the verdict is to stop.
    pub twist: Vector6<f64>,
    /// Carry on, or stop and why.
    pub verdict: Verdict,
    /// The figures of this step.
    pub telemetry: Telemetry,
}

/// The figures of one step (NaN where a figure does not apply: hidden basis points, a law
/// without a task function, a step that stopped before the law ran).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Telemetry {
    /// Control steps applied before this one.
    pub iteration: usize,
    /// `||s - s*||` to the reference image (sec. 2.3).
    pub invariant_error: f64,
    /// Largest distance of a point in use from its reference pixel, pixels.
    pub image_error: f64,
    /// tau_11, tau_21, tau_22 (eq. 21; the rz task reads them).
    pub tau: [f64; 3],
    /// `eps_z = det(Q*) tau_21`.
    pub eps_z: f64,
    /// The task function eps of eq. (14) after this step's law (invariant law only).
    pub eps: [f64; 5],
    /// `||s - s*(t)||` to the moving reference of a planned path (invariant law only).
    pub tracking_error: f64,
    /// Whether the law computed this step's twist.
    pub law_ran: bool,
    /// The basis the step was measured and controlled with (it changes when a basis point
    /// leaves the view).
    pub basis: [usize; 3],
    /// How many times the basis has changed so far.
    pub basis_switches: usize,
}

impl Telemetry {
    pub(crate) fn empty() -> Self {
        Self {
            iteration: 0,
            invariant_error: f64::NAN,
            image_error: f64::NAN,
            tau: [f64::NAN; 3],
            eps_z: f64::NAN,
            eps: [f64::NAN; 5],
            tracking_error: f64::NAN,
            law_ran: false,
            basis: [0, 1, 2],
            basis_switches: 0,
        }
    }
}
