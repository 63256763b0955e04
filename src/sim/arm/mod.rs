//! Serial arms from URDF: the chain of joints from the base link to an end-effector link,
//! forward kinematics of any link of the chain, geometric Jacobians in the base and
//! end-effector frames, manipulability, and inverse kinematics (damped least squares with
//! joint limits and several seeds, [`DampedLeastSquaresIk`]).
//!
//! Revolute, continuous, prismatic and fixed joints are supported (fixed joints are folded
//! into the next joint's origin). URDF origins are `Trans(xyz) Rz(yaw) Ry(pitch) Rx(roll)`.
//! Joint positions are `&[f64]`, one value per actuated joint, base to end-effector.
//!
//! Three models ship with the crate ([`BUILTIN_ARMS`], files under `robots/`): `ur5` and `ur5e`
//! (Universal Robots UR5 and UR5e from their standard DH parameters, end-effector `tool0`) and `panda`
//! (Franka Emika Panda from its modified DH parameters, end-effector `panda_hand_tcp`, the
//! hand's tool centre point 0.103 m past the flange `panda_link8`, turned by -pi/4 about z).
//!
//! ```
//! use vsinv::sim::arm::ArmModel;
//! let arm = ArmModel::builtin("ur5")?;
//! let q = [0.1, -1.2, 1.0, -0.5, 1.4, 0.3];
//! let pose = arm.fk(&q)?; // tool0 in base_link
//! let jac = arm.jacobian_end_effector(&q)?; // twist (v, w) of tool0 in tool0 per unit dq
//! assert_eq!(jac.shape(), (6, 6));
//! assert!(pose.translation.vector.norm() < 1.0 && arm.manipulability(&q)? > 0.0);
//! let back = arm.ik(&pose, None)?; // joints within the limits reaching the same pose
//! assert!(back.position_residual < 1e-9 && back.rotation_residual < 1e-9);
//! # Ok::<(), vsinv::sim::SimError>(())
//! ```

mod ik;
mod kinematics;
mod model;
pub mod servo;
mod urdf_shape;

pub use ik::{DampedLeastSquaresIk, IkSolution, InverseKinematics};
pub use model::{ArmJoint, ArmLimits, ArmModel, JointKind};
pub use servo::{ArmRobot, ArmStep, DEFAULT_DAMPING, damped_least_squares};
pub use urdf_shape::{MAX_URDF_DEPTH, MAX_URDF_NODES};

use crate::error::Error;
use crate::sim::error::Result;

/// Names of the built-in arms.
pub const BUILTIN_ARMS: [&str; 3] = ["ur5", "ur5e", "panda"];

/// URDF text and default end-effector link of a built-in arm.
const BUILTIN: [(&str, &str, &str); 3] = [
    ("ur5", include_str!("../../../robots/ur5.urdf"), "tool0"),
    ("ur5e", include_str!("../../../robots/ur5e.urdf"), "tool0"),
    ("panda", include_str!("../../../robots/panda.urdf"), "panda_hand_tcp"),
];

/// The URDF text of a built-in arm (see [`BUILTIN_ARMS`]).
pub fn builtin_urdf(name: &str) -> Result<&'static str> {
    builtin_entry(name).map(|(_, urdf, _)| urdf)
}

fn builtin_entry(name: &str) -> Result<(&'static str, &'static str, &'static str)> {
    Ok(BUILTIN.into_iter().find(|(n, _, _)| *n == name).ok_or_else(|| Error::InvalidParameter {
        name: "arm",
        reason: format!("unknown built-in arm `{name}` (built-in: {})", BUILTIN_ARMS.join(", ")),
    })?)
}

impl ArmModel {
    /// A built-in arm ([`BUILTIN_ARMS`]) up to its default end-effector: `tool0` for `ur5`, `ur5e`,
    /// `panda_hand_tcp` for `panda`.
    pub fn builtin(name: &str) -> Result<Self> {
        let (name, urdf, end_effector) = builtin_entry(name)?;
        Self::parse(urdf, end_effector, &format!("builtin:{name}"))
    }

    /// A built-in arm up to another link of its URDF (e.g. the Panda's flange
    /// `panda_link8`).
    pub fn builtin_with_end_effector(name: &str, end_effector: &str) -> Result<Self> {
        let (name, urdf, _) = builtin_entry(name)?;
        Self::parse(urdf, end_effector, &format!("builtin:{name}"))
    }
}
