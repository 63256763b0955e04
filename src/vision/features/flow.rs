//! Frame-to-frame tracks: pyramidal Lucas-Kanade (kornia-rs) forward, then backward from
//! where it landed; a track is kept when it comes back within [`FlowConfig::forward_backward`]
//! pixels of where it started (Kalal et al.'s forward-backward error), else it is lost.

use kornia_image::{Image, ImageSize};
use kornia_imgproc::optical_flow_pyr_lk::{
    BorderMode, PyrLKError, PyrLKParams, PyrLKPrecomputed, PyrLKResult, calc_optical_flow_pyr_lk_with_precomputed,
};

use crate::vision::error::{Result, VisionError};
use crate::vision::features::pyramid::{pyrdown, scharr};
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

/// One frame's Gaussian pyramid and the Scharr gradients of its levels: what pyramidal LK
/// needs of an image, built once per frame and used by the tracks to it (as `next`) and from
/// it (as `previous`, forward and backward), where kornia's one-call API rebuilds both
/// frames' pyramids at every call (four pyramids and two gradient sets per forward-backward
/// pair instead of one of each). The levels are kornia's own (`build_lk_precomputed`'s
/// `pyrdown_f32` and `scharr_spatial_gradient_float`, bit for bit), so the tracks are the same.
pub struct FramePyramid {
    levels: Vec<Image<f32, 1>>,
    grad_x: Vec<Image<f32, 1>>,
    grad_y: Vec<Image<f32, 1>>,
}

impl std::fmt::Debug for FramePyramid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FramePyramid").field("levels", &self.levels.len()).finish()
    }
}

impl FramePyramid {
    /// The pyramid of `image` with `levels` levels above it, and its gradients.
    pub fn new(image: &Image<f32, 1>, levels: usize) -> Result<Self> {
        Self::of(image.clone(), levels)
    }

    /// [`FramePyramid::new`] of an image given away (not copied). The filters are kornia's,
    /// computed by [`pyramid`](crate::vision::features::pyramid) (the same bits, faster).
    pub fn of(image: Image<f32, 1>, levels: usize) -> Result<Self> {
        let error =
            |e: kornia_image::ImageError| VisionError::InvalidImage { what: "image".into(), reason: e.to_string() };
        let mut pyramid = Vec::with_capacity(levels + 1);
        pyramid.push(image);
        for l in 1..=levels {
            pyramid.push(pyrdown(&pyramid[l - 1]).map_err(error)?);
        }
        let (mut grad_x, mut grad_y) = (Vec::with_capacity(levels + 1), Vec::with_capacity(levels + 1));
        for level in &pyramid {
            let (ix, iy) = scharr(level).map_err(error)?;
            grad_x.push(ix);
            grad_y.push(iy);
        }
        Ok(Self { levels: pyramid, grad_x, grad_y })
    }

    /// The image (level 0).
    pub fn image(&self) -> &Image<f32, 1> {
        &self.levels[0]
    }

    /// Levels above the image.
    pub fn depth(&self) -> usize {
        self.levels.len() - 1
    }
}

/// LK from `from` to `to` at `start`, the two pyramids lent to kornia's precomputed form
/// (moved in and back, not copied).
fn lk(
    from: &mut FramePyramid,
    to: &mut FramePyramid,
    start: &[[f32; 2]],
    params: &PyrLKParams,
) -> std::result::Result<PyrLKResult, PyrLKError> {
    let lent = PyrLKPrecomputed {
        prev_pyr: std::mem::take(&mut from.levels),
        next_pyr: std::mem::take(&mut to.levels),
        grad_x_pyr: std::mem::take(&mut from.grad_x),
        grad_y_pyr: std::mem::take(&mut from.grad_y),
    };
    let result = calc_optical_flow_pyr_lk_with_precomputed(&lent, start, None, params);
    (from.levels, to.levels, from.grad_x, from.grad_y) =
        (lent.prev_pyr, lent.next_pyr, lent.grad_x_pyr, lent.grad_y_pyr);
    result
}

/// Where each of `points` (pixels in `previous`) is in `next`: None where LK fails either
/// way, the forward-backward error exceeds the bound, or the point starts or lands outside
/// the image. Builds both pyramids; a loop over frames keeps them ([`track_pyramids`]).
pub fn track(
    previous: &Image<f32, 1>,
    next: &Image<f32, 1>,
    points: &[[f64; 2]],
    config: &FlowConfig,
) -> Result<Vec<Option<[f64; 2]>>> {
    if previous.size() != next.size() {
        let reason = format!("the two images differ in size: {:?} and {:?}", previous.size(), next.size());
        return Err(VisionError::InvalidImage { what: "next_image".into(), reason });
    }
    let mut from = FramePyramid::new(previous, config.levels)?;
    let mut to = FramePyramid::new(next, config.levels)?;
    track_pyramids(&mut from, &mut to, points, config)
}

/// [`track`] between two frames' pyramids (built with `config.levels` levels, of one size).
pub fn track_pyramids(
    previous: &mut FramePyramid,
    next: &mut FramePyramid,
    points: &[[f64; 2]],
    config: &FlowConfig,
) -> Result<Vec<Option<[f64; 2]>>> {
    // Points outside the image (or not finite) are not tracked: not found.
    let (w, h) = (previous.image().width() as f64, previous.image().height() as f64);
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

/// [`track_pyramids`] of points inside the image.
fn track_inside(
    previous: &mut FramePyramid,
    next: &mut FramePyramid,
    points: &[[f64; 2]],
    config: &FlowConfig,
) -> Result<Vec<Option<[f64; 2]>>> {
    if points.is_empty() {
        return Ok(Vec::new());
    }
    let params = PyrLKParams { max_level: config.levels, border_mode: BorderMode::Clamp, ..PyrLKParams::default() };
    let start: Vec<[f32; 2]> = points.iter().map(|&[u, v]| [u as f32, v as f32]).collect();
    let flow_error =
        |e: PyrLKError| VisionError::InvalidImage { what: "image".into(), reason: format!("cannot track: {e}") };
    let run = || -> Result<_> {
        let there = lk(previous, next, &start, &params).map_err(flow_error)?;
        let back = lk(next, previous, &there.next_pts, &params).map_err(flow_error)?;
        Ok((there, back))
    };
    let (there, back) = crate::parallel::install(run)??;
    let bound = config.forward_backward;
    let (width, height) = (next.image().width() as f64, next.image().height() as f64);
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

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use kornia_imgproc::optical_flow_pyr_lk::calc_optical_flow_pyr_lk;

    use super::*;

    fn texture(w: usize, h: usize, dx: f64, dy: f64) -> Image<f32, 1> {
        let f = |x: f64, y: f64| {
            120.0 + 50.0 * (0.21 * x + 0.05 * y).sin() * (0.17 * y - 0.03 * x).cos() + 30.0 * (0.09 * x).cos()
        };
        let data = (0..h).flat_map(|v| (0..w).map(move |u| f(u as f64 - dx, v as f64 - dy) as f32)).collect();
        Image::new(ImageSize { width: w, height: h }, data).unwrap()
    }

    /// The kept pyramids give kornia's one-call tracks exactly (forward and backward), over
    /// three frames where the middle one's pyramid serves twice; the tracks land on the shift.
    #[test]
    fn kept_pyramids_track_as_kornias_one_call_api() {
        let frames = [texture(160, 120, 0.0, 0.0), texture(160, 120, 2.3, -1.4), texture(160, 120, 4.1, -0.2)];
        let config = FlowConfig::default();
        let params = PyrLKParams { max_level: config.levels, border_mode: BorderMode::Clamp, ..PyrLKParams::default() };
        let mut pyramids: Vec<FramePyramid> =
            frames.iter().map(|f| FramePyramid::new(f, config.levels).unwrap()).collect();
        let start = vec![[60.0f32, 50.0], [90.5, 70.25], [40.0, 80.0]];
        for k in 0..2 {
            let (a, b) = pyramids.split_at_mut(k + 1);
            let kept = lk(&mut a[k], &mut b[0], &start, &params).unwrap();
            let direct = calc_optical_flow_pyr_lk(&frames[k], &frames[k + 1], &start, None, &params).unwrap();
            assert_eq!(kept.next_pts, direct.next_pts);
            assert_eq!(kept.status, direct.status);
            let back = lk(&mut b[0], &mut a[k], &kept.next_pts, &params).unwrap();
            let direct_back =
                calc_optical_flow_pyr_lk(&frames[k + 1], &frames[k], &kept.next_pts, None, &params).unwrap();
            assert_eq!(back.next_pts, direct_back.next_pts);
        }
        let points = [[60.0, 50.0], [90.5, 70.25]];
        let (a, b) = pyramids.split_at_mut(1);
        let tracked = track_pyramids(&mut a[0], &mut b[0], &points, &config).unwrap();
        for (p, t) in points.iter().zip(&tracked) {
            let t = t.expect("tracked");
            assert!((t[0] - p[0] - 2.3).abs() < 0.05 && (t[1] - p[1] + 1.4).abs() < 0.05, "{t:?}");
        }
    }
}
