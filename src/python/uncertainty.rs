//! The pose uncertainty that pixel noise leaves, and the pixel noise of an image stream.

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;

use super::arrays::{bool_array, from_matrix, points2, vec1};
use super::errors::invalid_argument;
use super::{depths_arg, pixels_arg};
use crate::core::noise_meter::PixelNoiseMeter;
use crate::core::uncertainty::{ImageNoise, MAX_PIXEL_SIGMA, PoseUncertainty};

/// The camera displacement from the goal that the images still allow (first-order
/// propagation of pixel noise through the law's Jacobian), in the current camera frame:
/// translation in metres (in the depth estimates' scale), rotation in radians.
#[pyclass(name = "PoseUncertainty", module = "vsinv._core", frozen)]
pub(super) struct PyPoseUncertainty {
    inner: PoseUncertainty,
}

#[pymethods]
impl PyPoseUncertainty {
    /// Covariance of (tx, ty, tz, rx, ry, rz) caused by the pixel noise, (6, 6).
    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        from_matrix(py, &self.inner.covariance)
    }
    /// J^+ (m - m*): the displacement the measured error itself implies, (6,).
    #[getter]
    fn offset<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, self.inner.offset.as_slice())
    }
    /// RMS translation the noise leaves, metres: sqrt(trace Cov(t)).
    #[getter]
    fn translation_sigma(&self) -> f64 {
        self.inner.translation_sigma()
    }
    /// RMS rotation the noise leaves, radians: sqrt(trace Cov(r)).
    #[getter]
    fn rotation_sigma(&self) -> f64 {
        self.inner.rotation_sigma()
    }
    /// sigmas * translation_sigma + |offset_t|: how far from the goal the camera centre may be, metres.
    #[pyo3(signature = (sigmas = 3.0))]
    fn translation_bound(&self, sigmas: f64) -> PyResult<f64> {
        check_sigmas(sigmas)?;
        Ok(self.inner.translation_bound(sigmas))
    }
    /// sigmas * rotation_sigma + |offset_r|, radians.
    #[pyo3(signature = (sigmas = 3.0))]
    fn rotation_bound(&self, sigmas: f64) -> PyResult<f64> {
        check_sigmas(sigmas)?;
        Ok(self.inner.rotation_bound(sigmas))
    }
    fn __repr__(&self) -> String {
        format!(
            "PoseUncertainty(translation_sigma={:.4e} m, rotation_sigma={:.4e} rad)",
            self.inner.translation_sigma(),
            self.inner.rotation_sigma()
        )
    }
}

fn check_sigmas(sigmas: f64) -> PyResult<()> {
    if sigmas.is_finite() && sigmas > 0.0 {
        Ok(())
    } else {
        Err(invalid_argument("sigmas", format!("sigmas: must be finite and > 0, got {sigmas:.4e}")))
    }
}

/// The arguments the controllers' `pose_uncertainty` shares: the arrays and the noise.
pub(super) struct UncertaintyArgs<'py> {
    pixels: super::arrays::F64Array<'py>,
    depths: super::arrays::F64Array<'py>,
    visible: Option<super::arrays::BoolArray<'py>>,
    noise: ImageNoise,
}

impl<'py> UncertaintyArgs<'py> {
    /// Reads `pixels (n, 2)`, `depths (n,)`, `visible (n,)` and the noise levels; the
    /// reference noise defaults to the current one.
    pub(super) fn read(
        pixels: &Bound<'py, PyAny>,
        depths: &Bound<'py, PyAny>,
        visible: Option<&Bound<'py, PyAny>>,
        pixel_sigma: f64,
        reference_sigma: Option<f64>,
        averaged_images: usize,
    ) -> PyResult<Self> {
        let (pixels, depths) = (pixels_arg(pixels, "pixels")?, depths_arg(depths)?);
        let n = pixels.shape()[0];
        let visible = visible.map(|v| bool_array(v, "visible", n)).transpose()?;
        let reference = reference_sigma.unwrap_or(pixel_sigma);
        for (what, value) in [("pixel_sigma", pixel_sigma), ("reference_sigma", reference)] {
            if !(value.is_finite() && (0.0..=MAX_PIXEL_SIGMA).contains(&value)) {
                return Err(invalid_argument(
                    what,
                    format!("{what}: a pixel standard deviation in [0, 1e6], got {value:.4e}"),
                ));
            }
        }
        if averaged_images == 0 {
            return Err(invalid_argument("averaged_images", "averaged_images: must be >= 1".into()));
        }
        let noise = ImageNoise { current: pixel_sigma, reference, averaged_images };
        Ok(Self { pixels, depths, visible, noise })
    }

    /// Calls `f(pixels, depths, visible, noise)` and wraps its answer.
    pub(super) fn apply(
        &self,
        f: impl FnOnce(&[[f64; 2]], &[f64], Option<&[bool]>, ImageNoise) -> crate::Result<PoseUncertainty>,
    ) -> PyResult<PyPoseUncertainty> {
        let visible = self.visible.as_ref().map(|v| v.as_slice()).transpose()?;
        let inner = f(points2(&self.pixels)?, self.depths.as_slice()?, visible, self.noise)?;
        Ok(PyPoseUncertainty { inner })
    }
}

/// The pixel noise of an image stream, measured from the images themselves: the second
/// difference of each point over three consecutive images cancels motion linear in time,
/// and E[d^2] = 6 sigma^2 for independent noise. `PixelNoiseMeter(capacity=32)`: a meter over
/// the last `capacity` images (3 to 4096).
#[pyclass(name = "PixelNoiseMeter", module = "vsinv._core")]
pub(super) struct PyPixelNoiseMeter {
    inner: PixelNoiseMeter,
}

#[pymethods]
impl PyPixelNoiseMeter {
    #[new]
    #[pyo3(signature = (capacity = 32))]
    fn new(#[pyo3(from_py_with = super::args::capacity)] capacity: usize) -> PyResult<Self> {
        Ok(Self { inner: PixelNoiseMeter::new(capacity)? })
    }
    /// Adds an image's pixels (n, 2); another number of points starts the measurement again.
    #[pyo3(signature = (pixels, visible = None))]
    fn push(&mut self, pixels: &Bound<'_, PyAny>, visible: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
        let a = pixels_arg(pixels, "pixels")?;
        let px = points2(&a)?;
        let v = visible.map(|v| bool_array(v, "visible", px.len())).transpose()?;
        let flags = v.as_ref().map(|v| v.as_slice()).transpose()?;
        Ok(self.inner.push(px, flags)?)
    }
    /// The standard deviation of a pixel coordinate, pixels; None until a point was seen in
    /// three consecutive images.
    #[getter]
    fn sigma(&self) -> Option<f64> {
        self.inner.sigma()
    }
    /// Forgets the images.
    fn clear(&mut self) {
        self.inner.clear();
    }
    fn __len__(&self) -> usize {
        self.inner.len()
    }
    fn __repr__(&self) -> String {
        format!("PixelNoiseMeter(images={}, sigma={:?})", self.inner.len(), self.inner.sigma())
    }
}

/// Adds `PoseUncertainty` and `PixelNoiseMeter`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyPoseUncertainty>()?;
    m.add_class::<PyPixelNoiseMeter>()?;
    Ok(())
}
