//! Robustness of the public Rust API, the controllers, the stability check, rigid motions, the rz
//! task, gains and saturation: proptest over every fallible function.
//!
//! For arbitrary inputs (NaN, +-inf, zero, negative, 1e300, 1e-300, wrong lengths, degenerate
//! geometry) every fallible function returns a finite `Ok` or an `Err` whose message names the
//! argument and, for a fault in an array, its row (and column). No panic: proptest reports one
//! as a failure. Iterative methods are bounded by their iteration caps, not by the clock. The
//! harness is tests/common/robustness/mod.rs, the properties of this file are in
//! tests/common/robustness/control.rs.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::robustness::control::{
    prop_gains, prop_ibvs_controller, prop_invariant_controller, prop_invariant_controller_reference, prop_rz_task,
    prop_se3, prop_stability,
};

// ---------------------------------------------------------------------------------------------
// The tests: cases per API group.

#[test]
fn invariant_controller() {
    prop_invariant_controller(384);
}
#[test]
fn invariant_controller_reference() {
    prop_invariant_controller_reference(256);
}
#[test]
fn ibvs_controller() {
    prop_ibvs_controller(384);
}
#[test]
fn stability() {
    prop_stability(384);
}
#[test]
fn se3_rz_task_gains() {
    prop_se3(512);
    prop_rz_task(384);
    prop_gains(512);
}
