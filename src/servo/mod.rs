//! The servo session (feature `servo`, no dependency beyond the core's): what makes a servo
//! loop dependable, outside any simulator. A robot driver, a ROS node, a user's own loop and
//! the simulator all run [`Servo`].
//!
//! | concept | module |
//! |---|---|
//! | the session: observe, decide, control | [`session`] |
//! | the laws, each owning its behaviour (points needed, stop rule, telemetry) | [`law`] |
//! | the reference image: s*, the basis, the rz reference (sec. 2.3) | `reference` |
//! | measurements of an image against the reference: tau (eq. 21), errors | `measure` |
//! | stop thresholds and the pixel and invariant rules (correction 8) | [`stop`] |
//! | the stop rules' averaging window | `stop_window` |
//! | the stall rule: the error stopped decreasing, the camera still (issue 27) | [`stall`] |
//! | the pose uncertainty the images allow when the rule is met | [`certainty`] |
//! | where the law's depths come from | [`depths`] |
//! | the planned path of sec. 3, followed step by step | [`path`] |
//! | what a step reports | [`telemetry`], [`verdict`] |
//!
//! ```
//! use vsinv::servo::{Law, Servo, ServoConfig, ServoDepths, ServoReference};
//! use vsinv::{Intrinsics, InvariantControllerConfig, project_points};
//! let k = Intrinsics::pinhole(800.0, 800.0, 384.0, 288.0)?;
//! let object: Vec<[f64; 3]> = vec![
//!     [-0.1, -0.1, 0.6], [0.12, -0.08, 0.62], [0.0, 0.11, 0.58],
//!     [0.05, 0.02, 0.7], [-0.06, 0.05, 0.55], [0.09, 0.09, 0.65], [-0.1, 0.0, 0.66],
//! ];
//! let (pixels, depths) = project_points(&object, &k)?;
//! let config = ServoConfig::new(Law::Invariant(InvariantControllerConfig::default()), k);
//! let reference = ServoReference { pixels: pixels.clone(), depths: Some(depths) };
//! let mut servo = Servo::new(config, reference, ServoDepths::Reference)?;
//! let step = servo.step(&pixels, None, None)?; // at the goal: a zero twist
//! assert!(step.twist.norm() < 1e-9 && step.verdict.is_running());
//! # Ok::<(), vsinv::Error>(())
//! ```

pub(crate) mod basis_hold;
pub mod certainty;
pub mod depths;
pub mod law;
pub(crate) mod measure;
pub mod path;
pub(crate) mod reference;
pub mod session;
pub mod stall;
pub mod stop;
pub(crate) mod stop_window;
pub mod telemetry;
pub mod verdict;

pub use self::certainty::Certainty;
pub use self::depths::ServoDepths;
pub use self::law::{Law, ServoLaw};
pub use self::path::PathPlan;
pub use self::session::{Servo, ServoConfig, ServoReference};
pub use self::stop::{StopRule, StopRules};
pub use self::telemetry::{ServoStep, Telemetry};
pub use self::verdict::{Status, Verdict};
pub use crate::core::depth_estimator::DepthEstimator;
