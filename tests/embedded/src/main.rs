//! `cargo run -p vsinv-embedded`: the 100 Hz loop on the control core, then the same loop
//! run by a servo session that decides when to stop; exits non-zero unless both end within
//! 1 mm and 0.1 degrees (the session with the status `converged`).

use vsinv::servo::Status;

fn main() -> std::process::ExitCode {
    let dt = vsinv_embedded::DT;
    let within = |t: f64, r: f64| t < 1e-3 && r.to_degrees() < 0.1;
    let core = match vsinv_embedded::run_invariant_loop(5000) {
        Ok((iterations, t, r)) => {
            println!(
                "invariant law at 100 Hz on the core only: {iterations} iterations ({:.1} s), final error {:.4} mm, {:.5} deg",
                iterations as f64 * dt,
                t * 1e3,
                r.to_degrees()
            );
            within(t, r)
        }
        Err(e) => {
            eprintln!("control loop failed: {e}");
            false
        }
    };
    let session = match vsinv_embedded::run_servo_loop() {
        Ok((status, iterations, t, r)) => {
            println!(
                "servo session at 100 Hz: {} after {iterations} iterations ({:.1} s), final error {:.4} mm, {:.5} deg",
                status.as_str(),
                iterations as f64 * dt,
                t * 1e3,
                r.to_degrees()
            );
            status == Status::Converged && within(t, r)
        }
        Err(e) => {
            eprintln!("servo session failed: {e}");
            false
        }
    };
    if core && session { std::process::ExitCode::SUCCESS } else { std::process::ExitCode::FAILURE }
}
