//! The reference image as the servo reads it: its pixels (pinhole, in K*), the basis, and
//! the invariant points s* and the rz reference they give (sec. 2.3, eq. 21).

use nalgebra::Vector3;

use crate::core::invariant::{BasisFrame, RzReference, non_basis_indices};
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
