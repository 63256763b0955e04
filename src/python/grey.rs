//! `to_grey`: a `(height, width, 3)` or `(height, width, 4)` uint8 colour array (RGB, BGR,
//! RGBA or BGRA) to the `(height, width)` grey array the detectors read, in Rust with the GIL
//! released (Rec. 601 luma, OpenCV's `COLOR_RGB2GRAY`/`COLOR_BGR2GRAY`/`COLOR_RGBA2GRAY`/
//! `COLOR_BGRA2GRAY` to the bit).

use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::vision::grey::{ChannelOrder, pixels_to_grey};

fn invalid(reason: String) -> PyErr {
    crate::Error::InvalidImage { what: "image".to_string(), reason }.into()
}

/// The grey image of a colour image: `image` a `(height, width, 3)` uint8 array, or
/// `(height, width, 4)` with alpha last (ignored), whose colour channels are in `order`
/// (`"rgb"`, the default when None, or `"bgr"`); a non-contiguous array is copied once.
#[pyfunction]
#[pyo3(signature = (image, order = None))]
pub fn to_grey<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    order: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArray2<u8>>> {
    let order = match order {
        None => ChannelOrder::Rgb,
        Some(order) => channel_order(order)?,
    };
    convert(py, image, order)
}

/// `"rgb"` or `"bgr"`; anything else raises `InvalidInput` naming `order`.
fn channel_order(order: &Bound<'_, PyAny>) -> PyResult<ChannelOrder> {
    match order.extract::<String>().ok().as_deref() {
        Some("rgb") => Ok(ChannelOrder::Rgb),
        Some("bgr") => Ok(ChannelOrder::Bgr),
        _ => {
            let other = order.repr().map_or_else(|_| "?".to_string(), |r| r.to_string());
            let reason = format!("expected 'rgb' or 'bgr', got {other}");
            Err(crate::Error::InvalidParameter { name: "order", reason }.into())
        }
    }
}

/// The conversion of a checked `(height, width, 3)` uint8 array, without the GIL.
fn convert<'py>(py: Python<'py>, image: &Bound<'py, PyAny>, order: ChannelOrder) -> PyResult<Bound<'py, PyArray2<u8>>> {
    let Ok(any) = image.cast::<numpy::PyUntypedArray>() else {
        let kind = image.get_type().name()?.to_string();
        return Err(invalid(format!("expected a (height, width, 3 or 4) uint8 NumPy array, got {kind}")));
    };
    let dtype = any.dtype().str()?.to_string();
    let shape = any.shape().to_vec();
    if shape.len() != 3 || !(shape[2] == 3 || shape[2] == 4) || dtype != "uint8" {
        return Err(invalid(format!(
            "expected a (height, width, 3) or (height, width, 4) uint8 array, got dtype {dtype} with shape {shape:?}"
        )));
    }
    let channels = shape[2];
    let (Ok(h), Ok(w)) = (u32::try_from(shape[0]), u32::try_from(shape[1])) else {
        return Err(invalid(format!("image too large {shape:?}")));
    };
    crate::vision::image::check_dimensions("image", u64::from(w), u64::from(h))?;
    let array = image
        .cast::<PyArray3<u8>>()?
        .try_readonly()
        .map_err(|e| invalid(format!("array is being written to ({e})")))?;
    // `as_slice` also takes a Fortran-ordered array, whose bytes are not rows: C order only.
    let c_order = if array.is_c_contiguous() { array.as_slice().ok() } else { None };
    let grey = match c_order {
        Some(data) => py.detach(|| pixels_to_grey("image", w, h, channels, channels * w as usize, data, order))?,
        None => {
            let owned: Vec<u8> = array.as_array().iter().copied().collect();
            py.detach(|| pixels_to_grey("image", w, h, channels, channels * w as usize, &owned, order))?
        }
    };
    let (w, h) = grey.dimensions();
    PyArray1::from_vec(py, grey.into_raw()).reshape([h as usize, w as usize])
}

/// Adds `to_grey`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(to_grey, m)?)
}
