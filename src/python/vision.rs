//! Images in Python: `render`, `render_view`, `degrade`, `detect_dots` and `DotTracker`. Images are read
//! by [`super::image_arg`] (grey read in place, colour BGR/BGRA converted to grey) and
//! returned as `(height, width)` uint8 arrays without a copy; the work runs with the GIL
//! released.

use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;

use super::arrays::{f64_array, mat, points2, pose_arg};
use super::image_arg::{image_arg, image_error};
use super::shared::Shared;
use super::sim::scenario_arg;
use crate::sim::views::{Shot, View, render_view as render_scenario_view};
use crate::vision::dots::{DetectConfig, Dot, detect_dots as detect};
use crate::vision::image::{GreyImage, load_image as load_image_file, save_png};
use crate::vision::polarity::Polarity;
use crate::vision::render::{RenderConfig, Renderer};
use crate::vision::tracker::{DotTracker, TrackerConfig};

/// `(n, 2)` pixels and `(n,)` flags, as returned to Python.
type PixelArray<'py> = Bound<'py, PyArray2<f64>>;
type FlagArray<'py> = Bound<'py, PyArray1<bool>>;
type ImageArray<'py> = Bound<'py, PyArray2<u8>>;

/// A `GreyImage` moved into a `(height, width)` uint8 array without a copy.
fn image_out(py: Python<'_>, image: GreyImage) -> PyResult<Bound<'_, PyArray2<u8>>> {
    let (w, h) = image.dimensions();
    PyArray1::from_vec(py, image.into_raw()).reshape([h as usize, w as usize])
}

/// The view of a scenario (built-in name, file, dict or Scenario).
fn scenario_view(
    py: Python<'_>,
    scenario: &Bound<'_, PyAny>,
    pose: Option<&Bound<'_, PyAny>>,
    time: f64,
    reference: bool,
) -> PyResult<View> {
    let config = scenario_arg(scenario)?.to_config()?;
    let pose = pose.map(pose_arg).transpose()?;
    let shot = if reference { Shot::Reference } else { Shot::Servo { time } };
    Ok(py.detach(|| render_scenario_view(&config, shot, pose.as_ref()))?)
}

/// The image a scenario's camera sees: the servo camera K(time) at `pose` (a 4x4 camera
/// frame in F*; default the start pose), or the reference camera K* (default at F*) when
/// `reference` is true; rendered with the scenario's `[vision]` settings.
#[pyfunction]
#[pyo3(signature = (scenario, pose = None, time = 0.0, reference = false))]
pub fn render<'py>(
    py: Python<'py>,
    scenario: &Bound<'py, PyAny>,
    pose: Option<&Bound<'py, PyAny>>,
    time: f64,
    reference: bool,
) -> PyResult<Bound<'py, PyArray2<u8>>> {
    image_out(py, scenario_view(py, scenario, pose, time, reference)?.image)
}

/// `image` (a grey or colour array, see `to_grey`) through the renderer's optics and sensor, as
/// a scenario's `[vision]` table describes them: blurred by a Gaussian PSF of `blur_sigma`
/// pixels in [0, 20] (near the border the kernel renormalised to the image), plus sensor noise
/// of `noise_sigma` grey levels in [0, 100] (the draws `render` takes for frame `frame` from
/// `seed`), rounded and clamped to 8 bits; what a MuJoCo run does to each render.
#[pyfunction]
#[pyo3(signature = (image, blur_sigma = 0.8, noise_sigma = 2.0, seed = 0, frame = 0))]
pub fn degrade<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    blur_sigma: f64,
    noise_sigma: f64,
    #[pyo3(from_py_with = super::args::seed)] seed: u64,
    #[pyo3(from_py_with = super::args::frame)] frame: u64,
) -> PyResult<ImageArray<'py>> {
    let image = image_arg(image, "image")?;
    let buffer = image.buffer("image")?;
    let config = RenderConfig { blur_sigma, noise_sigma, seed, ..RenderConfig::default() };
    let renderer = Renderer::new(config)?;
    image_out(py, py.detach(|| renderer.degrade(&buffer, frame))?)
}

/// `render` with what it shows: `(image, pixels (n, 2), visible (n,))`, the true
/// projections of the dots' centres and which dots are in the image.
#[pyfunction]
#[pyo3(signature = (scenario, pose = None, time = 0.0, reference = false))]
pub fn render_view<'py>(
    py: Python<'py>,
    scenario: &Bound<'py, PyAny>,
    pose: Option<&Bound<'py, PyAny>>,
    time: f64,
    reference: bool,
) -> PyResult<(ImageArray<'py>, PixelArray<'py>, FlagArray<'py>)> {
    let v = scenario_view(py, scenario, pose, time, reference)?;
    let n = v.pixels.len();
    Ok((image_out(py, v.image)?, mat(py, n, 2, v.pixels.into_flattened())?, PyArray1::from_vec(py, v.visible)))
}

/// Dots found in an image, sorted by row then column of their centroids.
#[pyclass(name = "Dots", module = "vsinv._core", frozen)]
pub struct PyDots {
    /// Subpixel centroids `(u, v)`, `(m, 2)` float64.
    #[pyo3(get)]
    centroids: Py<PyArray2<f64>>,
    /// Pixels above the threshold, `(m,)` float64.
    #[pyo3(get)]
    areas: Py<PyArray1<f64>>,
    /// Bounding boxes `[u_min, v_min, u_max, v_max]` (inclusive), `(m, 4)` int64.
    #[pyo3(get)]
    bboxes: Py<PyArray2<i64>>,
    count: usize,
}

#[pymethods]
impl PyDots {
    fn __len__(&self) -> usize {
        self.count
    }
    fn __repr__(&self) -> String {
        format!("Dots({} found)", self.count)
    }
}

fn dots_out(py: Python<'_>, dots: &[Dot]) -> PyResult<PyDots> {
    let m = dots.len();
    let centroids = mat(py, m, 2, dots.iter().flat_map(|d| d.centroid).collect())?;
    let areas = PyArray1::from_vec(py, dots.iter().map(|d| d.area).collect());
    let bboxes: Vec<i64> = dots.iter().flat_map(|d| d.bbox.map(i64::from)).collect();
    let bboxes = PyArray1::from_vec(py, bboxes).reshape([m, 4])?;
    Ok(PyDots { centroids: centroids.unbind(), areas: areas.unbind(), bboxes: bboxes.unbind(), count: m })
}

/// Bright dots on a dark background (`polarity="light"`), dark dots on a bright one
/// (`"dark"`: the bright dots of `255 - image`, threshold `t` standing for `255 - t`) or as the
/// image shows (`"auto"`): a local threshold (a pixel is a dot pixel when it stands out of the
/// background of its neighbourhood by half the contrast of the dots nearby and at least
/// `min_contrast`; `threshold=` sets one level for the whole image instead), 8-connected
/// components with `min_area <= area <= max_area` (pixels) and a fill ratio (area over that
/// of the ellipse of its second moments) of at least `min_fill` (less `0.2 / sqrt(area)`,
/// the digitised outline's share), a mean contrast over the background plane around it of at
/// least `min_contrast` grey levels and a ring around it that fits that plane (RMS residual at
/// most `max_ring_residual` times the contrast), intensity-weighted subpixel centroids over
/// that plane. A uniform image raises `InvalidInput`.
///
/// `threshold`: None (default) for the local threshold (per 32 px tile: half way between the
/// background of the neighbourhood and the brightest dot nearby, at least `min_contrast` above
/// the background), or one grey level for the whole image. A dot has `min_area <= area <=
/// max_area` pixels (default 8 and no limit), a fill ratio (area over that of the ellipse of
/// its second moments: 1 for a filled ellipse, 0.955 for a square) of at least `min_fill` in
/// [0, 1] (default 0.95, less `0.2 / sqrt(area)`: the digitised outline's share of a small
/// dot), a mean contrast over the background plane around it of at least `min_contrast` grey
/// levels in [0, 255] (default 20), and a plain ring around it: the RMS residual of that plane
/// on its bounding box's ring (grown by 2 px) at most `max_ring_residual` >= 0 times its
/// contrast (default 0.15; inf: no check).
#[pyfunction]
#[pyo3(signature = (
    image, threshold = None, min_area = 8, max_area = None, polarity = "light",
    min_fill = 0.95, min_contrast = 20, max_ring_residual = 0.15,
))]
#[allow(clippy::too_many_arguments)]
pub fn detect_dots(
    py: Python<'_>,
    image: &Bound<'_, PyAny>,
    #[pyo3(from_py_with = super::args::threshold)] threshold: Option<u8>,
    #[pyo3(from_py_with = super::args::min_area)] min_area: usize,
    #[pyo3(from_py_with = super::args::max_area)] max_area: Option<usize>,
    polarity: &str,
    min_fill: f64,
    #[pyo3(from_py_with = super::args::min_contrast)] min_contrast: u8,
    max_ring_residual: f64,
) -> PyResult<PyDots> {
    let image = image_arg(image, "image")?;
    let buffer = image.buffer("image")?;
    let polarity = polarity_arg(polarity)?;
    let config = DetectConfig { threshold, min_area, max_area, polarity, min_fill, min_contrast, max_ring_residual };
    let dots = py.detach(|| detect(&buffer, &config))?;
    dots_out(py, &dots)
}

/// `"light"`, `"dark"` or `"auto"`; anything else raises `InvalidInput` naming `polarity`.
pub(super) fn polarity_arg(name: &str) -> PyResult<Polarity> {
    Polarity::from_name(name).ok_or_else(|| {
        let names = Polarity::NAMES.map(|n| format!("{n:?}")).join(", ");
        super::errors::invalid_argument("polarity", format!("polarity: expected one of {names}, got {name:?}"))
    })
}

/// Tracks dots through images: `DotTracker(image, initial_pixels (n, 2), search_radius=20.0,
/// max_search_radius=80.0, min_area=4, polarity="light", max_area_ratio=1.5)` finds each dot
/// near its click in the first image (a dot larger than the window too; `"dark"`: dark dots,
/// `"auto"`: decided on the first image); `track(image)` returns `(pixels (n, 2), found (n,)
/// bool)`. The window follows each dot's size and motion; a dot whose area or shape changed
/// too much (merged with another region, say) is not found and keeps its last position with
/// `found` false; two dots are never swapped. Too much: a component whose area differs from
/// the dot's last area by more than `max_area_ratio` (beyond the boundary pixels), or whose
/// principal spreads differ by more than its square root, is not that dot.
///
/// Works from several threads: their calls take turns (each waits with the GIL released).
#[pyclass(name = "DotTracker", module = "vsinv._core", frozen)]
pub struct PyDotTracker {
    inner: Shared<DotTracker>,
}

#[pymethods]
impl PyDotTracker {
    #[new]
    #[pyo3(signature = (image, initial_pixels, search_radius = 20.0, max_search_radius = 80.0, min_area = 4, polarity = "light", max_area_ratio = 1.5))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        image: &Bound<'_, PyAny>,
        initial_pixels: &Bound<'_, PyAny>,
        search_radius: f64,
        max_search_radius: f64,
        #[pyo3(from_py_with = super::args::min_area)] min_area: usize,
        polarity: &str,
        max_area_ratio: f64,
    ) -> PyResult<Self> {
        let image = image_arg(image, "image")?;
        let buffer = image.buffer("image")?;
        let clicks = f64_array(initial_pixels, "initial_pixels", &[None, Some(2)])?;
        let clicks = points2(&clicks)?;
        let polarity = polarity_arg(polarity)?;
        let config = TrackerConfig { search_radius, max_search_radius, min_area, polarity, max_area_ratio };
        let inner = py.detach(|| DotTracker::new(&buffer, clicks, config))?;
        Ok(Self { inner: Shared::new(inner, "DotTracker") })
    }

    /// Finds the dots in the next image: `(pixels (n, 2), found (n,) bool)`.
    fn track<'py>(&self, py: Python<'py>, image: &Bound<'py, PyAny>) -> PyResult<(PixelArray<'py>, FlagArray<'py>)> {
        let image = image_arg(image, "image")?;
        let buffer = image.buffer("image")?;
        let result = self.inner.detached(py, |tracker| tracker.track(&buffer))??;
        let n = result.found.len();
        Ok((mat(py, n, 2, result.pixels.into_flattened())?, PyArray1::from_vec(py, result.found)))
    }

    /// The last known position of every dot, `(n, 2)`.
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let inner = self.inner.lock(py)?;
        mat(py, inner.len(), 2, inner.positions().as_flattened().to_vec())
    }

    fn __len__(&self, py: Python<'_>) -> PyResult<usize> {
        Ok(self.inner.lock(py)?.len())
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        Ok(format!("DotTracker({} dots)", self.inner.lock(py)?.len()))
    }
}

/// Reads an image file (PNG, PGM/PPM, JPEG, or GIF's first frame) as a `(height, width)`
/// uint8 array; colour images are converted to grey with the Rec. 601 luma weights (0.299,
/// 0.587, 0.114, as OpenCV), 16-bit images are refused. At most 64 MiB of file, 2^28 pixels
/// (65536 a side) and 512 MiB to decode; a PNG file's colour profile (iCCP) and text chunks are
/// skipped unread.
#[pyfunction]
pub fn load_image<'py>(py: Python<'py>, path: std::path::PathBuf) -> PyResult<ImageArray<'py>> {
    let image = py.detach(|| load_image_file(&path))?;
    image_out(py, image)
}

/// Writes an image as a grey PNG file (a colour array, BGR or BGRA, is written as its grey).
#[pyfunction]
pub fn save_image(py: Python<'_>, image: &Bound<'_, PyAny>, path: std::path::PathBuf) -> PyResult<()> {
    let image = image_arg(image, "image")?;
    let buffer = image.buffer("image")?;
    let owned = GreyImage::from_raw(buffer.width(), buffer.height(), buffer.as_raw().to_vec())
        .ok_or_else(|| image_error("image", "inconsistent size".into()))?;
    Ok(py.detach(|| save_png(&owned, &path))?)
}

/// Adds rendering, images and dot tracking.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyDots>()?;
    m.add_class::<PyDotTracker>()?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(render_view, m)?)?;
    m.add_function(wrap_pyfunction!(degrade, m)?)?;
    m.add_function(wrap_pyfunction!(detect_dots, m)?)?;
    m.add_function(wrap_pyfunction!(load_image, m)?)?;
    m.add_function(wrap_pyfunction!(save_image, m)?)?;
    Ok(())
}
