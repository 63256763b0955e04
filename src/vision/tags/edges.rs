//! Subpixel corners from the black square's four outer edges, and the check that a decoded
//! tag's corners are where its edges are.
//!
//! The quad fit of the AprilTag detector reads whole pixels along each edge's normal, so its
//! corners carry a bias of a quarter to a third of a pixel that changes with the pose, and now
//! and then one corner lands several pixels off along an edge while the code still decodes
//! (a thin quiet zone seen at a grazing angle). Each outer edge is measured again here: at
//! about every pixel along it, the grey profile across the edge (bilinear, half-pixel steps)
//! crosses the level halfway between the black border inside and the white quiet zone
//! outside; a line is fitted to those crossings (total least squares), and each corner is
//! the intersection of its two edges. Again, with profiles centred on the last lines, until
//! the corners settle (two or three readings). These readings reach half a cell on each side
//! and measure how wide each edge's step is; then the corners settle again on readings that
//! reach a few times that width (a sharp edge's few pixels, a blurred one's half cell), so that
//! the noise of the pixels away from a sharp edge stays out of its crossings (on tags rendered with exact corners,
//! noise of 10 grey levels: median corner error 0.075 -> 0.031 px; JPEG at quality 20: 0.093
//! -> 0.042 px; sharp and blurred tags unchanged, `benches/tags_robustness.py`).
//!
//! A tag is refused (`None`) when an edge is not supported (too few crossings, too little
//! contrast), is not straight (crossings scattered about the line), when the corners do not
//! settle, or when a corner ends far from the detector's (more than 2 px and 0.75 cell): its
//! corners are not reported rather than reported wrong.

use super::profile::crossings_along;
use crate::vision::image::{GreyBuffer, Pixels};

type P = [f64; 2];

/// The profiles reach half a cell on each side of the edge, and at least this far (pixels):
/// the detector's corners of a small tag are a third of a pixel off, and a crossing is only
/// taken a pixel inside the profile's ends.
const MIN_REACH: f64 = 1.5;
/// A sharp edge's profiles reach this many times its width ([`fit_edge`]): a step blurred by
/// a Gaussian of sigma is 1.35 sigma wide, and read over about 3.7 sigma on each side.
const REACH_PER_WIDTH: f64 = 2.75;
/// The least reach set by an edge's width: a sharp step sampled bilinearly spans 1.5 px on each
/// side (the pixel's area and the interpolation), and each end's level is read half a pixel
/// farther in, half a pixel off the edge at most once centred.
const MIN_WIDTH_REACH: f64 = 2.5;
/// Least share of the profiles along an edge that must cross it.
const MIN_SUPPORT: f64 = 0.6;
/// Largest RMS distance of the crossings from their line, pixels.
const MAX_EDGE_RMS: f64 = 0.35;
/// Largest move of a corner from the detector's, pixels, and in cells of the tag (the quad
/// fit puts a corner a few pixels off along an edge now and then: the edges bring it back).
const MAX_MOVE_PX: f64 = 2.0;
const MAX_MOVE_CELLS: f64 = 0.75;
/// The edges are read again, centred on the last pass's lines, until no corner moves by more
/// than [`SETTLED_PX`] (at most [`MAX_PASSES`] readings; a quad that does not settle is refused).
const SETTLED_PX: f64 = 0.05;
const MAX_PASSES: usize = 4;
/// The readings [`refine_blurred_corners`] allows a blurred tag's edges to settle in.
const MAX_BLURRED_PASSES: usize = 10;
/// At most this many profiles per edge (spread evenly along it): more add little to the
/// line's accuracy and cost time on large tags.
const MAX_PROFILES: usize = 200;
/// At most this many profiles per edge in the readings that reach half a cell (the first
/// stage of [`settle`]): they only measure each edge's width and bring the corners near
/// the narrow readings' lines, which then read every profile. Each of these profiles reads
/// up to 25 samples, a narrow one about 11: on five tags of 120-205 px at 1920 x 1080, a
/// tracked frame went from 1.9 to 1.3 ms on one thread with every profile read there.
const MAX_WIDE_PROFILES: usize = 64;

/// The square whose edges are read: its side in cells, and its polarity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Border {
    /// The square's side in cells (the layout's `width_at_border`).
    pub cells: f64,
    /// `false`: a dark square in a bright surround (the classic families); `true`: a bright
    /// square in a dark ring (AprilTag 3's families).
    pub reversed: bool,
}

/// The corners moved onto the four outer edges, or `None` when the edges do not support
/// them. `corners` are in [`Tag::corners`](super::Tag)'s order and convention (a closed
/// quadrilateral, either winding).
pub(super) fn refine_corners<C: Pixels>(image: &GreyBuffer<C>, corners: &[P; 4], border: Border) -> Option<[P; 4]> {
    settle(image, corners, border, MAX_PASSES)
}

/// As [`refine_corners`], with up to [`MAX_BLURRED_PASSES`] readings: for a small tag blurred
/// over about half a cell, whose edges [`refine_corners`] (and the smoothed crop) refuse
/// because they settle slowly.
///
/// The profiles of such an edge reach blur from the data cells inside the border and from
/// whatever lies beyond the one-cell quiet zone, which pulls each pass's crossings a little
/// towards the line the profiles were centred on: the corners creep by a shrinking step each
/// pass and settle on the line that the profiles centred on it give back (on tag 4 of ViSP's
/// 640 x 480 benchmark blurred by 2 px, 5 px cells, started on its true corners, the farthest
/// corner moves by 0.21, 0.13, 0.12, 0.07 and 0.04 px: five readings). Every check of
/// [`refine_corners`] applies. On that tag the detector's corners end 0.25-0.60 px from
/// ViSP's ground truth (the reference AprilTag library's: 0.38-1.08 px), on closed-form tags
/// blurred by 0.4-0.5 cell within a fifth of a cell (tests below).
pub(super) fn refine_blurred_corners<C: Pixels>(
    image: &GreyBuffer<C>,
    corners: &[P; 4],
    border: Border,
) -> Option<[P; 4]> {
    settle(image, corners, border, MAX_BLURRED_PASSES)
}

/// Reads the edges again and again from `corners` until they settle (at most `passes`
/// readings), as [`refine_corners`] describes: first with profiles reaching half a cell, then,
/// from where those settled, with profiles reaching a few times each edge's width as the last
/// of those readings measured it (a narrower profile would make a blurred edge look sharper).
/// Both stages settle from where the first one does, so a tag's corners do not depend on where
/// the refinement started (the detector's quad or a tracked tag's last corners).
fn settle<C: Pixels>(image: &GreyBuffer<C>, corners: &[P; 4], border: Border, passes: usize) -> Option<[P; 4]> {
    let cell = (0..4).map(|i| dist(corners[i], corners[(i + 1) % 4])).sum::<f64>() / (4.0 * border.cells);
    let limit = MAX_MOVE_PX.max(MAX_MOVE_CELLS * cell);
    let read = Readings { image, start: corners, border, passes, limit };
    let (wide, widths) = read.settle(*corners, [f64::INFINITY; 4])?;
    // Where the narrow readings do not settle (a noisy edge a few pixels wide), the wide ones'
    // corners stand: they passed every check.
    Some(read.settle(wide, widths.map(reach_for_width)).map_or(wide, |(narrow, _)| narrow))
}

/// The readings of one tag's edges: the image, the corners they started from, the square, and
/// the bounds (at most `passes` readings a stage, no corner farther than `limit` from the start).
struct Readings<'a, C: Pixels> {
    image: &'a GreyBuffer<C>,
    start: &'a [P; 4],
    border: Border,
    passes: usize,
    limit: f64,
}

impl<C: Pixels> Readings<'_, C> {
    /// The corners where readings from `current` with the profiles reaching at most `reaches`
    /// settle, and the edges' widths the last reading measured.
    fn settle(&self, mut current: [P; 4], reaches: [f64; 4]) -> Option<([P; 4], [f64; 4])> {
        for _ in 0..self.passes {
            let (lines, widths) = fit_edges(self.image, &current, self.border, &reaches)?;
            let next = intersect_all(&lines)?;
            if next.iter().zip(self.start).any(|(n, c)| dist(*n, *c) > self.limit) {
                return None;
            }
            let change = next.iter().zip(&current).map(|(n, c)| dist(*n, *c)).fold(0.0, f64::max);
            current = next;
            if change <= SETTLED_PX {
                return Some((current, widths));
            }
        }
        None
    }
}

/// A line `normal . x = offset` with a unit normal.
#[derive(Debug, Clone, Copy)]
struct Line {
    normal: P,
    offset: f64,
}

impl Line {
    /// The signed distance of `q` from the line.
    fn distance(&self, q: &P) -> f64 {
        dot(self.normal, *q) - self.offset
    }
}

/// The four edges' lines and their widths (see [`fit_edge`]); edge `i`'s profiles reach at
/// most `reaches[i]`.
fn fit_edges<C: Pixels>(
    image: &GreyBuffer<C>,
    corners: &[P; 4],
    border: Border,
    reaches: &[f64; 4],
) -> Option<([Line; 4], [f64; 4])> {
    let centre = [0, 1].map(|k| corners.iter().map(|c| c[k]).sum::<f64>() / 4.0);
    let mut lines = [Line { normal: [0.0, 0.0], offset: 0.0 }; 4];
    let mut widths = [0.0; 4];
    for i in 0..4 {
        let (a, b) = (corners[i], corners[(i + 1) % 4]);
        let opposite = mid(corners[(i + 2) % 4], corners[(i + 3) % 4]);
        (lines[i], widths[i]) = fit_edge(image, [a, b], centre, opposite, border, reaches[i])?;
    }
    Some((lines, widths))
}

/// How far the profiles of an edge of `width` ([`fit_edge`]) reach: [`REACH_PER_WIDTH`] times
/// it, at least [`MIN_WIDTH_REACH`]. A profile's crossing carries the noise of every sample it
/// reads (and of its two ends' levels, in proportion to its reach), so a sharp edge is read
/// over the few pixels its step spans rather than the half cell a blurred one needs.
fn reach_for_width(width: f64) -> f64 {
    (REACH_PER_WIDTH * width).max(MIN_WIDTH_REACH)
}

/// The outer edge from `a` to `b`: crossings of the profiles across it, fitted by a line, and
/// the edge's width: the median over its profiles of the distance from the level a quarter of
/// the way from black to white to the level three quarters of the way (0.67 px for a sharp
/// edge, 1.35 sigma for a step blurred by a Gaussian of sigma). The profiles reach half a cell
/// on each side, within [`MIN_REACH`] and 6 px, and at most `max_reach`.
fn fit_edge<C: Pixels>(
    image: &GreyBuffer<C>,
    [a, b]: [P; 2],
    centre: P,
    opposite: P,
    border: Border,
    max_reach: f64,
) -> Option<(Line, f64)> {
    let length = dist(a, b);
    let along = [(b[0] - a[0]) / length, (b[1] - a[1]) / length];
    let mut out = [along[1], -along[0]];
    if dot(out, sub(mid(a, b), centre)) < 0.0 {
        out = [-out[0], -out[1]];
    }
    // A cell measured across this edge: the square's depth from this edge to the opposite one.
    let cell = dot(out, sub(a, opposite)).abs() / border.cells;
    let reach = (0.5 * cell).clamp(MIN_REACH, 6.0).min(max_reach);
    let skip = reach + 1.0;
    if !length.is_finite() || length < 2.0 * skip + 2.0 {
        return None;
    }
    // Only the wide readings' widths are used (`settle`): the narrow ones skip the walk.
    let want_width = max_reach.is_infinite();
    let most = if want_width { MAX_WIDE_PROFILES } else { MAX_PROFILES };
    let count = ((length - 2.0 * skip).floor() as usize + 1).min(most);
    let spacing = (length - 2.0 * skip) / (count - 1).max(1) as f64;
    let points: Vec<P> = (0..count)
        .map(|k| {
            let s = skip + spacing * k as f64;
            [a[0] + along[0] * s, a[1] + along[1] * s]
        })
        .collect();
    let mut widths = Vec::with_capacity(if want_width { count } else { 0 });
    let mut crossings: Vec<P> = Vec::with_capacity(count);
    crossings_along(image, &points, out, reach, (border.reversed, want_width), |k, crossing| {
        if let (Some((e, width)), Some(p)) = (crossing, points.get(k)) {
            widths.extend(width);
            crossings.push([p[0] + out[0] * e, p[1] + out[1] * e]);
        }
    });
    if (crossings.len() as f64) < (MIN_SUPPORT * count as f64).max(3.0) {
        return None;
    }
    widths.sort_unstable_by(f64::total_cmp);
    let width = widths.get(widths.len() / 2).copied().unwrap_or(f64::INFINITY);
    Some((fit_line(&crossings)?, width))
}

/// The total least squares line of the points, one pass without the points farther than
/// three RMS; `None` when they scatter more than [`MAX_EDGE_RMS`].
fn fit_line(points: &[P]) -> Option<Line> {
    let line = total_least_squares(points.iter())?;
    let keep = 3.0 * rms(line, points.iter()).max(0.05);
    let kept: Vec<&P> = points.iter().filter(|q| line.distance(q).abs() <= keep).collect();
    let line = total_least_squares(kept.iter().copied())?;
    (kept.len() >= 3 && rms(line, kept.iter().copied()) <= MAX_EDGE_RMS).then_some(line)
}

/// The root mean square distance of the points from the line.
fn rms<'a>(line: Line, points: impl Iterator<Item = &'a P>) -> f64 {
    let (sum, n) = points.fold((0.0, 0usize), |(sum, n), q| (sum + line.distance(q).powi(2), n + 1));
    (sum / n as f64).sqrt()
}

fn total_least_squares<'a>(points: impl Iterator<Item = &'a P> + Clone) -> Option<Line> {
    let n = points.clone().count() as f64;
    let m = [0, 1].map(|k| points.clone().map(|q| q[k]).sum::<f64>() / n);
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for q in points {
        let (x, y) = (q[0] - m[0], q[1] - m[1]);
        sxx += x * x;
        sxy += x * y;
        syy += y * y;
    }
    // The normal is the eigenvector of the smaller eigenvalue of the scatter matrix.
    let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy) + std::f64::consts::FRAC_PI_2;
    let normal = [angle.cos(), angle.sin()];
    let line = Line { normal, offset: dot(normal, m) };
    line.offset.is_finite().then_some(line)
}

/// Corner `i` is where edge `i - 1` (into it) meets edge `i` (out of it).
fn intersect_all(lines: &[Line; 4]) -> Option<[P; 4]> {
    let mut corners = [[0.0; 2]; 4];
    for (i, corner) in corners.iter_mut().enumerate() {
        *corner = intersect(lines[(i + 3) % 4], lines[i])?;
    }
    Some(corners)
}

fn intersect(l: Line, m: Line) -> Option<P> {
    let det = l.normal[0] * m.normal[1] - l.normal[1] * m.normal[0];
    if det.abs() < 1e-6 {
        return None;
    }
    let x = (l.offset * m.normal[1] - m.offset * l.normal[1]) / det;
    let y = (l.normal[0] * m.offset - m.normal[0] * l.offset) / det;
    Some([x, y])
}

/// The grey level at `(u, v)` (pixel centres at integers), `None` outside the image.
///
/// Inlined into the profile loops, which spend most of a tracked frame here.
#[inline]
pub(super) fn bilinear<C: Pixels>(image: &GreyBuffer<C>, u: f64, v: f64) -> Option<f64> {
    if !inside(image, [u, v]) {
        return None;
    }
    sample(image, u, v)
}

/// Whether `[u, v]` is inside the image's pixel centres (where [`bilinear`] reads).
#[inline]
pub(super) fn inside<C: Pixels>(image: &GreyBuffer<C>, [u, v]: P) -> bool {
    let (w, h) = (image.width() as f64, image.height() as f64);
    u >= 0.0 && v >= 0.0 && u <= w - 1.0 && v <= h - 1.0
}

/// [`bilinear`] at a point known to be [`inside`] the image.
#[inline]
pub(super) fn sample<C: Pixels>(image: &GreyBuffer<C>, u: f64, v: f64) -> Option<f64> {
    // `u, v >= 0` and below 2^32: truncation is the floor, without a call to libm's `floor`; the
    // last column (row) is read between the one before it and itself. One conversion each way
    // and one bounds check a sample: the edges' profiles spend their time here.
    let (u0, v0) = ((u as u32).min(image.width().saturating_sub(2)), (v as u32).min(image.height().saturating_sub(2)));
    let (fu, fv) = (u - f64::from(u0), v - f64::from(v0));
    let stride = image.width() as usize;
    let first = v0 as usize * stride + u0 as usize;
    let pixels: &[u8] = image.as_raw();
    let square = pixels.get(first..first + stride + 2)?;
    let row = |left: u8, right: u8| f64::from(left) * (1.0 - fu) + f64::from(right) * fu;
    Some(row(square[0], square[1]) * (1.0 - fv) + row(square[stride], square[stride + 1]) * fv)
}

fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1]]
}

fn dot(a: P, b: P) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

fn dist(a: P, b: P) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

fn mid(a: P, b: P) -> P {
    [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0]
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
pub(super) mod tests {
    use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

    use super::*;
    use crate::core::camera::Intrinsics;
    use crate::core::distortion::Distortion;
    use crate::vision::image::GreyImage;
    use crate::vision::render::{CameraView, RenderConfig, Renderer};
    use crate::vision::tags::profile::crossing_and_width;
    use crate::vision::tags::synthetic::{Placement, corners, draw};
    use crate::vision::tags::{TagFamily, detect_tags};
    use crate::vision::target::tags::{RigTag, TagRig};

    const FAMILY: TagFamily = TagFamily::Tag36h11;
    /// tag36h11's black square: 8 cells.
    pub(crate) const BORDER: Border = Border { cells: 8.0, reversed: false };

    fn worst(a: &[P; 4], b: &[P; 4]) -> f64 {
        a.iter().zip(b).map(|(p, q)| dist(*p, *q)).fold(0.0, f64::max)
    }

    /// A vertical step from 30 (left) to 220 at `u = edge`, each pixel its exact area average,
    /// blurred by a Gaussian of `sigma` (none at 0).
    fn step_image(edge: f64, sigma: f32) -> GreyImage {
        let image = GreyImage::from_fn(80, 40, |u, _| {
            let white = (f64::from(u) + 0.5 - edge).clamp(0.0, 1.0);
            ::image::Luma([(30.0 + 190.0 * white).round() as u8])
        });
        if sigma > 0.0 { imageproc::filter::gaussian_blur_f32(&image, sigma) } else { image }
    }

    /// The width is the quartile-to-quartile distance of the step: for a Gaussian blur of sigma,
    /// 1.349 sigma once the pixel's area and the bilinear reading (variances 1/12 and 1/6) are
    /// added; a sharp step is about two thirds of a pixel. The crossing stays on the edge.
    #[test]
    fn the_width_of_an_edge_is_its_quartile_distance() {
        for (sigma, reach) in [(0.0f32, 2.5), (0.6, 3.0), (1.0, 6.0), (2.0, 7.5)] {
            let image = step_image(40.3, sigma);
            let (edge, width) = crossing_and_width(&image, [40.3, 20.0], [1.0, 0.0], reach, (false, true)).unwrap();
            let width = width.unwrap();
            let expected = 1.349 * (f64::from(sigma).powi(2) + 1.0 / 12.0 + 1.0 / 6.0).sqrt();
            assert!(edge.abs() < 0.02, "sigma {sigma}: crossing {edge}");
            assert!((width - expected).abs() < 0.15 * expected, "sigma {sigma}: width {width}, expected {expected}");
            // The reach it sets covers the step: at least 3.7 sigma for a blurred edge.
            assert!(reach_for_width(width) >= (3.5 * f64::from(sigma)).max(MIN_WIDTH_REACH), "sigma {sigma}");
        }
        // Reversed polarity reads the same width.
        let image = step_image(40.3, 1.0);
        let dark = GreyImage::from_fn(80, 40, |u, v| ::image::Luma([255 - image.get_pixel(u, v)[0]]));
        let (_, width) = crossing_and_width(&dark, [40.3, 20.0], [1.0, 0.0], 6.0, (true, true)).unwrap();
        let (_, same) = crossing_and_width(&image, [40.3, 20.0], [1.0, 0.0], 6.0, (false, true)).unwrap();
        assert!((width.unwrap() - same.unwrap()).abs() < 0.02);
    }

    /// Bilinear interpolation reproduces a function bilinear in `(u, v)` exactly, up to the
    /// last column and row (read between the pixel before and itself); outside it reads nothing.
    #[test]
    fn bilinear_reproduces_a_bilinear_function_up_to_the_last_pixel() {
        let f = |u: f64, v: f64| 5.0 + 3.0 * u + 2.0 * v + u * v;
        let image = GreyImage::from_fn(9, 7, |u, v| ::image::Luma([f(f64::from(u), f64::from(v)) as u8]));
        let points = [[0.0, 0.0], [8.0, 6.0], [8.0, 0.25], [0.6, 6.0], [3.3, 2.7], [7.99, 5.01], [4.0, 3.0]];
        for [u, v] in points {
            let g = bilinear(&image, u, v).unwrap();
            assert!((g - f(u, v)).abs() < 1e-9, "({u}, {v}): {g} vs {}", f(u, v));
        }
        for [u, v] in [[-0.01, 3.0], [8.01, 3.0], [3.0, -0.5], [3.0, 6.2], [f64::NAN, 1.0]] {
            assert_eq!(bilinear(&image, u, v), None, "({u}, {v})");
        }
    }

    #[test]
    fn corners_up_to_half_a_pixel_off_come_back_to_the_edges() {
        let p = Placement { id: 42, centre: [90.3, 70.6], cell: 9.2, quarter_turns: 1 };
        let image = draw(FAMILY, 180, 140, &[p]);
        let truth = corners(FAMILY, &p);
        let shifts = [[0.5, -0.3], [-0.4, 0.2], [0.1, 0.45], [-0.35, -0.35]];
        let start: [P; 4] = std::array::from_fn(|k| [truth[k][0] + shifts[k][0], truth[k][1] + shifts[k][1]]);
        let refined = refine_corners(&image, &start, BORDER).unwrap();
        assert!(worst(&refined, &truth) < 0.01, "{refined:?} vs {truth:?}");
    }

    #[test]
    fn a_corner_several_pixels_off_is_brought_back_or_refused_never_reported() {
        let p = Placement { id: 42, centre: [90.3, 70.6], cell: 9.2, quarter_turns: 0 };
        let image = draw(FAMILY, 180, 140, &[p]);
        let truth = corners(FAMILY, &p);
        // Along an edge (the quad slid along the border), outwards, inwards: within 0.75 cell
        // the edges bring the corner back; beyond, the tag is refused.
        let cases = [(0, [-6.0, 0.0], true), (2, [0.0, 4.0], true), (1, [-3.0, 3.0], true), (3, [2.5, 2.5], true)];
        for (k, shift, back) in cases.into_iter().chain([(0, [0.0, -12.8], false), (2, [9.0, 9.0], false)]) {
            let mut wrong = truth;
            wrong[k] = [truth[k][0] + shift[0], truth[k][1] + shift[1]];
            match refine_corners(&image, &wrong, BORDER) {
                Some(found) => {
                    assert!(back, "corner {k} moved by {shift:?}: reported");
                    assert!(worst(&found, &truth) < 0.01, "corner {k} moved by {shift:?}: {found:?}");
                }
                None => assert!(!back, "corner {k} moved by {shift:?}: refused"),
            }
        }
        // The quad on the border's inner edge (a cell in) or on the quiet zone's outer edge
        // (a cell out): no black-to-white step there.
        let centre = p.centre;
        for scale in [6.0 / 8.0, 10.0 / 8.0] {
            let quad = truth.map(|c| [centre[0] + scale * (c[0] - centre[0]), centre[1] + scale * (c[1] - centre[1])]);
            assert_eq!(refine_corners(&image, &quad, BORDER), None, "scaled by {scale}");
        }
        // Edges without a step (a blank image) support nothing.
        let blank = GreyBuffer::from_pixel(180, 140, ::image::Luma([200u8]));
        assert_eq!(refine_corners(&blank, &truth, BORDER), None);
        // A quad too small to read, or reaching out of the image.
        assert_eq!(refine_corners(&image, &[[10.0, 10.0], [12.0, 10.0], [12.0, 12.0], [10.0, 12.0]], BORDER), None);
        assert_eq!(
            refine_corners(&image, &[[-50.0, 10.0], [100.0, 10.0], [100.0, 100.0], [-50.0, 100.0]], BORDER),
            None
        );
    }

    /// A bright square in a dark ring (AprilTag 3's families): the drawn tag with its grey
    /// levels inverted has the same corners, read with the reversed polarity only.
    #[test]
    fn a_reversed_border_is_read_with_its_polarity() {
        let p = Placement { id: 7, centre: [90.3, 70.6], cell: 9.2, quarter_turns: 3 };
        let mut image = draw(FAMILY, 180, 140, &[p]);
        image.pixels_mut().for_each(|g| g[0] = 255 - g[0]);
        let truth = corners(FAMILY, &p);
        let start = truth.map(|c| [c[0] + 0.3, c[1] - 0.25]);
        let reversed = Border { reversed: true, ..BORDER };
        let found = refine_corners(&image, &start, reversed).unwrap();
        assert!(worst(&found, &truth) < 0.01, "{found:?} vs {truth:?}");
        assert_eq!(refine_corners(&image, &start, BORDER), None);
        assert_eq!(refine_corners(&draw(FAMILY, 180, 140, &[p]), &start, reversed), None);
    }

    /// A Gaussian blur of standard deviation `sigma` pixels, computed here (separable, a kernel
    /// reaching 5 sigma, the image's edge pixels repeated), independently of the crate's filters.
    pub(crate) fn gaussian(image: &GreyImage, sigma: f64) -> GreyImage {
        let radius = (5.0 * sigma).ceil() as i64;
        let weights: Vec<f64> = (-radius..=radius).map(|k| (-0.5 * (k as f64 / sigma).powi(2)).exp()).collect();
        let total: f64 = weights.iter().sum();
        let (w, h) = (i64::from(image.width()), i64::from(image.height()));
        let at = |values: &[f64], u: i64, v: i64| values[(v.clamp(0, h - 1) * w + u.clamp(0, w - 1)) as usize];
        let grey: Vec<f64> = image.as_raw().iter().map(|&g| f64::from(g)).collect();
        let pass = |values: &[f64], horizontal: bool| -> Vec<f64> {
            (0..w * h)
                .map(|i| {
                    let (u, v) = (i % w, i / w);
                    let sum = (-radius..=radius)
                        .zip(&weights)
                        .map(|(k, wk)| wk * if horizontal { at(values, u + k, v) } else { at(values, u, v + k) });
                    sum.sum::<f64>() / total
                })
                .collect()
        };
        let out = pass(&pass(&grey, true), false);
        GreyImage::from_raw(image.width(), image.height(), out.iter().map(|g| g.round() as u8).collect()).unwrap()
    }

    /// The drawn tag `p` with everything beyond its one-cell quiet zone black (exact pixel
    /// areas), as a tag printed without a margin on a dark background.
    fn on_black(image: &GreyImage, p: &Placement) -> GreyImage {
        let half = 5.0 * p.cell; // tag36h11: 10 cells with the quiet zone
        let inside = |c: f64, x: f64| ((x + 0.5).min(c + half) - (x - 0.5).max(c - half)).clamp(0.0, 1.0);
        let mut out = image.clone();
        for (u, v, g) in out.enumerate_pixels_mut() {
            let outside = 1.0 - inside(p.centre[0], f64::from(u)) * inside(p.centre[1], f64::from(v));
            g[0] = (f64::from(g[0]) - 190.0 * outside).round().max(30.0) as u8;
        }
        out
    }

    /// Small tags (4-6 px cells) blurred by 0.4-0.5 cell, on white or on black beyond the quiet
    /// zone: the edges settle slowly (the four readings of `refine_corners` do not always
    /// suffice), within a fifth of a cell of the true corners; the quads on the border's inner
    /// edge or the quiet zone's outer edge are still refused.
    #[test]
    fn small_blurred_tags_settle_slowly_near_their_corners() {
        let shifts = [[0.3, -0.2], [-0.25, 0.3], [0.2, 0.2], [-0.3, -0.3]];
        let mut slow = 0;
        for (cell, sigma) in [(4.0, 1.6), (5.0, 2.0), (5.0, 2.5), (6.0, 2.5)] {
            for (id, quarter_turns) in [(4, 0), (17, 1), (101, 3)] {
                let p = Placement { id, centre: [60.3, 60.15], cell, quarter_turns };
                let truth = corners(FAMILY, &p);
                let start: [P; 4] = std::array::from_fn(|k| [truth[k][0] + shifts[k][0], truth[k][1] + shifts[k][1]]);
                let white = draw(FAMILY, 120, 120, &[p]);
                for image in [gaussian(&white, sigma), gaussian(&on_black(&white, &p), sigma)] {
                    let found = refine_blurred_corners(&image, &start, BORDER).unwrap();
                    let error = worst(&found, &truth);
                    assert!(error < 0.2 * cell, "{p:?} sigma {sigma}: {error} px");
                    slow += usize::from(refine_corners(&image, &start, BORDER).is_none());
                    for scale in [6.0 / 8.0, 10.0 / 8.0] {
                        let quad = truth.map(|c| [60.3 + scale * (c[0] - 60.3), 60.15 + scale * (c[1] - 60.15)]);
                        assert_eq!(refine_blurred_corners(&image, &quad, BORDER), None, "{p:?} scaled by {scale}");
                    }
                }
            }
        }
        assert!(slow >= 6, "{slow} of the tags need more than four readings");
        // The whole detector reports such a tag (5 px cells blurred by 2 px), near its corners.
        for (id, quarter_turns) in [(4, 0), (17, 1), (101, 3)] {
            let p = Placement { id, centre: [60.3, 60.15], cell: 5.0, quarter_turns };
            let image = gaussian(&draw(FAMILY, 120, 120, &[p]), 2.0);
            let tags = detect_tags(&image, FAMILY).unwrap();
            assert_eq!(tags.iter().map(|t| t.id).collect::<Vec<_>>(), [id as u32], "{p:?}");
            assert!(worst(&tags[0].corners, &corners(FAMILY, &p)) < 1.0, "{p:?}: {:?}", tags[0].corners);
        }
    }

    /// Tags seen in perspective (the renderer's exact pixel areas, blur and noise as in the
    /// built-ins): the corners found are those the camera projects.
    #[test]
    fn tags_in_perspective_are_found_at_their_projected_corners() {
        let k = Intrinsics::pinhole(900.0, 900.0, 320.0, 240.0).unwrap();
        let tag = |id, axis: Vector3<f64>, angle: f64, x: f64| RigTag {
            id,
            size: 0.06,
            pose: Isometry3::from_parts(
                Translation3::new(x, 0.0, 0.6),
                UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
                    * UnitQuaternion::new(axis * angle.to_radians()),
            ),
        };
        let rig = TagRig::new(
            FAMILY,
            vec![tag(5, Vector3::y(), 50.0, -0.08), tag(9, Vector3::new(1.0, 1.0, 0.0).normalize(), 35.0, 0.08)],
        )
        .unwrap();
        let mut worst_error: f64 = 0.0;
        for (blur, noise) in [(0.0, 0.0), (0.8, 1.0), (1.2, 2.0)] {
            let config = RenderConfig {
                blur_sigma: blur,
                noise_sigma: noise,
                background: 30,
                foreground: 220,
                ..Default::default()
            };
            for shift in [0.0, 0.0013, 0.0027] {
                let pose = Isometry3::translation(shift, -shift, 0.0);
                let view =
                    CameraView { pose: &pose, intrinsics: &k, distortion: &Distortion::none(), size: (640, 480) };
                let image = Renderer::new(config).unwrap().render(&rig, None, &view, 0).unwrap().image;
                let found = detect_tags(&image, FAMILY).unwrap();
                assert_eq!(found.iter().map(|t| t.id).collect::<Vec<_>>(), [5, 9], "blur {blur}");
                for (found, truth) in found.iter().zip(rig.tags()) {
                    let projected = truth.corners().map(|c| {
                        let p = pose.inverse_transform_point(&Point3::from(c));
                        k.project(&p).unwrap().0
                    });
                    worst_error = worst_error.max(worst(&found.corners, &projected));
                }
            }
        }
        assert!(worst_error < 0.1, "worst corner error {worst_error} px");
    }
}
