//! Depth estimation up to scale (appendix A, correction 10).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common::*;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use vsinv::Intrinsics;
use vsinv::core::depth::{ResectionDepths, depths_from_translation};

/// The translation pair: a camera unknown to the controller, a first pose and a pure
/// translation.
fn pair() -> (Vec<[f64; 2]>, Vec<[f64; 2]>, Vec<f64>) {
    let k_bar = Intrinsics::new(900.0, 880.0, 300.0, 260.0, 1.52).unwrap();
    let first = Isometry3::from_parts(
        Translation3::new(0.05, 0.02, -0.1),
        UnitQuaternion::from_scaled_axis(Vector3::new(0.05, -0.1, 0.3)),
    );
    let second = Isometry3::from_parts(Translation3::new(0.15, 0.0, -0.05), first.rotation);
    let (p1, z1) = view(&object_points(), &first, &k_bar);
    let (p2, _) = view(&object_points(), &second, &k_bar);
    (p1, p2, z1)
}

fn assert_proportional(estimate: &[f64], truth: &[f64]) -> f64 {
    let kappa = estimate[0] / truth[0];
    assert!(kappa > 0.0);
    for (e, t) in estimate.iter().zip(truth) {
        assert!((e / t - kappa).abs() < 1e-9 * kappa, "{e} / {t} vs {kappa}");
    }
    kappa
}

/// Eq. (26): the depths of the first image up to one positive scale.
#[test]
fn pure_translation_gives_depths_up_to_scale() {
    let (p1, p2, z1) = pair();
    let est = depths_from_translation(&p1, &p2).unwrap();
    assert_proportional(&est.depths, &z1);
    assert!(est.residual < 1e-9);
    // No motion: refused.
    assert!(depths_from_translation(&p1, &p1).is_err());
}

/// Every iteration: estimated depths = kappa(t) * true depths with one kappa > 0, at random
/// poses with another camera; kappa follows (det K* / det K)^(1/3).
#[test]
fn resection_depths_are_kappa_times_true_depths() {
    let (p1, p2, _) = pair();
    let first = depths_from_translation(&p1, &p2).unwrap();
    let k_star = lens(1200.0);
    let (reference, z_star) = view(&object_points(), &Isometry3::identity(), &k_star);
    let mut est = ResectionDepths::new(&p1, &first.depths, &reference, 1.0).unwrap();
    let n = reference.len();
    let mut out = vec![0.0; n];
    est.estimate(&reference, &vec![true; n], &mut out).unwrap();
    let kappa_ref = assert_proportional(&out, &z_star);
    // The scale makes the reference depths average 1.
    assert!((out.iter().sum::<f64>() / n as f64 - 1.0).abs() < 1e-9);
    let mut rng = Lcg(21);
    for _ in 0..20 {
        let k = random_intrinsics(&mut rng);
        let pose = random_pose(&mut rng, 0.15, 0.5);
        let (px, z) = view(&object_points(), &pose, &k);
        let mut visible = vec![true; n];
        visible[4] = false; // a hidden point is extrapolated from the resected camera
        est.estimate(&px, &visible, &mut out).unwrap();
        let kappa = assert_proportional(&out, &z);
        let expected = kappa_ref * (k_star.matrix().determinant() / k.matrix().determinant()).cbrt();
        assert!((kappa - expected).abs() < 1e-8 * expected, "{kappa} vs {expected}");
    }
}

/// Coplanar points cannot be resected.
#[test]
fn coplanar_points_are_refused() {
    let planar: Vec<Vector3<f64>> =
        object_points().iter().map(|p| Vector3::new(p[0], p[1], 0.6 + 0.2 * p[0])).collect();
    let (px, _) =
        view(&planar.iter().map(|p| [p.x, p.y, p.z]).collect::<Vec<_>>(), &Isometry3::identity(), &lens(800.0));
    assert!(vsinv::core::depth::resect(&planar, &px).is_err());
    assert!(vsinv::core::depth::resect(&planar[..5], &px[..5]).is_err());
}
