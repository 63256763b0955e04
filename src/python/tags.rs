//! AprilTags in Python: `detect_tags(image, family="tag36h11") -> Tags`, ids and corners in
//! OpenCV's order and pixel convention (see `crate::vision::tags`); the work runs with the
//! GIL released.

use std::cell::RefCell;

use numpy::{PyArray1, PyArray3, PyArrayMethods};
use pyo3::prelude::*;

use super::image_arg::image_arg;
use crate::vision::error::Result;
use crate::vision::image::{GreyBuffer, Pixels};
use crate::vision::tags::{MAX_DECIMATION, Tag, TagDecoder, TagFamily, TagReport};

/// Images up to this many pixels keep their decoder (its buffers) for the next call on the
/// same thread; a larger one gets a decoder of its own, freed after the call.
const KEPT_DECODER_PIXELS: u64 = 16 << 20;

thread_local! {
    static DECODER: RefCell<Option<TagDecoder>> = const { RefCell::new(None) };
}

/// The tags in `image`, with this thread's last decoder when it fits.
fn detect<C: Pixels>(image: &GreyBuffer<C>, family: TagFamily, decimation: Option<u32>) -> Result<TagReport> {
    let fresh = || match decimation {
        Some(d) => TagDecoder::with_decimation(family, d),
        None => Ok(TagDecoder::new(family)),
    };
    if u64::from(image.width()) * u64::from(image.height()) > KEPT_DECODER_PIXELS {
        return fresh()?.detect_report(image);
    }
    DECODER.with(|cell| {
        let mut kept = cell.borrow_mut();
        let reusable = kept.as_ref().is_some_and(|d| d.family() == family && d.decimation() == decimation);
        if !reusable {
            *kept = Some(fresh()?);
        }
        match kept.as_mut() {
            Some(decoder) => decoder.detect_report(image),
            None => fresh()?.detect_report(image),
        }
    })
}

/// AprilTags found in an image, sorted by id.
#[pyclass(name = "Tags", module = "vsinv._core", frozen)]
pub struct PyTags {
    /// Tag ids, `(m,)` int64.
    #[pyo3(get)]
    ids: Py<PyArray1<i64>>,
    /// Corners (u, v) of each tag's black square, (m, 4, 2): top-left, top-right, bottom-right, bottom-left as
    /// OpenCV's aruco module orders them (clockwise in the image), pixel (u, v) centred at integer coordinates
    /// (OpenCV's convention).
    #[pyo3(get)]
    corners: Py<PyArray3<f64>>,
    /// Whether the search stopped early: the frame was too cluttered to be searched whole
    /// within the detector's bound on its work (some levels not searched, or some decoded
    /// candidates not measured); the tags found are still right, others may be missing.
    #[pyo3(get)]
    stopped_early: bool,
    family: TagFamily,
    count: usize,
}

#[pymethods]
impl PyTags {
    fn __len__(&self) -> usize {
        self.count
    }
    fn __repr__(&self) -> String {
        let early = if self.stopped_early { ", stopped early" } else { "" };
        format!("Tags({} {} found{early})", self.count, self.family.name())
    }
    /// The family searched for (`"tag36h11"`, ...).
    #[getter]
    fn family(&self) -> &'static str {
        self.family.name()
    }
}

pub(super) fn tags_out(py: Python<'_>, tags: &[Tag], family: TagFamily, stopped_early: bool) -> PyResult<PyTags> {
    let m = tags.len();
    let ids = PyArray1::from_vec(py, tags.iter().map(|t| i64::from(t.id)).collect());
    let flat: Vec<f64> = tags.iter().flat_map(|t| t.corners.as_flattened().to_vec()).collect();
    let corners = PyArray1::from_vec(py, flat).reshape([m, 4, 2])?;
    Ok(PyTags { ids: ids.unbind(), corners: corners.unbind(), stopped_early, family, count: m })
}

/// A name of [`TagFamily::NAMES`] (Python's `TAG_FAMILIES`); anything else raises
/// `InvalidInput` naming `family` and listing the names.
pub(super) fn family_arg(name: &str) -> PyResult<TagFamily> {
    TagFamily::from_name(name).ok_or_else(|| {
        let names = TagFamily::NAMES.map(|n| format!("{n:?}")).join(", ");
        super::errors::invalid_argument("family", format!("family: expected one of {names}, got {name:?}"))
    })
}

/// `None` (chosen per image) or `1..=8`; anything else raises `InvalidInput` naming `decimation`.
pub(super) fn decimation_arg(decimation: Option<i64>) -> PyResult<Option<u32>> {
    let Some(decimation) = decimation else { return Ok(None) };
    u32::try_from(decimation).ok().filter(|d| (1..=MAX_DECIMATION).contains(d)).map(Some).ok_or_else(|| {
        super::errors::invalid_argument(
            "decimation",
            format!("decimation: must be in 1..={MAX_DECIMATION}, got {decimation}"),
        )
    })
}

/// The AprilTags of `family` in an image (grey, or BGR/BGRA converted to grey), sorted by id, with the corners of
/// each black square in OpenCV's aruco order and pixel convention (the same numbers as cv2.aruco.ArucoDetector with
/// DICT_APRILTAG_36h11, within noise), measured on the square's outer edges; a tag whose edges do not support its
/// corners is left out. An empty image raises `InvalidInput`; an image without tags gives an empty result. Quads
/// are searched in the image shrunk by `decimation` (1..=8: larger is faster, smaller finds smaller tags; `None`:
/// chosen per image, 1 below 960 pixels on the shorter side, 2 at 1920 x 1080) and on the image halved again and
/// again, so large tags are found too; corners are measured at full size. Bounds: an image of at most 2^28 pixels
/// (65536 a side, as every image argument), a decimation that leaves at most about 2^22 pixels to search
/// (`InvalidInput` naming `decimation` and the one that fits otherwise; `None` always fits: the detector takes
/// some 70 bytes a searched pixel). The work per frame is bounded too: a level of the search holding more regions
/// (black or white, of the detector's threshold) than is left of the frame's budget of 4,096 is not searched, and
/// at most 512 decoded candidates have their corners measured (best first, one per id); the result's
/// `stopped_early` says when that happened (a cluttered frame: thousands of small squares or tags), never on
/// ordinary frames.
#[pyfunction]
#[pyo3(signature = (image, family = "tag36h11", decimation = None))]
pub fn detect_tags(
    py: Python<'_>,
    image: &Bound<'_, PyAny>,
    family: &str,
    decimation: Option<i64>,
) -> PyResult<PyTags> {
    let family = family_arg(family)?;
    let decimation = decimation_arg(decimation)?;
    let image = image_arg(image, "image")?;
    let buffer = image.buffer("image")?;
    let report = py.detach(|| detect(&buffer, family, decimation))?;
    tags_out(py, &report.tags, family, report.stopped_early)
}

/// Adds tag detection.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyTags>()?;
    m.add_function(wrap_pyfunction!(detect_tags, m)?)?;
    // The families every tag argument and scenario key accepts, from the one declaration.
    m.add("TAG_FAMILIES", pyo3::types::PyTuple::new(m.py(), TagFamily::NAMES)?)?;
    Ok(())
}
