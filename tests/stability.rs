//! Props. 1-3 (appendix B): the block form of A = J_hat^+ J and the verdicts.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common::*;
use approx::assert_relative_eq;
use nalgebra::{DMatrix, Matrix3};
use vsinv::{Intrinsics, a_matrix, check_stability, invariant_jacobian};

fn pinv(j: &DMatrix<f64>) -> DMatrix<f64> {
    j.clone().pseudo_inverse(1e-14).unwrap()
}

/// A = J_hat^+ J (computed from two Jacobians at a random pose, with depth estimates
/// kappa * zeta and a wrong skewed K_hat) equals blockdiag(kappa K_hat^-1 K, F(K_hat)^-1 F(K)).
#[test]
fn a_equals_its_block_form_at_any_pose() {
    let mut rng = Lcg(11);
    for _ in 0..20 {
        let k = random_intrinsics(&mut rng);
        let k_hat = random_intrinsics(&mut rng);
        let kappa = rng.uniform(0.2, 5.0);
        let pose = random_pose(&mut rng, 0.12, 0.4);
        let (px, z) = view(&object_points(), &pose, &k);
        let z_hat: Vec<f64> = z.iter().map(|v| v * kappa).collect();
        let j = invariant_jacobian(&px, &z, &k, [0, 3, 8]).unwrap();
        let j_hat = invariant_jacobian(&px, &z_hat, &k_hat, [0, 3, 8]).unwrap();
        let a_num = pinv(&j_hat) * j;
        let a_block = a_matrix(&k.matrix(), &k_hat.matrix(), kappa).unwrap();
        let a_block = DMatrix::from_iterator(5, 5, a_block.iter().copied());
        assert_relative_eq!(a_num, a_block, epsilon = 1e-7, max_relative = 1e-7);
    }
}

/// Prop. 1's verdict equals the signs of the eigenvalues of A over a grid of K_hat that
/// includes negative focal terms and skew; a kappa <= 0 (excluded by the paper: depth
/// estimates are kappa zeta > 0) is an error (issue 16).
#[test]
fn prop1_verdict_equals_eigenvalue_signs_over_a_grid() {
    let k = Intrinsics::new(1200.0, 1150.0, 390.0, 280.0, 1.5).unwrap().matrix();
    let mut checked = (0, 0);
    for &fku in &[-2000.0, -600.0, 300.0, 1200.0, 5000.0] {
        for &k11 in &[-1500.0, -100.0, 200.0, 1100.0, 4000.0] {
            for &k01 in &[-800.0, 0.0, 300.0] {
                for &kappa in &[-1.0, 0.5, 2.0] {
                    let k_hat = Matrix3::new(fku, k01, 300.0, 0.0, k11, 250.0, 0.0, 0.0, 1.0);
                    if kappa <= 0.0 {
                        assert!(check_stability(&[k], &k_hat, kappa, 1.0).is_err());
                        assert!(a_matrix(&k, &k_hat, kappa).is_err());
                        continue;
                    }
                    let report = check_stability(&[k], &k_hat, kappa, 1.0).unwrap();
                    let stable = report.eigenvalues[0].iter().all(|e| e.re > 0.0);
                    assert_eq!(report.prop1, stable, "K_hat = {k_hat}, kappa = {kappa}");
                    if stable { checked.0 += 1 } else { checked.1 += 1 }
                }
            }
        }
    }
    assert!(checked.0 > 10 && checked.1 > 10, "grid must contain both verdicts: {checked:?}");
}

/// Prop. 2 is sufficient: it implies Prop. 1 at every K of the schedule, and is stricter
/// (a large skew error keeps the eigenvalues positive but A + A^T indefinite).
#[test]
fn prop2_is_sufficient_and_stricter() {
    let schedule: Vec<Matrix3<f64>> = (0..6).map(|i| lens(2250.0 - 140.0 * i as f64).matrix()).collect();
    let good = check_stability(&schedule, &lens(1500.0).matrix(), 1.0, 1.0).unwrap();
    assert!(good.prop1 && good.prop2 && good.sigma > 0.0);
    let skewed = Matrix3::new(300.0, -3000.0, 384.0, 0.0, 5000.0, 288.0, 0.0, 0.0, 1.0);
    let r = check_stability(&schedule, &skewed, 1.0, 1.0).unwrap();
    assert!(r.prop1 && !r.prop2 && r.sigma <= 0.0, "{r:?}");
    // No bound when Prop. 2 fails: an error naming sigma (issue 16: was Ok(inf)).
    let e = r.tracking_bound(1.0).unwrap_err().to_string();
    assert!(e.contains("sigma"), "{e}");
}

/// Prop. 3: psi/phi with psi = 2 max||b|| and phi = lambda sigma.
#[test]
fn tracking_bound_formula() {
    let r = check_stability(&[lens(1200.0).matrix()], &lens(1200.0).matrix(), 1.0, 2.0).unwrap();
    // A = I, A + A^T = 2 I: sigma = 2, phi = 4, psi = 2 * 0.5.
    assert_relative_eq!(r.sigma, 2.0, epsilon = 1e-12);
    assert_relative_eq!(r.tracking_bound(0.5).unwrap(), 0.25, epsilon = 1e-12);
    assert!(vsinv::tracking_bound(0.0, 1.0, 1.0).is_err());
}

/// The cheap verdicts agree with the full report.
#[test]
fn verdicts_agree_with_the_report() {
    let k = Intrinsics::new(1200.0, 1150.0, 390.0, 280.0, 1.5).unwrap().matrix();
    for &fku in &[-600.0, 300.0, 1200.0, 5000.0] {
        for &k01 in &[-3000.0, 0.0, 300.0] {
            for &v0 in &[0.0, 250.0, 2000.0] {
                let k_hat = Matrix3::new(fku, k01, 300.0, 0.0, 900.0, v0, 0.0, 0.0, 1.0);
                let r = check_stability(&[k], &k_hat, 0.8, 1.0).unwrap();
                let (p1, p2, sigma) = vsinv::core::stability::stability_verdicts(&[k], &k_hat, 0.8, 1.0).unwrap();
                assert_eq!((p1, p2), (r.prop1, r.prop2));
                assert!((sigma - r.sigma).abs() < 1e-9 * (1.0 + r.sigma.abs()));
            }
        }
    }
}
