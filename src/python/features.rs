//! The keypoint target's pieces in Python (`crate::vision::features`): `match_features` (SIFT
//! matches across two cameras, checked by the fundamental matrix) and `track_points` (pyramidal
//! Lucas-Kanade with the forward-backward check), for checking them against OpenCV and for
//! users who want the matches themselves. The work runs with the GIL released.

use numpy::PyArray1;
use pyo3::prelude::*;

use super::arrays::{f64_array, mat, points2};
use super::image_arg::image_arg;
use crate::error::check_finite_points;
use crate::vision::detector::features::REFINE_LEVELS;
use crate::vision::error::{Result, VisionError};
use crate::vision::features::flow::{FlowConfig, plane, track};
use crate::vision::features::keypoints::sift;
use crate::vision::features::matching::{MIN_MATCHES, checked};
use crate::vision::features::refine::{pyramid, refine_matches};
use crate::vision::image::GreyView;

type Pixels<'py> = Bound<'py, numpy::PyArray2<f64>>;

fn positive(name: &'static str, value: f64) -> Result<f64> {
    if value > 0.0 && value.is_finite() {
        Ok(value)
    } else {
        Err(crate::error::Error::InvalidParameter {
            name,
            reason: format!("must be positive and finite, got {value:e}"),
        }
        .into())
    }
}

/// Pixels of the matches in each image.
type MatchPixels = (Vec<[f64; 2]>, Vec<[f64; 2]>);

fn matches(reference: &GreyView<'_>, image: &GreyView<'_>, threshold: f64) -> Result<MatchPixels> {
    let threshold = positive("threshold", threshold)?;
    let first = sift("reference_image", reference)?;
    if first.len() < MIN_MATCHES {
        return Err(VisionError::InvalidImage {
            what: "reference_image".into(),
            reason: format!("{} keypoints (too little texture), at least {MIN_MATCHES} needed", first.len()),
        });
    }
    let second = sift("image", image)?;
    let found = checked("image", &first, &second, threshold)?;
    let a: Vec<[f64; 2]> = found.iter().map(|m| first.pixels[m.reference]).collect();
    let b: Vec<[f64; 2]> = found.iter().map(|m| m.pixel).collect();
    let levels = pyramid(&plane("reference_image", reference)?, REFINE_LEVELS)?;
    let refined = refine_matches(&levels, &plane("image", image)?, &a, &b);
    Ok(a.into_iter().zip(refined).filter_map(|(p, q)| q.map(|q| (p, q))).unzip())
}

/// The SIFT matches of `reference_image` in `image` (two cameras, any intrinsics): mutual
/// nearest descriptors passing Lowe's ratio (0.8), then those within `threshold` pixels of the
/// epipolar lines of one fundamental matrix (RANSAC, seeded), agreeing with their neighbours (a
/// locally affine view), each refined to a fraction of a pixel by aligning the reference's
/// patch warped into `image` (a match whose patch does not align is dropped). Returns `(reference_pixels (m, 2),
/// pixels (m, 2))`; fewer than 12 matches (too little texture, another scene) raises
/// `InvalidImage` naming the image.
#[pyfunction]
#[pyo3(signature = (reference_image, image, threshold = 1.5))]
pub fn match_features<'py>(
    py: Python<'py>,
    reference_image: &Bound<'py, PyAny>,
    image: &Bound<'py, PyAny>,
    threshold: f64,
) -> PyResult<(Pixels<'py>, Pixels<'py>)> {
    let reference = image_arg(reference_image, "reference_image")?;
    let reference = reference.buffer("reference_image")?;
    let image = image_arg(image, "image")?;
    let image = image.buffer("image")?;
    let (a, b) = py.detach(|| matches(&reference, &image, threshold))?;
    Ok((mat(py, a.len(), 2, a.into_flattened())?, mat(py, b.len(), 2, b.into_flattened())?))
}

fn tracks(
    previous: &GreyView<'_>,
    next: &GreyView<'_>,
    points: &[[f64; 2]],
    max_error: f64,
) -> Result<Vec<Option<[f64; 2]>>> {
    let forward_backward = positive("max_error", max_error)?;
    check_finite_points("points", points)?;
    if previous.dimensions() != next.dimensions() {
        return Err(VisionError::InvalidImage {
            what: "next_image".into(),
            reason: format!("{:?} is not the size of previous_image {:?}", next.dimensions(), previous.dimensions()),
        });
    }
    let config = FlowConfig { forward_backward, ..FlowConfig::default() };
    track(&plane("previous_image", previous)?, &plane("next_image", next)?, points, &config)
}

/// Where `points` (n, 2) of `previous_image` are in `next_image` (same size): pyramidal
/// Lucas-Kanade (21 x 21 windows, 3 levels above the image) forward, then backward; a point
/// is found when both ways converge and it comes back within `max_error` pixels of where it
/// started. Returns `(pixels (n, 2), found (n,) bool)`, NaN where not found.
#[pyfunction]
#[pyo3(signature = (previous_image, next_image, points, max_error = 0.5))]
pub fn track_points<'py>(
    py: Python<'py>,
    previous_image: &Bound<'py, PyAny>,
    next_image: &Bound<'py, PyAny>,
    points: &Bound<'py, PyAny>,
    max_error: f64,
) -> PyResult<(Pixels<'py>, Bound<'py, PyArray1<bool>>)> {
    let previous = image_arg(previous_image, "previous_image")?;
    let previous = previous.buffer("previous_image")?;
    let next = image_arg(next_image, "next_image")?;
    let next = next.buffer("next_image")?;
    let points = f64_array(points, "points", &[None, Some(2)])?;
    let points = points2(&points)?.to_vec();
    let out = py.detach(|| tracks(&previous, &next, &points, max_error))?;
    let found: Vec<bool> = out.iter().map(Option::is_some).collect();
    let pixels: Vec<f64> = out.iter().flat_map(|p| p.unwrap_or([f64::NAN; 2])).collect();
    Ok((mat(py, out.len(), 2, pixels)?, PyArray1::from_vec(py, found)))
}

/// Adds `match_features` and `track_points`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(match_features, m)?)?;
    m.add_function(wrap_pyfunction!(track_points, m)?)?;
    Ok(())
}
