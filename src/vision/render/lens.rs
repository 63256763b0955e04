//! The lens between the ideal pinhole image (where the projected shapes are exact) and the
//! rendered image: pixel `p` shows what the ideal image shows at `K d^-1(K^-1 p)`.

use nalgebra::{Matrix2, Matrix3, Vector3};

use crate::core::camera::Intrinsics;
use crate::core::distortion::{Distortion, distort_normalised, undistort_point};

/// A pixel of the rendered image in the ideal pinhole image: where its centre falls and the
/// local Jacobian `d ideal / d pixel` (the identity without distortion).
pub(super) struct Local {
    pub(super) ideal: [f64; 2],
    pub(super) jacobian: Matrix2<f64>,
}

/// From the rendered (distorted) image to the ideal pinhole image the shapes live in.
pub(super) enum Warp {
    Pinhole,
    Lens { k: Intrinsics, distortion: Distortion },
}

impl Warp {
    pub(super) fn new(k: &Intrinsics, distortion: &Distortion) -> Self {
        if distortion.is_identity() { Warp::Pinhole } else { Warp::Lens { k: *k, distortion: *distortion } }
    }

    /// The ideal position of pixel `(u, v)` and the local Jacobian `K J_d(m)^-1 K^-1`
    /// (2 x 2 parts); None for a pixel beyond the image of the fold.
    #[inline]
    pub(super) fn local(&self, u: f64, v: f64) -> Option<Local> {
        let Warp::Lens { k, distortion } = self else {
            return Some(Local { ideal: [u, v], jacobian: Matrix2::identity() });
        };
        let ideal = undistort_point([u, v], k, distortion).ok()?;
        let m = k.normalise(ideal).ok()?;
        let k2 = k.matrix().fixed_view::<2, 2>(0, 0).into_owned();
        let jacobian = k2 * distortion.jacobian(m).ok()?.try_inverse()? * k2.try_inverse()?;
        Some(Local { ideal, jacobian })
    }

    /// The bounding box of a disc's distorted image, from 72 points of its rim (`h` maps the
    /// disc's plane to ideal pixels, `r` its radius) and one pixel of margin; None if part
    /// of the rim lies beyond the fold (or without a lens).
    pub(super) fn bbox_of_circle(&self, h: &Matrix3<f64>, r: f64) -> Option<[f64; 4]> {
        let Warp::Lens { k, distortion } = self else { return None };
        let mut bbox = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
        for i in 0..72 {
            let t = f64::from(i) * std::f64::consts::TAU / 72.0;
            let x = h * Vector3::new(r * t.cos(), r * t.sin(), 1.0);
            let p = distort_normalised(k.normalise([x.x / x.z, x.y / x.z]).ok()?, k, distortion)?;
            bbox = [bbox[0].min(p[0]), bbox[1].min(p[1]), bbox[2].max(p[0]), bbox[3].max(p[1])];
        }
        Some([bbox[0] - 1.0, bbox[1] - 1.0, bbox[2] + 1.0, bbox[3] + 1.0])
    }
}
