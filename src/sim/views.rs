//! A scenario's views as images: what the reference camera sees at F*, or the servo camera at
//! a pose and time, rendered with the scenario's `[vision]` settings (the defaults of
//! [`RenderConfig`](crate::vision::render::RenderConfig) without that table), with the true projections of the target's points.
//! The image of the servo camera at `time` carries the sensor noise of the simulator's
//! image at that iteration, so a view can be compared with a run.

use nalgebra::Isometry3;

use crate::error::{Error, Short};
use crate::sim::config::SimulationConfig;
use crate::sim::error::Result;
use crate::sim::image_loop::{pixel_size, scene_vision};
use crate::sim::scene::Observation;
use crate::vision::{CameraView, GreyImage, Renderer};

/// Which camera takes the picture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shot {
    /// The reference camera K* (at F* unless a pose is given).
    Reference,
    /// The servo camera K(time) (at the start pose unless a pose is given).
    Servo {
        /// Seconds since the start, for a zoom.
        time: f64,
    },
}

/// A rendered view and what it shows.
#[derive(Debug, Clone, PartialEq)]
pub struct View {
    /// The 8-bit image, `(height, width)`.
    pub image: GreyImage,
    /// True projections of the dots' centres through the lens (NaN behind the camera).
    pub pixels: Vec<[f64; 2]>,
    /// Per point: in front of the camera, inside the image, not occluded and drawn.
    pub visible: Vec<bool>,
}

/// Renders the view of `shot` from `pose` (camera frame in F*; None: F* for the reference
/// camera, the start pose for the servo camera).
pub fn render_view(config: &SimulationConfig, shot: Shot, pose: Option<&Isometry3<f64>>) -> Result<View> {
    let (camera, key, default_pose, time, frame) = match shot {
        Shot::Reference => (&config.reference_camera, "reference_camera", Isometry3::identity(), 0.0, 0),
        Shot::Servo { time } => {
            if !(time.is_finite() && time >= 0.0) {
                return Err(Error::InvalidParameter {
                    name: "time",
                    reason: format!("must be >= 0 s, got {}", Short(time)),
                }
                .into());
            }
            // The simulator's image of iteration i is frame i + 1.
            let frame = (time / config.dt).round() as u64 + 1;
            (&config.camera, "camera", config.start, time, frame)
        }
    };
    let pose = pose.copied().unwrap_or(default_pose);
    let k = camera.at(time)?;
    let size = pixel_size(camera.image, key)?;
    let mut obs = Observation::default();
    config.scene.observe_through(&pose, &k, &camera.distortion, camera.image, &mut obs);
    let vision = config.vision.unwrap_or_default();
    let target = scene_vision(&config.scene, &vision)?.target;
    let view = CameraView { pose: &pose, intrinsics: &k, distortion: &camera.distortion, size };
    let rendered = Renderer::new(vision)?.render(&*target, Some(&obs.visible), &view, frame)?;
    let visible = obs.visible.iter().zip(&rendered.drawn).map(|(&v, &d)| v && d).collect();
    Ok(View { image: rendered.image, pixels: obs.pixels, visible })
}
