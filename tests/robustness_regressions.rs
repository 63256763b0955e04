//! Robustness of the public Rust API: the regressions, one deterministic case for each fault the
//! properties of tests/robustness_*.rs found.
//!
//! For arbitrary inputs (NaN, +-inf, zero, negative, 1e300, 1e-300, wrong lengths, degenerate
//! geometry) every fallible function returns a finite `Ok` or an `Err` whose message names the
//! argument and, for a fault in an array, its row (and column). No panic: proptest reports one
//! as a failure. Iterative methods are bounded by their iteration caps, not by the clock. The
//! harness is tests/common/robustness/mod.rs.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common::{lens, object_points};
use crate::robustness::{CALIBRATION_FILES, invariants, scene, translation_pair};
use nalgebra::Vector3;
use vsinv::core::depth::{ResectionDepths, depths_from_translation, resect};
use vsinv::core::planning::{InvariantPath, estimate_plane_parallax};
use vsinv::{
    Distortion, IbvsController, Interaction, Intrinsics, InvariantController, check_stability, distort_points,
    invariant_jacobian, project_points, rz_coefficients, tracking_bound,
};

// ---------------------------------------------------------------------------------------------
// Regressions: the faults the properties of tests/robustness_*.rs found, one deterministic case each.

fn message<T: std::fmt::Debug, E: std::fmt::Display>(r: std::result::Result<T, E>) -> String {
    r.expect_err("an error").to_string()
}

#[test]
fn regression_step_visible_names_row_and_column_of_a_nan_pixel() {
    let sc = scene(1);
    let mut px = sc.pixels.clone();
    px[5][1] = f64::NAN;
    let visible = vec![true; 12];
    let mut ctl = InvariantController::new(&sc.reference, sc.k, [0, 3, 8], Default::default()).unwrap();
    let m = message(ctl.step_visible(&px, &sc.depths, &visible));
    assert!(m.contains("pixels") && m.contains("row 5, column 1"), "{m}");
    let mut ibvs = IbvsController::new(&sc.reference, sc.k, 1.0, Interaction::Current, None).unwrap();
    let m = message(ibvs.step_visible(&px, &sc.depths, &visible));
    assert!(m.contains("row 5, column 1"), "{m}");
}

#[test]
fn regression_point_arrays_are_named_by_row_and_column() {
    let m = message(project_points(&[[0.0, 0.0, 1.0], [0.1, 0.2, f64::NAN]], &lens(800.0)));
    assert!(m.contains("points") && m.contains("row 1, column 2"), "{m}");
    let sc = scene(2);
    let mut ctl = InvariantController::new(&sc.reference, sc.k, [0, 3, 8], Default::default()).unwrap();
    let mut s_star = vec![[0.2, 0.3, 0.5]; 9];
    s_star[4][1] = f64::INFINITY;
    let m = message(ctl.set_reference(&s_star, None));
    assert!(m.contains("s_star") && m.contains("row 4, column 1"), "{m}");
    let (q, mut q_star) = invariants(3);
    q_star[2].y = f64::NAN;
    let m = message(estimate_plane_parallax(&q, &q_star));
    assert!(m.contains("q_star") && m.contains("row 2, column 1"), "{m}");
}

#[test]
fn regression_resection_depths_estimate_checks_its_arguments() {
    let (a, b, _) = translation_pair(4);
    let first = depths_from_translation(&a, &b).unwrap().depths;
    let mut est = ResectionDepths::new(&a, &first, &b, 1.0).unwrap();
    let mut out = vec![0.0; 12];
    // Was: an index out of bounds panic.
    assert!(message(est.estimate(&b, &[true; 11], &mut out)).contains("visible"));
    assert!(message(est.estimate(&b[..10], &[true; 12], &mut out)).contains("pixels"));
    let mut px = b.clone();
    px[7][0] = f64::NAN;
    assert!(message(est.estimate(&px, &[true; 12], &mut out)).contains("row 7, column 0"));
}

#[test]
fn regression_overflow_is_an_error_not_an_ok_with_inf() {
    // Was Ok with a K of inf (fkv / sin(theta)), a pixel of inf, an inf Jacobian, an inf bound.
    assert!(Intrinsics::new(1.0, 1e300, 0.0, 0.0, 1e-300).is_err());
    assert!(Intrinsics::pinhole(5e-324, 1.0, 0.0, 0.0).is_err());
    assert!(message(project_points(&[[1e300, 0.0, 1e-300]], &lens(800.0))).contains("point 0"));
    let sc = scene(5);
    let mut z = sc.depths.clone();
    z[0] = 2.2e-308;
    assert!(message(invariant_jacobian(&sc.pixels, &z, &sc.k, [0, 3, 8])).contains("depths"));
    assert!(message(rz_coefficients(&sc.pixels, &z, &sc.reference, &sc.k, [0, 3, 8])).contains("depths"));
    assert!(tracking_bound(1e-300, 1e-300, 1.0).is_err());
    let d = Distortion::from_coefficients(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0176]).unwrap();
    assert!(distort_points(&[[f64::MAX, 0.0]], &lens(800.0), &d).is_err());
    let (q, q_star) = invariants(6);
    let est = estimate_plane_parallax(&q, &q_star).unwrap();
    assert!(InvariantPath::new(&q_star, &est, 5e-324).is_err());
}

#[test]
fn regression_no_hang_on_overflowing_resection_input() {
    // Was: the SVD of a non-finite DLT system never returned.
    let cloud: Vec<Vector3<f64>> = object_points().iter().map(|p| Vector3::from(*p)).collect();
    let mut px = scene(7).pixels;
    px[3] = [1e300, -1e300];
    assert!(resect(&cloud, &px).is_err());
}

#[test]
fn regression_huge_disc_normal_is_normalised() {
    let d = vsinv::vision::Disc::new([0.0, 0.0, 1.0], [1e300, 1e300, 0.0], 0.01).unwrap();
    assert!((d.normal.norm() - 1.0).abs() < 1e-12);
}

#[test]
fn regression_calibration_matrix_size_overflow() {
    let text = CALIBRATION_FILES[0].replace("rows: 3", "rows: 9223372036854775807");
    let m = message(vsinv::calibration::parse_calibration(&text, "big.yaml"));
    assert!(m.contains("camera_matrix"), "{m}");
}

#[test]
fn regression_extreme_but_finite_inputs_are_refused_not_overflowed() {
    // A principal point at f64::MAX made normalise overflow.
    assert!(Intrinsics::new(1000.0, 10.0, 0.0, f64::MAX, 0.2).is_err());
    assert!(Intrinsics::new(1000.0, 1000.0, 1e12, -1e12, 1.5).is_ok());
    // kappa near f64::MAX overflowed the eigenvalues of A.
    let k = Intrinsics::new(1187.0, 636.0, 436.6, 224.7, 1.2).unwrap().matrix();
    let m = message(check_stability(&[k], &k, f64::MAX, 0.2));
    assert!(m.contains("kappa"), "{m}");
    // A path shorter than a microsecond overflowed its rates.
    let (q, q_star) = invariants(3);
    let est = estimate_plane_parallax(&q, &q_star).unwrap();
    assert!(InvariantPath::new(&q_star, &est, f64::MIN_POSITIVE).is_err());
    assert!(InvariantPath::new(&q_star, &est, 1e-6).is_ok());
    // A mean depth of 1e300 gave infinite depths from ResectionDepths::estimate.
    let (a, b, z) = translation_pair(940);
    let mut est = ResectionDepths::new(&a, &z, &b, 1e300).unwrap();
    let mut out = vec![0.0; a.len()];
    let m = message(est.estimate(&scene(940).pixels, &vec![true; a.len()], &mut out));
    assert!(m.contains("reference_mean_depth"), "{m}");
}
