//! Sec. 3: a path planned in the invariant space from the first image, which the servo
//! session then follows by moving its reference `s*(t)` (and its rate) each step.

use nalgebra::Vector3;

use crate::core::control::InvariantController;
use crate::core::invariant::BasisFrame;
use crate::core::planning::{InvariantPath, estimate_plane_parallax};
use crate::error::{Error, Result};
use crate::servo::reference::ReferenceImage;

/// A path planned in the invariant space from the first image (sec. 3, the `[path]` table).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize), serde(deny_unknown_fields))]
pub struct PathPlan {
    /// Number of samples at the control period: the path lasts `samples * dt` (the paper's N).
    pub samples: usize,
}

/// The planned path and its samples.
pub(crate) struct PlannedPath {
    pub(crate) path: InvariantPath,
    /// RMS residual of the plane + parallax estimate.
    pub(crate) residual: f64,
    points: Vec<[f64; 3]>,
    rates: Vec<[f64; 3]>,
}

impl PlannedPath {
    /// Plans the path from the current (first) image; every point must be visible.
    pub(crate) fn plan(pixels: &[[f64; 2]], visible: &[bool], r: &ReferenceImage, duration: f64) -> Result<Self> {
        if let Some(i) = (0..pixels.len()).find(|&i| !visible[i]) {
            return Err(Error::InvalidParameter {
                name: "path",
                reason: format!("point {i} is not visible in the first image; the path needs every point"),
            });
        }
        let frame = BasisFrame::new(pixels, r.basis, "current")?;
        let q: Vec<Vector3<f64>> = r.others.iter().map(|&i| frame.transform(pixels[i])).collect();
        let estimate = estimate_plane_parallax(&q, &r.s_star)?;
        let m = r.others.len();
        Ok(Self {
            path: InvariantPath::new(&r.s_star, &estimate, duration)?,
            residual: estimate.residual,
            points: vec![[0.0; 3]; m],
            rates: vec![[0.0; 3]; m],
        })
    }

    /// Moves the controller's reference to `s*(t)` and its rate.
    pub(crate) fn follow(&mut self, t: f64, controller: &mut InvariantController) -> Result<()> {
        self.path.sample(t, &mut self.points, &mut self.rates)?;
        controller.set_reference(&self.points, Some(&self.rates))
    }
}
