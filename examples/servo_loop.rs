//! A robot's servo loop on a [`Servo`] session (feature `servo`: no simulator): the camera's
//! view is computed here in a few lines, with a little pixel noise, and the session decides
//! when to stop. The reference image was taken with a 12 mm lens, the servo camera has a
//! 6 mm lens known only roughly. Exits non-zero unless the session ends `converged` with the
//! camera within the pose uncertainty the images allowed (and within 5 mm and 0.5 degrees,
//! the default tolerance).
//!
//! Run with `cargo run --release --example servo_loop`.

use vsinv::core::se3::{exp_twist, pose_error};
use vsinv::nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use vsinv::servo::{Law, Servo, ServoConfig, ServoDepths, ServoReference, Status, Verdict};
use vsinv::{Intrinsics, InvariantControllerConfig};

/// The camera's view of the object from `pose`, with pixel noise from `noise`.
fn view(object: &[[f64; 3]], pose: &Isometry3<f64>, k: &Intrinsics, noise: &mut Noise) -> vsinv::Result<Vec<[f64; 2]>> {
    let inv = pose.inverse();
    let cam: Vec<[f64; 3]> = object.iter().map(|p| (inv * Point3::from(*p)).coords.into()).collect();
    let (pixels, _) = vsinv::project_points(&cam, k)?;
    Ok(pixels.into_iter().map(|[u, v]| [u + noise.next(), v + noise.next()]).collect())
}

/// A small deterministic noise, uniform in +-0.05 px (a camera's sub-pixel jitter).
struct Noise(u64);

impl Noise {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.1
    }
}

fn main() -> vsinv::Result<()> {
    let relief = [0.0, 0.06, -0.04, 0.03, -0.06, 0.05, 0.02, -0.03, 0.04, -0.05, 0.01, 0.06];
    let object: Vec<[f64; 3]> =
        (0..12).map(|i| [-0.15 + 0.1 * (i % 4) as f64, -0.12 + 0.12 * (i / 4) as f64, 0.6 + relief[i]]).collect();
    let k_star = Intrinsics::pinhole(1200.0, 1200.0, 384.0, 288.0)?; // 12 mm at 100 px/mm
    let k = Intrinsics::pinhole(600.0, 600.0, 384.0, 288.0)?; // 6 mm
    let k_hat = Intrinsics::pinhole(650.0, 570.0, 395.0, 280.0)?; // rough estimate of k
    let mut noise = Noise(7);
    let reference = view(&object, &Isometry3::identity(), &k_star, &mut noise)?;

    let mut config = ServoConfig::new(Law::Invariant(InvariantControllerConfig::default()), k_hat);
    config.stop.window = 10; // average the errors of the last 10 images: the noise averages out
    config.stop.invariant_error = 1e-3;
    config.stop.tau21 = 1e-3;
    // The reference depths zeta* (sec. 5.2): the reference camera is at F*, so they are the
    // points' z.
    let z_star: Vec<f64> = object.iter().map(|p| p[2]).collect();
    let mut servo =
        Servo::new(config, ServoReference { pixels: reference, depths: Some(z_star) }, ServoDepths::Reference)?;

    let start = Isometry3::from_parts(
        Translation3::new(0.08, -0.06, -0.1),
        UnitQuaternion::from_scaled_axis(Vector3::new(0.15, -0.2, 0.9)),
    );
    let (t0, r0) = pose_error(&Isometry3::identity(), &start);
    println!("start: {:.0} mm and {:.1} deg from the reference pose", t0 * 1e3, r0.to_degrees());
    let mut pose = start;
    let (status, reason) = loop {
        let pixels = view(&object, &pose, &k, &mut noise)?;
        let step = servo.step(&pixels, None, None)?;
        if let Verdict::Stop { status, reason, .. } = step.verdict {
            break (status, reason);
        }
        pose *= exp_twist(&(step.twist * config.dt).into())?; // the robot moves for one period
    };
    let (t, r) = pose_error(&Isometry3::identity(), &pose);
    println!(
        "servo session: {} after {} iterations ({reason}); final error {:.3} mm, {:.4} deg",
        status.as_str(),
        servo.iterations(),
        t * 1e3,
        r.to_degrees()
    );
    let Some(c) = servo.certainty() else {
        return Err(vsinv::Error::InvalidParameter { name: "example", reason: "no pose uncertainty".into() });
    };
    let (bt, br) = c.bound;
    println!(
        "  the images allowed {:.3} mm, {:.4} deg (pixel noise {:.3} px)",
        bt * 1e3,
        br.to_degrees(),
        c.pixel_sigma
    );
    if status != Status::Converged || t > bt || r > br {
        return Err(vsinv::Error::InvalidParameter { name: "example", reason: "the session did not converge".into() });
    }
    Ok(())
}
