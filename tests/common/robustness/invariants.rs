//! The invariant transform and the Jacobians.
//!
//! The properties of tests/robustness_invariants.rs (and the census of tests/robustness_census.rs).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::robustness::*;
use proptest::prelude::*;
use vsinv::{
    choose_basis, invariant_interaction, invariant_jacobian, invariant_points, jacobian_factors, rz_coefficients,
    structure_ratio, task_vector,
};

pub fn prop_invariant(cases: u32) {
    run(cases, (0u64..1000, fault(), basis()), |(seed, f, b)| {
        let mut px = scene(seed).pixels;
        let hit = f.apply(&mut px);
        let fault = nan_at("pixels", hit);
        let q = invariant_points(&px, b);
        check_located("invariant_points", &q, fault.clone(), |q| {
            let sums = q
                .iter()
                .all(|r| (r.iter().sum::<f64>() - 1.0).abs() < 1e-6 * (1.0 + r.iter().map(|v| v.abs()).sum::<f64>()));
            let unit = (0..3).all(|i| (q[b[i]][i] - 1.0).abs() < 1e-9);
            finite(q.as_flattened()) && sums && unit
        })?;
        let s = task_vector(&px, b);
        check_located("task_vector", &s, fault.clone(), |s| {
            finite(s)
                && s.len() == 3 * (px.len() - 3)
                && q.as_ref().is_ok_and(|q| {
                    let others: Vec<f64> = (0..px.len()).filter(|i| !b.contains(i)).flat_map(|i| q[i]).collect();
                    others == *s
                })
        })?;
        let chosen = choose_basis(&px);
        check_located("choose_basis", &chosen, fault, |c| c[0] < c[1] && c[1] < c[2] && c[2] < px.len())
    });
}

/// Pixels, depths (one of them faulty), intrinsics and a basis.
fn jacobian_inputs() -> impl Strategy<Value = (u64, bool, Fault, [usize; 3])> {
    (0u64..1000, any::<bool>(), fault(), basis())
}

pub fn prop_jacobians(cases: u32) {
    run(cases, jacobian_inputs(), |(seed, on_pixels, f, b)| {
        let sc = scene(seed);
        let (mut px, mut z) = (sc.pixels.clone(), sc.depths.clone());
        let fault = if on_pixels { nan_at("pixels", f.apply(&mut px)) } else { bad_depth_at(f.apply_flat(&mut z)) };
        let j = invariant_jacobian(&px, &z, &sc.k, b);
        check_located("invariant_jacobian", &j, fault.clone(), |j| finite(j.iter()) && j.ncols() == 5)?;
        let l = invariant_interaction(&px, &z, &sc.k, b);
        check_located("invariant_interaction", &l, fault.clone(), |l| {
            finite(l.iter()) && j.as_ref().is_ok_and(|j| l.columns(0, 5) == *j)
        })?;
        let factors = jacobian_factors(&px, &z, b);
        check_located("jacobian_factors", &factors, fault.clone(), |(phi, psi)| {
            // J = [Phi K, Psi F(K)] (sec. 4.1), against the direct form.
            let Ok(from) = vsinv::core::jacobian::jacobian_from_factors(phi, psi, &sc.k.matrix()) else {
                return false;
            };
            let scale = from.amax().max(1e-300);
            finite(phi.iter()) && finite(psi.iter()) && j.as_ref().is_ok_and(|j| (j - from).amax() <= 1e-6 * scale)
        })?;
        let rz = rz_coefficients(&px, &z, &sc.reference, &sc.k, b);
        check_located("rz_coefficients", &rz, fault.clone(), |(a, c)| a.is_finite() && finite(c.iter()))?;
        let ratio = structure_ratio(&px, &z, &sc.k, b);
        check_located("structure_ratio", &ratio, fault, |r| r.is_finite() && (0.0..=1.0 + 1e-12).contains(r))
    });
}
