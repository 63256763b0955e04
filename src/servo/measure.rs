//! Measurements of each image against the reference image, independent of the control law:
//! tau (eq. 21), the invariant and image errors, and the row the stop window averages.

use nalgebra::Vector3;

use crate::core::invariant::BasisFrame;
use crate::servo::reference::ReferenceImage;

/// Measurements that do not depend on the law, from the noisy pixels.
pub(crate) struct Metrics {
    pub(crate) invariant_error: f64,
    pub(crate) tau: [f64; 3],
    pub(crate) eps_z: f64,
    pub(crate) image_error: f64,
}

/// Measures one image against the reference: the summary metrics, and the error vectors of
/// the stop rule written into `row` (`tau_21`, then `s - s*`, then `p - p*`; NaN for
/// hidden points).
pub(crate) fn measure(pixels: &[[f64; 2]], visible: &[bool], r: &ReferenceImage, row: &mut Vec<f64>) -> Metrics {
    let (reference, basis, others, rz, s_star) = (&r.pixels, r.basis, &r.others, &r.rz, &r.s_star);
    let frame = if basis.iter().all(|&b| visible[b]) { BasisFrame::new(pixels, basis, "current").ok() } else { None };
    let (tau, eps_z) = match &frame {
        Some(f) => {
            let t = rz.t_matrix(f);
            let v = Vector3::new(pixels[basis[0]][1], pixels[basis[1]][1], pixels[basis[2]][1]);
            ([t[(0, 0)], t[(1, 0)], t[(1, 1)]], rz.eps_z(&v))
        }
        None => ([f64::NAN; 3], f64::NAN),
    };
    row.push(tau[1]);
    let mut err2 = 0.0;
    for (k, &i) in others.iter().enumerate() {
        let e = match &frame {
            Some(f) if visible[i] => f.transform(pixels[i]) - s_star[k],
            _ => Vector3::repeat(f64::NAN),
        };
        if visible[i] {
            err2 += e.norm_squared();
        }
        row.extend_from_slice(e.as_slice());
    }
    let mut image_error = f64::NAN; // NaN when no point is visible
    for (i, p) in pixels.iter().enumerate() {
        if visible[i] {
            let (du, dv) = (p[0] - reference[i][0], p[1] - reference[i][1]);
            image_error = image_error.max((du * du + dv * dv).sqrt());
            row.extend_from_slice(&[du, dv]);
        } else {
            row.extend_from_slice(&[f64::NAN; 2]);
        }
    }
    let invariant_error = if frame.is_some() { err2.sqrt() } else { f64::NAN };
    Metrics { invariant_error, tau, eps_z, image_error }
}
