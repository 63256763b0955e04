//! Safe commands: twist limits (the whole twist scaled, direction kept) and the adaptive gain
//! of ViSP's `vpAdaptiveGain`, in both controllers and in scenarios.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common::*;
use nalgebra::{Isometry3, Vector6};
use vsinv::core::adaptive_gain::AdaptiveGain;
use vsinv::core::saturation::TwistLimits;
use vsinv::sim::SimError;
use vsinv::sim::scenario::{Scenario, builtin};
use vsinv::sim::{Status, simulate};
use vsinv::{IbvsController, Interaction, InvariantController, InvariantControllerConfig};

/// The reference image with a 12 mm lens, the current one from the paper's start with 6 mm.
fn lens_change() -> (Vec<[f64; 2]>, Vec<[f64; 2]>, Vec<f64>) {
    let object = object_points();
    let (reference, z_star) = view(&object, &Isometry3::identity(), &lens(1200.0));
    let start = look_at([0.2, -0.15, -0.15], [0.0, 0.0, 0.6], 78f64.to_radians());
    let (current, _) = view(&object, &start, &lens(600.0));
    (reference, current, z_star)
}

fn invariant(config: InvariantControllerConfig) -> InvariantController {
    let (reference, _, _) = lens_change();
    let basis = vsinv::choose_basis(&reference).unwrap();
    InvariantController::new(&reference, lens(620.0), basis, config).unwrap()
}

fn speeds(t: &Vector6<f64>) -> (f64, f64) {
    (t.fixed_rows::<3>(0).norm(), t.fixed_rows::<3>(3).norm())
}

#[test]
fn limited_twist_is_the_free_twist_scaled_within_both_maxima() {
    let (_, current, z) = lens_change();
    let free = invariant(InvariantControllerConfig::default()).step(&current, &z).unwrap();
    let limits = TwistLimits::new(0.25, 60f64.to_radians()).unwrap();
    let mut ctl = invariant(InvariantControllerConfig { twist_limits: Some(limits), ..Default::default() });
    let limited = ctl.step(&current, &z).unwrap();
    let (v, w) = speeds(&free);
    assert!(w > 60f64.to_radians(), "the first twist must exceed the limit for this test: {w}");
    let expected = (0.25 / v).min(60f64.to_radians() / w);
    assert!((ctl.state().unwrap().saturation - expected).abs() < 1e-12);
    assert!((limited - free * expected).norm() < 1e-12 * free.norm());
    let (v, w) = speeds(&limited);
    assert!(v <= 0.25 + 1e-12 && w <= 60f64.to_radians() + 1e-12);
}

#[test]
fn adaptive_gain_equals_a_constant_gain_at_the_current_error() {
    // With the adaptive gain the twist is that of the constant law with lambda = lambda(x)
    // and eta = gain_rz lambda(x) / lambda_0, x = ||s - s*||.
    let (_, current, z) = lens_change();
    let g = AdaptiveGain::new(4.0, 0.4, 30.0).unwrap();
    let mut adaptive =
        invariant(InvariantControllerConfig { adaptive_gain: Some(g), gain_rz: 2.0, ..Default::default() });
    let twist = adaptive.step(&current, &z).unwrap();
    let x = adaptive.state().unwrap().invariant_error;
    let lambda = g.value(x);
    assert!((adaptive.state().unwrap().gain - lambda).abs() < 1e-15);
    assert!(lambda > 0.4 && lambda < 4.0, "{lambda}");
    let config = InvariantControllerConfig { gain: lambda, gain_rz: 2.0 * lambda / 4.0, ..Default::default() };
    let constant = invariant(config).step(&current, &z).unwrap();
    assert!((twist - constant).norm() < 1e-12 * constant.norm(), "{twist} vs {constant}");
}

#[test]
fn ibvs_adaptive_gain_uses_the_pixel_error_norm() {
    let (reference, current, z) = lens_change();
    let g = AdaptiveGain::new(2.0, 0.5, 0.01).unwrap();
    let mut ibvs = IbvsController::new(&reference, lens(620.0), 1.0, Interaction::Current, None).unwrap();
    let unit_gain = ibvs.step(&current, &z).unwrap();
    ibvs.set_adaptive_gain(Some(g)).unwrap();
    ibvs.set_twist_limits(Some(TwistLimits::new(0.1, 0.2).unwrap())).unwrap();
    let twist = ibvs.step(&current, &z).unwrap();
    let norm: f64 = reference.iter().zip(&current).map(|(a, b)| (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sum();
    let lambda = g.value(norm.sqrt());
    let (gain, scale) = ibvs.last_command().unwrap();
    assert!((gain - lambda).abs() < 1e-15);
    assert!(scale < 1.0);
    assert!((twist - unit_gain * (lambda * scale)).norm() < 1e-12 * twist.norm());
    assert!(ibvs.set_twist_limits(Some(TwistLimits { linear: -1.0, angular: 1.0 })).is_err());
    assert!(ibvs.set_adaptive_gain(Some(AdaptiveGain { at_zero: 1.0, at_infinity: 2.0, slope_at_zero: 1.0 })).is_err());
}

#[test]
fn built_in_lens_change_keeps_every_command_within_a_real_arms_limits() {
    let mut config = builtin("lens-12-6").unwrap().to_config().unwrap();
    config.record = true;
    let out = simulate(&config, &mut |_, _| true).unwrap();
    let s = &out.summary;
    assert_eq!(s.status, Status::Converged, "{}", s.message);
    assert!(s.final_translation_error < 1e-3 && s.final_rotation_error.to_degrees() < 0.1);
    let (v, w) = s.peak_speeds;
    assert!(v <= 0.25 + 1e-12 && w.to_degrees() <= 60.0 + 1e-9, "{v} m/s, {} deg/s", w.to_degrees());
    // The limit binds at the start (the free law asks for about 400 deg/s).
    assert!(w.to_degrees() > 59.0, "{}", w.to_degrees());
    let twists = &out.recording.unwrap().twist;
    for t in twists.chunks(6).filter(|t| t[0].is_finite()) {
        let t = Vector6::from_column_slice(t);
        let (v, w) = speeds(&t);
        assert!(v <= 0.25 + 1e-12 && w <= 60f64.to_radians() + 1e-12);
    }
}

#[test]
fn scenario_limits_and_gains_are_checked_with_their_keys() {
    let base = builtin("lens-12-6").unwrap().to_toml().unwrap();
    let cases = [
        ("max_linear_speed = 0.25", "max_linear_speed = -0.25", "control.max_linear_speed"),
        ("max_angular_speed_deg = 60.0", "max_angular_speed_deg = nan", "control.max_angular_speed_deg"),
        (
            "[control]",
            "[control]\nadaptive_gain = { at_zero = 1.0, at_infinity = 2.0, slope_at_zero = 3.0 }",
            "control.adaptive_gain",
        ),
        (
            "[control]",
            "[control]\nadaptive_gain = { at_zero = 1.0, at_infinity = 0.0, slope_at_zero = 3.0 }",
            "control.adaptive_gain.at_infinity",
        ),
        ("[control]", "[control]\nadaptive_gain = { at_zero = 1.0, at_infinity = 0.5 }", "control.adaptive_gain"),
    ];
    for (old, new, key) in cases {
        assert!(base.contains(old), "{old}");
        let text = base.replacen(old, new, 1);
        let err = Scenario::from_toml(&text).and_then(|s| s.to_config());
        match err {
            Err(SimError::Scenario { key: k, .. }) => assert!(k.to_string().starts_with(key), "{new}: key {k}"),
            other => panic!("{new}: {other:?}"),
        }
    }
}
