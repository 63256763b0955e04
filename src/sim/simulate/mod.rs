//! The world loop of a run: observe the scene with K(t) (exact projections with noise, or
//! rendered images and a dot tracker), hand the points to a [`Servo`], move the robot with
//! its twist, record. Everything a real loop also needs (stop rules, depths, the planned
//! path, the law) is the servo session's; the simulator keeps what only it knows: the
//! scene, the true pose and depths, the robot, Prop. 3's figures.

mod pixel_noise;
mod prop3;
mod run;

use nalgebra::Isometry3;

use crate::core::distortion::undistort_point;
use crate::error::{Error, check_positive};
use crate::servo::{Servo, ServoConfig, ServoDepths, ServoReference, StopRule};
use crate::sim::camera_model::CameraModel;
use crate::sim::config::SimulationConfig;
use crate::sim::depth_source::DepthSource;
use crate::sim::error::Result;
use crate::sim::image_loop::{ImageLoop, pixel_size};
use crate::sim::outcome::Outcome;
use crate::sim::scene::Observation;
use crate::vision::render::Renderer;

use self::pixel_noise::PixelNoise;
use self::run::Run;

/// Runs a simulation. `progress(done, max)` is called every few iterations; returning false
/// stops the run (its status is then `max_iterations`).
pub fn simulate(config: &SimulationConfig, progress: &mut dyn FnMut(usize, usize) -> bool) -> Result<Outcome> {
    validate(config)?;
    let (reference, reference_depths, renderer) = take_reference_image(config)?;
    let mut run = Run::new(config, reference, reference_depths, renderer)?;
    let end = loop {
        if let Some(end) = run.iterate(progress)? {
            break end;
        }
    };
    Ok(run.finish(end))
}

/// Checks what the scenario schema cannot (a config may also be built in code).
fn validate(config: &SimulationConfig) -> Result<()> {
    check_positive("dt", config.dt)?;
    config.reference_camera.validate()?;
    config.camera.validate()?;
    if !(config.noise.pixel_sigma.is_finite() && config.noise.pixel_sigma >= 0.0) {
        return Err(
            Error::InvalidParameter { name: "noise.pixel_sigma", reason: "must be finite and >= 0".into() }.into()
        );
    }
    config.stop.validate()?;
    config.robot.check_reachable(&config.start)?;
    // The points the law needs are the law's to check (when the servo session starts).
    Ok(())
}

/// The observation of the reference image, its depths zeta* and the run's renderer.
type Reference = (Observation, Vec<f64>, Option<Renderer>);

/// The reference image, taken at F* with K*: every point must be in view. Returns the
/// observation (pixels still noise-free), the reference depths zeta* and the renderer of the
/// `[vision]` table (one for the run: the reference image and every image of the loop).
fn take_reference_image(config: &SimulationConfig) -> Result<Reference> {
    let camera = &config.reference_camera;
    let k_star = camera.at(0.0)?;
    let mut obs = Observation::default();
    config.scene.observe_through(&Isometry3::identity(), &k_star, &camera.distortion, camera.image, &mut obs);
    let n = obs.depths.len();
    if let Some(i) = (0..n).find(|&i| obs.depths[i] <= 0.0) {
        return Err(Error::PointBehindCamera { index: i, depth: obs.depths[i] }.into());
    }
    if let Some(i) = (0..n).find(|&i| !obs.visible[i]) {
        return Err(Error::InvalidParameter {
            name: "object",
            reason: format!(
                "point {i} is not visible in the reference image: outside the reference_camera's image \
                 or occluded (check object.points[{i}] and the reference_camera table)"
            ),
        }
        .into());
    }
    let renderer = config.vision.map(Renderer::new).transpose()?;
    if let Some(renderer) = &renderer {
        let size = pixel_size(config.reference_camera.image, "reference_camera")?;
        ImageLoop::reference(renderer, &config.scene, &k_star, &camera.distortion, size, &mut obs)?;
    }
    let depths = obs.depths.clone();
    Ok((obs, depths, renderer))
}

/// The reference pixels as the servo takes them: with the reference image's noise, through
/// the reference camera's own calibration (pinhole pixels of K*).
fn reference_pixels(config: &SimulationConfig, obs: &mut Observation, noise: &mut PixelNoise) -> Result<Vec<[f64; 2]>> {
    let mut pixels = std::mem::take(&mut obs.pixels);
    if config.noise.on_reference {
        noise.add(&mut pixels, &obs.visible);
    }
    undistort_reference(&mut pixels, &config.reference_camera)?;
    Ok(pixels)
}

/// The reference image's points through its own calibration: pinhole pixels of K*.
fn undistort_reference(pixels: &mut [[f64; 2]], camera: &CameraModel) -> Result<()> {
    for (i, p) in pixels.iter_mut().enumerate() {
        *p = undistort_point(*p, &camera.intrinsics, &camera.distortion).map_err(|e| Error::InvalidParameter {
            name: "reference_camera.distortion",
            reason: format!("point {i} of the reference image cannot be undistorted: {e}"),
        })?;
    }
    Ok(())
}

/// The servo session of a run: the scenario's law, K_hat, stop rules and path; the pixel
/// rule when both images come from one camera (K = K* throughout), else the law's own.
fn start_servo(config: &SimulationConfig, pixels: Vec<[f64; 2]>, reference_depths: &[f64]) -> Result<Servo> {
    let same_camera = config.camera.zoom.is_none() && config.camera.intrinsics == config.reference_camera.intrinsics;
    let servo_config = ServoConfig {
        law: config.law,
        k_hat: config.estimate,
        distortion: config.estimate_distortion,
        basis: config.basis,
        basis_hold: crate::servo::session::BASIS_HOLD_IMAGES,
        basis_inset: 0,
        stop: config.stop,
        stop_rule: same_camera.then_some(StopRule::Pixel),
        path: config.path,
        dt: config.dt,
    };
    let depths = match &config.depths {
        DepthSource::True => ServoDepths::PerStep,
        DepthSource::Reference => ServoDepths::Reference,
        DepthSource::Estimated(factory) => ServoDepths::Estimated(factory.start(&config.scene, &pixels)?),
    };
    let reference = ServoReference { pixels, depths: Some(reference_depths.to_vec()) };
    Ok(Servo::new(servo_config, reference, depths)?)
}
