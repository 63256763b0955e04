//! `[reference_camera]`, `[camera]`, `[estimate]` and `depth_estimation.camera`: intrinsics,
//! image size and lens distortion, given as numbers or read from a calibration file, each
//! checked with an error naming its key.

use super::{MAX_IMAGE_SIDE, MAX_MAGNITUDE, check_positive, first_given};
use crate::calibration::load_calibration;
use crate::core::camera::Intrinsics;
use crate::core::distortion::{Distortion, DistortionModel};
use crate::error::Short;
use crate::sim::camera_model::CameraModel;
use crate::sim::error::Result;
use crate::sim::scenario::schema::CameraSpec;
use crate::sim::scenario::{FileScope, scenario_error};
use crate::sim::scene::ImageSize;

/// A camera table read: its intrinsics, image size and distortion.
pub(super) struct Lens {
    pub(super) intrinsics: Intrinsics,
    pub(super) image: Option<ImageSize>,
    pub(super) distortion: Distortion,
}

impl CameraSpec {
    /// The table as numbers, or its calibration file (which then replaces fku, fkv, u0, v0,
    /// width, height and distortion; a file has no skew).
    pub(super) fn lens(&self, key: &str, files: FileScope<'_>) -> Result<Lens> {
        match &self.calibration {
            Some(file) => self.read_calibration(key, file, files),
            None => Ok(Lens {
                intrinsics: self.intrinsics(key)?,
                image: self.image_size(key)?,
                distortion: self.distortion_of(key)?,
            }),
        }
    }

    fn read_calibration(&self, key: &str, file: &str, files: FileScope<'_>) -> Result<Lens> {
        let given = [
            ("fku", self.fku.is_some()),
            ("fkv", self.fkv.is_some()),
            ("u0", self.u0.is_some()),
            ("v0", self.v0.is_some()),
            ("width", self.width.is_some()),
            ("height", self.height.is_some()),
            ("distortion", self.distortion.is_some()),
            ("distortion_model", self.distortion_model.is_some()),
        ];
        if let Some(name) = first_given(given) {
            let reason = format!("given with {key}.calibration, which sets it: give one or the other");
            return Err(scenario_error(&format!("{key}.{name}"), reason));
        }
        if self.skew_deg != 90.0 {
            let reason = "calibration files have no skew: skew_deg must be 90 (the default) with calibration";
            return Err(scenario_error(&format!("{key}.skew_deg"), reason));
        }
        let cal_key = format!("{key}.calibration");
        let calibration =
            load_calibration(files.resolve(&cal_key, file)?).map_err(|e| scenario_error(&cal_key, e.to_string()))?;
        Ok(Lens {
            intrinsics: calibration.intrinsics,
            image: calibration
                .image_size
                .map(|(width, height)| ImageSize { width: f64::from(width), height: f64::from(height) }),
            distortion: calibration.distortion,
        })
    }

    /// fku, fkv, u0, v0 and skew_deg.
    pub(super) fn intrinsics(&self, key: &str) -> Result<Intrinsics> {
        let required = |name: &str, v: Option<f64>| {
            v.ok_or_else(|| scenario_error(&format!("{key}.{name}"), "missing (or give calibration = \"file\")"))
        };
        let (fku, fkv) = (required("fku", self.fku)?, required("fkv", self.fkv)?);
        let (u0, v0) = (required("u0", self.u0)?, required("v0", self.v0)?);
        for (name, v) in [("fku", fku), ("fkv", fkv)] {
            check_positive(&format!("{key}.{name}"), v)?;
            if v > MAX_MAGNITUDE {
                return Err(scenario_error(&format!("{key}.{name}"), format!("at most 1e6 px, got {}", Short(v))));
            }
        }
        for (name, v) in [("u0", u0), ("v0", v0)] {
            if !(v.abs() <= MAX_MAGNITUDE) {
                let reason = format!("must be finite and within +-1e6 px, got {}", Short(v));
                return Err(scenario_error(&format!("{key}.{name}"), reason));
            }
        }
        if !(self.skew_deg > 0.0 && self.skew_deg < 180.0) {
            let reason =
                format!("the angle between the image axes must be in (0, 180) degrees, got {}", Short(self.skew_deg));
            return Err(scenario_error(&format!("{key}.skew_deg"), reason));
        }
        Intrinsics::new(fku, fkv, u0, v0, self.skew_deg.to_radians()).map_err(|e| scenario_error(key, e.to_string()))
    }

    fn image_size(&self, key: &str) -> Result<Option<ImageSize>> {
        match (self.width, self.height) {
            (Some(width), Some(height)) => {
                for (name, v) in [("width", width), ("height", height)] {
                    if !(1.0..=MAX_IMAGE_SIDE).contains(&v) {
                        let reason = format!("pixels, from 1 to {MAX_IMAGE_SIDE}, got {}", Short(v));
                        return Err(scenario_error(&format!("{key}.{name}"), reason));
                    }
                }
                Ok(Some(ImageSize { width, height }))
            }
            (None, None) => Ok(None),
            _ => Err(scenario_error(key, "give both width and height, or neither")),
        }
    }

    fn distortion_of(&self, key: &str) -> Result<Distortion> {
        let model = match &self.distortion_model {
            None => None,
            Some(name) => Some(DistortionModel::from_name(name).ok_or_else(|| {
                let plain =
                    name.len() <= 32 && name.bytes().all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'_');
                let shown = if plain { format!("{name:?}") } else { format!("a name of {} bytes", name.len()) };
                scenario_error(
                    &format!("{key}.distortion_model"),
                    format!("unknown distortion model {shown}; expected {}", DistortionModel::NAMES),
                )
            })?),
        };
        let Some(c) = &self.distortion else {
            if model.is_some() {
                let reason = format!("needs {key}.distortion, the model's coefficients");
                return Err(scenario_error(&format!("{key}.distortion_model"), reason));
            }
            return Ok(Distortion::none());
        };
        let key = format!("{key}.distortion");
        if let Some(i) = c.iter().position(|v| !(v.abs() <= MAX_MAGNITUDE)) {
            return Err(scenario_error(
                &format!("{key}[{i}]"),
                format!("must be finite and within +-1e6, got {}", Short(c[i])),
            ));
        }
        match model {
            Some(m) => Distortion::with_model(m, c),
            None => Distortion::from_coefficients(c),
        }
        .map_err(|e| scenario_error(&key, e.to_string()))
    }

    /// The camera of a run: the table's lens with its zoom schedule.
    pub(super) fn model(&self, key: &str, files: FileScope<'_>) -> Result<CameraModel> {
        let lens = self.lens(key, files)?;
        let model = CameraModel {
            intrinsics: lens.intrinsics,
            zoom: self.zoom.clone(),
            image: lens.image,
            distortion: lens.distortion,
        };
        model.validate().map_err(|e| scenario_error(key, e.to_string()))?;
        Ok(model)
    }
}
