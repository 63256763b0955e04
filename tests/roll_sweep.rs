//! Any start angle about the optical axis (the general rz task): the lens-12-6 start, its
//! attitude `R_xy Rz(rz0)` rolled to every rz0 in [-179, 179] degrees (73 values), converges
//! within 1 mm and 0.1 degree. Run with `--nocapture` for the table.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use vsinv::core::rz_task::RzTask;
use vsinv::nalgebra::{UnitQuaternion, Vector3};
use vsinv::sim::scenario::builtin;
use vsinv::sim::{Law, Status, Summary, simulate};

fn rolled_start(rz0_deg: f64, task: RzTask) -> Summary {
    let mut s = builtin("lens-12-6").unwrap();
    let [rx, ry, _] = s.start.as_ref().unwrap().rotation_deg.map(f64::to_radians);
    let attitude = UnitQuaternion::from_scaled_axis(Vector3::new(rx, ry, 0.0))
        * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), rz0_deg.to_radians());
    s.start.as_mut().unwrap().rotation_deg = attitude.scaled_axis().map(f64::to_degrees).into();
    let mut config = s.to_config().unwrap();
    config.record = false;
    if let Law::Invariant(c) = &mut config.law {
        c.rz_task = task;
    }
    simulate(&config, &mut |_, _| true).unwrap().summary
}

fn angles() -> Vec<f64> {
    (0..72).map(|k| -179.0 + 5.0 * f64::from(k)).chain([179.0]).collect()
}

#[test]
fn every_roll_converges_with_the_angle_task() {
    println!("| rz0 (deg) | status | iterations | final translation error (mm) | final rotation error (deg) |");
    println!("|---|---|---|---|---|");
    let mut failed = Vec::new();
    for rz0 in angles() {
        let s = rolled_start(rz0, RzTask::Angle);
        let (mm, deg) = (s.final_translation_error * 1e3, s.final_rotation_error.to_degrees());
        println!("| {rz0} | {} | {} | {mm:.3} | {deg:.4} |", s.status.as_str(), s.iterations);
        if s.status != Status::Converged || mm > 1.0 || deg > 0.1 {
            failed.push((rz0, s.status, mm, deg));
        }
    }
    assert!(failed.is_empty(), "{failed:?}");
}

#[test]
fn the_papers_task_is_trapped_beyond_90_degrees_and_says_so() {
    // Eq. (24) alone: a start rolled by 150 degrees ends at the rz = pi equilibrium.
    let s = rolled_start(150.0, RzTask::Tau21);
    assert_eq!(s.status, Status::RzTrap, "{}", s.message);
    let s = rolled_start(30.0, RzTask::Tau21);
    assert_eq!(s.status, Status::Converged);
}
