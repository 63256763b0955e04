//! The subpixel centroid of one dot found by [`label`](crate::vision::runs::label): the
//! intensity-weighted mean over its bounding box grown by [`MARGIN`] pixels, each pixel
//! weighted by its level above a local background model, so that the anti-aliased edge
//! pixels under the threshold still count and pixels of other dots do not.
//!
//! The background is the least-squares plane `b(u, v) = a + b_u (u - u_c) + b_v (v - v_c)`
//! fitted to the border ring of the grown box, dot pixels left out: a lighting gradient
//! across the dot then cancels, where a constant background (the ring's median) leaves
//! weights `g - b` that lean towards the bright side and pull the centroid by a fraction of a
//! pixel (the first moment of a linear ramp over the dot's support).

use nalgebra::{Matrix3, Vector3};

use crate::vision::image::{GreyBuffer, Pixels};
use crate::vision::runs::{Component, Labelling, Run};

/// Pixels added around a component's bounding box for its centroid.
pub const MARGIN: u32 = 2;

/// Background pixels within this many ring RMS of the plane are noise, not the dot's edge.
const NOISE_FLOOR: f64 = 2.0;

/// Which pixels of a row segment: the background, the dot's own, or another dot's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Owner {
    Background,
    Own,
    Other,
}

/// A dot's centroid `(u, v)`, its contrast (the mean level of its pixels above the
/// background plane) and how well that plane fits the ring around it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Weighted {
    /// Subpixel centroid.
    pub centroid: [f64; 2],
    /// Mean level of the dot's pixels above the background, grey levels.
    pub contrast: f64,
    /// Root mean square deviation of the ring's background pixels from the plane, grey
    /// levels: the noise of a plain background, more for a dot in clutter.
    pub ring_residual: f64,
}

/// Which ring around a dot its background plane is fitted to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RingFit {
    /// The border of the dot's box grown by [`MARGIN`].
    Near,
    /// The plainest of the borders of its box grown by twice, four times... [`MARGIN`], up to
    /// twice the box's size and inside the image (the centroid then weighs that whole box): a
    /// shaded sphere's dim limb reaches past its lit part, and its surround is plain only
    /// outside its outline. A blob in clutter stays in clutter at every size.
    Grown,
}

/// The centroid of component `index` of `labelling`.
pub fn weighted_centroid<C: Pixels>(
    image: &GreyBuffer<C>,
    labelling: &Labelling,
    index: u32,
    dark: bool,
    fit: RingFit,
) -> Weighted {
    let c: &Component = &labelling.components[index as usize];
    let (w, h) = (image.width(), image.height());
    let flip = if dark { 255u8 } else { 0 };
    let level = |u: u32, v: u32| f64::from(image.as_raw()[v as usize * w as usize + u as usize] ^ flip);
    let Ring { bbox, centre, plane, residual: ring_residual } = match fit {
        RingFit::Near => Ring::fit(labelling, index, grow(c.bbox, MARGIN, w, h), &level),
        RingFit::Grown => grown_ring(labelling, index, c.bbox, w, h, &level),
    };
    let background =
        |u: u32, v: u32| plane[0] + plane[1] * (f64::from(u) - centre[0]) + plane[2] * (f64::from(v) - centre[1]);
    // A background pixel counts only above the ring's noise: its anti-aliased edge share.
    let floor = NOISE_FLOOR * ring_residual;
    let (mut sum, mut su, mut sv, mut own) = (0.0, 0.0, 0.0, 0.0);
    for v in bbox[1]..=bbox[3] {
        visit_row(labelling, index, v, bbox[0], bbox[2], |u0, u1, owner| {
            if owner == Owner::Other {
                return;
            }
            let line = &image.as_raw()[v as usize * w as usize..(v as usize + 1) * w as usize];
            // The sums in registers over the segment (captured ones live in memory).
            let (mut s, mut s_u, mut s_v, mut o) = (sum, su, sv, own);
            let quiet = quiet_level(owner, u0, u1, v, &background, floor);
            if owner == Owner::Own && c.area >= LANES_MIN_AREA {
                let [a, b, d, e] = own_in_lanes(&line[u0 as usize..u1 as usize], flip, u0, v, &background);
                (sum, su, sv, own) = (s + b, s_u + d, s_v + e, o + a);
                return;
            }
            for u in u0..u1 {
                if i16::from(line[u as usize] ^ flip) <= quiet {
                    continue;
                }
                let above = f64::from(line[u as usize] ^ flip) - background(u, v);
                let weight = if owner == Owner::Own {
                    o += above;
                    above.max(0.0)
                } else if above > floor {
                    above
                } else {
                    0.0
                };
                // A weight of zero adds nothing (the sums stay bit for bit what they were):
                // most of a grown box is background under the noise floor.
                if weight != 0.0 {
                    s += weight;
                    s_u += weight * f64::from(u);
                    s_v += weight * f64::from(v);
                }
            }
            (sum, su, sv, own) = (s, s_u, s_v, o);
        });
    }
    let centroid = if sum > 0.0 {
        [su / sum, sv / sum]
    } else {
        [0.5 * f64::from(c.bbox[0] + c.bbox[2]), 0.5 * f64::from(c.bbox[1] + c.bbox[3])]
    };
    Weighted { centroid, contrast: own / c.area as f64, ring_residual }
}

/// Components of at least this many pixels (a disc 72 px across) sum their own pixels in
/// [`LANES`] interleaved partial sums: one sum per pixel is a chain of additions, each waiting
/// for the last (4 cycles a pixel), where independent lanes run side by side (and the compiler
/// puts them in vector registers). Smaller dots keep the one chain, bit for bit as before.
const LANES_MIN_AREA: u64 = 4096;

/// Partial sums per [`own_in_lanes`] call.
const LANES: usize = 4;

/// `[own, sum, su, sv]` over a run of the dot's own pixels, `segment` starting at column
/// `u0` of row `v`: the same terms as the pixel-by-pixel loop, summed in [`LANES`] lanes.
fn own_in_lanes(segment: &[u8], flip: u8, u0: u32, v: u32, background: &impl Fn(u32, u32) -> f64) -> [f64; 4] {
    let mut lanes = [[0.0f64; LANES]; 4];
    let fv = f64::from(v);
    let mut add = |lane: usize, u: u32, g: u8| {
        let above = f64::from(g ^ flip) - background(u, v);
        let weight = above.max(0.0);
        lanes[0][lane] += above;
        lanes[1][lane] += weight;
        lanes[2][lane] += weight * f64::from(u);
        lanes[3][lane] += weight * fv;
    };
    let (chunks, tail) = segment.as_chunks::<LANES>();
    for (k, chunk) in chunks.iter().enumerate() {
        let u = u0 + (k * LANES) as u32;
        for (lane, &g) in chunk.iter().enumerate() {
            add(lane, u + lane as u32, g);
        }
    }
    let u = u0 + (chunks.len() * LANES) as u32;
    for (lane, &g) in tail.iter().enumerate() {
        add(lane, u + lane as u32, g);
    }
    lanes.map(|l| (l[0] + l[1]) + (l[2] + l[3]))
}

/// For a background segment `u0..u1` of row `v`, a level at or below which a pixel is under
/// the noise floor at every column of the segment (its weight zero: skipped, with a compare of
/// bytes, where most of a grown box lies); none (-1 as no level is below it) for the dot's own
/// pixels. The background is linear along the row: its least over the segment is at an end;
/// the margin of 1e-6 grey levels covers the rounding of the plane's evaluation (1e-13).
fn quiet_level(owner: Owner, u0: u32, u1: u32, v: u32, background: &impl Fn(u32, u32) -> f64, floor: f64) -> i16 {
    if owner != Owner::Background || u1 <= u0 || !floor.is_finite() {
        return -1;
    }
    let least = background(u0, v).min(background(u1 - 1, v)) + floor - 1e-6;
    if least.is_nan() { -1 } else { least.floor().clamp(-1.0, 255.0) as i16 }
}

/// `bbox` grown by `margin` pixels on each side, clipped to the `w` x `h` image.
fn grow(bbox: [u32; 4], margin: u32, w: u32, h: u32) -> [u32; 4] {
    [
        bbox[0].saturating_sub(margin),
        bbox[1].saturating_sub(margin),
        (bbox[2] + margin).min(w - 1),
        (bbox[3] + margin).min(h - 1),
    ]
}

/// A box around a dot and the background plane fitted to its border ring.
#[derive(Debug, Clone, Copy)]
struct Ring {
    bbox: [u32; 4],
    /// The box's centre, about which the plane is written.
    centre: [f64; 2],
    plane: [f64; 3],
    /// RMS residual of the ring's pixels from the plane.
    residual: f64,
}

impl Ring {
    fn fit(labelling: &Labelling, index: u32, bbox: [u32; 4], level: &impl Fn(u32, u32) -> f64) -> Self {
        let centre = [0.5 * f64::from(bbox[0] + bbox[2]), 0.5 * f64::from(bbox[1] + bbox[3])];
        let (plane, residual) = ring_plane(labelling, index, bbox, centre, level);
        Self { bbox, centre, plane, residual }
    }
}

/// [`RingFit::Grown`]: the plainest grown ring inside the image (an infinite residual when
/// none is).
fn grown_ring(
    labelling: &Labelling,
    index: u32,
    component: [u32; 4],
    w: u32,
    h: u32,
    level: &impl Fn(u32, u32) -> f64,
) -> Ring {
    let size = (component[2] - component[0]).max(component[3] - component[1]) + 1;
    let inside = |margin: u32| {
        component[0] >= margin && component[1] >= margin && component[2] + margin < w && component[3] + margin < h
    };
    let mut best: Option<Ring> = None;
    let mut margin = 2 * MARGIN;
    while margin <= 2 * size.max(MARGIN) && inside(margin) {
        let next = Ring::fit(labelling, index, grow(component, margin, w, h), level);
        if best.is_none_or(|b| next.residual < b.residual) {
            best = Some(next);
        }
        margin *= 2;
    }
    best.unwrap_or_else(|| Ring {
        residual: f64::INFINITY,
        ..Ring::fit(labelling, index, grow(component, MARGIN, w, h), level)
    })
}

/// Calls `f(u0, u1, owner)` for the segments `u0..u1` of row `v` between columns `first` and
/// `last` (inclusive), by owner.
fn visit_row(labelling: &Labelling, index: u32, v: u32, first: u32, last: u32, mut f: impl FnMut(u32, u32, Owner)) {
    let (runs, components): (&[Run], &[u32]) = labelling.row(v);
    let start = runs.partition_point(|r| r.u1 <= first);
    let mut u = first;
    for (run, &component) in runs[start..].iter().zip(&components[start..]) {
        if run.u0 > last {
            break;
        }
        let (a, b) = (run.u0.max(first), run.u1.min(last + 1));
        if a > u {
            f(u, a, Owner::Background);
        }
        f(a, b, if component == index { Owner::Own } else { Owner::Other });
        u = b;
    }
    if u <= last {
        f(u, last + 1, Owner::Background);
    }
}

/// The plane `[a, b_u, b_v]` (about `centre`) fitted by least squares to the background
/// pixels of the border ring of `bbox`, and the RMS of its residuals; when they do not fix a
/// plane (fewer than three, or all on one line), their mean (and 0 when there are none).
fn ring_plane(
    labelling: &Labelling,
    index: u32,
    bbox: [u32; 4],
    centre: [f64; 2],
    level: &impl Fn(u32, u32) -> f64,
) -> ([f64; 3], f64) {
    let mut sums = PlaneSums::default();
    visit_ring(labelling, index, bbox, |u, v| sums.add(u, v, centre, level(u, v)));
    sums.solve()
}

/// Calls `f(u, v)` for each background pixel of the border ring of `bbox` (its first and last
/// rows, and its first and last columns between them).
fn visit_ring(labelling: &Labelling, index: u32, bbox: [u32; 4], mut f: impl FnMut(u32, u32)) {
    for v in bbox[1]..=bbox[3] {
        let whole_row = v == bbox[1] || v == bbox[3];
        visit_row(labelling, index, v, bbox[0], bbox[2], |u0, u1, owner| {
            if owner != Owner::Background {
                return;
            }
            if whole_row {
                (u0..u1).for_each(|u| f(u, v));
            } else {
                for u in [bbox[0], bbox[2]] {
                    if (u0..u1).contains(&u) {
                        f(u, v);
                    }
                }
            }
        });
    }
}

/// The normal equations of a least-squares plane `g = a + b_u (u - u_c) + b_v (v - v_c)`.
#[derive(Debug, Default)]
struct PlaneSums {
    normal: Matrix3<f64>,
    rhs: Vector3<f64>,
    squares: f64,
}

impl PlaneSums {
    fn add(&mut self, u: u32, v: u32, centre: [f64; 2], g: f64) {
        let x = Vector3::new(1.0, f64::from(u) - centre[0], f64::from(v) - centre[1]);
        self.normal += x * x.transpose();
        self.rhs += x * g;
        self.squares += g * g;
    }

    fn count(&self) -> f64 {
        self.normal[(0, 0)]
    }

    /// The plane and the RMS of its residuals; the mean when the pixels do not fix a plane.
    fn solve(&self) -> ([f64; 3], f64) {
        let count = self.count();
        // Residual sum of squares of a least-squares fit: sum g^2 - p . (X^T g).
        let rms = |p: Vector3<f64>| ((self.squares - p.dot(&self.rhs)).max(0.0) / count).sqrt();
        match self.normal.try_inverse() {
            Some(inverse) if count >= 3.0 && (self.normal.determinant() / count.powi(3)).abs() > 1e-9 => {
                let p = inverse * self.rhs;
                ([p[0], p[1], p[2]], rms(p))
            }
            _ if count > 0.0 => {
                let mean = self.rhs[0] / count;
                ([mean, 0.0, 0.0], rms(Vector3::new(mean, 0.0, 0.0)))
            }
            _ => ([0.0; 3], 0.0),
        }
    }
}
