//! Robustness of the public Rust API: for arbitrary inputs (NaN, +-inf, zero, negative, 1e300,
//! 1e-300, wrong lengths, degenerate geometry) every fallible function returns a finite `Ok`
//! or an `Err` whose message names the argument and, for a fault in an array, its row (and
//! column). No panic: proptest reports one as a failure. Iterative methods are bounded by
//! their iteration caps, not by the clock.
//!
//! `cargo test --release --test robustness -- --ignored --nocapture census` prints, per API,
//! the calls tried and how many returned `Ok` and `Err`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::collections::BTreeMap;
use std::sync::Mutex;

use common::{Lcg, lens, object_points, random_intrinsics, random_pose, view};
use nalgebra::{Isometry3, Matrix3, Matrix4, Translation3, Vector3, Vector6};
use proptest::prelude::*;
use proptest::test_runner::{RngSeed, TestCaseError, TestRunner};
use vsinv::core::adaptive_gain::AdaptiveGain;
use vsinv::core::depth::{ResectionDepths, depths_from_translation, resect};
use vsinv::core::planning::{InvariantPath, estimate_plane_parallax};
use vsinv::core::rz_task::{RzTask, linearise};
use vsinv::core::saturation::TwistLimits;
use vsinv::core::se3;
use vsinv::{
    Distortion, DistortionModel, IbvsController, Interaction, Intrinsics, InvariantController,
    InvariantControllerConfig, Result, a_matrix, check_stability, choose_basis, distort_points, invariant_interaction,
    invariant_jacobian, invariant_points, jacobian_factors, project_points, rz_coefficients, structure_ratio,
    task_vector, tracking_bound, undistort_points,
};

type Prop = std::result::Result<(), TestCaseError>;

// ---------------------------------------------------------------------------------------------
// Harness: outcome census, checks, runner.

/// Per API: calls, `Ok`, `Err`.
static CENSUS: Mutex<BTreeMap<&'static str, [usize; 3]>> = Mutex::new(BTreeMap::new());

fn record(api: &'static str, ok: bool) {
    let mut census = CENSUS.lock().unwrap_or_else(|e| e.into_inner());
    let row = census.entry(api).or_default();
    row[0] += 1;
    row[if ok { 1 } else { 2 }] += 1;
}

fn finite<'a>(values: impl IntoIterator<Item = &'a f64>) -> bool {
    values.into_iter().all(|v| v.is_finite())
}

/// Records the outcome; an `Ok` must pass `valid` (finite, and correct where cheap), an `Err`
/// must have a message.
fn check<T>(api: &'static str, r: &Result<T>, valid: impl FnOnce(&T) -> bool) -> Prop {
    record(api, r.is_ok());
    match r {
        Ok(v) => prop_assert!(valid(v), "{api}: Ok with a non-finite or wrong output"),
        Err(e) => prop_assert!(!e.to_string().trim().is_empty(), "{api}: empty error message {e:?}"),
    }
    Ok(())
}

/// `check`, and when the input had a located fault, an `Err` whose message has every needle.
fn check_located<T: std::fmt::Debug>(
    api: &'static str,
    r: &Result<T>,
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

fn run<S: Strategy>(cases: u32, strategy: S, test: impl Fn(S::Value) -> Prop) {
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
fn num() -> impl Strategy<Value = f64> {
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
enum Fault {
    None,
    Value { row: usize, col: usize, value: f64 },
    Resize(usize),
}

fn fault() -> impl Strategy<Value = Fault> {
    prop_oneof![
        2 => Just(Fault::None),
        3 => (0usize..64, 0usize..3, num()).prop_map(|(row, col, value)| Fault::Value { row, col, value }),
        1 => (0usize..16).prop_map(Fault::Resize),
    ]
}

impl Fault {
    /// Applies the fault to rows of N values; returns `(row, column, value)` of a changed value.
    fn apply<const N: usize>(&self, a: &mut Vec<[f64; N]>) -> Option<(usize, usize, f64)> {
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
    fn apply_flat(&self, a: &mut Vec<f64>) -> Option<(usize, f64)> {
        let mut rows: Vec<[f64; 1]> = a.iter().map(|&v| [v]).collect();
        let hit = self.apply(&mut rows);
        *a = rows.into_iter().map(|[v]| v).collect();
        hit.map(|(row, _, value)| (row, value))
    }
}

/// The needles of a non-finite value at `(row, column)` of the point array `what`.
fn nan_at(what: &str, hit: Option<(usize, usize, f64)>) -> Option<Vec<String>> {
    hit.filter(|h| !h.2.is_finite()).map(|(r, c, _)| vec![what.to_string(), format!("row {r}, column {c}")])
}

/// The needles of a bad depth at `index`: non-finite names the index, `<= 0` the point.
fn bad_depth_at(hit: Option<(usize, f64)>) -> Option<Vec<String>> {
    match hit {
        Some((i, z)) if !z.is_finite() => Some(vec!["depths".into(), format!("index {i}")]),
        Some((i, z)) if z <= 0.0 => Some(vec![format!("point {i} ")]),
        _ => None,
    }
}

/// A valid scene: the 12-point object seen at F* with a 12 mm lens (reference) and from a
/// random pose with random intrinsics (current).
struct Scene {
    k: Intrinsics,
    reference: Vec<[f64; 2]>,
    reference_depths: Vec<f64>,
    pixels: Vec<[f64; 2]>,
    depths: Vec<f64>,
}

fn scene(seed: u64) -> Scene {
    let mut rng = Lcg(seed);
    let pose = random_pose(&mut rng, 0.1, 0.3);
    let k = random_intrinsics(&mut rng);
    let (reference, reference_depths) = view(&object_points(), &Isometry3::identity(), &lens(1200.0));
    let (pixels, depths) = view(&object_points(), &pose, &k);
    Scene { k, reference, reference_depths, pixels, depths }
}

fn basis() -> impl Strategy<Value = [usize; 3]> {
    prop_oneof![3 => Just([0, 3, 8]), 1 => prop::array::uniform3(0usize..14)]
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

// ---------------------------------------------------------------------------------------------
// Camera.

/// `(fku, fkv, u0, v0, theta)`: a plausible camera with at most one entry replaced by a
/// special value (often), or five arbitrary values (sometimes).
fn intrinsic_parameters() -> impl Strategy<Value = [f64; 5]> {
    let plausible = (10.0..5000.0f64, 10.0..5000.0f64, -1e3..1e3f64, -1e3..1e3f64, 0.2..2.9f64)
        .prop_map(|(fku, fkv, u0, v0, theta)| [fku, fkv, u0, v0, theta]);
    let one_off = (plausible, 0usize..10, num()).prop_map(|(mut p, i, v)| {
        if i < 5 {
            p[i] = v;
        }
        p
    });
    prop_oneof![3 => one_off, 1 => prop::array::uniform5(num())]
}

fn prop_intrinsics(cases: u32) {
    run(cases, (intrinsic_parameters(), prop::array::uniform2(num()), prop::array::uniform9(num())), |(p, px, m)| {
        let [fku, fkv, u0, v0, theta] = p;
        let r = Intrinsics::new(fku, fkv, u0, v0, theta);
        check("Intrinsics::new", &r, |k| {
            let km = k.matrix();
            let (s, c) = theta.sin_cos();
            finite(km.iter())
                && km[(0, 0)] == fku
                && km[(0, 2)] == u0
                && km[(1, 2)] == v0
                && (km[(1, 1)] - fkv / s).abs() <= 1e-12 * km[(1, 1)].abs()
                && (km[(0, 1)] + fku * c / s).abs() <= 1e-12 * (fku * c / s).abs().max(fku * 1e-15)
        })?;
        if let Ok(k) = r {
            let n = k.normalise(px);
            check("Intrinsics::normalise", &n, |n| finite(n))?;
            let moderate = [fku, fkv].iter().all(|f| (1e-3..1e9).contains(f)) && (0.01..3.13).contains(&theta);
            if moderate && finite(&px) && px.iter().all(|v| v.abs() < 1e6) {
                prop_assert!(n.is_ok(), "normalise({px:?}) = {n:?} for {k:?}");
                let n = n.unwrap();
                let back = k.matrix() * Vector3::new(n[0], n[1], 1.0);
                let scale = 1.0 + px[0].abs().max(px[1].abs()) + u0.abs().max(v0.abs());
                prop_assert!(max_abs_diff(&[back.x, back.y], &px) <= 1e-9 * scale, "K K^-1 p = {back:?} vs {px:?}");
            }
            let back = Intrinsics::from_matrix(&k.matrix());
            check("Intrinsics::from_matrix", &back, |b| {
                let rel = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1e-300);
                rel(b.fku(), fku) && rel(b.fkv(), fkv) && rel(b.theta(), theta) && b.u0() == u0 && b.v0() == v0
            })?;
        }
        let any = Matrix3::from_row_slice(&m);
        check("Intrinsics::from_matrix", &Intrinsics::from_matrix(&any), |k| finite(k.matrix().iter()))?;
        let r = Intrinsics::pinhole(fku, fkv, u0, v0);
        check("Intrinsics::pinhole", &r, |k| finite(k.matrix().iter()) && finite(k.f_matrix().iter()))
    });
}

fn point3() -> impl Strategy<Value = [f64; 3]> {
    prop_oneof![4 => (-1.0..1.0f64, -1.0..1.0f64, 0.05..5.0f64).prop_map(|(x, y, z)| [x, y, z]), 1 => prop::array::uniform3(num())]
}

fn prop_project_points(cases: u32) {
    run(cases, (prop::collection::vec(point3(), 0..8), fault(), 0u64..1000), |(mut points, f, seed)| {
        f.apply(&mut points);
        // The first non-finite coordinate (generated or injected) is the one named.
        let first = points.as_flattened().iter().position(|v| !v.is_finite());
        let hit = first.map(|i| (i / 3, i % 3, f64::NAN));
        let k = random_intrinsics(&mut Lcg(seed));
        let r = project_points(&points, &k);
        let km = k.matrix();
        check_located("project_points", &r, nan_at("points", hit), |(px, z)| {
            finite(px.as_flattened())
                && finite(z)
                && points.iter().zip(px).all(|(p, q)| {
                    let m = km * Vector3::new(p[0] / p[2], p[1] / p[2], 1.0);
                    max_abs_diff(&[m.x, m.y], q) <= 1e-9 * (1.0 + m.x.abs().max(m.y.abs()))
                })
        })
    });
}

// ---------------------------------------------------------------------------------------------
// The invariant transform and the Jacobians.

fn prop_invariant(cases: u32) {
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

fn prop_jacobians(cases: u32) {
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

// ---------------------------------------------------------------------------------------------
// Controllers.

fn config() -> impl Strategy<Value = InvariantControllerConfig> {
    let gain = prop_oneof![3 => 0.1..5.0f64, 1 => num()];
    let adaptive = prop::option::weighted(0.3, prop::array::uniform3(prop_oneof![2 => 0.1..10.0f64, 1 => num()]));
    let limits = prop::option::weighted(0.3, prop::array::uniform2(prop_oneof![2 => 0.01..1.0f64, 1 => num()]));
    let ratio = prop_oneof![3 => Just(1e-3), 1 => num()];
    (gain.clone(), gain, ratio, any::<bool>(), any::<bool>(), adaptive, limits).prop_map(
        |(gain, gain_rz, min_structure_ratio, feedforward, tau21, adaptive, limits)| InvariantControllerConfig {
            gain,
            gain_rz,
            feedforward,
            min_structure_ratio,
            rz_task: if tau21 { RzTask::Tau21 } else { RzTask::Angle },
            adaptive_gain: adaptive.map(|[at_zero, at_infinity, slope_at_zero]| AdaptiveGain {
                at_zero,
                at_infinity,
                slope_at_zero,
            }),
            twist_limits: limits.map(|[linear, angular]| TwistLimits { linear, angular }),
        },
    )
}

/// Which argument of a step gets the fault: pixels, depths or the visibility flags.
#[derive(Debug, Clone)]
struct StepInput {
    seed: u64,
    target: u8,
    fault: Fault,
    visible: Option<Vec<bool>>,
}

fn step_input() -> impl Strategy<Value = StepInput> {
    let visible = prop::option::weighted(0.4, prop::collection::vec(prop::bool::weighted(0.85), 10..14));
    (0u64..1000, 0u8..2, fault(), visible).prop_map(|(seed, target, fault, visible)| StepInput {
        seed,
        target,
        fault,
        visible,
    })
}

/// Pixels, depths, flags of a step and the needles of its located fault (if the point is used).
/// Pixels, depths, flags, and the needles of the located fault.
type StepArgs = (Vec<[f64; 2]>, Vec<f64>, Option<Vec<bool>>, Option<Vec<String>>);

fn step_args(inp: &StepInput) -> StepArgs {
    let sc = scene(inp.seed);
    let (mut px, mut z) = (sc.pixels, sc.depths);
    let (row, needles) = if inp.target == 0 {
        let hit = inp.fault.apply(&mut px);
        (hit.map(|h| h.0), nan_at("pixels", hit))
    } else {
        let hit = inp.fault.apply_flat(&mut z);
        (hit.map(|h| h.0), bad_depth_at(hit))
    };
    let visible = inp.visible.clone();
    let used = match (&visible, row) {
        (Some(v), Some(r)) => v.len() == px.len() && z.len() == px.len() && v[r],
        _ => true,
    };
    (px, z, visible, needles.filter(|_| used))
}

fn twist_ok(t: &Vector6<f64>) -> bool {
    finite(t.iter())
}

fn prop_invariant_controller(cases: u32) {
    let inputs = (0u64..1000, fault(), basis(), config(), prop::collection::vec(step_input(), 1..4));
    run(cases, inputs, |(seed, f, b, cfg, steps)| {
        let sc = scene(seed);
        let mut reference = sc.reference.clone();
        let fault = nan_at("reference_pixels", f.apply(&mut reference));
        let r = InvariantController::new(&reference, sc.k, b, cfg);
        check_located("InvariantController::new", &r, fault, |_| true)?;
        let Ok(mut ctl) = r else { return Ok(()) };
        let n = reference.len();
        for inp in &steps {
            let (px, z, visible, needles) = step_args(inp);
            let needles = needles.filter(|_| px.len() == n);
            let (api, r) = match &visible {
                Some(v) => ("InvariantController::step_visible", ctl.step_visible(&px, &z, v)),
                None => ("InvariantController::step", ctl.step(&px, &z)),
            };
            check_located(api, &r, needles, twist_ok)?;
            if let Ok(t) = &r {
                let s = ctl.state().expect("a state after a successful step");
                prop_assert!(finite(s.eps.iter()) && s.eps_z.is_finite() && s.invariant_error.is_finite());
                prop_assert!(finite(s.t.iter()) && s.a_hat.is_finite() && s.gain.is_finite() && s.saturation >= 0.0);
                if let Some(l) = cfg.twist_limits {
                    let (v, w) = (t.fixed_rows::<3>(0).norm(), t.fixed_rows::<3>(3).norm());
                    prop_assert!(v <= l.linear * (1.0 + 1e-12) && w <= l.angular * (1.0 + 1e-12));
                }
            }
        }
        Ok(())
    });
}

fn prop_invariant_controller_reference(cases: u32) {
    let rows = || prop::collection::vec(prop::array::uniform3(num()), 7..11);
    let inputs = (0u64..1000, rows(), prop::option::of(rows()), prop::array::uniform5(num()));
    run(cases, inputs, |(seed, s_star, rate, kp)| {
        let sc = scene(seed);
        let mut ctl = InvariantController::new(&sc.reference, sc.k, [0, 3, 8], Default::default()).unwrap();
        // Half of the time, valid invariant points (summing to 1) with one faulty coordinate.
        let r = ctl.set_reference(&s_star, rate.as_deref());
        check("InvariantController::set_reference", &r, |_| true)?;
        let mut valid: Vec<[f64; 3]> = s_star.iter().map(|q| [q[0], q[1], 1.0 - q[0] - q[1]]).collect();
        valid.truncate(9);
        let hit = (valid.len() == 9 && !finite(valid.as_flattened())).then(|| {
            let i = valid.as_flattened().iter().position(|v| !v.is_finite()).unwrap();
            (i / 3, i % 3, f64::NAN)
        });
        let r = ctl.set_reference(&valid, None);
        check_located("InvariantController::set_reference", &r, nan_at("s_star", hit), |_| true)?;
        if let Ok(k) = Intrinsics::new(kp[0], kp[1], kp[2], kp[3], kp[4]) {
            check("InvariantController::set_k_hat", &ctl.set_k_hat(k), |_| true)?;
        }
        let r = ctl.step(&sc.pixels, &sc.depths);
        check("InvariantController::step", &r, twist_ok)
    });
}

fn prop_ibvs_controller(cases: u32) {
    let interaction = prop::sample::select(vec![Interaction::Current, Interaction::Desired, Interaction::Mean]);
    let limits = prop::option::weighted(0.3, prop::array::uniform2(prop_oneof![2 => 0.01..1.0f64, 1 => num()]));
    let adaptive = prop::option::weighted(0.3, prop::array::uniform3(prop_oneof![2 => 0.1..10.0f64, 1 => num()]));
    let gain = prop_oneof![3 => 0.1..5.0f64, 1 => num()];
    let common = (0u64..1000, fault(), any::<bool>(), gain, interaction, any::<bool>());
    let inputs = (common, limits, adaptive, prop::collection::vec(step_input(), 1..4));
    run(cases, inputs, |((seed, f, on_pixels, gain, interaction, with_depths), limits, adaptive, steps)| {
        let sc = scene(seed);
        let (mut reference, mut z_star) = (sc.reference.clone(), sc.reference_depths.clone());
        let fault = if on_pixels {
            nan_at("reference_pixels", f.apply(&mut reference))
        } else if with_depths {
            // The gain is checked before the depths.
            bad_depth_at(f.apply_flat(&mut z_star)).filter(|_| gain.is_finite() && gain > 0.0)
        } else {
            None
        };
        let r = IbvsController::new(&reference, sc.k, gain, interaction, with_depths.then_some(z_star.as_slice()));
        check_located("IbvsController::new", &r, fault, |_| true)?;
        let Ok(mut ctl) = r else { return Ok(()) };
        let limits = limits.map(|[linear, angular]| TwistLimits { linear, angular });
        check("IbvsController::set_twist_limits", &ctl.set_twist_limits(limits), |_| true)?;
        let adaptive = adaptive.map(|[a, b, c]| AdaptiveGain { at_zero: a, at_infinity: b, slope_at_zero: c });
        check("IbvsController::set_adaptive_gain", &ctl.set_adaptive_gain(adaptive), |_| true)?;
        let n = reference.len();
        for inp in &steps {
            let (px, z, visible, needles) = step_args(inp);
            let needles = needles.filter(|_| px.len() == n);
            let (api, r) = match &visible {
                Some(v) => ("IbvsController::step_visible", ctl.step_visible(&px, &z, v)),
                None => ("IbvsController::step", ctl.step(&px, &z)),
            };
            check_located(api, &r, needles, twist_ok)?;
            if r.is_ok() {
                prop_assert!(ctl.last_pixel_error().is_some_and(f64::is_finite));
            }
        }
        Ok(())
    });
}

// ---------------------------------------------------------------------------------------------
// Stability.

/// A 3x3 matrix: intrinsics (sometimes with negative focal terms), or anything.
fn k_matrix() -> impl Strategy<Value = Matrix3<f64>> {
    let physical = (0u64..1000, prop::array::uniform2(prop::sample::select(vec![1.0, -1.0, 1e-300, 1e300]))).prop_map(
        |(seed, [a, b])| {
            let mut k = random_intrinsics(&mut Lcg(seed)).matrix();
            k[(0, 0)] *= a;
            k[(1, 1)] *= b;
            k
        },
    );
    prop_oneof![3 => physical, 1 => prop::array::uniform9(num()).prop_map(|m| Matrix3::from_row_slice(&m))]
}

fn prop_stability(cases: u32) {
    let positive = || prop_oneof![3 => 0.2..5.0f64, 1 => num()];
    let inputs =
        (prop::collection::vec(k_matrix(), 0..4), k_matrix(), positive(), positive(), prop::array::uniform3(num()));
    run(cases, inputs, |(schedule, k_hat, kappa, gain, bound)| {
        let r = check_stability(&schedule, &k_hat, kappa, gain);
        prop_assert!(kappa > 0.0 || r.is_err(), "check_stability with kappa {}", kappa);
        check("check_stability", &r, |s| {
            let ev = s.eigenvalues.iter().flatten().all(|z| z.re.is_finite() && z.im.is_finite());
            ev && s.sigma.is_finite() && s.eigenvalues.len() == schedule.len()
        })?;
        if let Ok(s) = &r {
            let b = s.tracking_bound(bound[0].abs());
            check("StabilityReport::tracking_bound", &b, |b| b.is_finite())?;
            prop_assert!(s.sigma > 0.0 || b.is_err(), "tracking_bound with sigma {} gave {:?}", s.sigma, b);
        }
        if let Some(k) = schedule.first() {
            check("a_matrix", &a_matrix(k, &k_hat, kappa), |a| finite(a.iter()))?;
            // A = I for K_hat = K and kappa = 1 (eq. 19).
            check("a_matrix", &a_matrix(k, k, 1.0), |a| (a - nalgebra::Matrix5::identity()).amax() < 1e-9)?;
        }
        let t = tracking_bound(bound[0], bound[1], bound[2]);
        check("tracking_bound", &t, |t| t.is_finite() && *t >= 0.0)
    });
}

// ---------------------------------------------------------------------------------------------
// Depths, planning.

/// Two views of the object related by a pure translation (eq. 26), with camera-frame depths
/// of the first.
fn translation_pair(seed: u64) -> (Vec<[f64; 2]>, Vec<[f64; 2]>, Vec<f64>) {
    let mut rng = Lcg(seed);
    let first = random_pose(&mut rng, 0.1, 0.3);
    let t = Vector3::new(rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1));
    let second = Translation3::from(first.rotation * t) * first;
    let k = random_intrinsics(&mut rng);
    let (a, z) = view(&object_points(), &first, &k);
    let (b, _) = view(&object_points(), &second, &k);
    (a, b, z)
}

fn prop_depths(cases: u32) {
    let inputs = (0u64..1000, any::<bool>(), fault(), prop::collection::vec(any::<bool>(), 10..14), num());
    run(cases, inputs, |(seed, on_first, f, visible, mean_depth)| {
        let (mut a, mut b, z) = translation_pair(seed);
        let clean = matches!(f, Fault::None);
        let hit = f.apply(if on_first { &mut a } else { &mut b });
        let what = if on_first { "first image" } else { "second image" };
        let r = depths_from_translation(&a, &b);
        check_located("depths_from_translation", &r, nan_at(what, hit), |d| {
            let mean = z.iter().sum::<f64>() / z.len() as f64;
            let exact = !clean || d.depths.iter().zip(&z).all(|(e, t)| (e - t / mean).abs() < 1e-6);
            finite(&d.depths) && d.depths.iter().all(|&v| v > 0.0) && finite(d.epipole.iter()) && exact
        })?;
        let cloud: Vec<Vector3<f64>> = object_points().iter().map(|p| Vector3::from(*p)).collect();
        check("resect", &resect(&cloud, &b), |p| finite(p.iter()))?;
        let first_depths = r.map(|d| d.depths).unwrap_or(z);
        let est = ResectionDepths::new(&a, &first_depths, &b, mean_depth);
        check("ResectionDepths::new", &est, |_| true)?;
        let Ok(mut est) = est else { return Ok(()) };
        let sc = scene(seed);
        let (mut px, mut out) = (sc.pixels.clone(), vec![0.0; visible.len()]);
        let hit = f.apply(&mut px);
        let used = hit.filter(|h| visible.len() == 12 && px.len() == 12 && visible[h.0]);
        let r = est.estimate(&px, &visible, &mut out);
        check_located("ResectionDepths::estimate", &r, nan_at("pixels", used), |_| finite(&out))
    });
}

/// Invariant points of the non-basis points at F* and at a random pose (basis 0, 3, 8).
fn invariants(seed: u64) -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>) {
    let sc = scene(seed);
    let rows = |px: &[[f64; 2]]| -> Vec<Vector3<f64>> {
        let q = invariant_points(px, [0, 3, 8]).unwrap();
        (0..12).filter(|i| ![0, 3, 8].contains(i)).map(|i| Vector3::from(q[i])).collect()
    };
    (rows(&sc.pixels), rows(&sc.reference))
}

fn prop_planning(cases: u32) {
    let inputs = (0u64..1000, any::<bool>(), fault(), 4usize..10, num(), prop::collection::vec(num(), 1..4));
    run(cases, inputs, |(seed, on_q, f, m, duration, times)| {
        let (q, q_star) = invariants(seed);
        let (mut q, mut q_star): (Vec<[f64; 3]>, Vec<[f64; 3]>) =
            (q.iter().take(m).map(|v| (*v).into()).collect(), q_star.iter().take(m).map(|v| (*v).into()).collect());
        let hit = f.apply(if on_q { &mut q } else { &mut q_star });
        let what = if on_q { "q" } else { "q_star" };
        let (q, q_star): (Vec<Vector3<f64>>, Vec<Vector3<f64>>) =
            (q.into_iter().map(Vector3::from).collect(), q_star.into_iter().map(Vector3::from).collect());
        let r = estimate_plane_parallax(&q, &q_star);
        check_located("estimate_plane_parallax", &r, nan_at(what, hit), |p| {
            let mu = p.mu_e.iter().all(|v| finite(v.iter()));
            finite(p.gamma.iter()) && finite(p.epipole.iter()) && finite(&p.gamma_k) && p.residual.is_finite() && mu
        })?;
        let Ok(est) = r else { return Ok(()) };
        let path = InvariantPath::new(&q_star, &est, duration);
        check("InvariantPath::new", &path, |p| p.duration() == duration)?;
        let Ok(path) = path else { return Ok(()) };
        let (mut points, mut rates) = (vec![[0.0; 3]; q_star.len()], vec![[0.0; 3]; q_star.len()]);
        for t in times {
            let r = path.sample(t, &mut points, &mut rates);
            check("InvariantPath::sample", &r, |_| true)?;
            prop_assert_eq!(r.is_err(), t.is_nan(), "sample({}) = {:?}", t, r);
            if !t.is_nan() {
                prop_assert!(finite(points.as_flattened()) && finite(rates.as_flattened()), "sample({t})");
                let sums = points.iter().all(|p| (p.iter().sum::<f64>() - 1.0).abs() < 1e-6);
                prop_assert!(sums, "path points off the invariant plane at t = {t}: {points:?}");
            }
        }
        Ok(())
    });
}

// ---------------------------------------------------------------------------------------------
// Rigid motions, rz task, gains, saturation.

fn prop_se3(cases: u32) {
    let small = prop::array::uniform3(-3.0..3.0f64);
    run(
        cases,
        (prop::array::uniform6(num()), small.clone(), small, prop::array::uniform16(num())),
        |(tw, p, tu, m)| {
            // exp of a rotation-only twist is the rotation of its theta-u vector (the log).
            let rot = se3::exp_twist(&[0.0, 0.0, 0.0, tu[0], tu[1], tu[2]]).unwrap();
            let back = se3::thetau_from_pose(&rot);
            let angle = Vector3::from(tu).norm();
            if angle < std::f64::consts::PI - 1e-6 {
                prop_assert!(max_abs_diff(&back, &tu) < 1e-9, "log(exp({tu:?})) = {back:?}");
            }
            let pose = se3::pose_from_position_thetau(p, tu).unwrap();
            let r = se3::pose_from_matrix(&se3::pose_to_matrix(&pose));
            check("se3::pose_from_matrix", &r, |b| {
                let (dt, dr) = se3::pose_error(&pose, b);
                dt < 1e-12 && dr < 1e-7
            })?;
            let r = se3::pose_from_matrix(&Matrix4::from_row_slice(&m));
            check("se3::pose_from_matrix", &r, |b| finite(b.to_homogeneous().iter()))?;
            let e = se3::exp_twist(&tw);
            check("se3::exp_twist", &e, |e| finite(e.to_homogeneous().iter()))?;
            if finite(&tw) && tw.iter().all(|v| v.abs() < 1e6) {
                prop_assert!(e.is_ok(), "exp_twist({tw:?}) = {e:?}");
                let e = e.unwrap();
                // exp(t) exp(-t) = identity.
                let back = se3::exp_twist(&tw.map(|v| -v)).unwrap();
                let (dt, dr) = se3::pose_error(&(e * back), &Isometry3::identity());
                prop_assert!(dt < 1e-6 * (1.0 + tw.iter().map(|v| v.abs()).sum::<f64>()) && dr < 1e-6);
            }
            Ok(())
        },
    );
}

fn prop_rz_task(cases: u32) {
    let words = prop::sample::select(vec!["angle", "tau21", "", "Angle", "tau", "nan", "angle "]);
    let m3 = || prop::array::uniform9(num()).prop_map(|m| Matrix3::from_row_slice(&m));
    let lx = prop::array::uniform3(prop::array::uniform12(num()));
    run(
        cases,
        (words, m3(), m3(), num(), m3(), lx, 0u64..1000, any::<bool>()),
        |(w, t, qs, det, k, lx, seed, sane)| {
            check("RzTask::from_str", &w.parse::<RzTask>(), |t| {
                matches!((w, t), ("angle", RzTask::Angle) | ("tau21", RzTask::Tau21))
            })?;
            let lx = lx.map(|l| nalgebra::Matrix2x6::from_row_slice(&l));
            for task in [RzTask::Angle, RzTask::Tau21] {
                let r = if sane {
                    // A real image: T, Q*^-1 and the interaction matrices of a scene.
                    let sc = scene(seed);
                    let frame =
                        |px: &[[f64; 2]]| vsinv::core::invariant::BasisFrame::new(px, [0, 3, 8], "image").unwrap();
                    let (cur, refr) = (frame(&sc.pixels), frame(&sc.reference));
                    let kinv = sc.k.matrix().try_inverse().unwrap();
                    let l = [0, 3, 8].map(|i| {
                        let m = kinv * Vector3::new(sc.pixels[i][0], sc.pixels[i][1], 1.0);
                        vsinv::core::camera::normalised_interaction(m.x, m.y, sc.depths[i]).unwrap()
                    });
                    let t = cur.q * refr.q_inv;
                    linearise(task, &t, &refr.q_inv, refr.q.determinant(), &sc.k.matrix(), &l)
                } else {
                    linearise(task, &t, &qs, det, &k, &lx)
                };
                check("rz_task::linearise", &r, |l| l.value.is_finite() && l.a.is_finite() && finite(l.c.iter()))?;
            }
            Ok(())
        },
    );
}

fn prop_gains(cases: u32) {
    run(
        cases,
        (prop::array::uniform3(num()), prop::array::uniform2(num()), prop::array::uniform6(num()), num()),
        |(g, l, tw, x)| {
            let r = AdaptiveGain::new(g[0], g[1], g[2]);
            check("AdaptiveGain::new", &r, |g| {
                [0.0, if x.is_nan() { 1.0 } else { x.abs() }, 1e-300, 1e300, f64::INFINITY].iter().all(|&x| {
                    let v = g.value(x);
                    v.is_finite() && v >= g.at_infinity * (1.0 - 1e-12) && v <= g.at_zero * (1.0 + 1e-12)
                })
            })?;
            let r = TwistLimits::new(l[0], l[1]);
            check("TwistLimits::new", &r, |lim| {
                let mut t = Vector6::from(tw);
                let s = lim.apply(&mut t);
                let (v, w) = (t.fixed_rows::<3>(0).norm(), t.fixed_rows::<3>(3).norm());
                let within = v <= lim.linear * (1.0 + 1e-12) && w <= lim.angular * (1.0 + 1e-12);
                // Only a finite twist can be brought within the limits.
                !finite(&tw) || ((0.0..=1.0).contains(&s) && within)
            })?;
            Ok(())
        },
    );
}

// ---------------------------------------------------------------------------------------------
// Lens distortion.

/// Coefficients: small realistic ones, or anything, of any length.
fn coefficients() -> impl Strategy<Value = Vec<f64>> {
    let small = prop::sample::select(vec![4usize, 5, 8]).prop_flat_map(|n| prop::collection::vec(-0.05..0.05f64, n));
    prop_oneof![3 => small, 1 => prop::collection::vec(num(), 0..10)]
}

fn pixels_in_image() -> impl Strategy<Value = Vec<[f64; 2]>> {
    prop::collection::vec((0.0..832.0f64, 0.0..624.0f64).prop_map(|(u, v)| [u, v]), 0..8)
}

fn prop_distortion(cases: u32) {
    let tol = prop_oneof![3 => Just(1e-10), 1 => num()];
    let inputs = (coefficients(), any::<bool>(), pixels_in_image(), fault(), tol, 0usize..60, 0u64..1000);
    run(cases, inputs, |(c, rational, mut px, f, tol, max_iter, seed)| {
        let model = if rational { DistortionModel::RationalPolynomial } else { DistortionModel::PlumbBob };
        check("Distortion::with_model", &Distortion::with_model(model, &c), |d| d.coefficients().len() == model.len())?;
        let d = Distortion::from_coefficients(&c);
        check("Distortion::from_coefficients", &d, |d| d.coefficients()[..c.len().min(5)] == c[..c.len().min(5)])?;
        let Ok(d) = d else { return Ok(()) };
        let hit = f.apply(&mut px);
        let k = random_intrinsics(&mut Lcg(seed));
        let dist = distort_points(&px, &k, &d);
        check_located("distort_points", &dist, nan_at("pixels", hit), |p| finite(p.as_flattened()))?;
        let und = undistort_points(&px, &k, &d, tol, max_iter);
        let needles = nan_at("pixels", hit).or_else(|| match () {
            _ if !(tol.is_finite() && tol >= 0.0) => Some(vec!["tol".to_string()]),
            _ if max_iter == 0 => Some(vec!["max_iter".to_string()]),
            _ => None,
        });
        check_located("undistort_points", &und, needles, |p| finite(p.as_flattened()))?;
        // Round trip where the lens cannot fold (small coefficients, |m| <= 1): back to the
        // ideal pixels within 1e-6 px.
        let no_fold = c.iter().all(|v| v.abs() <= 0.05)
            && px.iter().all(|&p| k.normalise(p).is_ok_and(|m| m[0].hypot(m[1]) <= 1.0));
        if let (true, Ok(dist)) = (no_fold, &dist) {
            let back = undistort_points(dist, &k, &d, 1e-10, 50);
            check("undistort_points", &back, |b| max_abs_diff(b.as_flattened(), px.as_flattened()) < 1e-6)?;
        }
        Ok(())
    });
}

// ---------------------------------------------------------------------------------------------
// Text inputs: calibration files and scenarios, mutated.

/// One edit of a text: delete a line, replace a number on it, duplicate it, or truncate.
#[derive(Debug, Clone, Copy)]
enum Edit {
    Delete(usize),
    Replace(usize, usize, usize),
    Duplicate(usize),
    Truncate(usize),
}

fn edits() -> impl Strategy<Value = Vec<Edit>> {
    let edit = prop_oneof![
        1 => any::<usize>().prop_map(Edit::Delete),
        4 => (any::<usize>(), 0usize..8, any::<usize>()).prop_map(|(l, n, r)| Edit::Replace(l, n, r)),
        1 => any::<usize>().prop_map(Edit::Duplicate),
        1 => any::<usize>().prop_map(Edit::Truncate),
    ];
    prop::collection::vec(edit, 0..4)
}

const REPLACEMENTS: &[&str] = &[
    "nan",
    "-nan",
    ".nan",
    "inf",
    "-inf",
    "-.inf",
    "-1",
    "0",
    "-0.0",
    "1e400",
    "1e300",
    "1e-300",
    "text",
    "\"text\"",
    "[]",
    "true",
    "9223372036854775807",
    "-9223372036854775808",
    "99999999999999999999",
    "",
];

/// The byte ranges of the numbers of a line.
fn numbers(line: &str) -> Vec<(usize, usize)> {
    let b = line.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts = b[i].is_ascii_digit() && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_'));
        if !starts {
            i += 1;
            continue;
        }
        let start = if i > 0 && b[i - 1] == b'-' { i - 1 } else { i };
        while i < b.len() && (b[i].is_ascii_digit() || b".eE+-".contains(&b[i])) {
            i += 1;
        }
        out.push((start, i));
    }
    out
}

fn mutate(text: &str, edits: &[Edit]) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    for &e in edits {
        if lines.is_empty() {
            break;
        }
        let n = lines.len();
        match e {
            Edit::Delete(l) => {
                lines.remove(l % n);
            }
            Edit::Duplicate(l) => lines.insert(l % n, lines[l % n].clone()),
            Edit::Replace(l, k, r) => {
                let line = &mut lines[l % n];
                if let Some(&(a, b)) = numbers(line).get(k) {
                    line.replace_range(a..b, REPLACEMENTS[r % REPLACEMENTS.len()]);
                }
            }
            Edit::Truncate(at) => {
                let mut text = lines.join("\n");
                let mut cut = at % (text.len() + 1);
                while !text.is_char_boundary(cut) {
                    cut -= 1;
                }
                text.truncate(cut);
                lines = text.lines().map(str::to_string).collect();
            }
        }
    }
    lines.join("\n")
}

const CALIBRATION_FILES: &[&str] = &[
    include_str!("fixtures/calibration/ros_plumb_bob.yaml"),
    include_str!("fixtures/calibration/ros_rational_polynomial.yaml"),
    include_str!("fixtures/calibration/opencv.yaml"),
    include_str!("fixtures/calibration/opencv.xml"),
];

fn prop_calibration(cases: u32) {
    run(cases, (0..CALIBRATION_FILES.len(), edits()), |(i, e)| {
        let text = mutate(CALIBRATION_FILES[i], &e);
        let r = vsinv::calibration::parse_calibration(&text, "fuzz.yaml");
        check("calibration::parse_calibration", &r, |c| {
            finite(c.intrinsics.matrix().iter())
                && finite(c.distortion.coefficients())
                && c.image_size.is_none_or(|(w, h)| w > 0 && h > 0)
        })?;
        if let Err(e) = &r {
            prop_assert!(e.to_string().contains("fuzz.yaml"), "{e} does not name the file");
        }
        Ok(())
    });
}

fn prop_scenario(cases: u32) {
    let names = vsinv::sim::scenario::BUILTIN;
    run(cases, (0..names.len(), edits(), prop::bool::weighted(0.25)), |(i, e, simulate)| {
        let text = mutate(names[i].1, &e);
        let r = vsinv::sim::Scenario::from_toml(&text);
        check("Scenario::from_toml", &r, |_| true)?;
        let Ok(scenario) = r else { return Ok(()) };
        let config = scenario.to_config();
        check("Scenario::to_config", &config, |c| c.dt > 0.0 && c.dt.is_finite())?;
        let Ok(mut config) = config else { return Ok(()) };
        if simulate {
            config.stop.max_iterations = 3;
            let out = vsinv::sim::simulate(&config, &mut |_, _| true);
            check("sim::simulate (3 iterations)", &out, |o| {
                let s = &o.summary;
                s.iterations <= 3 && s.final_translation_error.is_finite() && s.final_rotation_error.is_finite()
            })?;
        }
        Ok(())
    });
}

// ---------------------------------------------------------------------------------------------
// Vision: detection, tracking, rendering.

/// A small image: noise, or bright squares on a dark background.
fn small_image() -> impl Strategy<Value = vsinv::vision::GreyImage> {
    let size = (1u32..40, 1u32..40);
    let noise =
        size.prop_flat_map(|(w, h)| prop::collection::vec(any::<u8>(), (w * h) as usize).prop_map(move |d| (w, h, d)));
    let dots = (8u32..40, 8u32..40, prop::collection::vec((0u32..40, 0u32..40, 1u32..6, any::<u8>()), 0..6)).prop_map(
        |(w, h, squares)| {
            let mut d = vec![20u8; (w * h) as usize];
            for (x, y, s, level) in squares {
                for v in y..(y + s).min(h) {
                    for u in x..(x + s).min(w) {
                        d[(v * w + u) as usize] = level;
                    }
                }
            }
            (w, h, d)
        },
    );
    prop_oneof![noise, dots].prop_map(|(w, h, d)| vsinv::vision::GreyImage::from_raw(w, h, d).unwrap())
}

fn prop_detect_and_track(cases: u32) {
    let detect = (prop::option::of(any::<u8>()), 0usize..20, prop::option::of(0usize..50));
    let clicks = prop::collection::vec(prop::array::uniform2(prop_oneof![3 => -2.0..42.0f64, 1 => num()]), 0..5);
    let tracker = (num(), num(), num(), 0usize..10);
    // Often the clicks are the user's: within 1.5 px of the dots detected in the first image.
    let on_dots = (prop::bool::weighted(0.6), prop::array::uniform2(-1.5..1.5f64));
    run(
        cases,
        (small_image(), small_image(), detect, clicks, tracker, on_dots),
        |(a, b, (threshold, min_area, max_area), clicks, t, (on_dots, offset))| {
            let cfg = vsinv::vision::DetectConfig { threshold, min_area, max_area };
            let dots = vsinv::vision::detect_dots(&a, &cfg);
            let clicks = match (&dots, on_dots) {
                (Ok(found), true) if !found.is_empty() => {
                    found.iter().take(5).map(|d| [d.centroid[0] + offset[0], d.centroid[1] + offset[1]]).collect()
                }
                _ => clicks,
            };
            check("vision::detect_dots", &dots, |d| {
                let inside =
                    |p: [f64; 2]| p[0] >= -0.5 && p[1] >= -0.5 && p[0] <= a.width() as f64 && p[1] <= a.height() as f64;
                d.iter().all(|d| finite(&d.centroid) && inside(d.centroid) && d.area >= min_area as f64)
            })?;
            let default = vsinv::vision::TrackerConfig::default();
            let configs = [
                default,
                vsinv::vision::TrackerConfig {
                    search_radius: t.0,
                    max_search_radius: t.1,
                    max_area_ratio: t.2,
                    min_area: t.3,
                },
            ];
            for config in configs {
                let hit = clicks
                    .iter()
                    .position(|c| !finite(c))
                    .map(|r| (r, usize::from(clicks[r][0].is_finite()), f64::NAN));
                let first_bad = hit.filter(|_| config.search_radius.is_finite() && config == default);
                let r = vsinv::vision::DotTracker::new(&a, &clicks, config);
                let needles = nan_at("initial_pixels", first_bad).filter(|n| !n.is_empty());
                // Earlier clicks may fail first (outside the image, no dot): only the row is checked
                // when every earlier click found its dot, which this test cannot know; so name only.
                let located = needles.map(|_| vec!["initial_pixels".to_string()]);
                check_located("vision::DotTracker::new", &r, located.filter(|_| !clicks.is_empty()), |t| {
                    t.len() == clicks.len()
                })?;
                let Ok(mut tracker) = r else { continue };
                for image in [&a, &b, &b] {
                    let r = tracker.track(image);
                    check("vision::DotTracker::track", &r, |t| {
                        finite(t.pixels.as_flattened()) && t.found.len() == clicks.len()
                    })?;
                }
            }
            Ok(())
        },
    );
}

fn prop_render(cases: u32) {
    let cfg =
        (num(), prop_oneof![Just(0.8), num()], prop_oneof![Just(2.0), num()], any::<u8>(), any::<u8>(), any::<u64>());
    let pose = (prop::array::uniform3(prop_oneof![3 => -0.5..0.5f64, 1 => num()]), prop::array::uniform3(-4.0..4.0f64));
    let points = prop::collection::vec(point3(), 0..6);
    let size = (0u32..48, 0u32..48);
    let vis = prop::option::of(prop::collection::vec(any::<bool>(), 0..6));
    run(cases, (cfg, pose, points, size, vis, 0u64..1000), |(c, (t, r), points, size, vis, seed)| {
        let config = vsinv::vision::RenderConfig {
            dot_radius: c.0.abs() * 1e-3,
            blur_sigma: c.1,
            noise_sigma: c.2,
            background: c.3,
            foreground: c.4,
            seed: c.5,
        };
        let renderer = vsinv::vision::Renderer::new(config);
        check("vision::Renderer::new", &renderer, |_| true)?;
        let Ok(renderer) = renderer else { return Ok(()) };
        let pose = se3::pose_from_position_thetau(t, r);
        check("se3::pose_from_position_thetau", &pose, |p| finite(p.to_homogeneous().iter()))?;
        let Ok(pose) = pose else { return Ok(()) };
        let k = random_intrinsics(&mut Lcg(seed));
        let out = renderer.render_points(&points, vis.as_deref(), &pose, &k, size, seed);
        check("vision::Renderer::render_points", &out, |o| {
            o.image.dimensions() == size && o.drawn.len() == points.len()
        })?;
        let disc = vsinv::vision::Disc::new(points.first().copied().unwrap_or([0.0; 3]), t, c.0);
        check("vision::Disc::new", &disc, |d| finite(d.center.iter()) && (d.normal.norm() - 1.0).abs() < 1e-9)
    });
}

// ---------------------------------------------------------------------------------------------
// The tests: cases per API group (about 20 s in release on two cores).

#[test]
fn intrinsics() {
    prop_intrinsics(512);
}
#[test]
fn projection() {
    prop_project_points(512);
}
#[test]
fn invariant_transform() {
    prop_invariant(384);
}
#[test]
fn jacobians() {
    prop_jacobians(384);
}
#[test]
fn invariant_controller() {
    prop_invariant_controller(384);
}
#[test]
fn invariant_controller_reference() {
    prop_invariant_controller_reference(256);
}
#[test]
fn ibvs_controller() {
    prop_ibvs_controller(384);
}
#[test]
fn stability() {
    prop_stability(384);
}
#[test]
fn depths() {
    prop_depths(256);
}
#[test]
fn planning() {
    prop_planning(256);
}
#[test]
fn se3_rz_task_gains() {
    prop_se3(512);
    prop_rz_task(384);
    prop_gains(512);
}
#[test]
fn distortion() {
    prop_distortion(512);
}
#[test]
fn calibration_files() {
    prop_calibration(384);
}
#[test]
fn scenario_files() {
    prop_scenario(96);
}
#[test]
fn vision() {
    prop_detect_and_track(256);
    prop_render(192);
}

/// Every group with `CENSUS_CASES` cases (default 200), then the table of calls per API.
#[test]
#[ignore = "a report: cargo test --release --test robustness -- --ignored --nocapture census"]
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

// ---------------------------------------------------------------------------------------------
// Regressions: the faults the properties above found, one deterministic case each.

fn message<T: std::fmt::Debug>(r: Result<T>) -> String {
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
