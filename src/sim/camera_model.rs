//! The cameras of a run: fixed intrinsics, or a zoom (a piecewise-linear schedule of the
//! intrinsics in time, sec. 5.1), with an optional image size and lens distortion.

use nalgebra::Matrix3;

use crate::core::camera::Intrinsics;
use crate::core::distortion::Distortion;
use crate::error::{Error, check_finite};
use crate::sim::error::Result;
use crate::sim::scene::ImageSize;

/// A piecewise-linear schedule of the intrinsics in time (a zoom; `zoom = { ... }` in a
/// scenario's camera table).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Zoom {
    /// Knot times in seconds, increasing.
    pub times: Vec<f64>,
    /// `f ku` at each knot.
    pub fku: Vec<f64>,
    /// `f kv` at each knot.
    pub fkv: Vec<f64>,
    /// `u0` at each knot (None: the camera's own).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub u0: Option<Vec<f64>>,
    /// `v0` at each knot (None: the camera's own).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub v0: Option<Vec<f64>>,
}

/// A camera: intrinsics, an optional zoom schedule, an optional image size and the lens's
/// distortion (the image point of a normalised point `m` is `K d(m)`).
#[derive(Debug, Clone, PartialEq)]
pub struct CameraModel {
    /// The intrinsics (before the first zoom knot and when there is no zoom).
    pub intrinsics: Intrinsics,
    /// Optional zoom schedule.
    pub zoom: Option<Zoom>,
    /// Optional image bounds; points outside are not visible.
    pub image: Option<ImageSize>,
    /// Lens distortion (none by default); not with a zoom, whose distortion would change with
    /// the focal length.
    pub distortion: Distortion,
}

fn interpolate(times: &[f64], values: &[f64], t: f64) -> f64 {
    match times.iter().position(|&k| k > t) {
        Some(0) => values[0],
        None => values[values.len() - 1],
        Some(i) => {
            let w = (t - times[i - 1]) / (times[i] - times[i - 1]);
            values[i - 1] + w * (values[i] - values[i - 1])
        }
    }
}

impl CameraModel {
    /// A fixed camera.
    pub fn fixed(intrinsics: Intrinsics, image: Option<ImageSize>) -> Self {
        Self { intrinsics, zoom: None, image, distortion: Distortion::none() }
    }

    /// The same camera with lens distortion.
    pub fn with_distortion(mut self, distortion: Distortion) -> Self {
        self.distortion = distortion;
        self
    }

    /// Checks the zoom schedule and the image size.
    pub fn validate(&self) -> Result<()> {
        if let Some(s) = self.image
            && !(s.width.is_finite() && s.height.is_finite() && s.width > 0.0 && s.height > 0.0)
        {
            return Err(
                Error::InvalidParameter { name: "camera", reason: "width and height must be > 0".into() }.into()
            );
        }
        let Some(z) = &self.zoom else { return Ok(()) };
        let bad = |reason: String| Err(Error::InvalidParameter { name: "camera.zoom", reason }.into());
        if !self.distortion.is_identity() {
            return bad(
                "a zoom lens's distortion changes with the focal length: give distortion or zoom, not both".into()
            );
        }
        let m = z.times.len();
        if m == 0 {
            return bad("times must not be empty".into());
        }
        let lens = [Some(z.fku.len()), Some(z.fkv.len()), z.u0.as_ref().map(Vec::len), z.v0.as_ref().map(Vec::len)];
        if lens.iter().flatten().any(|&l| l != m) {
            return bad(format!("times, fku, fkv (and u0, v0 if given) must have the same length {m}"));
        }
        check_finite("camera.zoom", &z.times)?;
        if z.times.windows(2).any(|w| w[1] <= w[0]) {
            return bad("times must be strictly increasing".into());
        }
        for i in 0..m {
            self.at_knot(i)?;
        }
        Ok(())
    }

    fn at_knot(&self, i: usize) -> Result<Intrinsics> {
        let k = &self.intrinsics;
        let Some(z) = &self.zoom else { return Ok(*k) };
        Ok(Intrinsics::new(
            z.fku[i],
            z.fkv[i],
            z.u0.as_ref().map_or(k.u0(), |u| u[i]),
            z.v0.as_ref().map_or(k.v0(), |v| v[i]),
            k.theta(),
        )?)
    }

    /// The intrinsics at time `t`.
    pub fn at(&self, t: f64) -> Result<Intrinsics> {
        let k = &self.intrinsics;
        let Some(z) = &self.zoom else { return Ok(*k) };
        let f = |v: &[f64]| interpolate(&z.times, v, t);
        Ok(Intrinsics::new(
            f(&z.fku),
            f(&z.fkv),
            z.u0.as_deref().map_or(k.u0(), f),
            z.v0.as_deref().map_or(k.v0(), f),
            k.theta(),
        )?)
    }

    /// The intrinsics at every knot of the schedule (one matrix without zoom).
    pub fn schedule(&self) -> Result<Vec<Matrix3<f64>>> {
        let m = self.zoom.as_ref().map_or(1, |z| z.times.len());
        (0..m).map(|i| self.at_knot(i).map(|k| k.matrix())).collect()
    }
}
