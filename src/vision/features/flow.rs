//! Frame-to-frame tracks: pyramidal Lucas-Kanade (kornia-rs) forward, then backward from
//! where it landed; a track is kept when it comes back within [`FlowConfig::forward_backward`]
//! pixels of where it started (Kalal et al.'s forward-backward error), else it is lost.

use kornia_image::{Image, ImageSize};
use kornia_imgproc::optical_flow_pyr_lk::{
    BorderMode, PyrLKError, PyrLKParams, PyrLKPrecomputed, PyrLKResult, calc_optical_flow_pyr_lk_with_precomputed,
};

use crate::vision::error::{Result, VisionError};
use crate::vision::features::pyramid::{Plane, pyrdown_into, scharr_into};
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
/// `pyrdown_f32` and `scharr_spatial_gradient_float`, bit for bit).
///
/// Each level (and its gradients) is then given a margin of its edge pixels repeated
/// (`margin`), so that every window of a point inside the image is inside the padded level:
/// kornia samples a window that crosses a level's edge one pixel at a time through its
/// border mode (`sample_at`, most of a frame's time at 640 x 480, where a level-3 window
/// crosses the edge for half of the image's points), and an inside one with its vectorised
/// kernels. The repeated edge is what the border mode `Clamp` reads there, so the tracks are
/// kornia's up to the rounding of the shifted coordinates (f32).
pub struct FramePyramid {
    image: Image<f32, 1>,
    levels: Vec<Image<f32, 1>>,
    grad_x: Vec<Image<f32, 1>>,
    grad_y: Vec<Image<f32, 1>>,
}

impl std::fmt::Debug for FramePyramid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FramePyramid").field("levels", &self.levels.len()).finish()
    }
}

/// kornia's LK window's half side plus the bilinear's second pixel: a window centred at least
/// this far inside a level is read by the vectorised kernels (`is_interior_for_lk`).
const WINDOW_REACH: usize = 11;

/// Level `level`'s margin in a pyramid of `levels` levels above the image: one shift of the
/// points at level 0 ([`FramePyramid::shift`]) is `margin(levels, l)` at every level `l`, and
/// the coarsest level's is [`WINDOW_REACH`].
fn margin(levels: usize, level: usize) -> usize {
    WINDOW_REACH << (levels - level)
}

/// The margin of the plane `p` of `buffer` (`m` pixels on each side) filled with its edge
/// pixels repeated (the border mode `Clamp`).
fn fill_margin(buffer: &mut [f32], p: Plane, m: usize) {
    for r in m..m + p.height {
        let row = &mut buffer[r * p.stride..(r + 1) * p.stride];
        let (first, last) = (row[m], row[m + p.width - 1]);
        row[..m].fill(first);
        row[m + p.width..].fill(last);
    }
    for r in 0..m {
        buffer.copy_within(m * p.stride..(m + 1) * p.stride, r * p.stride);
        let bottom = m + p.height - 1;
        buffer.copy_within(bottom * p.stride..(bottom + 1) * p.stride, (bottom + 1 + r) * p.stride);
    }
}

/// `image` copied into the plane `p` of `buffer` (its size).
fn copy_into(image: &Image<f32, 1>, buffer: &mut [f32], p: Plane) {
    for (r, row) in image.as_slice().chunks_exact(p.width).enumerate() {
        buffer[p.offset + r * p.stride..][..p.width].copy_from_slice(row);
    }
}

/// A buffer of `len` values from `pool` (a spare pyramid's), or a new one. A spare buffer
/// keeps its old values: every value of a level and of its gradients is written (the plane by
/// its filter, the margin by [`fill_margin`]), so it is not cleared first.
fn take(pool: &mut Vec<Vec<f32>>, len: usize) -> Vec<f32> {
    let mut buffer = pool.pop().unwrap_or_default();
    buffer.resize(len, 0.0);
    buffer
}

impl FramePyramid {
    /// The pyramid of `image` with `levels` levels above it, and its gradients.
    pub fn new(image: &Image<f32, 1>, levels: usize) -> Result<Self> {
        Self::of(image.clone(), levels, None)
    }

    /// [`FramePyramid::new`] of an image given away (not copied), in the buffers of `spare` (a
    /// pyramid done with: no fresh memory a frame). The filters are kornia's, computed by
    /// [`pyramid`](crate::vision::features::pyramid) (the same bits, faster), each level's
    /// straight into its place inside its margin.
    pub fn of(image: Image<f32, 1>, levels: usize, spare: Option<FramePyramid>) -> Result<Self> {
        let error =
            |e: kornia_image::ImageError| VisionError::InvalidImage { what: "image".into(), reason: e.to_string() };
        let (mut w, mut h) = (image.width(), image.height());
        if w == 0 || h == 0 {
            return Err(VisionError::InvalidImage { what: "image".into(), reason: "empty".into() });
        }
        let mut pool: Vec<Vec<f32>> = spare.map(FramePyramid::into_buffers).unwrap_or_default();
        pool.reverse();
        let (mut pyramid, mut grad_x, mut grad_y): (Vec<Image<f32, 1>>, Vec<_>, Vec<_>) =
            (Vec::new(), Vec::new(), Vec::new());
        let mut above: Option<Plane> = None;
        for l in 0..=levels {
            let m = margin(levels, l);
            let stride = w + 2 * m;
            let plane = Plane { width: w, height: h, stride, offset: m * stride + m };
            let len = stride * (h + 2 * m);
            let mut level = take(&mut pool, len);
            match (above, pyramid.last()) {
                (Some(from), Some(buffer)) => pyrdown_into(buffer.as_slice(), from, &mut level, plane),
                _ => copy_into(&image, &mut level, plane),
            }
            let (mut gx, mut gy) = (take(&mut pool, len), take(&mut pool, len));
            scharr_into(&level, plane, &mut gx, &mut gy, plane);
            for buffer in [&mut level, &mut gx, &mut gy] {
                fill_margin(buffer, plane, m);
            }
            let size = ImageSize { width: stride, height: h + 2 * m };
            pyramid.push(Image::new(size, level).map_err(error)?);
            grad_x.push(Image::new(size, gx).map_err(error)?);
            grad_y.push(Image::new(size, gy).map_err(error)?);
            above = Some(plane);
            (w, h) = (w.div_ceil(2), h.div_ceil(2));
        }
        Ok(Self { image, levels: pyramid, grad_x, grad_y })
    }

    /// The buffers, level by level (the level, then its gradients).
    fn into_buffers(self) -> Vec<Vec<f32>> {
        let mut out = Vec::with_capacity(3 * self.levels.len());
        for ((level, gx), gy) in self.levels.into_iter().zip(self.grad_x).zip(self.grad_y) {
            out.extend([level.into_vec(), gx.into_vec(), gy.into_vec()]);
        }
        out
    }

    /// The image (level 0, without its margin).
    pub fn image(&self) -> &Image<f32, 1> {
        &self.image
    }

    /// Levels above the image.
    pub fn depth(&self) -> usize {
        self.levels.len() - 1
    }

    /// Level 0's margin: a point's shift from the image into the padded levels.
    fn shift(&self) -> f32 {
        margin(self.depth(), 0) as f32
    }
}

/// LK from `from` to `to` at `start` (image pixels), the two padded pyramids lent to kornia's
/// precomputed form (moved in and back, not copied); the points shifted into the padded
/// levels and back.
fn lk(
    from: &mut FramePyramid,
    to: &mut FramePyramid,
    start: &[[f32; 2]],
    params: &PyrLKParams,
) -> std::result::Result<PyrLKResult, PyrLKError> {
    let shift = from.shift();
    let shifted: Vec<[f32; 2]> = start.iter().map(|&[u, v]| [u + shift, v + shift]).collect();
    let lent = PyrLKPrecomputed {
        prev_pyr: std::mem::take(&mut from.levels),
        next_pyr: std::mem::take(&mut to.levels),
        grad_x_pyr: std::mem::take(&mut from.grad_x),
        grad_y_pyr: std::mem::take(&mut from.grad_y),
    };
    let result = calc_optical_flow_pyr_lk_with_precomputed(&lent, &shifted, None, params);
    (from.levels, to.levels, from.grad_x, from.grad_y) =
        (lent.prev_pyr, lent.next_pyr, lent.grad_x_pyr, lent.grad_y_pyr);
    let mut result = result?;
    for p in &mut result.next_pts {
        *p = [p[0] - shift, p[1] - shift];
    }
    Ok(result)
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

    /// Each padded level is kornia's level (and gradients) bit for bit inside its margin, its
    /// edge repeated outside; built again in a spare pyramid's buffers, the same bits.
    #[test]
    fn padded_levels_are_kornias_with_their_edges_repeated() {
        use kornia_imgproc::filter::scharr_spatial_gradient_float;
        use kornia_imgproc::optical_flow_pyr_lk::build_lk_precomputed;
        let (frame, other) = (texture(53, 37, 0.4, 0.0), texture(53, 37, 0.0, 0.0));
        let direct = build_lk_precomputed(&frame, &frame, 3).unwrap();
        let spare = FramePyramid::new(&other, 3).unwrap();
        for pyramid in [FramePyramid::new(&frame, 3).unwrap(), FramePyramid::of(frame.clone(), 3, Some(spare)).unwrap()]
        {
            for l in 0..=3 {
                let (want, m) = (&direct.prev_pyr[l], margin(3, l));
                let (mut ix, mut iy) =
                    (Image::from_size_val(want.size(), 0.0).unwrap(), Image::from_size_val(want.size(), 0.0).unwrap());
                scharr_spatial_gradient_float(want, &mut ix, &mut iy).unwrap();
                for (got, want) in [(&pyramid.levels[l], want), (&pyramid.grad_x[l], &ix), (&pyramid.grad_y[l], &iy)] {
                    let (w, h, stride) = (want.width(), want.height(), got.width());
                    assert_eq!((stride, got.height()), (w + 2 * m, h + 2 * m));
                    for r in 0..h + 2 * m {
                        for c in 0..stride {
                            let (y, x) = (r.clamp(m, m + h - 1) - m, c.clamp(m, m + w - 1) - m);
                            assert_eq!(got.as_slice()[r * stride + c].to_bits(), want.as_slice()[y * w + x].to_bits());
                        }
                    }
                }
            }
        }
    }

    /// The kept, padded pyramids give kornia's one-call tracks (forward and backward; to the
    /// rounding of the shifted f32 coordinates) over three frames where the middle one's
    /// pyramid serves twice, points near the edges included (their windows cross the edge of
    /// every level, where kornia reads the border mode pixel by pixel); the tracks land on the
    /// shift.
    #[test]
    fn kept_pyramids_track_as_kornias_one_call_api() {
        let frames = [texture(160, 120, 0.0, 0.0), texture(160, 120, 2.3, -1.4), texture(160, 120, 4.1, -0.2)];
        let config = FlowConfig::default();
        let params = PyrLKParams { max_level: config.levels, border_mode: BorderMode::Clamp, ..PyrLKParams::default() };
        let mut pyramids: Vec<FramePyramid> =
            frames.iter().map(|f| FramePyramid::new(f, config.levels).unwrap()).collect();
        let start = vec![[60.0f32, 50.0], [90.5, 70.25], [40.0, 80.0], [3.0, 4.5], [155.5, 117.0], [80.0, 1.0]];
        let close = |a: &[[f32; 2]], b: &[[f32; 2]]| {
            a.iter().zip(b).all(|(p, q)| (p[0] - q[0]).abs() < 2e-3 && (p[1] - q[1]).abs() < 2e-3)
        };
        for k in 0..2 {
            let (a, b) = pyramids.split_at_mut(k + 1);
            let kept = lk(&mut a[k], &mut b[0], &start, &params).unwrap();
            let direct = calc_optical_flow_pyr_lk(&frames[k], &frames[k + 1], &start, None, &params).unwrap();
            assert!(close(&kept.next_pts, &direct.next_pts), "{:?} {:?}", kept.next_pts, direct.next_pts);
            assert_eq!(kept.status, direct.status);
            let back = lk(&mut b[0], &mut a[k], &kept.next_pts, &params).unwrap();
            let direct_back =
                calc_optical_flow_pyr_lk(&frames[k + 1], &frames[k], &direct.next_pts, None, &params).unwrap();
            assert!(close(&back.next_pts, &direct_back.next_pts), "{:?} {:?}", back.next_pts, direct_back.next_pts);
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
