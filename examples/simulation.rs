//! A simulated run (feature `sim`): the built-in `lens-12-6` scenario (sec. 5.2, experiment
//! 2: reference image with a 12 mm lens, servo with a 6 mm lens) and the same scenario
//! edited in code to servo with classic IBVS. Exits non-zero unless the invariant law
//! converges within 1 mm and 0.1 degrees.
//!
//! Run with `cargo run --release --example simulation`.

use vsinv::sim::scenario::{LawName, builtin};
use vsinv::sim::{Status, Summary, simulate};

fn print(name: &str, s: &Summary) {
    println!(
        "{name}: {} after {} iterations ({}), final error {:.3} mm, {:.4} deg",
        s.status.as_str(),
        s.iterations,
        s.message,
        s.final_translation_error * 1e3,
        s.final_rotation_error.to_degrees()
    );
}

fn main() -> Result<(), vsinv::sim::SimError> {
    let scenario = builtin("lens-12-6")?;
    let outcome = simulate(&scenario.to_config()?, &mut |_, _| true)?;
    print("invariant law", &outcome.summary);
    let recording = outcome.recording.as_ref().map_or(0, |r| r.len());
    println!("recorded {recording} iterations of {} points", scenario.object.points.len());

    let mut ibvs = scenario.clone();
    ibvs.control.law = LawName::Ibvs;
    print("classic IBVS", &simulate(&ibvs.to_config()?, &mut |_, _| true)?.summary);

    let s = &outcome.summary;
    if s.status != Status::Converged || s.final_translation_error > 1e-3 || s.final_rotation_error.to_degrees() > 0.1 {
        return Err(
            vsinv::Error::InvalidParameter { name: "example", reason: "lens-12-6 did not converge".into() }.into()
        );
    }
    Ok(())
}
