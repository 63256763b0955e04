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
use crate::vision::image_servo::{ImageServo, ImageServoConfig, ImageTargetKind};
use crate::vision::targets::{self, ArgKind, ArgValue, TARGETS, TargetArg, TargetArgs, TargetSpec};
use crate::vision::tracker::{SettingKind, SettingValue, TrackerConfig, tracker_setting, tracker_setting_names};

/// The `tracker` dictionary over the default tracker settings, each read as its entry of
/// [`TRACKER_SETTINGS`] says; an unknown key is refused by name.
fn tracker_config(tracker: Option<&Bound<'_, PyDict>>) -> PyResult<TrackerConfig> {
    let mut config = TrackerConfig::default();
    let Some(tracker) = tracker else { return Ok(config) };
    for (key, value) in tracker.iter() {
        let key: String =
            key.extract().map_err(|_| invalid_argument("tracker", "tracker: keys must be strings".into()))?;
        let name = format!("tracker.{key}");
        let Some(setting) = tracker_setting(&key) else {
            let known = tracker_setting_names();
            return Err(invalid_argument(&name, format!("{name}: unknown key; known: {known}")));
        };
        let value = match setting.kind {
            SettingKind::Number { .. } => SettingValue::Number(
                value.extract().map_err(|_| invalid_argument(&name, format!("{name}: expected a number")))?,
            ),
            SettingKind::Count => SettingValue::Count(super::args::count(&value, setting.name).map_err(|e| {
                // Not a number at all (a bare TypeError): named as the other kinds are.
                if e.is_instance_of::<pyo3::exceptions::PyTypeError>(value.py()) {
                    invalid_argument(&name, format!("{name}: expected a whole number"))
                } else {
                    e
                }
            })?),
            SettingKind::Choice(names) => {
                let p: String =
                    value.extract().map_err(|_| invalid_argument(&name, format!("{name}: expected a string")))?;
                if !names.contains(&p.as_str()) {
                    let names = names.iter().map(|n| format!("{n:?}")).collect::<Vec<_>>().join(", ");
                    let key = setting.name;
                    return Err(invalid_argument(key, format!("{key}: expected one of {names}, got {p:?}")));
                }
                SettingValue::Choice(p)
            }
        };
        config.set(setting.name, value)?;
    }
    Ok(config)
}

/// `(n, 2)` approximate pixels.
fn points_arg(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[f64; 2]>> {
    let a = f64_array(obj, what, &[None, Some(2)])?;
    Ok(points2(&a)?.to_vec())
}

/// A target's argument as its kind says (`vsinv._core.TARGETS`); None is unset.
fn target_arg(arg: &TargetArg, value: &Bound<'_, PyAny>) -> PyResult<ArgValue> {
    let name = arg.name;
    let bad = |what: &str| invalid_argument(name, format!("{name}: expected {what}"));
    Ok(match arg.kind {
        ArgKind::Points => ArgValue::Points(points_arg(value, name)?),
        ArgKind::Choice(_) => ArgValue::Name(value.extract().map_err(|_| bad("a string"))?),
        ArgKind::Ids => {
            ArgValue::Ids(value.extract().map_err(|_| bad("a sequence of tag ids (non-negative integers)"))?)
        }
        ArgKind::Count { .. } => ArgValue::Count(value.extract().map_err(|_| bad("an integer"))?),
        ArgKind::Tracker => ArgValue::Tracker(tracker_config(Some(value.cast().map_err(|_| bad("a dict"))?))?),
    })
}

/// Splits the keyword arguments into the target's (each converted by its kind) and the servo
/// session's; an argument of another target is refused by name.
fn split_options<'py>(
    py: Python<'py>,
    spec: &TargetSpec,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<(TargetArgs, Bound<'py, PyDict>)> {
    let (mut args, servo) = (TargetArgs::default(), PyDict::new(py));
    for (key, value) in options.map(|o| o.iter()).into_iter().flatten() {
        let name: String = key.extract()?;
        let of_target = |t: &TargetSpec| t.args.iter().find(|a| a.name == name);
        match (of_target(spec), TARGETS.iter().find_map(of_target)) {
            (_, None) => servo.set_item(key, value)?,
            _ if value.is_none() => {}
            (Some(arg), _) => args.0.push((arg.name, target_arg(arg, &value)?)),
            (None, Some(_)) => {
                let target = spec.name;
                return Err(invalid_argument(&name, format!("{name}: not an argument of target {target:?}")));
            }
        }
    }
    Ok((args, servo))
}

/// The target named `target` (`vsinv._core.TARGETS`) from its arguments; an error of the
/// target's names the argument.
fn image_target(spec: &TargetSpec, args: &TargetArgs) -> PyResult<Box<dyn ImageTargetKind>> {
    (spec.image)(args).map_err(|e| match e {
        crate::vision::VisionError::Core(crate::Error::InvalidParameter { name, reason }) => {
            invalid_argument(name, format!("{name}: {reason}"))
        }
        other => other.into(),
    })
}

/// The pipeline from image to twist: finds the target in the reference image (taken with any camera: no K* needed),
/// then each `step(image)` detects or tracks it, matches the points by identity, undistorts them with `K_hat` and
/// `distortion` and steps a `Servo` session.
///
/// `target` is a name of `vsinv._core.TARGETS`, whose entry lists the keyword arguments it takes (another
/// target's are refused by name). `target="dots"`: `reference_points` (n, 2) are approximate pixels of the dots in
/// the reference image, `first_points` (n, 2) in the first frame (None: near those found in the reference image);
/// `tracker` a dict of search_radius, max_search_radius, min_area, max_area_ratio, polarity. `target="tags"`:
/// AprilTags of `family`, decoded in every frame (searched near their last corners first, the whole frame when
/// one is lost), the corners of the tags `tag_ids` (None: every tag decoded in the reference image), corner c of
/// tag t under identity 4 t + c: no clicks, correspondences by identity between any two cameras. `decimation`
/// (1..=8, None: the detector's default) is the quad search's, as in `detect_tags`. `target="features"`: no
/// markers, no clicks: a spread of `max_points` (default 150) SIFT keypoints of the reference image, keypoint i
/// under identity i, matched in the first frame by descriptors checked by the fundamental matrix (no intrinsics
/// needed), then tracked (Lucas-Kanade, forward-backward check) and checked against the reference again each
/// frame; a point failing a check is not visible (never at a wrong place), and a point not found is looked for
/// again in each frame where its found neighbours put it (aligned on its reference patch), so it comes back into
/// view; the frame is matched afresh when fewer than `min_tracked` (default 24) remain; `point_ids` (None: all) keeps some of the points. The reference depths of natural
/// keypoints are unknown: estimate them by appendix A (`depths=ResectionDepths(...)` over the points of a
/// translation pair, those given to `point_ids`; `vsinv.vision.match_features` and `track_points` find them).
///
/// `reference_K` and `reference_distortion` undistort the reference points. Every other keyword argument is the
/// `Servo` session's (law, reference_depths, depths, basis, gain, ..., dt) and an unknown one is refused by name.
/// A point not found in a frame is not visible for that step; a basis point missing for at most 3 consecutive frames
/// keeps the basis (the last twist is repeated, no stop is judged), longer changes it. The stall rule is on unless
/// `stop={"stall": False}`: real detections of one pose by two lenses disagree, so the run ends when the error
/// stopped decreasing and the camera is still, `converged` if the bound (with the measured disagreement floor) is
/// within the tolerance. A first frame where no point is found (blank, dark) is the verdict `lost_features` with a
/// zero twist. As for `Servo`, a stop is final.
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
    #[pyo3(signature = (reference_image, target, K_hat, *, distortion = None, reference_K = None, reference_distortion = None, **options))]
    fn new(
        py: Python<'_>,
        reference_image: &Bound<'_, PyAny>,
        target: &str,
        K_hat: &Bound<'_, PyAny>,
        distortion: Option<&Bound<'_, PyAny>>,
        reference_K: Option<&Bound<'_, PyAny>>,
        reference_distortion: Option<&Bound<'_, PyAny>>,
        options: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let reference_image = image_arg(reference_image, "reference_image")?;
        let image = reference_image.buffer("reference_image")?;
        let spec = targets::target(target).ok_or_else(|| {
            let names = targets::target_names().iter().map(|n| format!("{n:?}")).collect::<Vec<_>>().join(", ");
            invalid_argument("target", format!("target: expected one of {names}, got {target:?}"))
        })?;
        let (target_args, servo) = split_options(py, spec, options)?;
        let target = image_target(spec, &target_args)?;
        let k_hat = intrinsics(K_hat, "K_hat")?;
        let options = ServoOptions::from_kwargs(Some(&servo))?;
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
        let inner = py.detach(|| ImageServo::new(&image, &*target, config, depths))?;
        Ok(Self { inner: Shared::new(inner, "ImageServo") })
    }

    /// One frame (an image: grey, or BGR/BGRA converted): the twist to send, the verdict, the
    /// telemetry, and per point the pixel found and whether it was found.
    fn step(&self, py: Python<'_>, image: &Bound<'_, PyAny>) -> PyResult<Py<PyImageStep>> {
        let image = image_arg(image, "image")?;
        let image = image.buffer("image")?;
        let (step, found, pixels, stopped_early) = self.inner.detached(py, |pipeline| {
            let step = pipeline.step(&image)?;
            Ok::<_, crate::vision::VisionError>((
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
    /// The basis in use (it changes when a basis point is not visible).
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
    /// How many images were ridden out with a basis point missing: the basis kept and the last
    /// twist repeated (`basis_hold`).
    #[getter]
    fn basis_held_images(&self, py: Python<'_>) -> PyResult<usize> {
        Ok(self.inner.lock(py)?.servo().basis_held_images())
    }
    /// The pixel noise measured on the last frames (None before three), pixels.
    #[getter]
    fn pixel_sigma(&self, py: Python<'_>) -> PyResult<Option<f64>> {
        Ok(self.inner.lock(py)?.servo().pixel_sigma())
    }
    /// What the frames say about the pose, as `Servo.certainty()` (pixel_sigma, reference_pixel_sigma,
    /// translation_sigma, translation_bound in metres, rotation_sigma, rotation_bound in radians: the accuracy
    /// ceiling, floor_pixel_sigma: the measured disagreement between reference and frame detections, pixels); None
    /// when it cannot be computed.
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
