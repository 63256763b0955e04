//! `vsinv.ImageServo`: the pipeline from image to twist (the `vision` layer's `ImageServo`)
//! stepped with NumPy images; each step runs with the GIL released.

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::arrays::{f64_array, mat, points2};
use super::errors::invalid_argument;
use super::image_arg::image_arg;
use super::intrinsics;
use super::lens::distortion_arg;
use super::servo::{PyServoStep, ServoOptions};
use super::shared::Shared;
use super::tags::{decimation_arg, family_arg};
use super::vision::polarity_arg;
use crate::vision::image_servo::{ImageServo, ImageServoConfig, ImageTarget};
use crate::vision::tracker::TrackerConfig;

/// The `tracker` dictionary over the default tracker settings; an unknown key is refused by
/// name.
fn tracker_config(tracker: Option<&Bound<'_, PyDict>>) -> PyResult<TrackerConfig> {
    let mut config = TrackerConfig::default();
    let Some(tracker) = tracker else { return Ok(config) };
    for (key, value) in tracker.iter() {
        let key: String =
            key.extract().map_err(|_| invalid_argument("tracker", "tracker: keys must be strings".into()))?;
        let name = format!("tracker.{key}");
        let bad = |_| invalid_argument(&name, format!("{name}: expected a number"));
        match key.as_str() {
            "search_radius" => config.search_radius = value.extract().map_err(bad)?,
            "max_search_radius" => config.max_search_radius = value.extract().map_err(bad)?,
            "min_area" => config.min_area = super::args::min_area(&value)?,
            "max_area_ratio" => config.max_area_ratio = value.extract().map_err(bad)?,
            "polarity" => {
                let p: String =
                    value.extract().map_err(|_| invalid_argument(&name, format!("{name}: expected a string")))?;
                config.polarity = polarity_arg(&p)?;
            }
            _ => {
                let known = "search_radius, max_search_radius, min_area, max_area_ratio, polarity";
                return Err(invalid_argument(&name, format!("{name}: unknown key; known: {known}")));
            }
        }
    }
    Ok(config)
}

/// `(n, 2)` approximate pixels, or None.
fn points_arg(obj: Option<&Bound<'_, PyAny>>, what: &str) -> PyResult<Option<Vec<[f64; 2]>>> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else { return Ok(None) };
    let a = f64_array(obj, what, &[None, Some(2)])?;
    Ok(Some(points2(&a)?.to_vec()))
}

/// The target of `target="dots"` from its keyword arguments.
fn dots_target(
    reference_points: Option<&Bound<'_, PyAny>>,
    first_points: Option<&Bound<'_, PyAny>>,
    tracker: Option<&Bound<'_, PyDict>>,
) -> PyResult<ImageTarget> {
    let reference_points = points_arg(reference_points, "reference_points")?.ok_or_else(|| {
        let reason =
            "reference_points: target \"dots\" needs the dots' approximate pixels (n, 2) in the reference image";
        invalid_argument("reference_points", reason.into())
    })?;
    let first_points = points_arg(first_points, "first_points")?;
    Ok(ImageTarget::Dots { reference_points, first_points, tracker: tracker_config(tracker)? })
}

/// The target of `target="tags"` from its keyword arguments.
fn tags_target(family: &str, tag_ids: Option<&Bound<'_, PyAny>>, decimation: Option<i64>) -> PyResult<ImageTarget> {
    let family = family_arg(family)?;
    let decimation = decimation_arg(decimation)?;
    let ids = match tag_ids.filter(|t| !t.is_none()) {
        None => None,
        Some(t) => {
            let ids: Vec<u32> = t.extract().map_err(|_| {
                invalid_argument("tag_ids", "tag_ids: expected a sequence of tag ids (non-negative integers)".into())
            })?;
            if ids.is_empty() {
                return Err(invalid_argument(
                    "tag_ids",
                    "tag_ids: empty (None: every tag in the reference image)".into(),
                ));
            }
            Some(ids)
        }
    };
    Ok(ImageTarget::Tags { family, ids, decimation })
}

/// Keyword arguments given that the target does not take, refused by name.
fn refuse_foreign(target: &str, given: &[(&str, bool)]) -> PyResult<()> {
    match given.iter().find(|(_, g)| *g) {
        Some((name, _)) => Err(invalid_argument(name, format!("{name}: not an argument of target {target:?}"))),
        None => Ok(()),
    }
}

/// The pipeline from image to twist: finds the target in the reference image (taken with any
/// camera), then each `step(image)` detects or tracks it, matches the points by identity,
/// undistorts them with K_hat and `distortion`, and steps the servo session. Keyword
/// arguments after the target's are the `Servo` session's (law, depths, gain, stop, ...).
///
/// Works from several threads: their calls take turns (each waits with the GIL released).
#[pyclass(name = "ImageServo", module = "vsinv._core", frozen)]
pub(super) struct PyImageServo {
    inner: Shared<ImageServo>,
}

#[pymethods]
impl PyImageServo {
    #[new]
    #[allow(non_snake_case, clippy::too_many_arguments)]
    #[pyo3(signature = (reference_image, target, K_hat, *, reference_points = None, first_points = None, tracker = None, family = "tag36h11", tag_ids = None, decimation = None, distortion = None, reference_K = None, reference_distortion = None, **servo))]
    fn new(
        py: Python<'_>,
        reference_image: &Bound<'_, PyAny>,
        target: &str,
        K_hat: &Bound<'_, PyAny>,
        reference_points: Option<&Bound<'_, PyAny>>,
        first_points: Option<&Bound<'_, PyAny>>,
        tracker: Option<&Bound<'_, PyDict>>,
        family: &str,
        tag_ids: Option<&Bound<'_, PyAny>>,
        decimation: Option<i64>,
        distortion: Option<&Bound<'_, PyAny>>,
        reference_K: Option<&Bound<'_, PyAny>>,
        reference_distortion: Option<&Bound<'_, PyAny>>,
        servo: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let reference_image = image_arg(reference_image, "reference_image")?;
        let image = reference_image.buffer("reference_image")?;
        let given = |o: Option<&Bound<'_, PyAny>>| o.is_some_and(|o| !o.is_none());
        let target = match target {
            "dots" => {
                let tag_args = [
                    ("tag_ids", given(tag_ids)),
                    ("family", family != "tag36h11"),
                    ("decimation", decimation.is_some()),
                ];
                refuse_foreign(target, &tag_args)?;
                dots_target(reference_points, first_points, tracker)?
            }
            "tags" => {
                let dot_args = [
                    ("reference_points", given(reference_points)),
                    ("first_points", given(first_points)),
                    ("tracker", tracker.is_some()),
                ];
                refuse_foreign(target, &dot_args)?;
                tags_target(family, tag_ids, decimation)?
            }
            other => {
                return Err(invalid_argument(
                    "target",
                    format!("target: expected \"dots\" or \"tags\", got {other:?}"),
                ));
            }
        };
        let k_hat = intrinsics(K_hat, "K_hat")?;
        let options = ServoOptions::from_kwargs(servo)?;
        // Real cameras: the stall rule is on unless `stop` says otherwise (issue 27).
        let stall_unset = !options.stop_sets("stall");
        let (mut servo_config, reference_depths, depths) = options.session(k_hat)?;
        servo_config.stop.stall |= stall_unset;
        if let Some(d) = distortion.filter(|d| !d.is_none()) {
            servo_config.distortion = distortion_arg(d)?;
        }
        let reference_lens = match (reference_K.filter(|k| !k.is_none()), reference_distortion.filter(|d| !d.is_none()))
        {
            (Some(k), d) => {
                Some((intrinsics(k, "reference_K")?, d.map(distortion_arg).transpose()?.unwrap_or_default()))
            }
            (None, Some(_)) => {
                return Err(invalid_argument(
                    "reference_distortion",
                    "reference_distortion: needs reference_K (the reference camera's intrinsics) to undistort with"
                        .into(),
                ));
            }
            (None, None) => None,
        };
        let config = ImageServoConfig { servo: servo_config, reference_lens, reference_depths };
        let inner = py.detach(|| ImageServo::new(&image, &target, config, depths))?;
        Ok(Self { inner: Shared::new(inner, "ImageServo") })
    }

    /// One frame (an image: grey, or BGR/BGRA converted): the twist to send, the verdict, the
    /// telemetry, and per point the pixel found and whether it was found.
    fn step(&self, py: Python<'_>, image: &Bound<'_, PyAny>) -> PyResult<Py<PyImageStep>> {
        let image = image_arg(image, "image")?;
        let image = image.buffer("image")?;
        let (step, found, pixels, stopped_early) = self.inner.detached(py, |pipeline| {
            let step = pipeline.step(&image)?;
            Ok::<_, crate::Error>((
                step,
                pipeline.found().to_vec(),
                pipeline.pixels().to_vec(),
                pipeline.stopped_early(),
            ))
        })??;
        let image_step = PyImageStep { found, pixels, stopped_early };
        let init = PyClassInitializer::from(PyServoStep::from(step)).add_subclass(image_step);
        Py::new(py, init)
    }

    /// The points' identities, in the session's order (n,).
    #[getter]
    fn ids<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<u32>>> {
        Ok(PyArray1::from_slice(py, self.inner.lock(py)?.ids()))
    }
    /// The reference pixels (n, 2), undistorted with reference_K when given.
    #[getter]
    fn reference_pixels<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let inner = self.inner.lock(py)?;
        let px = inner.servo().reference_pixels();
        mat(py, px.len(), 2, px.as_flattened().to_vec())
    }
    /// Control steps applied.
    #[getter]
    fn iterations(&self, py: Python<'_>) -> PyResult<usize> {
        Ok(self.inner.lock(py)?.servo().iterations())
    }
    /// The basis in use (three point indices).
    #[getter]
    fn basis(&self, py: Python<'_>) -> PyResult<(usize, usize, usize)> {
        let [a, b, c] = self.inner.lock(py)?.servo().basis();
        Ok((a, b, c))
    }
    /// How many times the basis changed because one of its points was not visible.
    #[getter]
    fn basis_switches(&self, py: Python<'_>) -> PyResult<usize> {
        Ok(self.inner.lock(py)?.servo().basis_switches())
    }
    /// The pixel noise measured on the last frames (None before three), pixels.
    #[getter]
    fn pixel_sigma(&self, py: Python<'_>) -> PyResult<Option<f64>> {
        Ok(self.inner.lock(py)?.servo().pixel_sigma())
    }
    /// What the frames say about the pose, as `Servo.certainty()`: pixel_sigma,
    /// reference_pixel_sigma (pixels), translation_sigma, translation_bound (metres),
    /// rotation_sigma, rotation_bound (radians); None when it cannot be computed.
    fn certainty<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        super::servo::certainty_dict(py, self.inner.lock(py)?.servo())
    }
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let inner = self.inner.lock(py)?;
        let s = inner.servo();
        Ok(format!("ImageServo(law={:?}, points={}, iterations={})", s.law().name(), inner.ids().len(), s.iterations()))
    }
}

/// What one `ImageServo.step` returns: a `ServoStep` with the points found.
#[pyclass(name = "ImageStep", module = "vsinv._core", frozen, extends = PyServoStep)]
pub(super) struct PyImageStep {
    found: Vec<bool>,
    pixels: Vec<[f64; 2]>,
    /// Whether the detector's search of this frame stopped at its bound on its work (a frame
    /// too cluttered to be searched whole, as `Tags.stopped_early`): a point not found may be
    /// in view.
    #[pyo3(get)]
    stopped_early: bool,
}

#[pymethods]
impl PyImageStep {
    /// Per point: found in this frame (n,).
    #[getter]
    fn found<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        PyArray1::from_slice(py, &self.found)
    }
    /// Per point: the pixel found (distorted, as detected), or its last known pixel (n, 2).
    #[getter]
    fn pixels<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        mat(py, self.pixels.len(), 2, self.pixels.as_flattened().to_vec())
    }
}

/// Adds the image pipeline's classes to the module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyImageServo>()?;
    m.add_class::<PyImageStep>()?;
    Ok(())
}
