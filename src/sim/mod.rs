//! The kinematic simulator (feature `sim`): a camera on a robot servoing on an object in a
//! rapier3d-f64 scene, cameras that may differ between the reference image (K*) and the
//! servo (K(t), with a zoom), pixel noise, depth sources, stop rules and a recording;
//! scenario files describe runs, and [`batch`] runs many at once (feature `batch`).
//!
//! | concept | module |
//! |---|---|
//! | feature points, occluding bodies, visibility | [`scene`] |
//! | free-flying camera, Cartesian robot with joint limits | [`robot`] |
//! | serial arms from URDF: kinematics, Jacobians, built-in UR5 and Panda | [`arm`] |
//! | fixed cameras and zooms | [`camera_model`] |
//! | true, reference and estimated depths (appendix A) | [`depth_source`] |
//! | what a run needs: law, noise, stop rules | [`config`] |
//! | the world loop: observe the scene, drive a [`crate::servo::Servo`], move the robot, record | [`simulate`](mod@simulate) |
//! | images in the loop: render, detect, track (`[vision]`) | `image_loop` (private) |
//! | a scenario's views as images (reference, start, any pose) | [`views`] |
//! | status, summary, recording | [`outcome`] |
//! | scenario files (TOML, JSON) and the built-in scenarios | [`scenario`] |
//! | many runs in parallel (rayon) | [`batch`] |
//! | many runs of one scenario with keys overridden per run | [`sweep`] |

pub mod arm;
#[cfg(feature = "batch")]
pub mod batch;
pub mod camera_model;
pub mod config;
pub mod depth_source;
pub mod error;
mod image_loop;
pub mod outcome;
mod record_budget;
pub mod robot;
pub mod scenario;
pub mod scene;
pub mod simulate;
#[cfg(feature = "batch")]
pub mod sweep;
pub mod views;

pub use camera_model::{CameraModel, Zoom};
pub use config::{Law, Noise, SimulationConfig, StopRules};
pub use depth_source::{DepthEstimator, DepthEstimatorFactory, DepthSource, TranslationPairDepths};
pub use error::SimError;
pub use outcome::{Outcome, Recording, Status, StopRule, Summary, Tracking};
pub use record_budget::MAX_RECORD_BYTES;
pub use scenario::Scenario;
pub use simulate::simulate;
pub use views::{Shot, View, render_view};
