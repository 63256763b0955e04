//! Where the camera is: on the flange (eye-in-hand) or fixed beside the robot (eye-to-hand),
//! and the reduction of the second to the first.
//!
//! Eye-to-hand: the camera is fixed in the base frame and the target rides on the flange. The
//! inputs are the same (gripper-to-base `G_i` from the robot, target-to-camera `C_i` from the
//! camera); the unknown is the camera-to-base `Y`. With the target-to-flange `T` fixed,
//! `G_i T = Y C_i` at every station; eliminating `T = G_i^-1 Y C_i` between stations `i < j`
//! gives `A Y = Y B` with `A = G_j G_i^-1` and `B = C_j C_i^-1`. This is eye-in-hand's
//! `A = G'_j^-1 G'_i` with `G'_i = G_i^-1`
//! (base-to-gripper): the eye-in-hand solver fed the inverted gripper poses returns `Y`
//! (Tsai and Lenz 1989, sec. I; OpenCV's `calibrateHandEye` documentation, eye-to-hand note).

use crate::calibration::error::Result;
use crate::error::Error;

/// Where the camera is mounted, which decides what the calibration's transform is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum HandEyeSetup {
    /// The camera rides on the flange and the target is fixed in the base frame: the result
    /// is camera-to-gripper (the camera frame in the gripper frame).
    #[default]
    EyeInHand,
    /// The camera is fixed in the base frame and the target rides on the flange: the result
    /// is camera-to-base (the camera frame in the base frame).
    EyeToHand,
}

impl HandEyeSetup {
    /// Both set-ups.
    pub const ALL: [HandEyeSetup; 2] = [HandEyeSetup::EyeInHand, HandEyeSetup::EyeToHand];

    /// The set-up's name: `eye_in_hand` or `eye_to_hand`.
    pub fn name(self) -> &'static str {
        match self {
            HandEyeSetup::EyeInHand => "eye_in_hand",
            HandEyeSetup::EyeToHand => "eye_to_hand",
        }
    }

    /// The frame the camera is found in: `gripper` (eye-in-hand) or `base` (eye-to-hand).
    pub fn reference_frame(self) -> &'static str {
        match self {
            HandEyeSetup::EyeInHand => "gripper",
            HandEyeSetup::EyeToHand => "base",
        }
    }

    /// The set-up of a name: `eye_in_hand` or `eye_to_hand`; case-insensitive, `-` read as `_`.
    pub fn from_name(name: &str) -> Result<HandEyeSetup> {
        match name.to_ascii_lowercase().replace('-', "_").as_str() {
            "eye_in_hand" => Ok(HandEyeSetup::EyeInHand),
            "eye_to_hand" => Ok(HandEyeSetup::EyeToHand),
            _ => Err(Error::InvalidParameter {
                name: "setup",
                reason: format!(
                    "unknown hand-eye setup {:?}: expected 'eye_in_hand' or 'eye_to_hand'",
                    name.chars().take(40).collect::<String>()
                ),
            }
            .into()),
        }
    }
}
