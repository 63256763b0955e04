//! Robustness of the public Rust API, vision: detection, tracking, rendering: proptest over every
//! fallible function.
//!
//! For arbitrary inputs (NaN, +-inf, zero, negative, 1e300, 1e-300, wrong lengths, degenerate
//! geometry) every fallible function returns a finite `Ok` or an `Err` whose message names the
//! argument and, for a fault in an array, its row (and column). No panic: proptest reports one
//! as a failure. Iterative methods are bounded by their iteration caps, not by the clock. The
//! harness is tests/common/robustness/mod.rs, the properties of this file are in
//! tests/common/robustness/vision.rs.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::robustness::vision::{prop_detect_and_track, prop_render};

// ---------------------------------------------------------------------------------------------
// The tests: cases per API group.

#[test]
fn vision() {
    prop_detect_and_track(256);
    prop_render(192);
}
