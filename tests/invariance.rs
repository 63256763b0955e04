//! The projective invariant transform (sec. 2.3) and the Jacobians (sec. 4.1) against
#![allow(clippy::unwrap_used, clippy::expect_used)]
//! independent computations: re-projection with other cameras and finite differences.

use crate::common::*;
use approx::assert_relative_eq;
use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use proptest::prelude::*;
use vsinv::core::se3::exp_twist;
use vsinv::{Intrinsics, invariant_jacobian, invariant_points, jacobian_factors};

fn q_at(pose: &Isometry3<f64>, k: &Intrinsics, basis: [usize; 3]) -> Vec<[f64; 3]> {
    let (px, _) = view(&object_points(), pose, k);
    invariant_points(&px, basis).unwrap()
}

fn max_diff(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter().flatten().zip(b.iter().flatten()).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// q does not depend on K: any upper-triangular K (skew, non-square pixels, shifted
    /// principal point) gives the same invariant points at the same pose.
    #[test]
    fn q_invariant_to_intrinsics(
        fku in 200.0..4000.0f64, fkv in 200.0..4000.0f64, u0 in -300.0..1000.0f64,
        v0 in -300.0..800.0f64, theta in 1.0..2.1f64, seed in 0u64..1000,
    ) {
        let mut rng = Lcg(seed);
        let pose = random_pose(&mut rng, 0.1, 0.3);
        let k1 = Intrinsics::new(fku, fkv, u0, v0, theta).unwrap();
        let k2 = lens(1200.0);
        let d = max_diff(&q_at(&pose, &k1, [0, 3, 8]), &q_at(&pose, &k2, [0, 3, 8]));
        prop_assert!(d < 1e-9, "max |q1 - q2| = {d}");
    }

    /// q does not change under a rotation about the optical axis (G = R_z of sec. 2.3).
    #[test]
    fn q_invariant_to_rotation_about_optical_axis(rz in -3.1..3.1f64, seed in 0u64..1000) {
        let mut rng = Lcg(seed);
        let pose = random_pose(&mut rng, 0.1, 0.3);
        let rolled = pose * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), rz);
        let k = random_intrinsics(&mut rng);
        let d = max_diff(&q_at(&pose, &k, [0, 3, 8]), &q_at(&rolled, &k, [0, 3, 8]));
        prop_assert!(d < 1e-9, "max |q - q_rolled| = {d}");
    }
}

/// Each of the other five dof changes q.
#[test]
fn q_changed_by_the_other_five_dof() {
    let k = lens(1200.0);
    let pose = Isometry3::identity();
    let q0 = q_at(&pose, &k, [0, 3, 8]);
    for axis in 0..5 {
        let mut tw = [0.0; 6];
        tw[axis] = 0.01; // 10 mm or 0.01 rad
        let moved = pose * exp_twist(&tw).unwrap();
        let d = max_diff(&q0, &q_at(&moved, &k, [0, 3, 8]));
        assert!(d > 1e-4, "dof {axis} moved q by only {d}");
    }
}

/// J against central differences of q along each twist direction (random poses, skewed K);
/// the sixth column (w_z) is zero.
#[test]
fn jacobian_matches_finite_differences() {
    let mut rng = Lcg(42);
    let basis = [1, 6, 10];
    for _ in 0..25 {
        let k = random_intrinsics(&mut rng);
        let pose = random_pose(&mut rng, 0.12, 0.4);
        let (px, z) = view(&object_points(), &pose, &k);
        let full = vsinv::invariant_interaction(&px, &z, &k, basis).unwrap();
        let j = invariant_jacobian(&px, &z, &k, basis).unwrap();
        assert_eq!(j.shape(), (27, 5));
        let h = 1e-6;
        for col in 0..6 {
            let mut tw = [0.0; 6];
            tw[col] = h;
            let (pp, _) = view(&object_points(), &(pose * exp_twist(&tw).unwrap()), &k);
            tw[col] = -h;
            let (pm, _) = view(&object_points(), &(pose * exp_twist(&tw).unwrap()), &k);
            let sp = vsinv::task_vector(&pp, basis).unwrap();
            let sm = vsinv::task_vector(&pm, basis).unwrap();
            let scale = full.column(col).amax().max(1e-3);
            for r in 0..27 {
                let fd = (sp[r] - sm[r]) / (2.0 * h);
                assert!(
                    (fd - full[(r, col)]).abs() < 1e-5 * scale.max(1.0),
                    "col {col} row {r}: fd {fd} vs J {}",
                    full[(r, col)]
                );
            }
        }
        let col6 = full.column(5).amax();
        let col_max = full.columns(0, 5).amax();
        assert!(col6 < 1e-9 * col_max, "w_z column not zero: {col6}");
    }
}

/// The direct form equals the factorization `[Phi K, Psi F(K)]` (correction 2).
#[test]
fn factorization_equals_direct_form() {
    let mut rng = Lcg(7);
    for _ in 0..20 {
        let k = random_intrinsics(&mut rng);
        let pose = random_pose(&mut rng, 0.15, 0.5);
        let (px, z) = view(&object_points(), &pose, &k);
        let direct = invariant_jacobian(&px, &z, &k, [0, 5, 11]).unwrap();
        let (phi, psi) = jacobian_factors(&px, &z, [0, 5, 11]).unwrap();
        let fact = vsinv::core::jacobian::jacobian_from_factors(&phi, &psi, &k.matrix()).unwrap();
        assert_relative_eq!(direct, fact, max_relative = 1e-8, epsilon = 1e-12);
    }
}

/// a and c of eq. (23) against central differences of eps_z = det(Q*) tau_21.
#[test]
fn rz_coefficients_match_finite_differences() {
    let mut rng = Lcg(3);
    let basis = [0, 3, 8];
    let k_star = lens(1200.0);
    let (reference, _) = view(&object_points(), &Isometry3::identity(), &k_star);
    for _ in 0..20 {
        let k = random_intrinsics(&mut rng);
        let pose = random_pose(&mut rng, 0.1, 0.4);
        let (px, z) = view(&object_points(), &pose, &k);
        let (a, c) = vsinv::rz_coefficients(&px, &z, &reference, &k, basis).unwrap();
        let eps_z = |p: &Isometry3<f64>| {
            let (q, _) = view(&object_points(), p, &k);
            let star = vsinv::core::invariant::BasisFrame::new(&reference, basis, "reference").unwrap();
            let cur = vsinv::core::invariant::BasisFrame::new(&q, basis, "current").unwrap();
            let rz = vsinv::core::invariant::RzReference::new(&star);
            rz.det_q_star * rz.t_matrix(&cur)[(1, 0)]
        };
        let h = 1e-6;
        let coeffs = [c[0], c[1], c[2], c[3], c[4], a];
        let scale = coeffs.iter().fold(1.0_f64, |m, x| m.max(x.abs()));
        for (col, &want) in coeffs.iter().enumerate() {
            let mut tw = [0.0; 6];
            tw[col] = h;
            let plus = eps_z(&(pose * exp_twist(&tw).unwrap()));
            tw[col] = -h;
            let minus = eps_z(&(pose * exp_twist(&tw).unwrap()));
            let fd = (plus - minus) / (2.0 * h);
            assert!((fd - want).abs() < 1e-6 * scale, "col {col}: fd {fd} vs {want}");
        }
    }
}

/// The degenerate-structure measure: planar object and equal depth estimates are caught,
/// an object with relief is not.
#[test]
fn structure_ratio_flags_planar_objects_and_equal_depths() {
    let k = lens(1200.0);
    let pose = Isometry3::identity();
    let (px, z) = view(&object_points(), &pose, &k);
    let good = vsinv::structure_ratio(&px, &z, &k, [0, 3, 8]).unwrap();
    assert!(good > 0.05, "object with relief: {good}");
    let equal = vec![0.6; z.len()];
    let flat = vsinv::structure_ratio(&px, &equal, &k, [0, 3, 8]).unwrap();
    assert!(flat < 1e-6, "equal depths: {flat}");
    let planar: Vec<[f64; 3]> = object_points().iter().map(|p| [p[0], p[1], 0.6 + 0.2 * p[0]]).collect();
    let (ppx, pz) = view(&planar, &random_pose(&mut Lcg(1), 0.05, 0.2), &k);
    let ratio = vsinv::structure_ratio(&ppx, &pz, &k, [0, 3, 8]).unwrap();
    assert!(ratio < 1e-6, "planar object: {ratio}");
}
