//! Where a tag's four outer edges moved to, searched along each edge's normal within a
//! bounded window around where they were: the start that the edge refinement (`edges.rs`,
//! whose profiles reach only half a cell around its start) needs when a tag moved by more than
//! about a pixel since the last frame.
//!
//! Across each edge, at a few points along it, the grey profile is read (bilinear, half-pixel
//! steps) within [`WINDOW_CELLS`] of a cell on both sides, and the steepest step from the
//! square's side (dark for the classic families) to the outside is taken; the edge is moved
//! along its normal by the median of those shifts, when most of them agree, then by the
//! median of the edge's level crossings on profiles centred there (the crossings the edge
//! refinement reads, so that a tag which slid starts its refinement on its edges and settles
//! in one reading rather than two), and the corners are where the moved edges meet. The window stays within the black border and the quiet
//! zone around the tag (one cell each): inside, the first step of the same polarity is a
//! data cell two cells in. A wrong start is caught after it: the edge refinement checks the
//! edges' support and straightness, and the follower the tag's bits.

use super::edges::{Border, bilinear};
use super::profile;
use crate::vision::image::{GreyBuffer, Pixels};

type P = [f64; 2];

/// The window, each side of the last edge, in cells of the tag.
const WINDOW_CELLS: f64 = 0.75;
/// Profiles across each edge, evenly spread over its middle [`SPREAD`] (away from corners).
const PROFILES: usize = 9;
const SPREAD: f64 = 0.6;
/// Of the profiles, at least this many must find the edge within [`AGREE_PX`] of their median.
const MIN_AGREEING: usize = 6;
const AGREE_PX: f64 = 1.0;
/// Half-pixel steps along the profiles.
const STEP: f64 = 0.5;
/// The least step (difference of the grey levels one pixel apart), grey levels.
const MIN_STEP: f64 = 10.0;
/// The profiles of the edge's refinement (`edges.rs`) reach half a cell each side of the
/// edge, within these bounds (pixels): [`subpixel`] reads the crossings as it does.
const REACH_CELLS: f64 = 0.5;
const MIN_REACH: f64 = 1.5;
const MAX_REACH: f64 = 6.0;

/// The corners of the quad whose edges are those of `corners` ([`Tag::corners`](super::Tag)'s
/// order) each moved along its normal to where the image's edge now is; `None` when an edge
/// is not found in its window.
pub(super) fn moved_corners<C: Pixels>(image: &GreyBuffer<C>, corners: &[P; 4], border: Border) -> Option<[P; 4]> {
    let centre = [0, 1].map(|k| corners.iter().map(|c| c[k]).sum::<f64>() / 4.0);
    let mut lines = [([0.0; 2], [0.0; 2]); 4];
    for (i, line) in lines.iter_mut().enumerate() {
        let (a, b) = (corners[i], corners[(i + 1) % 4]);
        let (along, out) = frame(a, b, centre)?;
        let shift = edge_shift(image, a, b, out, border)?;
        *line = ([a[0] + out[0] * shift, a[1] + out[1] * shift], along);
    }
    let mut moved = [[0.0; 2]; 4];
    for (i, corner) in moved.iter_mut().enumerate() {
        *corner = meet(lines[(i + 3) % 4], lines[i])?;
    }
    Some(moved)
}

/// The unit vector from `a` to `b`, and the unit normal pointing away from `centre`.
fn frame(a: P, b: P, centre: P) -> Option<(P, P)> {
    let length = (b[0] - a[0]).hypot(b[1] - a[1]);
    if !(length.is_finite() && length > 0.0) {
        return None;
    }
    let along = [(b[0] - a[0]) / length, (b[1] - a[1]) / length];
    let out = [along[1], -along[0]];
    let middle = [(a[0] + b[0]) / 2.0 - centre[0], (a[1] + b[1]) / 2.0 - centre[1]];
    let sign = if out[0] * middle[0] + out[1] * middle[1] < 0.0 { -1.0 } else { 1.0 };
    Some((along, [sign * out[0], sign * out[1]]))
}

/// How far along `out` the edge from `a` to `b` moved: the median of the profiles' steepest
/// steps, when at least [`MIN_AGREEING`] of them agree, then to a fraction of a pixel where
/// the edge's refinement would put it ([`subpixel`]).
fn edge_shift<C: Pixels>(image: &GreyBuffer<C>, a: P, b: P, out: P, border: Border) -> Option<f64> {
    let cell = (b[0] - a[0]).hypot(b[1] - a[1]) / border.cells;
    let window = WINDOW_CELLS * cell;
    let points: [P; PROFILES] = std::array::from_fn(|k| {
        let t = (1.0 - SPREAD) / 2.0 + SPREAD * k as f64 / (PROFILES - 1) as f64;
        [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]
    });
    let shifts: Vec<f64> =
        points.iter().filter_map(|&p| steepest_step(image, p, out, window, border.reversed)).collect();
    let coarse = agreed(shifts)?;
    let reach = (REACH_CELLS * cell).clamp(MIN_REACH, MAX_REACH);
    Some(subpixel(image, &points, out, coarse, reach, border.reversed).unwrap_or(coarse))
}

/// The median of `shifts`, when at least [`MIN_AGREEING`] of them are within [`AGREE_PX`] of it.
fn agreed(mut shifts: Vec<f64>) -> Option<f64> {
    if shifts.len() < MIN_AGREEING {
        return None;
    }
    shifts.sort_by(f64::total_cmp);
    let median = *shifts.get(shifts.len() / 2)?;
    let agreeing = shifts.iter().filter(|s| (*s - median).abs() <= AGREE_PX).count();
    (agreeing >= MIN_AGREEING).then_some(median)
}

/// The shift `coarse` (a step found to the half pixel) moved to the median of the edge's
/// crossings of the profiles centred there (the level crossing the edge refinement reads,
/// `edges.rs`): the refinement then starts on the edge, and a tag that only slid settles in
/// one reading instead of two. `None` when too few profiles cross or agree.
fn subpixel<C: Pixels>(
    image: &GreyBuffer<C>,
    points: &[P],
    out: P,
    coarse: f64,
    reach: f64,
    reversed: bool,
) -> Option<f64> {
    let centred: Vec<P> = points.iter().map(|p| [p[0] + out[0] * coarse, p[1] + out[1] * coarse]).collect();
    let mut crossings: Vec<f64> = Vec::with_capacity(points.len());
    profile::crossings_along(image, &centred, out, reach, (reversed, false), |_, crossing| {
        crossings.extend(crossing.map(|(edge, _)| edge));
    });
    Some(coarse + agreed(crossings)?)
}

/// The offset within `±window` of `p` along `out` where the grey level rises the most from
/// inside to outside (falls, when `reversed`), over one pixel (the peak of a parabola through
/// the steepest half-pixel step and its neighbours); `None` below [`MIN_STEP`]. Each
/// half-pixel sample is read once.
fn steepest_step<C: Pixels>(image: &GreyBuffer<C>, p: P, out: P, window: f64, reversed: bool) -> Option<f64> {
    let steps = (window / STEP).floor() as i64;
    let grey = |j: i64| {
        let o = STEP * j as f64;
        let g = bilinear(image, p[0] + out[0] * o, p[1] + out[1] * o)?;
        Some(if reversed { 255.0 - g } else { g })
    };
    // Samples -steps - 1 ..= steps + 1 (every rise in the window needs them all).
    let reads: Vec<f64> = (-steps - 1..=steps + 1).map(grey).collect::<Option<_>>()?;
    let read = |j: i64| match usize::try_from(j + steps + 1).ok().and_then(|i| reads.get(i)) {
        Some(&g) => Some(g),
        None => grey(j),
    };
    // The rise at offset STEP * k: over one pixel, from sample k - 1 to sample k + 1.
    let rise = |k: i64| Some(read(k + 1)? - read(k - 1)?);
    let mut best: Option<(f64, i64)> = None;
    for k in -steps..=steps {
        let r = rise(k)?;
        if r >= MIN_STEP && best.is_none_or(|(b, _)| r > b) {
            best = Some((r, k));
        }
    }
    let (r, k) = best?;
    let (before, after) = (rise(k - 1)?, rise(k + 1)?);
    let curvature = before - 2.0 * r + after;
    let peak = if curvature < 0.0 { 0.5 * (before - after) / curvature } else { 0.0 };
    Some(STEP * k as f64 + STEP * peak.clamp(-0.5, 0.5))
}

/// Where the line through `p` along `d` meets the line through `q` along `e`.
fn meet((p, d): (P, P), (q, e): (P, P)) -> Option<P> {
    let det = d[0] * e[1] - d[1] * e[0];
    if det.abs() < 1e-6 {
        return None;
    }
    let s = ((q[0] - p[0]) * e[1] - (q[1] - p[1]) * e[0]) / det;
    Some([p[0] + s * d[0], p[1] + s * d[1]])
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::vision::tags::TagFamily;
    use crate::vision::tags::edges::tests::BORDER;
    use crate::vision::tags::synthetic::{Placement, corners, draw};

    const FAMILY: TagFamily = TagFamily::Tag36h11;

    fn worst(a: &[P; 4], b: &[P; 4]) -> f64 {
        a.iter().zip(b).map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1])).fold(0.0, f64::max)
    }

    /// A tag moved by up to two thirds of a cell is found within a twentieth of a pixel,
    /// whichever way it moved; moved by more than the window, it is not found there.
    #[test]
    fn finds_edges_moved_within_the_window() {
        let before = Placement { id: 42, centre: [90.3, 70.6], cell: 6.0, quarter_turns: 1 };
        let start = corners(FAMILY, &before);
        for shift in [[0.0, 0.0], [3.9, 0.0], [-2.7, 2.7], [1.3, -3.6], [-0.4, 0.9]] {
            let after = Placement { centre: [before.centre[0] + shift[0], before.centre[1] + shift[1]], ..before };
            let image = draw(FAMILY, 180, 140, &[after]);
            let found = moved_corners(&image, &start, BORDER).unwrap();
            // To the edges' level crossings (subpixel), not only to the half-pixel steps.
            assert!(worst(&found, &corners(FAMILY, &after)) < 0.05, "{shift:?}: {found:?}");
        }
        let far = Placement { centre: [before.centre[0] + 7.0, before.centre[1]], ..before };
        let moved = moved_corners(&draw(FAMILY, 180, 140, &[far]), &start, BORDER);
        assert!(moved.is_none_or(|m| worst(&m, &corners(FAMILY, &far)) > 1.0), "{moved:?}");
        assert!(moved_corners(&draw(FAMILY, 180, 140, &[]), &start, BORDER).is_none());
    }

    #[test]
    fn lines_meet_where_they_cross() {
        let m = meet(([0.0, 1.0], [1.0, 0.0]), ([3.0, -2.0], [0.6, 0.8])).unwrap();
        assert!((m[0] - 5.25).abs() < 1e-12 && (m[1] - 1.0).abs() < 1e-12, "{m:?}");
        assert!(meet(([0.0, 1.0], [1.0, 0.0]), ([3.0, -2.0], [-1.0, 0.0])).is_none());
    }
}
