//! A 100 Hz visual control loop that embeds vsinv's control core alone (no simulator): the
//! camera's view is computed here with the pinhole model, the controller gives a twist, and
//! the pose is integrated with the SE(3) exponential, as a robot controller would.

use vsinv::core::se3::{exp_twist, pose_error};
use vsinv::nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use vsinv::servo::{Law, Servo, ServoConfig, ServoDepths, ServoReference, Status, Verdict};
use vsinv::{IbvsController, Interaction, Intrinsics, InvariantController, InvariantControllerConfig, Result};

/// Control period of a 100 Hz loop, seconds.
pub const DT: f64 = 0.01;

/// Twelve points with relief, about 600 mm in front of the reference camera.
pub fn object() -> Vec<[f64; 3]> {
    let relief = [0.0, 0.06, -0.04, 0.03, -0.06, 0.05, 0.02, -0.03, 0.04, -0.05, 0.01, 0.06];
    (0..12).map(|i| [-0.15 + 0.1 * (i % 4) as f64, -0.12 + 0.12 * (i / 4) as f64, 0.6 + relief[i]]).collect()
}

/// Pixels and depths of the object seen by a camera at `pose` (camera frame in F*), into
/// buffers reused from one period to the next.
pub fn view(
    object: &[[f64; 3]],
    pose: &Isometry3<f64>,
    k: &Intrinsics,
    pixels: &mut [[f64; 2]],
    depths: &mut [f64],
) -> Result<()> {
    let inv = pose.inverse();
    for (i, p) in object.iter().enumerate() {
        let c = inv * Point3::from(*p);
        let (px, z) = k.project(&c)?;
        pixels[i] = px;
        depths[i] = z;
    }
    Ok(())
}

/// A start about 100 mm and 25 degrees from the reference pose.
pub fn start_pose() -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(0.06, -0.05, -0.07),
        UnitQuaternion::from_scaled_axis(Vector3::new(0.1, -0.15, 0.35)),
    )
}

/// The reference image (12 mm lens), the servo lens (6 mm) and a rough estimate of it.
pub fn cameras() -> Result<(Intrinsics, Intrinsics, Intrinsics)> {
    Ok((
        Intrinsics::pinhole(1200.0, 1200.0, 384.0, 288.0)?,
        Intrinsics::pinhole(600.0, 600.0, 384.0, 288.0)?,
        Intrinsics::pinhole(650.0, 570.0, 395.0, 280.0)?,
    ))
}

/// The two controllers for the reference image, with reference depths zeta*.
pub fn controllers() -> Result<(InvariantController, IbvsController, Vec<f64>)> {
    let (k_star, _, k_hat) = cameras()?;
    let object = object();
    let (mut reference, mut z_star) = (vec![[0.0; 2]; object.len()], vec![0.0; object.len()]);
    view(&object, &Isometry3::identity(), &k_star, &mut reference, &mut z_star)?;
    let basis = vsinv::choose_basis(&reference)?;
    let invariant = InvariantController::new(&reference, k_hat, basis, InvariantControllerConfig::default())?;
    let ibvs = IbvsController::new(&reference, k_hat, 1.0, Interaction::Current, Some(&z_star))?;
    Ok((invariant, ibvs, z_star))
}

/// Runs the invariant law at 100 Hz until it converges; returns the iterations and the
/// final distance (m) and angle (rad) from the reference pose.
pub fn run_invariant_loop(max_iterations: usize) -> Result<(usize, f64, f64)> {
    let (_, k, _) = cameras()?;
    let (mut ctl, _, z_star) = controllers()?;
    let object = object();
    let (mut pixels, mut depths) = (vec![[0.0; 2]; object.len()], vec![0.0; object.len()]);
    let mut pose = start_pose();
    let mut iterations = 0;
    while iterations < max_iterations && !ctl.converged(1e-6, 1e-6) {
        view(&object, &pose, &k, &mut pixels, &mut depths)?;
        let twist = ctl.step(&pixels, &z_star)?;
        pose *= exp_twist(&(twist * DT).into())?;
        iterations += 1;
    }
    let (t, r) = pose_error(&Isometry3::identity(), &pose);
    Ok((iterations, t, r))
}

/// The servo session for the reference image: the invariant law with K_hat, the reference
/// depths zeta*, default stop rules, at 100 Hz.
pub fn servo() -> Result<Servo> {
    let (k_star, _, k_hat) = cameras()?;
    let object = object();
    let (mut reference, mut z_star) = (vec![[0.0; 2]; object.len()], vec![0.0; object.len()]);
    view(&object, &Isometry3::identity(), &k_star, &mut reference, &mut z_star)?;
    let mut config = ServoConfig::new(Law::Invariant(InvariantControllerConfig::default()), k_hat);
    config.dt = DT;
    config.stop.max_iterations = 5000;
    Servo::new(config, ServoReference { pixels: reference, depths: Some(z_star) }, ServoDepths::Reference)
}

/// Runs a servo session at 100 Hz until its verdict stops it; returns the status, the
/// iterations and the final distance (m) and angle (rad) from the reference pose.
pub fn run_servo_loop() -> Result<(Status, usize, f64, f64)> {
    let (_, k, _) = cameras()?;
    let mut servo = servo()?;
    let object = object();
    let (mut pixels, mut depths) = (vec![[0.0; 2]; object.len()], vec![0.0; object.len()]);
    let mut pose = start_pose();
    let status = loop {
        view(&object, &pose, &k, &mut pixels, &mut depths)?;
        let step = servo.step(&pixels, None, None)?;
        if let Verdict::Stop { status, .. } = step.verdict {
            break status;
        }
        pose *= exp_twist(&(step.twist * DT).into())?;
    };
    let (t, r) = pose_error(&Isometry3::identity(), &pose);
    Ok((status, servo.iterations(), t, r))
}
