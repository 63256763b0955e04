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

use crate::error::Error;
use crate::vision::error::{Result, VisionError};
use crate::vision::image::{GreyBuffer, Pixels};
use crate::vision::own_sums::{Plane, background_sums, own_sums, weight};
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

/// The centroid of component `index` of `labelling`, which labelled `image`. An index that is
/// no component, or a labelling of an image of another size, is an error.
pub fn weighted_centroid<C: Pixels>(
    image: &GreyBuffer<C>,
    labelling: &Labelling,
    index: u32,
    dark: bool,
    fit: RingFit,
) -> Result<Weighted> {
    let (size, count) = (labelling.size(), labelling.components.len());
    if size != [image.width(), image.height()] {
        let reason = format!(
            "the labelling is of a {} x {} image, this one is {} x {} (height x width)",
            size[1],
            size[0],
            image.height(),
            image.width()
        );
        return Err(VisionError::InvalidImage { what: "image".to_string(), reason });
    }
    if index as usize >= count {
        let reason = format!("{index} is no component: the labelling has {count}");
        return Err(Error::InvalidParameter { name: "index", reason }.into());
    }
    Ok(centroid_of(image, labelling, index, dark, fit))
}

/// [`weighted_centroid`] of a component of a labelling of `image` (the detector's own).
fn centroid_of<C: Pixels>(
    image: &GreyBuffer<C>,
    labelling: &Labelling,
    index: u32,
    dark: bool,
    fit: RingFit,
) -> Weighted {
    let dot = Dot::new(image, labelling, index, dark);
    let ring = match fit {
        RingFit::Near => dot.near_ring(),
        RingFit::Grown => grown_ring(labelling, index, dot.component.bbox, dot.size, &dot.levels),
    };
    if dot.component.area < LANES_MIN_AREA {
        return dot.weighted(&ring, dot.chained_sums(&ring));
    }
    let own = dot.own_sums(&ring);
    dot.weighted(&ring, own.plus(dot.background_sums(&ring)))
}

/// The centroid of component `index` against its near ring when `keep_near(ring_residual,
/// contrast)` of that measure holds, against its grown ring otherwise: [`weighted_centroid`]
/// with the fit so chosen, bit for bit. A large dot's own pixels are summed first (its
/// contrast), and its near ring's background only when the near ring is kept.
pub(crate) fn near_or_grown_centroid<C: Pixels>(
    image: &GreyBuffer<C>,
    labelling: &Labelling,
    index: u32,
    dark: bool,
    keep_near: impl FnOnce(f64, f64) -> bool,
) -> Weighted {
    let dot = Dot::new(image, labelling, index, dark);
    if dot.component.area < LANES_MIN_AREA {
        let near = centroid_of(image, labelling, index, dark, RingFit::Near);
        return if keep_near(near.ring_residual, near.contrast) {
            near
        } else {
            centroid_of(image, labelling, index, dark, RingFit::Grown)
        };
    }
    let ring = dot.near_ring();
    let own = dot.own_sums(&ring);
    if keep_near(ring.residual, own.own / dot.component.area as f64) {
        dot.weighted(&ring, own.plus(dot.background_sums(&ring)))
    } else {
        centroid_of(image, labelling, index, dark, RingFit::Grown)
    }
}

/// The sums of a centroid: the weights, their moments in `u` and `v`, and the dot's own
/// pixels' levels above the background.
#[derive(Debug, Clone, Copy, Default)]
struct Sums {
    sum: f64,
    su: f64,
    sv: f64,
    own: f64,
}

impl Sums {
    fn plus(self, o: Sums) -> Sums {
        Sums { sum: self.sum + o.sum, su: self.su + o.su, sv: self.sv + o.sv, own: self.own + o.own }
    }
}

/// One component and the image it is measured in.
struct Dot<'a> {
    labelling: &'a Labelling,
    index: u32,
    component: &'a Component,
    levels: Levels<'a>,
    size: [u32; 2],
}

impl<'a> Dot<'a> {
    fn new<C: Pixels>(image: &'a GreyBuffer<C>, labelling: &'a Labelling, index: u32, dark: bool) -> Self {
        let flip = if dark { 255u8 } else { 0 };
        let levels = Levels { data: image.as_raw(), width: image.width() as usize, flip };
        let component = &labelling.components[index as usize];
        Self { labelling, index, component, levels, size: [image.width(), image.height()] }
    }

    fn near_ring(&self) -> Ring {
        let [w, h] = self.size;
        Ring::fit(self.labelling, self.index, grow(self.component.bbox, MARGIN, w, h), &self.levels)
    }

    /// The centroid from the sums over `ring`'s box (the box's centre when nothing weighs).
    fn weighted(&self, ring: &Ring, s: Sums) -> Weighted {
        let [u0, v0, u1, v1] = self.component.bbox;
        let centroid = if s.sum > 0.0 {
            [s.su / s.sum, s.sv / s.sum]
        } else {
            [0.5 * f64::from(u0 + u1), 0.5 * f64::from(v0 + v1)]
        };
        Weighted { centroid, contrast: s.own / self.component.area as f64, ring_residual: ring.residual }
    }

    /// Calls `f(u0, u1, v, owner, pixels)` for the segments of each row of `ring`'s box that
    /// are not another dot's.
    fn visit(&self, ring: &Ring, mut f: impl FnMut(u32, u32, u32, Owner, &[u8])) {
        let bbox = ring.bbox;
        for v in bbox[1]..=bbox[3] {
            visit_row(self.labelling, self.index, v, bbox[0], bbox[2], |u0, u1, owner| {
                if owner != Owner::Other {
                    f(u0, u1, v, owner, self.levels.run(u0, u1, v));
                }
            });
        }
    }

    /// A large dot's own pixels ([`own_sums`]), a sum per run chained in the rows' order.
    fn own_sums(&self, ring: &Ring) -> Sums {
        let plane = Plane { coefficients: ring.plane, centre: ring.centre };
        let mut s = Sums::default();
        self.visit(ring, |u0, _, v, owner, segment| {
            if owner == Owner::Own {
                let [own, sum, su, sv] = own_sums(segment, self.levels.flip, u0, v, &plane);
                s = s.plus(Sums { sum, su, sv, own });
            }
        });
        s
    }

    /// A large dot's background above the noise floor ([`background_sums`]), a sum per loud
    /// block chained in the rows' order (a quiet block weighs nothing).
    fn background_sums(&self, ring: &Ring) -> Sums {
        let plane = Plane { coefficients: ring.plane, centre: ring.centre };
        let background = |u: u32, v: u32| plane.at(u, v);
        let floor = NOISE_FLOOR * ring.residual;
        let flip = self.levels.flip;
        let mut s = Sums::default();
        self.visit(ring, |u0, _, v, owner, segment| {
            if owner != Owner::Background {
                return;
            }
            let quiet = |a: u32, b: u32| quiet_level(owner, a, b, v, &background, floor);
            for (a, pixels, _) in loud_blocks(segment, u0, flip, quiet) {
                let [sum, su, sv] = background_sums(pixels, flip, a, v, &plane, floor);
                s = s.plus(Sums { sum, su, sv, own: 0.0 });
            }
        });
        s
    }

    /// A small dot's sums pixel by pixel, in one chain over the box's rows (its own pixels and
    /// the background's as they come).
    fn chained_sums(&self, ring: &Ring) -> Sums {
        let plane = Plane { coefficients: ring.plane, centre: ring.centre };
        let background = |u: u32, v: u32| plane.at(u, v);
        // A background pixel counts only above the ring's noise: its anti-aliased edge share.
        let floor = NOISE_FLOOR * ring.residual;
        let flip = self.levels.flip;
        let (mut sum, mut su, mut sv, mut own) = (0.0, 0.0, 0.0, 0.0);
        self.visit(ring, |u0, u1, v, owner, segment| {
            // The sums in registers over the segment (captured ones live in memory).
            let (mut s, mut s_u, mut s_v, mut o) = (sum, su, sv, own);
            let mut add = |a: u32, pixels: &[u8], quiet: i16| {
                for (u, &g) in (a..).zip(pixels) {
                    if i16::from(g ^ flip) <= quiet {
                        continue;
                    }
                    let above = f64::from(g ^ flip) - background(u, v);
                    if owner == Owner::Own {
                        o += above;
                    }
                    let weight = weight(above, (owner == Owner::Background).then_some(floor));
                    // A weight of zero adds nothing (the sums stay bit for bit what they were):
                    // most of a grown box is background under the noise floor.
                    if weight != 0.0 {
                        s += weight;
                        s_u += weight * f64::from(u);
                        s_v += weight * f64::from(v);
                    }
                }
            };
            // A run of the dot's own pixels, or a short one, in one go; a long run of
            // background block by block (most blocks of a grown box are quiet).
            if owner == Owner::Own || segment.len() <= BLOCK {
                add(u0, segment, quiet_level(owner, u0, u1, v, &background, floor));
            } else {
                let quiet = |a: u32, b: u32| quiet_level(owner, a, b, v, &background, floor);
                for (a, pixels, quiet) in loud_blocks(segment, u0, flip, quiet) {
                    add(a, pixels, quiet);
                }
            }
            (sum, su, sv, own) = (s, s_u, s_v, o);
        });
        Sums { sum, su, sv, own }
    }
}

/// Components of at least this many pixels (a disc 72 px across) sum their own pixels and their
/// background's in [`LANES`](super::own_sums::LANES) interleaved partial sums ([`own_sums`],
/// [`background_sums`]): one sum per pixel is a chain of additions, each waiting for the last
/// (4 cycles a pixel), where independent lanes run side by side. Smaller dots keep the one
/// chain, bit for bit as before.
const LANES_MIN_AREA: u64 = 4096;

/// Pixels per block of [`loud_blocks`].
const BLOCK: usize = 32;

/// The blocks of [`BLOCK`] pixels of `segment` (from column `u0`) that hold a level above
/// their own `quiet(a, b)` level (columns `a..b`; every block when it is negative), as (first
/// column, pixels, quiet level): a block of background under the noise floor, most of a grown
/// box, is passed over with one maximum of its bytes (vectorised), and a block's own level is
/// closer to its pixels' than the whole segment's where the background slopes.
fn loud_blocks(
    segment: &[u8],
    u0: u32,
    flip: u8,
    quiet: impl Fn(u32, u32) -> i16,
) -> impl Iterator<Item = (u32, &[u8], i16)> {
    segment.chunks(BLOCK).enumerate().filter_map(move |(k, block)| {
        let a = u0 + (k * BLOCK) as u32;
        let quiet = quiet(a, a + block.len() as u32);
        let loud = quiet < 0 || i16::from(block.iter().fold(0u8, |m, &g| m.max(g ^ flip))) > quiet;
        loud.then_some((a, block, quiet))
    })
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

/// The image's bytes, its width, and the flip of its levels (`g ^ flip`: 255 for dark dots).
struct Levels<'a> {
    data: &'a [u8],
    width: usize,
    flip: u8,
}

impl Levels<'_> {
    /// The bytes of columns `u0..u1` of row `v`.
    fn run(&self, u0: u32, u1: u32, v: u32) -> &[u8] {
        let first = v as usize * self.width;
        &self.data[first + u0 as usize..first + u1 as usize]
    }
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
    fn fit(labelling: &Labelling, index: u32, bbox: [u32; 4], levels: &Levels) -> Self {
        Self::new(bbox, ring_plane(labelling, index, bbox, levels))
    }

    /// The ring of `bbox` with its fitted plane and residual.
    fn new(bbox: [u32; 4], (plane, residual): ([f64; 3], f64)) -> Self {
        let centre = [0.5 * f64::from(bbox[0] + bbox[2]), 0.5 * f64::from(bbox[1] + bbox[3])];
        Self { bbox, centre, plane, residual }
    }
}

/// [`RingFit::Grown`]: the plainest grown ring inside the image (an infinite residual when
/// none is); the first of the plainest when several are as plain.
fn grown_ring(labelling: &Labelling, index: u32, component: [u32; 4], [w, h]: [u32; 2], levels: &Levels) -> Ring {
    let size = (component[2] - component[0]).max(component[3] - component[1]) + 1;
    let inside = |margin: u32| {
        component[0] >= margin && component[1] >= margin && component[2] + margin < w && component[3] + margin < h
    };
    let margins = std::iter::successors(Some(2 * MARGIN), |m| m.checked_mul(2));
    let boxes: Vec<[u32; 4]> =
        margins.take_while(|&m| m <= 2 * size.max(MARGIN) && inside(m)).map(|m| grow(component, m, w, h)).collect();
    let mut best: Option<Ring> = None;
    for (&bbox, fitted) in boxes.iter().zip(ring_planes(labelling, index, &boxes, levels)) {
        if best.is_none_or(|b| fitted.1 < b.residual) {
            best = Some(Ring::new(bbox, fitted));
        }
    }
    best.unwrap_or_else(|| Ring {
        residual: f64::INFINITY,
        ..Ring::fit(labelling, index, grow(component, MARGIN, w, h), levels)
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

/// The plane `[a, b_u, b_v]` (about `centre`, the centre of `bbox`) fitted by least squares
/// to the background pixels of the border ring of `bbox`, and the RMS of its residuals; when
/// they do not fix a plane (fewer than three, or all on one line), their mean (and 0 when there
/// are none).
fn ring_plane(labelling: &Labelling, index: u32, bbox: [u32; 4], levels: &Levels) -> ([f64; 3], f64) {
    let planes = ring_planes(labelling, index, std::slice::from_ref(&bbox), levels);
    // One box gives one plane (the fallback, a ring without pixels, is never taken).
    planes.into_iter().next().unwrap_or_else(|| PlaneSums::new(bbox).solve())
}

/// [`ring_plane`] of each of `boxes`, each box inside the next (the grown rings of one dot): one
/// pass over the rows of the last, each row's runs read once for every ring crossing it (the
/// sums are whole numbers: the same whatever the order of the pixels, see [`PlaneSums`]).
fn ring_planes(labelling: &Labelling, index: u32, boxes: &[[u32; 4]], levels: &Levels) -> Vec<([f64; 3], f64)> {
    let mut sums: Vec<PlaneSums> = boxes.iter().map(|&bbox| PlaneSums::new(bbox)).collect();
    let Some(outer) = boxes.last() else { return Vec::new() };
    for v in outer[1]..=outer[3] {
        for (&bbox, sums) in boxes.iter().zip(&mut sums).filter(|(b, _)| (b[1]..=b[3]).contains(&v)) {
            visit_ring_row(labelling, index, bbox, v, |u0, u1| sums.add_run(u0, levels.run(u0, u1, v), v, levels.flip));
        }
    }
    sums.iter().map(PlaneSums::solve).collect()
}

/// Calls `f(u0, u1)` for each run `u0..u1` of background pixels of row `v` (inside `bbox`) on
/// the border ring of `bbox` (its first and last rows, and its first and last columns between
/// them). Between the first and last rows only the two columns are looked up (a search in the
/// row's runs each), not the row's runs across the box: a grown ring's box is many times the
/// dot's.
fn visit_ring_row(labelling: &Labelling, index: u32, bbox: [u32; 4], v: u32, mut f: impl FnMut(u32, u32)) {
    if v == bbox[1] || v == bbox[3] {
        visit_row(labelling, index, v, bbox[0], bbox[2], |u0, u1, owner| {
            if owner == Owner::Background {
                f(u0, u1);
            }
        });
        return;
    }
    let (runs, _) = labelling.row(v);
    for u in [bbox[0], bbox[2]] {
        let covered = runs.get(runs.partition_point(|r| r.u1 <= u)).is_some_and(|r| r.u0 <= u);
        if !covered {
            f(u, u + 1);
        }
    }
}

/// The normal equations of a least-squares plane `g = a + b_u (u - u_c) + b_v (v - v_c)`, as
/// integer sums of `x = (1, 2 (u - u_c), 2 (v - v_c))` (integers: `u_c` is a whole or half
/// pixel). Every sum of the equations in `f64` (products of halves and levels, a multiple of
/// 1/4 below 2^50 for any image of at most 2^26 pixels) is exact in any order, so these are
/// the sums pixel by pixel in `f64`, bit for bit (tested).
#[derive(Debug, Default)]
struct PlaneSums {
    /// `2 u_c`, `2 v_c`.
    twice_centre: [i64; 2],
    /// `sum x x^T` (upper triangle: 00, 01, 02, 11, 12, 22).
    normal: [i64; 6],
    /// `sum x g`.
    rhs: [i64; 3],
    /// `sum g^2`.
    squares: i64,
}

impl PlaneSums {
    fn new(bbox: [u32; 4]) -> Self {
        let twice_centre = [i64::from(bbox[0] + bbox[2]), i64::from(bbox[1] + bbox[3])];
        Self { twice_centre, ..Self::default() }
    }

    /// Pixels `run` of row `v` from column `u0`, levels `g ^ flip`.
    fn add_run(&mut self, u0: u32, run: &[u8], v: u32, flip: u8) {
        let y = 2 * i64::from(v) - self.twice_centre[1];
        let (mut n, mut sx, mut sxx, mut sg, mut sxg, mut sgg) = (0i64, 0i64, 0i64, 0i64, 0i64, 0i64);
        for (u, &g) in (u0..).zip(run) {
            let (x, g) = (2 * i64::from(u) - self.twice_centre[0], i64::from(g ^ flip));
            n += 1;
            sx += x;
            sxx += x * x;
            sg += g;
            sxg += x * g;
            sgg += g * g;
        }
        let [s00, s01, s02, s11, s12, s22] = &mut self.normal;
        (*s00, *s01, *s02, *s11, *s12, *s22) =
            (*s00 + n, *s01 + sx, *s02 + y * n, *s11 + sxx, *s12 + y * sx, *s22 + y * y * n);
        self.rhs = [self.rhs[0] + sg, self.rhs[1] + sxg, self.rhs[2] + y * sg];
        self.squares += sgg;
    }

    /// The sums of `(1, u - u_c, v - v_c)` (halves of the integer ones): exact in `f64`.
    fn equations(&self) -> (Matrix3<f64>, Vector3<f64>) {
        let [s00, s01, s02, s11, s12, s22] = self.normal.map(|s| s as f64);
        let normal =
            Matrix3::new(s00, s01 / 2.0, s02 / 2.0, s01 / 2.0, s11 / 4.0, s12 / 4.0, s02 / 2.0, s12 / 4.0, s22 / 4.0);
        let rhs = Vector3::new(self.rhs[0] as f64, self.rhs[1] as f64 / 2.0, self.rhs[2] as f64 / 2.0);
        (normal, rhs)
    }

    /// The plane and the RMS of its residuals; the mean when the pixels do not fix a plane.
    fn solve(&self) -> ([f64; 3], f64) {
        let (normal, rhs) = self.equations();
        let (count, squares) = (normal[(0, 0)], self.squares as f64);
        // Residual sum of squares of a least-squares fit: sum g^2 - p . (X^T g).
        let rms = |p: Vector3<f64>| ((squares - p.dot(&rhs)).max(0.0) / count).sqrt();
        match normal.try_inverse() {
            Some(inverse) if count >= 3.0 && (normal.determinant() / count.powi(3)).abs() > 1e-9 => {
                let p = inverse * rhs;
                ([p[0], p[1], p[2]], rms(p))
            }
            _ if count > 0.0 => {
                let mean = rhs[0] / count;
                ([mean, 0.0, 0.0], rms(Vector3::new(mean, 0.0, 0.0)))
            }
            _ => ([0.0; 3], 0.0),
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn a_ring_visits_the_background_pixels_of_its_border_in_order() {
        // Blobs of every size on a 90 x 70 image, labelled; against each pixel of the ring
        // looked up in the runs of its row (every run, not a search), rings of many boxes.
        use crate::vision::background::TileThresholds;
        use crate::vision::image::GreyImage;
        use crate::vision::runs::label;
        let image = GreyImage::from_fn(90, 70, |u, v| {
            let (x, y) = (f64::from(u), f64::from(v));
            let blob = (x * 0.37).sin() * (y * 0.23).cos() + 0.4 * (x * 0.11 + y * 0.17).sin();
            ::image::Luma([if blob > 0.35 { 200 } else { 30 }])
        });
        let labelling = label(&image, &TileThresholds::uniform(&image, 100), false);
        assert!(labelling.components.len() > 5, "{} components", labelling.components.len());
        let covered = |u: u32, v: u32| labelling.row(v).0.iter().any(|r| (r.u0..r.u1).contains(&u));
        for (k, bbox) in [[0u32, 0, 89, 69], [3, 4, 40, 30], [10, 10, 10, 40], [50, 2, 88, 3], [20, 33, 71, 33]]
            .into_iter()
            .enumerate()
        {
            let mut seen = Vec::new();
            for v in bbox[1]..=bbox[3] {
                visit_ring_row(&labelling, k as u32, bbox, v, |u0, u1| seen.extend((u0..u1).map(|u| (u, v))));
            }
            let mut expected = Vec::new();
            for v in bbox[1]..=bbox[3] {
                let columns: Vec<u32> =
                    if v == bbox[1] || v == bbox[3] { (bbox[0]..=bbox[2]).collect() } else { vec![bbox[0], bbox[2]] };
                expected.extend(columns.into_iter().filter(|&u| !covered(u, v)).map(|u| (u, v)));
            }
            assert_eq!(seen, expected, "{bbox:?}");
        }
    }

    #[test]
    fn the_near_or_grown_centroid_is_the_chosen_fits_bit_for_bit() {
        // A large disc (lanes, its own pixels summed first) and a small one (one chain) on a
        // sloped, textured background, each kept near and sent to the grown ring.
        use crate::vision::background::TileThresholds;
        use crate::vision::image::GreyImage;
        use crate::vision::runs::label;
        let image = GreyImage::from_fn(400, 300, |u, v| {
            let (x, y) = (f64::from(u), f64::from(v));
            let disc =
                |cx: f64, cy: f64, r: f64| (r + 0.5 - ((x - cx).powi(2) + (y - cy).powi(2)).sqrt()).clamp(0.0, 1.0);
            let inside = disc(150.0, 140.0, 60.0).max(disc(320.0, 90.0, 12.0));
            let ground = 40.0 + 0.1 * x + 0.05 * y + f64::from((u * 7 + v * 13) % 5);
            ::image::Luma([(ground + inside * 150.0).round() as u8])
        });
        let labelling = label(&image, &TileThresholds::uniform(&image, 120), false);
        let areas: Vec<u64> = labelling.components.iter().map(|c| c.area).collect();
        assert!(areas.iter().any(|&a| a >= LANES_MIN_AREA) && areas.iter().any(|&a| a < LANES_MIN_AREA), "{areas:?}");
        for index in 0..labelling.components.len() as u32 {
            for (keep, fit) in [(true, RingFit::Near), (false, RingFit::Grown)] {
                let mut asked = None;
                let chosen = near_or_grown_centroid(&image, &labelling, index, false, |residual, contrast| {
                    asked = Some((residual, contrast));
                    keep
                });
                assert_eq!(
                    chosen,
                    weighted_centroid(&image, &labelling, index, false, fit).unwrap(),
                    "{index} {fit:?}"
                );
                // It decided on the near ring's own measure.
                let near = weighted_centroid(&image, &labelling, index, false, RingFit::Near).unwrap();
                let (residual, contrast) = asked.unwrap();
                assert_eq!(
                    (residual.to_bits(), contrast.to_bits()),
                    (near.ring_residual.to_bits(), near.contrast.to_bits())
                );
            }
        }
    }

    #[test]
    fn integer_plane_sums_are_the_float_sums_bit_for_bit() {
        // The float sums pixel by pixel (the former code) against the integer ones, on boxes
        // with whole and half-pixel centres, far from the origin, both polarities.
        let mut state = 17u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            state >> 33
        };
        for (bbox, flip) in [([3u32, 5, 40, 22], 0u8), ([1000, 2000, 1713, 2390], 255), ([0, 0, 8191, 8191], 0)] {
            let centre = [0.5 * f64::from(bbox[0] + bbox[2]), 0.5 * f64::from(bbox[1] + bbox[3])];
            let (mut normal, mut rhs, mut squares) = (Matrix3::<f64>::zeros(), Vector3::<f64>::zeros(), 0.0);
            let mut sums = PlaneSums::new(bbox);
            for v in [bbox[1], bbox[1] + 1, bbox[3]] {
                let (u0, u1) = (bbox[0] + (next() % 3) as u32, bbox[2] + 1);
                let run: Vec<u8> = (u0..u1).map(|_| (next() % 256) as u8).collect();
                for (u, &g) in (u0..).zip(&run) {
                    let g = f64::from(g ^ flip);
                    let x = Vector3::new(1.0, f64::from(u) - centre[0], f64::from(v) - centre[1]);
                    normal += x * x.transpose();
                    rhs += x * g;
                    squares += g * g;
                }
                sums.add_run(u0, &run, v, flip);
            }
            let (n, r) = sums.equations();
            assert_eq!(n, normal, "{bbox:?}");
            assert_eq!(r, rhs, "{bbox:?}");
            assert_eq!(sums.squares as f64, squares);
        }
    }

    /// An index that is no component and a labelling of another image are errors naming
    /// them, never a panic; a row outside the labelling has no runs.
    #[test]
    fn a_wrong_index_or_labelling_is_an_error() {
        use crate::vision::background::TileThresholds;
        use crate::vision::image::GreyImage;
        use crate::vision::runs::label;
        let image =
            GreyImage::from_fn(40, 30, |u, v| ::image::Luma([if (u / 10 + v / 10) % 2 == 0 { 200 } else { 20 }]));
        let labelling = label(&image, &TileThresholds::uniform(&image, 120), false);
        let count = labelling.components.len() as u32;
        assert!(count > 0 && weighted_centroid(&image, &labelling, count - 1, false, RingFit::Near).is_ok());
        for index in [count, u32::MAX] {
            let err = weighted_centroid(&image, &labelling, index, false, RingFit::Grown).unwrap_err();
            assert!(err.to_string().contains("index") && err.to_string().contains("no component"), "{err}");
        }
        let other = GreyImage::from_fn(41, 30, |_, _| ::image::Luma([0]));
        let err = weighted_centroid(&other, &labelling, 0, false, RingFit::Near).unwrap_err();
        assert!(err.to_string().starts_with("image: the labelling is of a 30 x 40 image"), "{err}");
        assert_eq!(labelling.size(), [40, 30]);
        assert!(labelling.row(30).0.is_empty() && labelling.row(u32::MAX).0.is_empty());
    }
}
