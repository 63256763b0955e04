//! `to_grey`: a colour uint8 array (RGB or BGR, with or without alpha) to the `(height, width)`
//! grey array the detectors read, in Rust with the GIL released (Rec. 601 luma, OpenCV's
//! `COLOR_RGB2GRAY`/`COLOR_BGR2GRAY` to the bit), through the one image reader
//! ([`super::image_arg`]) every image-taking binding uses.

use numpy::PyArray2;
use pyo3::prelude::*;

use super::image_arg::read_image;
use crate::vision::grey::ChannelOrder;

/// The (height, width) uint8 grey image of a (height, width, 3) uint8 colour image, or a (height, width, 4) one
/// with alpha last (ignored), whose colour channels are in `order` (None: `"rgb"`), by Rec. 601 luma in integer
/// arithmetic (OpenCV's COLOR_RGB2GRAY, COLOR_BGR2GRAY, COLOR_RGBA2GRAY, COLOR_BGRA2GRAY to the bit), vectorised
/// (AVX2 when the processor has it), in Rust with the GIL released; a non-contiguous array is copied once, a grey
/// (height, width) or (height, width, 1) array is returned as a copy. Another shape or dtype raises InvalidInput,
/// another order InvalidInput naming `order`. (Every function that takes an image reads colour itself, in OpenCV's
/// BGR order.)
#[pyfunction]
#[pyo3(signature = (image, order = None))]
pub fn to_grey<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    order: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArray2<u8>>> {
    let order = match order {
        None => ChannelOrder::Rgb,
        Some(order) => {
            super::args::choice(order, "order", &[("rgb", ChannelOrder::Rgb), ("bgr", ChannelOrder::Bgr)], false)?
        }
    };
    read_image(image, "image", order)?.into_array(py)
}

/// Adds `to_grey`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(to_grey, m)?)
}
