//! Robustness of the public Rust API, the camera: intrinsics, projection and lens distortion:
//! proptest over every fallible function.
//!
//! For arbitrary inputs (NaN, +-inf, zero, negative, 1e300, 1e-300, wrong lengths, degenerate
//! geometry) every fallible function returns a finite `Ok` or an `Err` whose message names the
//! argument and, for a fault in an array, its row (and column). No panic: proptest reports one
//! as a failure. Iterative methods are bounded by their iteration caps, not by the clock. The
//! harness is tests/common/robustness/mod.rs, the properties of this file are in
//! tests/common/robustness/camera.rs.
#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "common/robustness/camera.rs"]
mod camera;
mod common;
#[path = "common/robustness/mod.rs"]
mod robustness;

use camera::{prop_distortion, prop_intrinsics, prop_project_points};

// ---------------------------------------------------------------------------------------------
// The tests: cases per API group.

#[test]
fn intrinsics() {
    prop_intrinsics(512);
}
#[test]
fn projection() {
    prop_project_points(512);
}
#[test]
fn distortion() {
    prop_distortion(512);
}
