//! `[vision]` limits checked when a scenario loads, not found by the run (issue 28, finding
//! 6): each camera's image within what the renderer and detectors take, and each tag of a
//! rig large enough in the reference image to be read (a 1e-9 m tag was refused by the run as
//! "the reference image's dots cannot be detected").

use nalgebra::Point3;

use crate::core::camera::Intrinsics;
use crate::error::Short;
use crate::sim::camera_model::CameraModel;
use crate::sim::error::Result;
use crate::sim::scenario::scenario_error;
use crate::vision::TagRig;
use crate::vision::render::MAX_RENDER_PIXELS;

/// The shortest side a tag's black square may have in the reference image, pixels: one pixel
/// per cell of its 8 x 8 cells (tag36h11; a smaller tag cannot be decoded).
pub const MIN_TAG_SIDE_PIXELS: f64 = 8.0;

/// The camera table `key`'s image (rendered in the loop) has at most [`MAX_RENDER_PIXELS`].
pub(super) fn check_image_pixels(key: &str, model: &CameraModel) -> Result<()> {
    let Some(size) = model.image else { return Ok(()) };
    let pixels = size.width * size.height;
    if pixels > MAX_RENDER_PIXELS as f64 {
        let reason = format!(
            "{key}.width x {key}.height = {} x {} = {pixels:e} pixels; images in the loop (rendered and read by the detectors) have at most {MAX_RENDER_PIXELS} (2^28)",
            size.width, size.height
        );
        return Err(scenario_error(&format!("{key}.width"), reason));
    }
    Ok(())
}

/// Each tag's shortest projected side in the reference image (K* at t = 0, the reference
/// pose is F*'s origin) is at least [`MIN_TAG_SIDE_PIXELS`].
pub(super) fn check_tags_readable(rig: &TagRig, reference: &Intrinsics) -> Result<()> {
    for (i, tag) in rig.tags().iter().enumerate() {
        let mut pixels = [[0.0; 2]; 4];
        for (px, c) in pixels.iter_mut().zip(tag.corners()) {
            // Behind the camera: the scene's own check names it.
            let Ok((p, _)) = reference.project(&Point3::from(c)) else { return Ok(()) };
            *px = p;
        }
        let side = (0..4)
            .map(|j| {
                let (a, b) = (pixels[j], pixels[(j + 1) % 4]);
                (a[0] - b[0]).hypot(a[1] - b[1])
            })
            .fold(f64::INFINITY, f64::min);
        if !(side >= MIN_TAG_SIDE_PIXELS) {
            let reason = format!(
                "a tag of {} m spans {} px in the reference image: at least {MIN_TAG_SIDE_PIXELS} px (one per cell) are needed to read it",
                Short(tag.size),
                Short(side)
            );
            return Err(scenario_error(&format!("object.tags[{i}].size"), reason));
        }
    }
    Ok(())
}
