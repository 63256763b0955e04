//! Robustness of the public Rust API: the census of the calls tried per API by the properties of
//! tests/robustness_*.rs.
//!
//! `cargo test --release --test integration robustness_census:: -- --ignored --nocapture` prints, per
//! API, the calls tried and how many returned `Ok` and `Err`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::robustness::CENSUS;
use crate::robustness::camera::{prop_distortion, prop_intrinsics, prop_project_points};
use crate::robustness::control::{
    prop_gains, prop_ibvs_controller, prop_invariant_controller, prop_invariant_controller_reference, prop_rz_task,
    prop_se3, prop_stability,
};
use crate::robustness::files::{prop_calibration, prop_scenario};
use crate::robustness::invariants::{prop_invariant, prop_jacobians};
use crate::robustness::planning::{prop_depths, prop_planning};
use crate::robustness::vision::{prop_detect_and_track, prop_render};

/// Every group with `CENSUS_CASES` cases (default 200), then the table of calls per API.
#[test]
#[ignore = "a report: cargo test --release --test integration robustness_census:: -- --ignored --nocapture"]
fn census() {
    let n = std::env::var("CENSUS_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(200);
    let groups: &[fn(u32)] = &[
        prop_intrinsics,
        prop_project_points,
        prop_invariant,
        prop_jacobians,
        prop_invariant_controller,
        prop_invariant_controller_reference,
        prop_ibvs_controller,
        prop_stability,
        prop_depths,
        prop_planning,
        prop_se3,
        prop_rz_task,
        prop_gains,
        prop_distortion,
        prop_calibration,
        prop_scenario,
        prop_detect_and_track,
        prop_render,
    ];
    for group in groups {
        group(n);
    }
    let census = CENSUS.lock().unwrap();
    println!("{:<40} {:>8} {:>8} {:>8}", "API", "calls", "Ok", "Err");
    for (api, [calls, ok, err]) in census.iter() {
        println!("{api:<40} {calls:>8} {ok:>8} {err:>8}");
    }
    let total: usize = census.values().map(|r| r[0]).sum();
    println!("{:<40} {total:>8}", "total");
    assert!(census.len() >= 40, "{} APIs", census.len());
}
