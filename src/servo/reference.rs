//! The reference image as the servo reads it: its pixels (pinhole, in K*), the basis, and
//! the invariant points s* and the rz reference they give (sec. 2.3, eq. 21).

use nalgebra::Vector3;

use crate::core::convex_hull::convex_hull;
use crate::core::invariant::{BasisFrame, RzReference, choose_basis, non_basis_indices};
use crate::error::Result;

/// What the reference image provides to the measurements.
pub(crate) struct ReferenceImage {
    pub(crate) pixels: Vec<[f64; 2]>,
    pub(crate) basis: [usize; 3],
    pub(crate) others: Vec<usize>,
    pub(crate) s_star: Vec<Vector3<f64>>,
    pub(crate) rz: RzReference,
}

impl ReferenceImage {
    /// The reference image's invariant points s* and rz reference for a basis.
    pub(crate) fn new(pixels: Vec<[f64; 2]>, basis: [usize; 3]) -> Result<Self> {
        let others = non_basis_indices(pixels.len(), basis);
        let frame = BasisFrame::new(&pixels, basis, "reference")?;
        let s_star = others.iter().map(|&i| frame.transform(pixels[i])).collect();
        Ok(Self { rz: RzReference::new(&frame), pixels, basis, others, s_star })
    }
}

/// Peeling a layer of convex hull off the candidates stops when fewer points would remain.
pub(crate) const INSET_MIN_POINTS: usize = 12;

/// The basis among the points flagged visible: the widest triangle of their *reference*
/// pixels (the reference image fixes s*, so the choice does not depend on the current view);
/// indices into all the points. With `inset` > 0, that many layers of convex hull are set
/// aside first (while at least [`INSET_MIN_POINTS`] remain): the basis matrix Q of eq. (5)
/// stays well conditioned (a wide triangle, sec. 5.1) without resting on the outermost
/// points, which for keypoints on an object are the most foreshortened and the noisiest, and
/// each of whose errors enters every invariant point q_k = Q^-1 m_k.
pub(crate) fn choose_visible_basis(
    reference_pixels: &[[f64; 2]],
    visible: &[bool],
    inset: usize,
) -> Result<[usize; 3]> {
    let mut seen: Vec<usize> = (0..reference_pixels.len()).filter(|&i| visible[i]).collect();
    for _ in 0..inset {
        let pixels: Vec<[f64; 2]> = seen.iter().map(|&i| reference_pixels[i]).collect();
        let hull: Vec<usize> = convex_hull(&pixels).into_iter().map(|h| seen[h]).collect();
        if seen.len() < INSET_MIN_POINTS + hull.len() {
            break;
        }
        seen.retain(|i| !hull.contains(i));
    }
    let pixels: Vec<[f64; 2]> = seen.iter().map(|&i| reference_pixels[i]).collect();
    let [a, b, c] = choose_basis(&pixels)?;
    Ok([seen[a], seen[b], seen[c]])
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    /// The widest triangle of the visible points, checked by brute force over all triples.
    #[test]
    fn visible_basis_is_the_widest_visible_triangle() {
        let px: [[f64; 2]; 7] =
            [[0.0, 0.0], [100.0, 0.0], [0.0, 100.0], [60.0, 70.0], [10.0, 40.0], [90.0, 20.0], [30.0, 95.0]];
        let area = |i: usize, j: usize, k: usize| {
            let (a, b, c) = (px[i], px[j], px[k]);
            ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs()
        };
        for hidden in 0..px.len() {
            let visible: Vec<bool> = (0..px.len()).map(|i| i != hidden).collect();
            let got = choose_visible_basis(&px, &visible, 0).unwrap();
            assert!(!got.contains(&hidden), "{got:?} uses hidden point {hidden}");
            let mut best = 0.0f64;
            for i in 0..px.len() {
                for j in i + 1..px.len() {
                    for k in j + 1..px.len() {
                        if visible[i] && visible[j] && visible[k] {
                            best = best.max(area(i, j, k));
                        }
                    }
                }
            }
            assert_eq!(area(got[0], got[1], got[2]), best, "hidden {hidden}: {got:?}");
        }
        let few = [true, true, false, false, false, false, false];
        assert!(choose_visible_basis(&px, &few, 0).is_err());
    }

    /// With an inset of one layer, the basis is the widest triangle (brute force) of the
    /// points that are not convex-hull vertices (a 6 x 6 grid: the 20 border points are the
    /// hull's vertices or on its edges; strictly, only the 4 corners are vertices).
    #[test]
    fn inset_basis_leaves_out_the_hull() {
        let mut px: Vec<[f64; 2]> = Vec::new();
        for i in 0..6 {
            for j in 0..6 {
                // A slight bulge makes every border point a strict hull vertex.
                let (x, y) = (f64::from(i) * 20.0, f64::from(j) * 20.0);
                let bulge = |t: f64| 3.0 * (t / 100.0) * (1.0 - t / 100.0);
                let side = |k: i32, t: f64| match k {
                    0 => -bulge(t),
                    5 => bulge(t),
                    _ => 0.0,
                };
                let (dx, dy) = (side(i, y), side(j, x));
                px.push([x + dx, y + dy]);
            }
        }
        let visible = vec![true; px.len()];
        let outer = choose_visible_basis(&px, &visible, 0).unwrap();
        let inner = choose_visible_basis(&px, &visible, 1).unwrap();
        let border = |k: usize| k / 6 == 0 || k / 6 == 5 || k.is_multiple_of(6) || k % 6 == 5;
        assert!(outer.iter().all(|&k| border(k)), "{outer:?}");
        assert!(inner.iter().all(|&k| !border(k)), "{inner:?}");
        let area = |t: [usize; 3]| {
            let (a, b, c) = (px[t[0]], px[t[1]], px[t[2]]);
            ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs()
        };
        let mut best = 0.0f64;
        for i in 0..36 {
            for j in i + 1..36 {
                for k in j + 1..36 {
                    if !border(i) && !border(j) && !border(k) {
                        best = best.max(area([i, j, k]));
                    }
                }
            }
        }
        assert_eq!(area(inner), best);
        // A second layer takes the inner 4 x 4's corners (its only strict hull vertices), which
        // leaves 12 points; a third would leave 4 (the octagon of 8 is the hull): it stops.
        let second = choose_visible_basis(&px, &visible, 2).unwrap();
        assert!(second.iter().all(|&k| !border(k) && ![7, 10, 25, 28].contains(&k)), "{second:?}");
        assert_eq!(choose_visible_basis(&px, &visible, 3).unwrap(), second);
    }
}
