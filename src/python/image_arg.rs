//! The one reader of image arguments: every binding that takes an image (`detect_dots`,
//! `DotTracker`, `detect_tags`, `TagTracker`, `ImageServo`, `save_image`, `to_grey`) reads it
//! here. An image is a uint8 NumPy array, grey `(height, width)` or `(height, width, 1)`, or
//! colour `(height, width, 3)` (BGR, OpenCV's order, unless the binding says otherwise) or
//! `(height, width, 4)` (the same with alpha, ignored), in any memory order (C, Fortran,
//! strided). Colour is converted to grey in Rust (`vision::grey`: Rec. 601 luma, OpenCV's
//! `COLOR_BGR2GRAY` to the bit) with the GIL released; a C-contiguous grey array is read in
//! place, any other grey array copied once.

use numpy::{PyArray1, PyArray2, PyArray3, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;

use crate::vision::grey::{ChannelOrder, pixels_to_grey};
use crate::vision::image::{GreyBuffer, GreyImage, check_dimensions, view};

/// What an image argument may be, for error messages.
const EXPECTED: &str = "a uint8 NumPy array: grey (height, width) or (height, width, 1), colour (height, width, 3) \
                        or (height, width, 4) with alpha";

/// `InvalidInput("{what}: {reason}")`, the vision layer's `VisionError::InvalidImage` (kind `invalid_image`).
pub(super) fn image_error(what: &str, reason: String) -> PyErr {
    crate::vision::VisionError::InvalidImage { what: what.to_string(), reason }.into()
}

/// A grey image read from Python: the array itself (C-contiguous grey) or its conversion.
pub(super) enum ImageArg<'py> {
    Borrowed(PyReadonlyArrayDyn<'py, u8>),
    Converted(GreyImage),
}

impl ImageArg<'_> {
    /// The image's grey pixels, in place.
    pub(super) fn buffer(&self, what: &str) -> PyResult<GreyBuffer<&[u8]>> {
        match self {
            Self::Borrowed(array) => {
                let shape = array.shape();
                let data = array.as_slice().map_err(|e| image_error(what, e.to_string()))?;
                let (Ok(h), Ok(w)) = (u32::try_from(shape[0]), u32::try_from(shape[1])) else {
                    return Err(image_error(what, format!("image too large {shape:?}")));
                };
                Ok(view(what, w, h, data)?)
            }
            Self::Converted(image) => Ok(view(what, image.width(), image.height(), image.as_raw())?),
        }
    }

    /// A new `(height, width)` array of the grey pixels (a conversion is moved, not copied).
    pub(super) fn into_array(self, py: Python<'_>) -> PyResult<Bound<'_, PyArray2<u8>>> {
        let image = match self {
            Self::Converted(image) => image,
            Self::Borrowed(array) => {
                let (h, w) = (array.shape()[0], array.shape()[1]);
                let data = array.as_slice().map_err(|e| image_error("image", e.to_string()))?.to_vec();
                let owned =
                    u32::try_from(w).ok().zip(u32::try_from(h).ok()).and_then(|(w, h)| GreyImage::from_raw(w, h, data));
                owned.ok_or_else(|| image_error("image", "inconsistent size".into()))?
            }
        };
        let (w, h) = image.dimensions();
        PyArray1::from_vec(py, image.into_raw()).reshape([h as usize, w as usize])
    }
}

/// Reads `obj` as an image, colour in OpenCV's order (BGR, BGRA): see the module documentation.
/// Anything else is refused with `InvalidInput` naming `what`, the dtype and the shape, as is
/// an image larger than `check_dimensions` allows (2^28 pixels, 65536 a side).
pub(super) fn image_arg<'py>(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<ImageArg<'py>> {
    read_image(obj, what, ChannelOrder::Bgr)
}

/// [`image_arg`] with colour channels in `order` (`Rgb` or `Bgr`; a fourth channel is alpha).
pub(super) fn read_image<'py>(obj: &Bound<'py, PyAny>, what: &str, order: ChannelOrder) -> PyResult<ImageArg<'py>> {
    let Ok(any) = obj.cast::<numpy::PyUntypedArray>() else {
        let kind = obj.get_type().name()?.to_string();
        return Err(image_error(what, format!("expected {EXPECTED}, got {kind}")));
    };
    let dtype = any.dtype().str()?.to_string();
    let shape = any.shape().to_vec();
    let channels = match shape.as_slice() {
        [_, _] => 1,
        [_, _, c @ (1 | 3 | 4)] => *c,
        _ => 0,
    };
    if channels == 0 || dtype != "uint8" {
        let shape = shape_text(&shape);
        return Err(image_error(what, format!("expected {EXPECTED}, got dtype {dtype} with shape {shape}")));
    }
    // The size is checked before anything is allocated for it (a zero-stride view of a huge
    // image is copied below, and the detectors allocate after its pixels).
    check_dimensions(what, shape[1] as u64, shape[0] as u64)?;
    if channels == 1 {
        return grey(obj, what);
    }
    Ok(ImageArg::Converted(colour(obj, what, channels, order)?))
}

/// A shape as NumPy writes it: `(10, 10, 2)`, `(5,)`.
fn shape_text(shape: &[usize]) -> String {
    let items: Vec<String> = shape.iter().map(usize::to_string).collect();
    if items.len() == 1 { format!("({},)", items[0]) } else { format!("({})", items.join(", ")) }
}

/// A grey array read in place when C-contiguous, else copied once into C order.
fn grey<'py>(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<ImageArg<'py>> {
    let py = obj.py();
    let mut array = obj.cast::<PyArrayDyn<u8>>()?.clone();
    if !array.is_c_contiguous() {
        static CONTIGUOUS: PyOnceLock<Py<PyAny>> = PyOnceLock::new();
        let f = CONTIGUOUS
            .get_or_try_init(py, || Ok::<_, PyErr>(py.import("numpy")?.getattr("ascontiguousarray")?.unbind()))?;
        array = f.call1(py, (obj,))?.bind(py).cast::<PyArrayDyn<u8>>()?.clone();
    }
    let array = array.try_readonly().map_err(|e| image_error(what, format!("array is being written to ({e})")))?;
    Ok(ImageArg::Borrowed(array))
}

/// The grey image of a checked `(height, width, channels)` array, without the GIL; a
/// non-C-contiguous array is copied once into C order first.
fn colour(obj: &Bound<'_, PyAny>, what: &str, channels: usize, order: ChannelOrder) -> PyResult<GreyImage> {
    let py = obj.py();
    let array = obj
        .cast::<PyArray3<u8>>()?
        .try_readonly()
        .map_err(|e| image_error(what, format!("array is being written to ({e})")))?;
    let shape = array.shape();
    let (Ok(h), Ok(w)) = (u32::try_from(shape[0]), u32::try_from(shape[1])) else {
        return Err(image_error(what, format!("image too large {shape:?}")));
    };
    let stride = channels * w as usize;
    // `as_slice` also takes a Fortran-ordered array, whose bytes are not rows: C order only.
    let c_order = if array.is_c_contiguous() { array.as_slice().ok() } else { None };
    let image = match c_order {
        Some(data) => py.detach(|| pixels_to_grey(what, w, h, channels, stride, data, order))?,
        None => {
            let view = array.as_array();
            py.detach(|| {
                let owned: Vec<u8> = view.iter().copied().collect();
                pixels_to_grey(what, w, h, channels, stride, &owned, order)
            })?
        }
    };
    Ok(image)
}
