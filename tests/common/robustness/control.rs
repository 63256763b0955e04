//! The controllers, the stability check, rigid motions, the rz task, gains and saturation.
//!
//! The properties of tests/robustness_control.rs (and the census of tests/robustness_census.rs).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common::{Lcg, random_intrinsics};
use crate::robustness::*;
use nalgebra::{Isometry3, Matrix3, Matrix4, Vector3, Vector6};
use proptest::prelude::*;
use vsinv::core::adaptive_gain::AdaptiveGain;
use vsinv::core::rz_task::{RzTask, linearise};
use vsinv::core::saturation::TwistLimits;
use vsinv::core::se3;
use vsinv::{
    IbvsController, Interaction, Intrinsics, InvariantController, InvariantControllerConfig, a_matrix, check_stability,
    tracking_bound,
};

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

pub fn prop_invariant_controller(cases: u32) {
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

pub fn prop_invariant_controller_reference(cases: u32) {
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

pub fn prop_ibvs_controller(cases: u32) {
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

pub fn prop_stability(cases: u32) {
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
// Rigid motions, rz task, gains, saturation.

pub fn prop_se3(cases: u32) {
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

pub fn prop_rz_task(cases: u32) {
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

pub fn prop_gains(cases: u32) {
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
