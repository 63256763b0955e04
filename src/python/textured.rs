//! Textured planar faces in Python: `render_faces`, the renderer's textured faces
//! (`vision::render::TexturedFace`) seen by one camera, with the renderer's blur and noise.

use std::sync::Arc;

use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;

use super::arrays::{f64_array, points2, points3, pose_arg};
use super::camera::intrinsics;
use super::errors::{invalid_argument, reraise_item};
use super::image_arg::image_arg;
use crate::core::distortion::Distortion;
use crate::vision::image::{GreyImage, check_dimensions};
use crate::vision::render::{CameraView, MAX_FACES, RenderConfig, Renderer, TexturedFace, TexturedFaces};

/// The image a camera sees of textured faces: `faces` a sequence of `(vertices (n, 3),
/// texture_coords (n, 2), texture)`, each a convex planar polygon of F* (metres, n >= 3, front
/// side the one its vertices turn counter-clockwise around) whose vertex `k` shows texture pixel
/// `texture_coords[k]` (`(u, v)`, the texel `(i, j)` centred on `(i, j)`, a texture of w x h
/// texels spanning `[-0.5, w - 0.5] x [-0.5, h - 0.5]`; a projective map from the face: affine
/// for a triangle, the homography of the first four otherwise), `texture` a grey or colour uint8
/// image (as `to_grey` reads it). The camera frame `pose` (4x4, in F*), its intrinsics `K`
/// (`Intrinsics` or 3x3; a pinhole, no distortion), an image of `width` x `height` pixels. A
/// pixel shows the area average over its footprint of the texture read bilinearly between texel
/// centres (OpenGL's linear filter; the nearest face per sample; faces seen from behind are not
/// drawn), on a background of grey level `background`, then the Gaussian PSF
/// of `blur_sigma` pixels and the noise of `noise_sigma` grey levels (draw `frame` of `seed`), as
/// `render`. More faces than the limit (`MAX_FACES` of the crate's renderer) are refused.
/// Returns the `(height, width)` uint8 image.
#[pyfunction]
#[pyo3(signature = (
    faces, pose, K, width, height, blur_sigma = 0.8, noise_sigma = 2.0,
    background = 30, seed = 0, frame = 0,
))]
#[allow(clippy::too_many_arguments, non_snake_case)]
pub fn render_faces<'py>(
    py: Python<'py>,
    faces: &Bound<'py, PyAny>,
    pose: &Bound<'py, PyAny>,
    K: &Bound<'py, PyAny>,
    #[pyo3(from_py_with = super::args::width)] width: u32,
    #[pyo3(from_py_with = super::args::height)] height: u32,
    blur_sigma: f64,
    noise_sigma: f64,
    #[pyo3(from_py_with = super::args::background)] background: u8,
    #[pyo3(from_py_with = super::args::seed)] seed: u64,
    #[pyo3(from_py_with = super::args::frame)] frame: u64,
) -> PyResult<Bound<'py, PyArray2<u8>>> {
    check_dimensions("width x height", u64::from(width), u64::from(height))?;
    let faces = faces_arg(faces)?;
    let pose = pose_arg(pose)?;
    let k = intrinsics(K, "K")?;
    let distortion = Distortion::none();
    // The discs' grey level is not used (`args::background` keeps it above the background).
    let config = RenderConfig { blur_sigma, noise_sigma, background, foreground: 255, seed, ..RenderConfig::default() };
    let renderer = Renderer::new(config)?;
    let view = CameraView { pose: &pose, intrinsics: &k, distortion: &distortion, size: (width, height) };
    let rendered = py.detach(|| renderer.render(&faces, None, &view, frame))?;
    let (w, h) = rendered.image.dimensions();
    PyArray1::from_vec(py, rendered.image.into_raw()).reshape([h as usize, w as usize])
}

/// `faces`: a sequence of `(vertices, texture_coords, texture)`; an error names `faces[i]`.
fn faces_arg(obj: &Bound<'_, PyAny>) -> PyResult<TexturedFaces> {
    let Ok(items) = obj.try_iter() else {
        let kind = obj.get_type().name()?.to_string();
        return Err(invalid_argument("faces", format!("faces: expected a sequence of faces, got {kind}")));
    };
    let mut faces = Vec::new();
    for (i, item) in items.enumerate() {
        // Read no further than one past the limit: an endless iterable is refused, not read forever.
        if i == MAX_FACES {
            let msg = format!("faces[{i}]: more than {MAX_FACES} faces");
            return Err(reraise_item(&invalid_argument("faces", msg.clone()), msg, "faces", i));
        }
        let face = item.and_then(|item| face_arg(&item, i)).map_err(|e| {
            let msg = e.value(obj.py()).to_string();
            let msg = if msg.starts_with("faces[") { msg } else { format!("faces[{i}]: {msg}") };
            reraise_item(&e, msg, "faces", i)
        })?;
        faces.push(face);
    }
    Ok(TexturedFaces(faces))
}

/// Face `i`: `(vertices (n, 3), texture_coords (n, 2), texture)`.
fn face_arg(item: &Bound<'_, PyAny>, i: usize) -> PyResult<TexturedFace> {
    let parts: Vec<Bound<'_, PyAny>> = match item.try_iter() {
        // At most one part past the three: an endless iterable is refused, not read forever.
        Ok(parts) => parts.take(4).collect::<PyResult<_>>()?,
        Err(_) => Vec::new(),
    };
    let [vertices, coords, texture] = parts.as_slice() else {
        let reason =
            format!("faces[{i}]: expected (vertices, texture_coords, texture), got {}", item.get_type().name()?);
        return Err(invalid_argument("faces", reason));
    };
    let vertices = f64_array(vertices, &format!("faces[{i}] vertices"), &[None, Some(3)])?;
    let coords = f64_array(coords, &format!("faces[{i}] texture_coords"), &[None, Some(2)])?;
    let what = format!("faces[{i}] texture");
    let texture = image_arg(texture, &what)?;
    let buffer = texture.buffer(&what)?;
    let owned = GreyImage::from_raw(buffer.width(), buffer.height(), buffer.as_raw().to_vec())
        .ok_or_else(|| invalid_argument("faces", format!("{what}: inconsistent size")))?;
    Ok(TexturedFace::new(points3(&vertices)?.to_vec(), points2(&coords)?.to_vec(), Arc::new(owned))?)
}

/// Adds `render_faces`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(render_faces, m)?)?;
    Ok(())
}
