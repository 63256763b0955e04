//! Frame-to-frame tracks: pyramidal Lucas-Kanade (kornia-rs) forward, then backward from
//! where it landed; a track is kept when it comes back within [`FlowConfig::forward_backward`]
//! pixels of where it started (Kalal et al.'s forward-backward error), else it is lost.

use kornia_image::{Image, ImageSize};
use kornia_imgproc::optical_flow_pyr_lk::{
    BorderMode, PyrLKParams, build_lk_precomputed, calc_optical_flow_pyr_lk_with_precomputed,
};

use crate::vision::error::{Result, VisionError};
use crate::vision::image::GreyView;

/// The tracker's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlowConfig {
    /// Pyramid levels above the image (3: motions up to about 80 pixels between frames).
    pub levels: usize,
    /// The largest forward-backward error kept, pixels.
    pub forward_backward: f64,
}

impl Default for FlowConfig {
    fn default() -> Self {
        Self { levels: 3, forward_backward: 0.5 }
    }
}

/// An image as kornia's `f32` plane (grey levels 0..255).
pub fn plane(what: &str, image: &GreyView<'_>) -> Result<Image<f32, 1>> {
    let (w, h) = (image.width() as usize, image.height() as usize);
    let data: Vec<f32> = image.as_raw().iter().take(w * h).map(|&v| f32::from(v)).collect();
    Image::new(ImageSize { width: w, height: h }, data)
        .map_err(|e| VisionError::InvalidImage { what: what.into(), reason: e.to_string() })
}

/// Where each of `points` (pixels in `previous`) is in `next`: None where LK fails either
/// way, the forward-backward error exceeds the bound, or the point starts or lands outside
/// the image.
pub fn track(
    previous: &Image<f32, 1>,
    next: &Image<f32, 1>,
    points: &[[f64; 2]],
    config: &FlowConfig,
) -> Result<Vec<Option<[f64; 2]>>> {
    // Points outside the image (or not finite) are not tracked: not found.
    let (w, h) = (previous.width() as f64, previous.height() as f64);
    let inside: Vec<usize> = (0..points.len())
        .filter(|&i| (0.0..=w - 1.0).contains(&points[i][0]) && (0.0..=h - 1.0).contains(&points[i][1]))
        .collect();
    let mut out = vec![None; points.len()];
    let kept: Vec<[f64; 2]> = inside.iter().map(|&i| points[i]).collect();
    for (i, p) in inside.into_iter().zip(track_inside(previous, next, &kept, config)?) {
        out[i] = p;
    }
    Ok(out)
}

/// [`track`] of points inside the image.
fn track_inside(
    previous: &Image<f32, 1>,
    next: &Image<f32, 1>,
    points: &[[f64; 2]],
    config: &FlowConfig,
) -> Result<Vec<Option<[f64; 2]>>> {
    if points.is_empty() {
        return Ok(Vec::new());
    }
    let params = PyrLKParams { max_level: config.levels, border_mode: BorderMode::Clamp, ..PyrLKParams::default() };
    let start: Vec<[f32; 2]> = points.iter().map(|&[u, v]| [u as f32, v as f32]).collect();
    let flow_error = |e: kornia_imgproc::optical_flow_pyr_lk::PyrLKError| VisionError::InvalidImage {
        what: "image".into(),
        reason: format!("cannot track: {e}"),
    };
    let run = || -> Result<_> {
        let forward = build_lk_precomputed(previous, next, config.levels).map_err(flow_error)?;
        let there = calc_optical_flow_pyr_lk_with_precomputed(&forward, &start, None, &params).map_err(flow_error)?;
        let backward = build_lk_precomputed(next, previous, config.levels).map_err(flow_error)?;
        let back =
            calc_optical_flow_pyr_lk_with_precomputed(&backward, &there.next_pts, None, &params).map_err(flow_error)?;
        Ok((there, back))
    };
    let (there, back) = crate::parallel::install(run)??;
    let bound = config.forward_backward;
    let (width, height) = (next.width() as f64, next.height() as f64);
    Ok((0..points.len())
        .map(|i| {
            let ok = there.status.get(i) == Some(&1) && back.status.get(i) == Some(&1);
            let [u, v] = there.next_pts.get(i).copied().unwrap_or([f32::NAN; 2]);
            let [bu, bv] = back.next_pts.get(i).copied().unwrap_or([f32::NAN; 2]);
            let error = (f64::from(bu) - points[i][0]).hypot(f64::from(bv) - points[i][1]);
            let (u, v) = (f64::from(u), f64::from(v));
            let landed = (0.0..=width - 1.0).contains(&u) && (0.0..=height - 1.0).contains(&v);
            (ok && error <= bound && landed).then_some([u, v])
        })
        .collect())
}
