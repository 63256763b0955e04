//! Python bindings (feature `python`): the only module that knows about Python. Thin
//! wrappers that read NumPy arrays in place, call the core and map errors to the package's
//! exception hierarchy; no panic crosses into Python.
//!
//! Each binding file covers one area and adds its classes and functions to the module with
//! its `register`; errors convert with `?` (`impl From<E> for PyErr` in `errors`, for the error
//! of every layer).

mod args;
mod arrays;
mod batch_watch;
mod camera;
mod compressed;
mod control;
mod errors;
mod features;
mod grey;
mod hand_eye;
mod image_arg;
mod image_servo;
mod invariant;
mod kinematics;
mod law_options;
mod lens;
mod logs;
mod planning;
mod run_record;
mod scenario_arm;
mod se3;
mod servo;
mod shared;
mod sim;
mod stability;
mod sweep;
mod tag_tracker;
mod tags;
mod targets;
mod textured;
mod uncertainty;
mod values;
mod vision;

use pyo3::prelude::*;

pub(crate) use args::BasisArg;
pub(crate) use arrays::{depths_arg, pixels_arg};
pub(crate) use camera::{PyIntrinsics, intrinsics, intrinsics_repr};

/// The compiled core of vsinv (Rust, PyO3). Its names are imported from the package's levels,
/// which re-export them: `vsinv`, `vsinv.laws`, `vsinv.vision`, `vsinv.sim`,
/// `vsinv.calibration`, `vsinv.kinematics`, `vsinv.geometry` and `vsinv.errors`.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    errors::register(m)?;
    camera::register(m)?;
    invariant::register(m)?;
    stability::register(m)?;
    control::register(m)?;
    servo::register(m)?;
    law_options::register(m)?;
    uncertainty::register(m)?;
    planning::register(m)?;
    sim::register(m)?;
    sweep::register(m)?;
    vision::register(m)?;
    textured::register(m)?;
    features::register(m)?;
    grey::register(m)?;
    compressed::register(m)?;
    image_servo::register(m)?;
    targets::register(m)?;
    tags::register(m)?;
    tag_tracker::register(m)?;
    se3::register(m)?;
    kinematics::register(m)?;
    scenario_arm::register(m)?;
    lens::register(m)?;
    hand_eye::register(m)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
