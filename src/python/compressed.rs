//! `decode_image`: the PNG or JPEG bytes of a compressed camera frame (a ROS
//! `sensor_msgs/CompressedImage`'s data) to a `(height, width)` uint8 grey array, in Rust
//! with the GIL released, the declared size checked against the pixel limit before decoding.

use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::input_file::MAX_IMAGE_BYTES;
use crate::vision::compressed::{Compression, decode_compressed};

fn invalid(reason: String) -> PyErr {
    crate::vision::VisionError::InvalidImage { what: "data".to_string(), reason }.into()
}

/// The (height, width) uint8 grey image of PNG or JPEG bytes (a ROS sensor_msgs/CompressedImage's data), in Rust
/// with the GIL released: the declared size is checked against the pixel limit (2^28, 65536 a side) before
/// decoding, at most 64 MiB of data and 512 MiB to decode; colour by Rec. 601 luma. `format` "png" or "jpeg"
/// refuses the other one (None: either). Empty, unknown, corrupt or truncated data, or 16-bit samples, raise
/// InvalidInput; another `format` InvalidInput naming it.
#[pyfunction]
#[pyo3(signature = (data, format = None))]
pub fn decode_image<'py>(
    py: Python<'py>,
    data: &Bound<'py, PyAny>,
    format: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArray2<u8>>> {
    let choices = [("png", Compression::Png), ("jpeg", Compression::Jpeg)];
    let expected = format.map(|f| super::args::choice(f, "format", &choices, true)).transpose()?;
    let bytes = owned_bytes(py, data)?;
    let grey = py.detach(|| decode_compressed("data", &bytes, expected))?;
    let (w, h) = grey.dimensions();
    PyArray1::from_vec(py, grey.into_raw()).reshape([h as usize, w as usize])
}

/// The bytes of `data` (copied once: a compressed frame is small), through a memoryview for
/// anything but bytes (the buffer protocol, which the stable ABI lacks in Rust); at most
/// [`MAX_IMAGE_BYTES`], counted before the copy.
fn owned_bytes(py: Python<'_>, data: &Bound<'_, PyAny>) -> PyResult<Vec<u8>> {
    let bytes = match data.cast::<PyBytes>() {
        Ok(b) => b.clone(),
        Err(_) => {
            let builtins = py.import("builtins")?;
            let Ok(view) = builtins.getattr("memoryview")?.call1((data,)) else {
                let kind = data.get_type().name()?.to_string();
                return Err(invalid(format!("expected bytes (or an object with a buffer of bytes), got {kind}")));
            };
            let size: u64 = view.getattr("nbytes")?.extract()?;
            if size > MAX_IMAGE_BYTES {
                return Err(invalid(format!("{size} bytes of data: more than {MAX_IMAGE_BYTES}")));
            }
            view.call_method0("tobytes")?.cast_into::<PyBytes>()?
        }
    };
    let slice = bytes.as_bytes();
    if slice.len() as u64 > MAX_IMAGE_BYTES {
        return Err(invalid(format!("{} bytes of data: more than {MAX_IMAGE_BYTES}", slice.len())));
    }
    Ok(slice.to_vec())
}

/// Adds `decode_image`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(decode_image, m)?)
}
