//! Images in the loop (a scenario's `[vision]` table): the simulator renders what each camera
//! sees, detects the reference dots, initialises a tracker from the start image (the user's
//! clicks, seeded with the projected points) and feeds the tracked centroids, with `found`
//! as visibility, to the control law. Detection errors are measured against the true
//! projections of the dots' centres.

use nalgebra::Isometry3;

use crate::core::camera::Intrinsics;
use crate::core::distortion::Distortion;
use crate::error::{Error, Result};
use crate::sim::scene::{ImageSize, Observation, Scene};
use crate::vision::GreyImage;
use crate::vision::render::{CameraView, Disc, RenderConfig, Renderer};
use crate::vision::tracker::{DotTracker, TrackerConfig};

/// The image size of a camera, which vision needs.
pub(crate) fn pixel_size(image: Option<ImageSize>, key: &'static str) -> Result<(u32, u32)> {
    let s = image.ok_or(Error::InvalidParameter { name: key, reason: "[vision] needs width and height".into() })?;
    Ok((s.width.ceil() as u32, s.height.ceil() as u32))
}

/// The dots of a scene: discs of `radius` at its points, with its normals (default: facing
/// the reference camera).
pub(crate) fn scene_discs(scene: &Scene, radius: f64) -> Result<Vec<Disc>> {
    let points = scene.points().iter();
    match scene.normals() {
        Some(normals) => points.zip(normals).map(|(&p, &n)| Disc::new(p, n, radius)).collect(),
        None => points.map(|&p| Disc::facing_reference(p, radius)).collect(),
    }
}

/// What tracking gives the run, per point.
pub(crate) struct Tracked<'a> {
    pub(crate) pixels: &'a mut [[f64; 2]],
    pub(crate) visible: &'a mut [bool],
    pub(crate) detection: &'a mut [f64],
}

/// Rendering and tracking through a run.
pub(crate) struct ImageLoop {
    renderer: Renderer,
    discs: Vec<Disc>,
    size: (u32, u32),
    tracker: Option<DotTracker>,
    frame: u64,
    /// Every detection error of a found point, pixels.
    pub(crate) errors: Vec<f64>,
}

impl ImageLoop {
    pub(crate) fn new(config: RenderConfig, scene: &Scene, size: (u32, u32)) -> Result<Self> {
        Ok(Self {
            discs: scene_discs(scene, config.dot_radius)?,
            renderer: Renderer::new(config)?,
            size,
            tracker: None,
            frame: 0,
            errors: Vec::new(),
        })
    }

    /// The reference image rendered with K* at F*, its dots detected around their projected
    /// positions: the reference pixels become the detected centroids.
    pub(crate) fn reference(
        config: RenderConfig,
        scene: &Scene,
        k_star: &Intrinsics,
        distortion: &Distortion,
        size: (u32, u32),
        obs: &mut Observation,
    ) -> Result<GreyImage> {
        let renderer = Renderer::new(config)?;
        let view = CameraView { pose: &Isometry3::identity(), intrinsics: k_star, distortion, size };
        let rendered =
            renderer.render_through(&scene_discs(scene, config.dot_radius)?, Some(&obs.visible), &view, 0)?;
        let tracker =
            DotTracker::new(&rendered.image, &obs.pixels, TrackerConfig::default()).map_err(|e| reference_error(&e))?;
        obs.pixels.copy_from_slice(tracker.positions());
        Ok(rendered.image)
    }

    /// Renders the current image with K(t) at `pose` and tracks the dots (initialising the
    /// tracker from the first image); `run` gets the tracked pixels, `found && visible` as
    /// visibility and each point's detection error (NaN if not found).
    pub(crate) fn observe(
        &mut self,
        pose: &Isometry3<f64>,
        k: &Intrinsics,
        distortion: &Distortion,
        obs: &Observation,
        run: Tracked<'_>,
    ) -> Result<()> {
        self.frame += 1;
        let view = CameraView { pose, intrinsics: k, distortion, size: self.size };
        let rendered = self.renderer.render_through(&self.discs, Some(&obs.visible), &view, self.frame)?;
        let tracker = match self.tracker.as_mut() {
            Some(t) => t,
            None => self.tracker.insert(DotTracker::new(&rendered.image, &obs.pixels, TrackerConfig::default())?),
        };
        let tracked = tracker.track(&rendered.image)?;
        for i in 0..run.pixels.len() {
            run.visible[i] = obs.visible[i] && tracked.found[i];
            run.pixels[i] = tracked.pixels[i];
            run.detection[i] = if run.visible[i] {
                let e = (run.pixels[i][0] - obs.pixels[i][0]).hypot(run.pixels[i][1] - obs.pixels[i][1]);
                self.errors.push(e);
                e
            } else {
                f64::NAN
            };
        }
        Ok(())
    }

    /// The median and largest detection error of the found points, pixels (NaN if none).
    pub(crate) fn error_summary(&self) -> (f64, f64) {
        if self.errors.is_empty() {
            return (f64::NAN, f64::NAN);
        }
        let mut sorted = self.errors.clone();
        sorted.sort_by(f64::total_cmp);
        let n = sorted.len();
        let median = if n % 2 == 1 { sorted[n / 2] } else { 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]) };
        (median, sorted[n - 1])
    }
}

fn reference_error(e: &Error) -> Error {
    Error::InvalidParameter { name: "vision", reason: format!("the reference image's dots cannot be detected: {e}") }
}
