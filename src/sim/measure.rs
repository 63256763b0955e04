//! Measurements of each image against the reference image, independent of the control law:
//! tau (eq. 21), the invariant and image errors, and the stop rules' averaging window.

use nalgebra::Vector3;

use crate::core::invariant::{BasisFrame, RzReference, non_basis_indices};
use crate::error::Result;
use crate::sim::config::StopRules;
use crate::sim::outcome::StopRule;

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

/// Measurements that do not depend on the law, from the noisy pixels.
pub(crate) struct Metrics {
    pub(crate) invariant_error: f64,
    pub(crate) tau: [f64; 3],
    pub(crate) eps_z: f64,
    pub(crate) image_error: f64,
}

/// The stop rules' low-pass filter: the error *vectors* (`tau_21`, `s - s*`, `p - p*`, NaN
/// for hidden points) averaged over the last `window` images, so that zero-mean pixel noise
/// averages out instead of adding up in a norm.
pub(crate) struct StopWindow {
    window: usize,
    rows: std::collections::VecDeque<Vec<f64>>,
    mean: Vec<f64>,
}

impl StopWindow {
    pub(crate) fn new(window: usize) -> Self {
        Self { window, rows: std::collections::VecDeque::with_capacity(window.min(1024) + 1), mean: Vec::new() }
    }

    /// A row to fill with [`measure`] (the oldest row, recycled, once the window is full).
    pub(crate) fn next_row(&mut self) -> Vec<f64> {
        let mut row =
            if self.rows.len() == self.window { self.rows.pop_front().unwrap_or_default() } else { Vec::new() };
        row.clear();
        row
    }

    /// The means returned by the last [`push`](Self::push) (None before the window is full).
    pub(crate) fn mean(&self) -> Option<&[f64]> {
        match self.window {
            _ if self.rows.len() < self.window => None,
            1 => self.rows.back().map(Vec::as_slice),
            _ => Some(&self.mean),
        }
    }

    /// Adds the errors of one image; returns the means once the window is full.
    pub(crate) fn push(&mut self, row: Vec<f64>) -> Option<&[f64]> {
        self.rows.push_back(row);
        if self.rows.len() < self.window {
            return None;
        }
        if self.window == 1 {
            return self.rows.front().map(Vec::as_slice);
        }
        let len = self.rows[0].len();
        self.mean.clear();
        self.mean.resize(len, 0.0);
        for r in &self.rows {
            self.mean.iter_mut().zip(r).for_each(|(m, v)| *m += v);
        }
        let w = self.window as f64;
        self.mean.iter_mut().for_each(|m| *m /= w);
        Some(&self.mean)
    }
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

/// Whether the window-averaged errors (`mean`, laid out as [`measure`] writes its rows) meet
/// the stop rule; `tau` are the current image's tau_11, tau_21, tau_22. NaN (a point hidden
/// in the window) never passes a comparison.
pub(crate) fn stop_rule_met(rule: StopRule, stop: &StopRules, mean: &[f64], n_others: usize, tau: [f64; 3]) -> bool {
    let m_inv = 3 * n_others;
    match rule {
        StopRule::Pixel => {
            let image = mean[1 + m_inv..]
                .chunks_exact(2)
                .map(|c| (c[0] * c[0] + c[1] * c[1]).sqrt())
                .fold(0.0, |a: f64, b| if b.is_nan() { f64::INFINITY } else { a.max(b) });
            image < stop.pixel_error
        }
        // correction 8: tau_21 near zero alone also admits the rz = pi equilibrium.
        StopRule::Invariant => {
            let invariant = mean[1..1 + m_inv].iter().map(|v| v * v).sum::<f64>().sqrt();
            invariant < stop.invariant_error && mean[0].abs() < stop.tau21 && tau[0] > 0.0 && tau[2] > 0.0
        }
    }
}
