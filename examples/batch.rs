//! Many runs in parallel (feature `batch`): the `lens-12-6` scenario with the estimated
//! focal length K_hat off by -50 % to +200 %, run on a rayon pool without recording. Prints
//! one line per run and exits non-zero unless every run converged (Prop. 1 holds for any
//! positive focal estimate).
//!
//! Run with `cargo run --release --example batch`.

use vsinv::sim::Status;
use vsinv::sim::batch::run_batch;
use vsinv::sim::scenario::builtin;

fn main() -> Result<(), vsinv::sim::SimError> {
    let base = builtin("lens-12-6")?;
    let errors = [-0.5, -0.25, 0.0, 0.5, 1.0, 2.0];
    let mut configs = Vec::new();
    for e in errors {
        let mut s = base.clone();
        let estimate = s.estimate.as_mut().ok_or(vsinv::Error::InvalidParameter {
            name: "example",
            reason: "lens-12-6 has an [estimate] table".into(),
        })?;
        estimate.fku = Some(600.0 * (1.0 + e));
        estimate.fkv = Some(600.0 * (1.0 + e));
        configs.push(s.to_config()?);
    }
    let results = run_batch(&configs, Some(2))?;
    let mut all_converged = true;
    println!("focal error | status | iterations | final error (mm)");
    for (e, result) in errors.iter().zip(&results) {
        let s = result.as_ref().map_err(Clone::clone)?;
        all_converged &= s.status == Status::Converged;
        println!(
            "{:+10.0} % | {} | {} | {:.3}",
            e * 100.0,
            s.status.as_str(),
            s.iterations,
            s.final_translation_error * 1e3
        );
    }
    if !all_converged {
        return Err(vsinv::Error::InvalidParameter { name: "example", reason: "a run did not converge".into() }.into());
    }
    Ok(())
}
