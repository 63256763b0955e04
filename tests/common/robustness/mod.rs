//! The harness of the robustness properties (tests/robustness_*.rs): the outcome census, the
//! checks, the runner, the input strategies (special values, faults injected in valid arrays) and
//! the valid scenes. The properties of each API area are in the submodules below, run by the
//! module of their area (tests/robustness_camera.rs runs `camera`'s) and all by the census.
#![allow(clippy::unwrap_used, clippy::expect_used)]
#![allow(dead_code)]

pub mod camera;
pub mod control;
pub mod files;
pub mod invariants;
pub mod planning;
pub mod vision;

use std::collections::BTreeMap;
use std::sync::Mutex;

use crate::common::{Lcg, lens, object_points, random_intrinsics, random_pose, view};
use nalgebra::{Isometry3, Translation3, Vector3};
use proptest::prelude::*;
use proptest::test_runner::{RngSeed, TestCaseError, TestRunner};
use std::result::Result;
use vsinv::{Intrinsics, invariant_points};

pub type Prop = std::result::Result<(), TestCaseError>;

// ---------------------------------------------------------------------------------------------
// Harness: outcome census, checks, runner.

/// Per API: calls, `Ok`, `Err`.
pub static CENSUS: Mutex<BTreeMap<&'static str, [usize; 3]>> = Mutex::new(BTreeMap::new());

pub fn record(api: &'static str, ok: bool) {
    let mut census = CENSUS.lock().unwrap_or_else(|e| e.into_inner());
    let row = census.entry(api).or_default();
    row[0] += 1;
    row[if ok { 1 } else { 2 }] += 1;
}

pub fn finite<'a>(values: impl IntoIterator<Item = &'a f64>) -> bool {
    values.into_iter().all(|v| v.is_finite())
}

/// Records the outcome; an `Ok` must pass `valid` (finite, and correct where cheap), an `Err`
/// must have a message.
pub fn check<T, E: std::fmt::Display + std::fmt::Debug>(
    api: &'static str,
    r: &Result<T, E>,
    valid: impl FnOnce(&T) -> bool,
) -> Prop {
    record(api, r.is_ok());
    match r {
        Ok(v) => prop_assert!(valid(v), "{api}: Ok with a non-finite or wrong output"),
        Err(e) => prop_assert!(!e.to_string().trim().is_empty(), "{api}: empty error message {e:?}"),
    }
    Ok(())
}

/// `check`, and when the input had a located fault, an `Err` whose message has every needle.
pub fn check_located<T: std::fmt::Debug, E: std::fmt::Display + std::fmt::Debug>(
    api: &'static str,
    r: &Result<T, E>,
    fault: Option<Vec<String>>,
    valid: impl FnOnce(&T) -> bool,
) -> Prop {
    check(api, r, valid)?;
    if let Some(needles) = fault {
        let message = match r {
            Ok(v) => return Err(TestCaseError::fail(format!("{api}: Ok({v:?}) despite a fault ({needles:?})"))),
            Err(e) => e.to_string(),
        };
        for n in &needles {
            prop_assert!(message.contains(n.as_str()), "{api}: {message:?} does not name {n:?}");
        }
    }
    Ok(())
}

pub fn run<S: Strategy>(cases: u32, strategy: S, test: impl Fn(S::Value) -> Prop) {
    // A fixed sequence of cases in CI (a red run must mean a bug); `make fuzz` sets
    // VSINV_PROPTEST_RANDOM=1 for new ones.
    let random = std::env::var_os("VSINV_PROPTEST_RANDOM").is_some();
    let rng_seed = if random { RngSeed::Random } else { RngSeed::Fixed(0x5eed) };
    let config = ProptestConfig { cases, failure_persistence: None, rng_seed, ..ProptestConfig::default() };
    if let Err(e) = TestRunner::new(config).run(&strategy, test) {
        panic!("{e}");
    }
}

// ---------------------------------------------------------------------------------------------
// Inputs: special values, faults injected in valid arrays, a valid scene.

/// Mostly ordinary values, often the special ones.
pub fn num() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -2e3..2e3f64,
        1 => prop::sample::select(vec![
            f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 0.0, -0.0, -1.0, 1.0, 1e300, -1e300, 1e-300, -1e-300,
            1e150, f64::MAX, f64::MIN_POSITIVE, 5e-324,
        ]),
    ]
}

/// One thing wrong with an array (or nothing): a value at a row and column, or a new length.
#[derive(Debug, Clone, Copy)]
pub enum Fault {
    None,
    Value { row: usize, col: usize, value: f64 },
    Resize(usize),
}

pub fn fault() -> impl Strategy<Value = Fault> {
    prop_oneof![
        2 => Just(Fault::None),
        3 => (0usize..64, 0usize..3, num()).prop_map(|(row, col, value)| Fault::Value { row, col, value }),
        1 => (0usize..16).prop_map(Fault::Resize),
    ]
}

impl Fault {
    /// Applies the fault to rows of N values; returns `(row, column, value)` of a changed value.
    pub fn apply<const N: usize>(&self, a: &mut Vec<[f64; N]>) -> Option<(usize, usize, f64)> {
        match *self {
            Fault::None => None,
            Fault::Resize(n) => {
                let fill = a.first().copied().unwrap_or([1.0; N]);
                a.resize(n, fill);
                None
            }
            Fault::Value { row, col, value } if !a.is_empty() => {
                let (row, col) = (row % a.len(), col % N);
                a[row][col] = value;
                Some((row, col, value))
            }
            Fault::Value { .. } => None,
        }
    }

    /// The same on a flat list; returns `(index, value)`.
    pub fn apply_flat(&self, a: &mut Vec<f64>) -> Option<(usize, f64)> {
        let mut rows: Vec<[f64; 1]> = a.iter().map(|&v| [v]).collect();
        let hit = self.apply(&mut rows);
        *a = rows.into_iter().map(|[v]| v).collect();
        hit.map(|(row, _, value)| (row, value))
    }
}

/// The needles of a non-finite value at `(row, column)` of the point array `what`.
pub fn nan_at(what: &str, hit: Option<(usize, usize, f64)>) -> Option<Vec<String>> {
    hit.filter(|h| !h.2.is_finite()).map(|(r, c, _)| vec![what.to_string(), format!("row {r}, column {c}")])
}

/// The needles of a bad depth at `index`: non-finite names the index, `<= 0` the point.
pub fn bad_depth_at(hit: Option<(usize, f64)>) -> Option<Vec<String>> {
    match hit {
        Some((i, z)) if !z.is_finite() => Some(vec!["depths".into(), format!("index {i}")]),
        Some((i, z)) if z <= 0.0 => Some(vec![format!("point {i} ")]),
        _ => None,
    }
}

/// A valid scene: the 12-point object seen at F* with a 12 mm lens (reference) and from a
/// random pose with random intrinsics (current).
pub struct Scene {
    pub k: Intrinsics,
    pub reference: Vec<[f64; 2]>,
    pub reference_depths: Vec<f64>,
    pub pixels: Vec<[f64; 2]>,
    pub depths: Vec<f64>,
}

pub fn scene(seed: u64) -> Scene {
    let mut rng = Lcg(seed);
    let pose = random_pose(&mut rng, 0.1, 0.3);
    let k = random_intrinsics(&mut rng);
    let (reference, reference_depths) = view(&object_points(), &Isometry3::identity(), &lens(1200.0));
    let (pixels, depths) = view(&object_points(), &pose, &k);
    Scene { k, reference, reference_depths, pixels, depths }
}

pub fn basis() -> impl Strategy<Value = [usize; 3]> {
    prop_oneof![3 => Just([0, 3, 8]), 1 => prop::array::uniform3(0usize..14)]
}

pub fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

pub fn point3() -> impl Strategy<Value = [f64; 3]> {
    prop_oneof![4 => (-1.0..1.0f64, -1.0..1.0f64, 0.05..5.0f64).prop_map(|(x, y, z)| [x, y, z]), 1 => prop::array::uniform3(num())]
}

// ---------------------------------------------------------------------------------------------
// Scenes shared by the depth and planning properties and the regressions.

/// Two views of the object related by a pure translation (eq. 26), with camera-frame depths
/// of the first.
pub fn translation_pair(seed: u64) -> (Vec<[f64; 2]>, Vec<[f64; 2]>, Vec<f64>) {
    let mut rng = Lcg(seed);
    let first = random_pose(&mut rng, 0.1, 0.3);
    let t = Vector3::new(rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1));
    let second = Translation3::from(first.rotation * t) * first;
    let k = random_intrinsics(&mut rng);
    let (a, z) = view(&object_points(), &first, &k);
    let (b, _) = view(&object_points(), &second, &k);
    (a, b, z)
}

/// Invariant points of the non-basis points at F* and at a random pose (basis 0, 3, 8).
pub fn invariants(seed: u64) -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>) {
    let sc = scene(seed);
    let rows = |px: &[[f64; 2]]| -> Vec<Vector3<f64>> {
        let q = invariant_points(px, [0, 3, 8]).unwrap();
        (0..12).filter(|i| ![0, 3, 8].contains(i)).map(|i| Vector3::from(q[i])).collect()
    };
    (rows(&sc.pixels), rows(&sc.reference))
}

pub const CALIBRATION_FILES: &[&str] = &[
    include_str!("../../fixtures/calibration/ros_plumb_bob.yaml"),
    include_str!("../../fixtures/calibration/ros_rational_polynomial.yaml"),
    include_str!("../../fixtures/calibration/opencv.yaml"),
    include_str!("../../fixtures/calibration/opencv.xml"),
];
