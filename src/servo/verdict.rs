//! What a servo step concludes: carry on, or stop with a status and the reason.

use crate::error::Error;

/// How a servo session (or a simulated run) ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize), serde(rename_all = "snake_case"))]
pub enum Status {
    /// The stop rule was met.
    Converged,
    /// The iteration limit was reached.
    MaxIterations,
    /// Fewer points in view than the law needs (or a basis point hidden).
    LostFeatures,
    /// The camera ran away, the twist became non-finite, or the rz law became singular.
    Diverged,
    /// The structure cannot be servoed (planar object, equal depth estimates, collinear basis).
    Degenerate,
    /// The invariant law settled at the rz = pi equilibrium (`s = s*`, `tau_21 = 0`, but
    /// `tau_11 < 0` or `tau_22 < 0`): the camera is rotated by about 180 degrees about its
    /// optical axis (the paper's eq. 24 alone, from a start beyond 90 degrees).
    RzTrap,
    /// No control (`law = "none"`, a stationary camera): every image was taken.
    Observed,
    /// An arm joint would have left its position limits (clamped there); reported by the robot.
    JointLimit,
    /// The arm's manipulability fell below `[robot] min_manipulability`; reported by the robot.
    Singular,
    /// The image stop rule was met, but the pose uncertainty the images allow (measured pixel
    /// noise propagated to the pose, [`crate::core::uncertainty`]) is above the tolerance
    /// `[stop] max_translation_uncertainty` or `max_rotation_uncertainty_deg`: the loop is
    /// still, but the images cannot tell that the camera is at the goal.
    Settled,
}

impl Status {
    /// The name used in summaries and JSON.
    pub fn as_str(&self) -> &'static str {
        match self {
            Status::Converged => "converged",
            Status::MaxIterations => "max_iterations",
            Status::LostFeatures => "lost_features",
            Status::Diverged => "diverged",
            Status::Degenerate => "degenerate",
            Status::RzTrap => "rz_trap",
            Status::Observed => "observed",
            Status::JointLimit => "joint_limit",
            Status::Singular => "singular",
            Status::Settled => "settled",
        }
    }

    /// Why a control step's error ends the loop.
    pub fn of_error(err: &Error) -> Status {
        match err {
            Error::TooFewPoints { .. } | Error::PointBehindCamera { .. } => Status::LostFeatures,
            Error::RzSingular { .. } | Error::NonFinite { .. } | Error::NonFinitePoint { .. } => Status::Diverged,
            _ => Status::Degenerate,
        }
    }
}

/// The verdict of a servo step.
#[derive(Debug, Clone, PartialEq)]
pub enum Verdict {
    /// Carry on: send the twist.
    Running,
    /// Stop the robot.
    Stop {
        /// Why, as a status.
        status: Status,
        /// Why, in words (the core's).
        reason: String,
        /// The control error that stopped the loop, if one did: a higher layer words it in
        /// its own terms ([`Error::message_with_remedy`]).
        cause: Option<Error>,
    },
}

impl Verdict {
    /// A stop with its reason.
    pub fn stop(status: Status, reason: impl Into<String>) -> Self {
        Verdict::Stop { status, reason: reason.into(), cause: None }
    }

    /// A stop on a control error: its status ([`Status::of_error`]), its message and the error.
    pub fn stop_on(err: Error) -> Self {
        Verdict::Stop { status: Status::of_error(&err), reason: err.to_string(), cause: Some(err) }
    }

    /// The reason of a stop with `remedy` (a higher layer's way to pass depths, in its words)
    /// added to the cause's remedies ([`Error::message_with_remedy`]); None while running.
    pub fn reason_with_remedy(&self, remedy: &str) -> Option<String> {
        match self {
            Verdict::Running => None,
            Verdict::Stop { cause: Some(e), .. } => Some(e.message_with_remedy(remedy)),
            Verdict::Stop { reason, .. } => Some(reason.clone()),
        }
    }

    /// Whether the loop goes on.
    pub fn is_running(&self) -> bool {
        matches!(self, Verdict::Running)
    }

    /// The status of a stop (None while running).
    pub fn status(&self) -> Option<Status> {
        match self {
            Verdict::Running => None,
            Verdict::Stop { status, .. } => Some(*status),
        }
    }
}
