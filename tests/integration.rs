//! The integration tests, built as one binary: each `tests/NAME.rs` is the module `NAME` of this
//! crate, so its tests are named `NAME::test`, and the release build links once (with thin LTO)
//! instead of once a file (issue 29, item 6: 33 links took most of a warm `make test-rust`).
//! Cargo.toml sets `autotests = false` so Cargo does not build each file as a binary of its own.
//!
//! One file's tests: `cargo test --release --test integration NAME::`, e.g. the check that every
//! built-in gives its recorded result, `cargo test --release --test integration builtin_results::`
//! (also `make test-builtins`). A new file is a new `mod` line below (the last test here fails
//! on a file of tests/ that has none).
#![allow(clippy::unwrap_used, clippy::expect_used)]

/// Scene helpers shared by the tests (tests/common/mod.rs).
mod common;
/// The harness of the robustness properties; each `robustness_*` module includes the properties
/// of its area from tests/common/robustness/ with `#[path]`.
#[path = "common/robustness/mod.rs"]
mod robustness;

mod api_contracts;
#[cfg(feature = "sim")]
mod arm_ik;
#[cfg(feature = "sim")]
mod arm_kinematics;
mod arm_servo;
#[cfg(feature = "sim")]
mod builtin_results;
mod closed_loop;
mod commands;
mod depth;
mod distortion_loop;
#[cfg(feature = "vision")]
mod fuzz_images;
mod invariance;
mod law_keys;
mod law_options;
mod planning;
#[cfg(feature = "sim")]
mod readme;
mod robustness_camera;
#[cfg(feature = "sim")]
mod robustness_census;
mod robustness_control;
#[cfg(feature = "sim")]
mod robustness_files;
mod robustness_invariants;
#[cfg(feature = "sim")]
mod robustness_limits;
#[cfg(feature = "sim")]
mod robustness_nesting;
mod robustness_planning;
#[cfg(all(feature = "vision", feature = "calibration"))]
mod robustness_regressions;
#[cfg(feature = "vision")]
mod robustness_vision;
mod roll_sweep;
#[cfg(feature = "servo")]
mod servo;
mod servo_partial;
mod servo_stall;
#[cfg(feature = "sim")]
mod simulator;
mod stability;
#[cfg(feature = "sim")]
mod targets;
#[cfg(feature = "sim")]
mod units;
#[cfg(feature = "sim")]
mod vision_loop;
#[cfg(feature = "vision")]
mod vision_tracking;

/// With `autotests = false` a file of tests/ that is not declared above would never be built:
/// every `tests/*.rs` but this one is a `mod` line of this file.
#[test]
fn every_test_file_is_a_module_of_this_binary() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    let this = std::fs::read_to_string(dir.join("integration.rs")).unwrap();
    let declared: std::collections::BTreeSet<&str> =
        this.lines().filter_map(|l| l.strip_prefix("mod ")?.strip_suffix(';')).collect();
    let mut files = std::collections::BTreeSet::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        if let Some(stem) = name.strip_suffix(".rs").filter(|s| *s != "integration") {
            files.insert(stem.to_string());
        }
    }
    let missing: Vec<&String> = files.iter().filter(|f| !declared.contains(f.as_str())).collect();
    assert!(missing.is_empty(), "tests/*.rs not declared as `mod NAME;` in tests/integration.rs: {missing:?}");
    assert!(declared.len() >= 33 && declared.contains("builtin_results"), "{declared:?}");
}
