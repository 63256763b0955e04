//! `to_grey`: a colour uint8 array (RGB or BGR, with or without alpha) to the `(height, width)`
//! grey array the detectors read, in Rust with the GIL released (Rec. 601 luma, OpenCV's
//! `COLOR_RGB2GRAY`/`COLOR_BGR2GRAY` to the bit), through the one image reader
//! ([`super::image_arg`]) every image-taking binding uses.

use numpy::PyArray2;
use pyo3::prelude::*;

use super::image_arg::read_image;
use crate::vision::grey::ChannelOrder;

/// The grey image of `image`: `(height, width, 3)` or `(height, width, 4)` (alpha ignored)
/// uint8 whose colour channels are in `order` (`"rgb"`, the default when None, or `"bgr"`);
/// a grey `(height, width)` or `(height, width, 1)` array is returned as a copy.
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
