//! An embedded control loop on the control core alone (no simulator needed): the paper's
//! lens-change experiment (sec. 5.2, experiment 2) with the camera's view computed in a few
//! lines: reference image with a 12 mm lens, servo with a 6 mm lens, start about 300 mm and
//! 80 degrees away; the invariant law against classic IBVS. Exits non-zero unless the
//! invariant law ends within 1 mm and 0.1 degrees.
//!
//! Run with `cargo run --release --example control_loop`.

use vsinv::core::se3::{exp_twist, pose_error};
use vsinv::nalgebra::{Isometry3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use vsinv::{IbvsController, Interaction, Intrinsics, InvariantController, InvariantControllerConfig};

fn view(object: &[[f64; 3]], pose: &Isometry3<f64>, k: &Intrinsics) -> vsinv::Result<(Vec<[f64; 2]>, Vec<f64>)> {
    let inv = pose.inverse();
    let cam: Vec<[f64; 3]> = object.iter().map(|p| (inv * Point3::from(*p)).coords.into()).collect();
    vsinv::project_points(&cam, k)
}

fn main() -> vsinv::Result<()> {
    // 12 points, 300 x 240 mm, 600 mm away, with relief.
    let relief = [0.0, 0.06, -0.04, 0.03, -0.06, 0.05, 0.02, -0.03, 0.04, -0.05, 0.01, 0.06];
    let object: Vec<[f64; 3]> =
        (0..12).map(|i| [-0.15 + 0.1 * (i % 4) as f64, -0.12 + 0.12 * (i / 4) as f64, 0.6 + relief[i]]).collect();
    let k_star = Intrinsics::pinhole(1200.0, 1200.0, 384.0, 288.0)?; // 12 mm at 100 px/mm
    let k = Intrinsics::pinhole(600.0, 600.0, 384.0, 288.0)?; // 6 mm
    let k_hat = Intrinsics::pinhole(650.0, 570.0, 395.0, 280.0)?; // rough estimate of k
    let (reference, z_star) = view(&object, &Isometry3::identity(), &k_star)?;

    let center = Vector3::new(0.2, -0.15, -0.15);
    let look = Rotation3::rotation_between(&Vector3::z(), &(Vector3::new(0.0, 0.0, 0.6) - center))
        .unwrap_or_else(Rotation3::identity);
    let start = Isometry3::from_parts(
        Translation3::from(center),
        UnitQuaternion::from_rotation_matrix(&look)
            * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 78f64.to_radians()),
    );
    let (t0, r0) = pose_error(&Isometry3::identity(), &start);
    println!("start: {:.0} mm and {:.1} deg from the reference pose", t0 * 1e3, r0.to_degrees());

    let dt = 0.04;
    let basis = vsinv::choose_basis(&reference)?;
    let mut invariant = InvariantController::new(&reference, k_hat, basis, InvariantControllerConfig::default())?;
    let mut pose = start;
    let mut iterations = 0;
    while iterations < 2000 && !invariant.converged(1e-5, 1e-5) {
        let (px, _) = view(&object, &pose, &k)?;
        let twist = invariant.step(&px, &z_star)?; // reference depths, as in the paper
        pose *= exp_twist(&(twist * dt).into())?;
        iterations += 1;
    }
    let (t, r) = pose_error(&Isometry3::identity(), &pose);
    println!("invariant law: {iterations} iterations, final error {:.3} mm, {:.4} deg", t * 1e3, r.to_degrees());
    if !(t < 1e-3 && r.to_degrees() < 0.1) {
        return Err(vsinv::Error::InvalidParameter {
            name: "example",
            reason: "the invariant law did not converge".into(),
        });
    }

    let mut ibvs = IbvsController::new(&reference, k_hat, 1.0, Interaction::Current, Some(&z_star))?;
    let mut pose = Isometry3::from_parts(Translation3::new(0.05, -0.04, -0.05), UnitQuaternion::identity());
    for _ in 0..2000 {
        let (px, z) = view(&object, &pose, &k)?;
        let twist = ibvs.step(&px, &z)?;
        pose *= exp_twist(&(twist * dt).into())?;
    }
    let (t, r) = pose_error(&Isometry3::identity(), &pose);
    println!(
        "classic IBVS (from a 80 mm start): final error {:.1} mm, {:.2} deg, image error {:.1} px",
        t * 1e3,
        r.to_degrees(),
        ibvs.last_pixel_error().unwrap_or(f64::NAN)
    );
    Ok(())
}
