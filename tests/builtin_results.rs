//! Every built-in scenario gives bit for bit the results recorded in
//! `tests/fixtures/builtin_results.txt`: the guard of refactors that must keep behaviour.
//!
//! Each line holds a scenario's status, iteration count and a 64-bit FNV-1a digest of every
//! number of its summary and recording (the bits of each f64, in a fixed order). Record the
//! table anew (only for a change that is meant to alter results, and say so in its commit)
//! with `VSINV_RECORD_BUILTINS=1 cargo test --release --test integration builtin_results::` (or
//! `VSINV_RECORD_BUILTINS=1 make test-builtins`).
//!
//! Only the kinematic built-ins are in the table: a built-in with `[world] engine = "mujoco"`
//! (`mujoco-*`) runs in Python's `vsinv.mujoco` through MuJoCo's renders, which this crate's
//! simulator refuses and whose results depend on MuJoCo's version and renderer; their verdicts
//! are checked by tests/test_mujoco_builtins.py. The test below checks that each skipped one
//! is indeed refused by the simulator.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use vsinv::sim::scenario::{BUILTIN, Engine, builtin};
use vsinv::sim::{Outcome, simulate};

const TABLE: &str = "tests/fixtures/builtin_results.txt";

/// FNV-1a over the bits of the numbers fed to it.
struct Digest(u64);

impl Digest {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
    fn bytes(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.0 = (self.0 ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    fn f(&mut self, values: &[f64]) {
        self.bytes(&(values.len() as u64).to_le_bytes());
        values.iter().for_each(|v| self.bytes(&v.to_bits().to_le_bytes()));
    }
    fn opt(&mut self, values: Option<&[f64]>) {
        match values {
            Some(v) => self.f(v),
            None => self.bytes(b"none"),
        }
    }
}

/// The digest of a run's numbers: its summary, then its recording.
fn digest(o: &Outcome) -> u64 {
    let mut d = Digest::new();
    let s = &o.summary;
    d.bytes(s.message.as_bytes());
    d.f(&[s.final_translation_error, s.final_rotation_error, s.final_image_error, s.final_invariant_error]);
    d.f(&s.final_tau);
    d.f(&[s.start_error.0, s.start_error.1, s.max_line_deviation, s.peak_speeds.0, s.peak_speeds.1]);
    d.f(&s.basis.map(|b| b as f64));
    d.bytes(&[u8::from(s.prop1), u8::from(s.prop2), u8::from(s.within_tolerance)]);
    d.bytes(format!("{:?}", s.stop_rule).as_bytes());
    let tracking =
        s.tracking.map(|t| vec![t.sigma, t.psi, t.phi, t.bound, t.max_eps, t.duration, t.plane_parallax_residual]);
    d.opt(tracking.as_deref());
    d.opt(s.detection_error.map(|(a, b)| [a, b]).as_ref().map(|v| &v[..]));
    d.opt(s.min_manipulability.map(|m| [m]).as_ref().map(|v| &v[..]));
    let certainty =
        s.certainty.map(|c| [c.pixel_sigma, c.reference_pixel_sigma, c.sigma.0, c.sigma.1, c.bound.0, c.bound.1]);
    d.opt(certainty.as_ref().map(|v| &v[..]));
    d.f(&o.reference_pixels.concat());
    if let Some(r) = &o.recording {
        for column in [
            &r.time,
            &r.pose,
            &r.twist,
            &r.joints,
            &r.joint_velocities,
            &r.pixels,
            &r.invariant_error,
            &r.tracking_error,
            &r.eps,
            &r.eps_z,
            &r.image_error,
            &r.translation_error,
            &r.rotation_error,
            &r.detection_error,
        ] {
            d.f(column);
        }
        d.bytes(&r.visible.iter().map(|&v| u8::from(v)).collect::<Vec<_>>());
    }
    d.0
}

/// One line of the table: name, status, iterations, digest.
fn line(name: &str) -> String {
    let mut config = builtin(name).unwrap().to_config().unwrap();
    config.record = true;
    let o = simulate(&config, &mut |_, _| true).unwrap();
    format!("{name} {} {} {:016x}", o.summary.status.as_str(), o.summary.iterations, digest(&o))
}

/// The built-ins this crate's simulator runs (`[world] engine = "kinematic"`), in order.
fn kinematic_builtins() -> Vec<&'static str> {
    BUILTIN
        .iter()
        .map(|(name, _)| *name)
        .filter(|name| builtin(name).unwrap().world.engine == Engine::Kinematic)
        .collect()
}

#[test]
fn builtin_results_are_bit_identical_to_the_recorded_table() {
    let names = kinematic_builtins();
    let lines: Vec<String> = names.iter().map(|name| line(name)).collect();
    if std::env::var_os("VSINV_RECORD_BUILTINS").is_some() {
        std::fs::write(TABLE, lines.join("\n") + "\n").unwrap();
        return;
    }
    let recorded = std::fs::read_to_string(TABLE).unwrap();
    let recorded: Vec<&str> = recorded.lines().collect();
    assert_eq!(recorded.len(), names.len(), "the table has a line per kinematic built-in scenario");
    let changed: Vec<String> = lines
        .iter()
        .zip(&recorded)
        .filter(|(now, then)| now.as_str() != **then)
        .map(|(now, then)| format!("recorded: {then}\n     now: {now}"))
        .collect();
    assert!(changed.is_empty(), "results changed:\n{}", changed.join("\n"));
}

#[test]
fn the_builtins_left_out_of_the_table_are_the_mujoco_ones_and_the_simulator_refuses_them() {
    let kinematic = kinematic_builtins();
    let others: Vec<&str> = BUILTIN.iter().map(|(n, _)| *n).filter(|n| !kinematic.contains(n)).collect();
    assert!(!others.is_empty(), "the MuJoCo built-ins are in BUILTIN");
    for name in others {
        let scenario = builtin(name).unwrap();
        assert_eq!(scenario.world.engine, Engine::Mujoco, "{name}");
        assert!(name.starts_with("mujoco-"), "{name}: a MuJoCo built-in is named mujoco-*");
        let refused = scenario.to_config().unwrap_err().to_string();
        assert!(refused.contains("world.engine"), "{name}: {refused}");
    }
}
