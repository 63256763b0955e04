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

use crate::robustness::camera::{prop_distortion, prop_intrinsics, prop_project_points};

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

/// Issue 28: `undistort_points` with `tol = 0` looped to the caller's `max_iter` however large
/// (the residual stops at rounding error, never 0). `tol <= 0` is refused by name, and a
/// residual that stops decreasing ends the work whatever `max_iter`.
#[test]
fn undistortion_work_is_bounded() {
    use std::time::Instant;
    use vsinv::{Distortion, Error, Intrinsics, distort_points, undistort_points};
    let k = Intrinsics::pinhole(500.0, 500.0, 320.0, 240.0).unwrap();
    let d = Distortion::from_coefficients(&[-0.28, 0.07, 0.0, 0.0, 0.0]).unwrap();
    let px: Vec<[f64; 2]> = (0..200).map(|i| [20.0 + 3.0 * i as f64, 30.0 + 2.0 * i as f64]).collect();
    let distorted = distort_points(&px, &k, &d).unwrap();
    for tol in [0.0, -0.0, -1.0, f64::NAN] {
        match undistort_points(&distorted, &k, &d, tol, usize::MAX) {
            Err(Error::InvalidParameter { name: "tol", reason }) => assert!(reason.contains("> 0"), "{reason}"),
            other => panic!("tol = {tol}: {other:?}"),
        }
    }
    // The smallest positive tolerance and no iteration cap: done in a bounded time, each
    // point either within 1e-300 px (exact) or refused as stalled at rounding error.
    let t = Instant::now();
    for p in &distorted {
        match undistort_points(&[*p], &k, &d, 1e-300, usize::MAX) {
            Ok(back) => assert!(back[0].iter().all(|v| v.is_finite())),
            Err(Error::Distortion { reason, .. }) => assert!(reason.contains("stopped decreasing"), "{reason}"),
            Err(e) => panic!("{e}"),
        }
    }
    assert!(t.elapsed().as_secs_f64() < 1.0, "{:?}", t.elapsed());
    // An ordinary tolerance still reaches the ideal pixels.
    let back = undistort_points(&distorted, &k, &d, 1e-10, usize::MAX).unwrap();
    for (b, p) in back.iter().zip(&px) {
        assert!((b[0] - p[0]).abs() < 1e-8 && (b[1] - p[1]).abs() < 1e-8, "{b:?} {p:?}");
    }
}
