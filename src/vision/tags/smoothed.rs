//! The edges read again on a smoothed copy of the tag's neighbourhood, for a tag whose edges
//! in the image itself do not support its corners (noise scatters the edge crossings).
//!
//! The crossing of a profile is the integral of its whiteness (`edges.rs`), which a symmetric
//! blur leaves where it was (the blurred step keeps its area), while it averages the noise of
//! each sample over some `2 sqrt(pi) sigma^2` pixels. The blur is kept below a third of a cell
//! so the data cells next to the border do not spill into the profiles (which reach half a
//! cell on each side of the edge). The checks of `edges.rs` (support, straightness, settling,
//! bounded moves) all apply: a tag is still refused rather than reported with a wrong corner.

use super::edges;
use crate::vision::image::{GreyBuffer, GreyImage, Pixels};

type P = [f64; 2];

/// The blur's standard deviation, pixels, between these bounds and at most a third of a cell.
const MIN_SIGMA: f64 = 0.8;
const MAX_SIGMA: f64 = 2.0;

/// The corners measured on a blurred crop around the quad, or `None` (as
/// [`edges::refine_corners`]).
pub(super) fn refine_corners<C: Pixels>(
    image: &GreyBuffer<C>,
    corners: &[P; 4],
    border: edges::Border,
) -> Option<[P; 4]> {
    let side = (0..4).map(|i| dist(corners[i], corners[(i + 1) % 4])).sum::<f64>() / 4.0;
    let cell = side / border.cells;
    let sigma = (cell / 3.0).min(MAX_SIGMA);
    if sigma < MIN_SIGMA {
        return None;
    }
    let margin = 2.0 * cell + 4.0 * sigma + 4.0;
    let lo = [0, 1].map(|k| corners.iter().map(|c| c[k]).fold(f64::INFINITY, f64::min) - margin);
    let hi = [0, 1].map(|k| corners.iter().map(|c| c[k]).fold(f64::NEG_INFINITY, f64::max) + margin);
    let (u0, v0) = (lo[0].max(0.0).floor() as u32, lo[1].max(0.0).floor() as u32);
    let (u1, v1) =
        (hi[0].min(f64::from(image.width())).ceil() as u32, hi[1].min(f64::from(image.height())).ceil() as u32);
    if !(lo[0].is_finite() && hi[0].is_finite() && lo[1].is_finite() && hi[1].is_finite())
        || u1 <= u0 + 2
        || v1 <= v0 + 2
    {
        return None;
    }
    let crop = crop(image, u0, v0, u1 - u0, v1 - v0)?;
    let blurred = imageproc::filter::gaussian_blur_f32(&crop, sigma as f32);
    let shift = [f64::from(u0), f64::from(v0)];
    let local = corners.map(|c| [c[0] - shift[0], c[1] - shift[1]]);
    let found = edges::refine_corners(&blurred, &local, border)?;
    Some(found.map(|c| [c[0] + shift[0], c[1] + shift[1]]))
}

fn crop<C: Pixels>(image: &GreyBuffer<C>, u0: u32, v0: u32, w: u32, h: u32) -> Option<GreyImage> {
    let stride = image.width() as usize;
    let pixels: &[u8] = image.as_raw();
    let mut out = Vec::with_capacity(w as usize * h as usize);
    for v in v0..v0 + h {
        let start = v as usize * stride + u0 as usize;
        out.extend_from_slice(pixels.get(start..start + w as usize)?);
    }
    GreyImage::from_raw(w, h, out)
}

fn dist(a: P, b: P) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::vision::tags::edges::tests::BORDER;
    use crate::vision::tags::synthetic::{Placement, corners, draw};
    use crate::vision::tags::{TagFamily, detect_tags};

    /// Gaussian noise of standard deviation `sigma` (Box-Muller on a fixed linear congruential
    /// sequence), clamped to 0..=255.
    fn noisy(image: &GreyImage, sigma: f64) -> GreyImage {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = || {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        let mut out = image.clone();
        for p in out.pixels_mut() {
            let n = (-2.0 * uniform().ln()).sqrt() * (std::f64::consts::TAU * uniform()).cos();
            p[0] = (f64::from(p[0]) + sigma * n).round().clamp(0.0, 255.0) as u8;
        }
        out
    }

    fn worst(a: &[P; 4], b: &[P; 4]) -> f64 {
        a.iter().zip(b).map(|(p, q)| dist(*p, *q)).fold(0.0, f64::max)
    }

    #[test]
    fn noisy_edges_refused_in_the_image_are_measured_on_the_smoothed_crop() {
        let p = Placement { id: 42, centre: [150.3, 120.6], cell: 12.0, quarter_turns: 1 };
        let truth = corners(TagFamily::Tag36h11, &p);
        let image = noisy(&draw(TagFamily::Tag36h11, 300, 240, &[p]), 30.0);
        let start = truth.map(|c| [c[0] + 0.3, c[1] - 0.3]);
        // In the image itself the crossings scatter too much: refused.
        assert_eq!(edges::refine_corners(&image, &start, BORDER), None);
        let found = refine_corners(&image, &start, BORDER).unwrap();
        assert!(worst(&found, &truth) < 0.15, "{found:?} vs {truth:?}");
        // The whole detector reports the tag, at those corners.
        let tags = detect_tags(&image, TagFamily::Tag36h11).unwrap();
        assert_eq!(tags.iter().map(|t| t.id).collect::<Vec<_>>(), [42]);
        assert!(worst(&tags[0].corners, &truth) < 0.15);
    }

    #[test]
    fn quads_off_the_edges_or_too_small_are_still_refused() {
        let p = Placement { id: 42, centre: [150.3, 120.6], cell: 12.0, quarter_turns: 0 };
        let truth = corners(TagFamily::Tag36h11, &p);
        let image = noisy(&draw(TagFamily::Tag36h11, 300, 240, &[p]), 20.0);
        // On the border's inner edge (a cell in): no black-to-white step there.
        let inner =
            truth.map(|c| [p.centre[0] + 0.75 * (c[0] - p.centre[0]), p.centre[1] + 0.75 * (c[1] - p.centre[1])]);
        assert_eq!(refine_corners(&image, &inner, BORDER), None);
        // Cells under 2.4 px: no blur fits in a third of a cell.
        assert_eq!(refine_corners(&image, &[[10.0, 10.0], [28.0, 10.0], [28.0, 28.0], [10.0, 28.0]], BORDER), None);
        // Reaching out of the image.
        assert_eq!(
            refine_corners(&image, &[[-50.0, 10.0], [100.0, 10.0], [100.0, 100.0], [-50.0, 100.0]], BORDER),
            None
        );
    }
}
