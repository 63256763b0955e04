//! `cargo run -p vsinv-embedded`: the 100 Hz loop on the control core; exits non-zero if it
//! does not converge to within 1 mm and 0.1 degrees.

fn main() -> std::process::ExitCode {
    match vsinv_embedded::run_invariant_loop(5000) {
        Ok((iterations, t, r)) => {
            println!(
                "invariant law at 100 Hz on the core only: {iterations} iterations ({:.1} s), final error {:.4} mm, {:.5} deg",
                iterations as f64 * vsinv_embedded::DT,
                t * 1e3,
                r.to_degrees()
            );
            if t < 1e-3 && r.to_degrees() < 0.1 {
                std::process::ExitCode::SUCCESS
            } else {
                std::process::ExitCode::FAILURE
            }
        }
        Err(e) => {
            eprintln!("control loop failed: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}
