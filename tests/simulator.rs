//! The simulator and the scenario runner.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use vsinv::scenario::{Scenario, builtin};
use vsinv::simulator::{Outcome, Status, simulate};

fn run(s: &Scenario) -> Outcome {
    simulate(&s.to_config().unwrap(), &mut |_, _| true).unwrap()
}

fn report(o: &Outcome) -> String {
    let s = &o.summary;
    format!(
        "{} after {} it: {:.3} mm, {:.4} deg, image {:.2} px, invariant {:.2e} ({})",
        s.status.as_str(),
        s.iterations,
        s.final_translation_error * 1e3,
        s.final_rotation_error.to_degrees(),
        s.final_image_error,
        s.final_invariant_error,
        s.message
    )
}

#[test]
fn lens_change_12_to_6_converges() {
    let o = run(&builtin("lens-12-6").unwrap());
    eprintln!("{}", report(&o));
    let s = &o.summary;
    assert_eq!(s.status, Status::Converged, "{}", report(&o));
    assert!(s.final_translation_error < 1e-3 && s.final_rotation_error.to_degrees() < 0.1, "{}", report(&o));
}

#[test]
fn all_builtins_summary() {
    for (name, _) in vsinv::scenario::BUILTIN {
        let s = builtin(name).unwrap();
        let o = run(&s);
        eprintln!("{name:16} {}", report(&o));
    }
}
