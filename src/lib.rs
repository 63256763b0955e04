//! # vsinv: visual servoing invariant to the camera's intrinsic parameters
//!
//! An implementation of E. Malis, *Visual servoing invariant to changes in camera intrinsic
//! parameters*, INRIA research report RR-4309 (2001): position a camera with respect to a
//! non-planar object from a reference image that may have been taken with another camera,
//! lens or zoom.
//!
//! ## Layers and features
//! | layer | module | Cargo feature | dependencies |
//! |---|---|---|---|
//! | the control core: the paper's mathematics | [`core`] | always | nalgebra, thiserror |
//! | errors: the core's, and the trait of every layer's (each layer declares its own in its `error.rs`) | [`error`] | always | |
//! | where an error is (keys and indices) | [`location`] | always | |
//! | the servo session: stop rules, depth sources, path following, verdicts | `servo` | `servo` | |
//! | simulator: scene, robots, closed loop, scenario files | `sim` | `sim` (default) | rapier3d-f64, serde, toml, rand |
//! | many runs in parallel | `sim::batch` | `batch` (default) | rayon |
//! | worker pools that a forked child rebuilds | `parallel` | `batch` or `vision` | rayon |
//! | images: rendering, dot detection and tracking | `vision` | `vision` (default) | image, imageproc |
//! | camera calibration files (ROS YAML, OpenCV YAML and XML), hand-eye calibration | [`calibration`] | `calibration` (default) | yaml-rust2, roxmltree |
//! | Python bindings (the only module that knows about Python) | `python` (private) | `python` | pyo3, numpy |
//!
//! A controller that needs only the control law depends on
//! `vsinv = { version = "0.1", default-features = false }` and gets nalgebra and thiserror
//! alone; [`nalgebra`] is re-exported so that dependents use the same version.
//!
//! ## Where each concept of the paper lives
//! | paper | module |
//! |---|---|
//! | camera model, eq. (4), point interaction matrix | [`core::camera`] |
//! | projective invariant transform, sec. 2.3, eq. (21) | [`core::invariant`] |
//! | invariant Jacobian, sec. 4.1, eqs. (11)-(13), (23) | [`core::jacobian`] |
//! | control laws, eqs. (14), (17), (24) | [`core::control`] |
//! | classic IBVS baseline | [`core::ibvs`] |
//! | Props. 1-3, appendix B | [`core::stability`] |
//! | plane + parallax (eq. 9), the invariant-space path (eq. 10) | [`core::planning`] |
//! | depths up to scale (eq. 26, appendix A) | [`core::depth`] |
//! | rigid motions, exact twist integration | [`core::se3`] |
//! | lens distortion (OpenCV's models; not in the paper) | [`core::distortion`] |
//!
//! ## Conventions
//! - SI units: metres, radians, seconds; pixels for image points.
//! - Image points are `(u, v)` pairs, `[[f64; 2]]` in Rust and `(n, 2)` arrays in Python.
//! - The camera twist is `(vx, vy, vz, wx, wy, wz)` in the *current camera frame* (ViSP's
//!   order): linear velocity in m/s, then angular velocity in rad/s.
//! - Poses are 4x4 homogeneous matrices (`Isometry3` in Rust) of the camera frame expressed
//!   in F*, the camera frame where the reference image was taken.
//! - The basis is three point indices; the task vector `s` stacks the invariant points of the
//!   other points in increasing index order.
//! - Depths passed to the controllers are per-point estimates; any common positive scale
//!   (`kappa` of sec. 4.1) is allowed for the invariant law.
//!
//! The paper's formulas contain misprints; `docs/paper-corrections.md` lists them with the
//! readings this crate implements and the tests that check them, and the code cites them
//! as "correction N" next to the formulas they affect.
//!
//! ## Example
//! ```
//! use vsinv::{Intrinsics, InvariantController, InvariantControllerConfig, project_points};
//! let k_star = Intrinsics::pinhole(1200.0, 1200.0, 384.0, 288.0)?; // reference lens
//! let k = Intrinsics::pinhole(600.0, 600.0, 384.0, 288.0)?;       // servo lens
//! let object: Vec<[f64; 3]> = vec![
//!     [-0.1, -0.1, 0.6], [0.12, -0.08, 0.62], [0.0, 0.11, 0.58],
//!     [0.05, 0.02, 0.7], [-0.06, 0.05, 0.55], [0.09, 0.09, 0.65], [-0.1, 0.0, 0.66],
//! ];
//! let (reference, _) = project_points(&object, &k_star)?;
//! let mut ctl = InvariantController::new(&reference, k, [0, 1, 2], InvariantControllerConfig::default())?;
//! let (pixels, depths) = project_points(&object, &k)?;
//! let twist = ctl.step(&pixels, &depths)?; // at the reference pose: ~zero twist
//! assert!(twist.norm() < 1e-9);
//! # Ok::<(), vsinv::Error>(())
//! ```

#[cfg(feature = "calibration")]
pub mod calibration;
pub mod core;
pub mod error;
#[cfg(any(feature = "calibration", feature = "vision"))]
pub mod input_file;
pub mod location;
#[cfg(any(feature = "batch", feature = "vision"))]
pub mod parallel;
#[cfg(feature = "servo")]
pub mod servo;
#[cfg(feature = "sim")]
pub mod sim;
#[cfg(feature = "vision")]
pub mod vision;

#[cfg(feature = "python")]
mod python;

pub use nalgebra;

pub use crate::core::camera::{Intrinsics, project_points};
pub use crate::core::control::{ControlState, Controller, InvariantController, InvariantControllerConfig};
pub use crate::core::distortion::{Distortion, DistortionModel, distort_points, undistort_points};
pub use crate::core::ibvs::{IbvsController, Interaction};
pub use crate::core::invariant::{choose_basis, invariant_points, task_vector};
pub use crate::core::jacobian::{
    invariant_interaction, invariant_jacobian, jacobian_factors, rz_coefficients, structure_ratio,
};
pub use crate::core::noise_meter::PixelNoiseMeter;
pub use crate::core::stability::{StabilityReport, a_matrix, check_stability, tracking_bound};
pub use crate::core::uncertainty::{
    ImageNoise, Measurement, PoseUncertainty, invariant_pose_uncertainty, pixel_pose_uncertainty,
};
pub use error::{Error, Located, Result};
pub use location::Location;
