//! The reference image as the servo reads it: its pixels (pinhole, in K*), the basis, and
//! the invariant points s* and the rz reference they give (sec. 2.3, eq. 21).

use nalgebra::Vector3;

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

/// The basis among the points flagged visible: the widest triangle of their *reference*
/// pixels (the reference image fixes s*, so the choice does not depend on the current view);
/// indices into all the points.
pub(crate) fn choose_visible_basis(reference_pixels: &[[f64; 2]], visible: &[bool]) -> Result<[usize; 3]> {
    let seen: Vec<usize> = (0..reference_pixels.len()).filter(|&i| visible[i]).collect();
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
            let got = choose_visible_basis(&px, &visible).unwrap();
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
        assert!(choose_visible_basis(&px, &few).is_err());
    }
}
