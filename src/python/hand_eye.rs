//! Hand-eye calibration in Python: `calibrate_hand_eye` and `compare_hand_eye_methods` on
//! `(n, 4, 4)` arrays of gripper-to-base and target-to-camera poses (OpenCV's convention),
//! returning `HandEyeCalibration` (the camera-to-gripper `matrix` for `setup="eye_in_hand"`,
//! camera-to-base for `setup="eye_to_hand"`, and its diagnostics) and `HandEyeAgreement`.

use nalgebra::Matrix4;
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::arrays::{f64_array, from_matrix, mat, vec1};
use super::errors::invalid_argument;
use crate::calibration::hand_eye::{self, HandEyeAgreement, HandEyeCalibration, HandEyeMethod, HandEyeSetup};

/// Reads an `(n, 4, 4)` array of poses.
fn poses_arg(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<Matrix4<f64>>> {
    let a = f64_array(obj, what, &[None, Some(4), Some(4)])?;
    Ok(a.as_slice()?.chunks_exact(16).map(Matrix4::from_row_slice).collect())
}

fn method_arg(obj: &Bound<'_, PyAny>) -> PyResult<HandEyeMethod> {
    let name: String = obj.extract().map_err(|_| {
        invalid_argument("method", "method: expected a string: 'tsai', 'park' or 'daniilidis'".to_string())
    })?;
    Ok(HandEyeMethod::from_name(&name)?)
}

fn setup_arg(obj: Option<&Bound<'_, PyAny>>) -> PyResult<HandEyeSetup> {
    let Some(obj) = obj else { return Ok(HandEyeSetup::EyeInHand) };
    let name: String = obj.extract().map_err(|_| {
        invalid_argument("setup", "setup: expected a string: 'eye_in_hand' or 'eye_to_hand'".to_string())
    })?;
    Ok(HandEyeSetup::from_name(&name)?)
}

/// A hand-eye calibration: the camera-to-gripper (eye_in_hand) or camera-to-base (eye_to_hand)
/// transform and its diagnostics.
///
/// For stations i < j the gripper motion A = G_j^-1 G_i and the camera motion B = C_j C_i^-1
/// satisfy A X = X B (eye_to_hand: A = G_j G_i^-1); every pair is a motion (as in OpenCV).
#[pyclass(name = "HandEyeCalibration", module = "vsinv._core", frozen)]
pub struct PyHandEyeCalibration {
    inner: HandEyeCalibration,
}

#[pymethods]
impl PyHandEyeCalibration {
    /// The 4x4 transform X: camera-to-gripper (eye_in_hand) or camera-to-base (eye_to_hand),
    /// the camera frame in the gripper frame or in the base frame.
    #[getter]
    fn matrix<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        from_matrix(py, &self.inner.transform.to_homogeneous())
    }
    /// Where the camera is: 'eye_in_hand' (on the flange; `matrix` is camera-to-gripper) or
    /// 'eye_to_hand' (fixed in the base frame; `matrix` is camera-to-base).
    #[getter]
    fn setup(&self) -> &'static str {
        self.inner.setup.name()
    }
    /// The method: 'tsai', 'park' or 'daniilidis'.
    #[getter]
    fn method(&self) -> &'static str {
        self.inner.method.name()
    }
    /// (m, 2): the residual of A X = X B for every pair of stations i < j (order of `pairs`):
    /// rotation in degrees, translation in metres (eye_to_hand: A = G_j G_i^-1, in the base frame).
    #[getter]
    fn residuals<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let r = &self.inner.residuals;
        mat(py, r.len(), 2, r.iter().flat_map(|p| [p.rotation_deg, p.translation_m]).collect())
    }
    /// (m, 2): the stations (i, j), i < j, of each residual row.
    #[getter]
    fn pairs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        let r = &self.inner.residuals;
        let flat: Vec<i64> = r.iter().flat_map(|p| [p.first as i64, p.second as i64]).collect();
        PyArray1::from_vec(py, flat).reshape([r.len(), 2])
    }
    /// The spread of the rotation axes of the gripper motions, degrees: 2 atan(sqrt(l2/l1)) of the eigenvalues of
    /// the mean u u^T of their unit axes (the angle between the axes for two motions; 0 when all are parallel, 90
    /// for axes spread evenly).
    #[getter]
    fn axis_spread_deg(&self) -> f64 {
        self.inner.axis_spread.spread_deg
    }
    /// (3,): the eigenvalues of the mean u u^T of the motions' unit axes, descending, sum 1.
    #[getter]
    fn axis_eigenvalues<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, &self.inner.axis_spread.eigenvalues)
    }
    /// The number of gripper motions that rotate by 0.1 degree or more.
    #[getter]
    fn rotating_motions(&self) -> usize {
        self.inner.axis_spread.rotating_motions
    }
    /// The number of motions the method used (Tsai-Lenz leaves out those rotating outside 17.3-116.4 degrees, as
    /// OpenCV does).
    #[getter]
    fn motions_used(&self) -> usize {
        self.inner.motions_used
    }
    /// The RMS of the rotation residuals, degrees.
    #[getter]
    fn rms_rotation_deg(&self) -> f64 {
        self.inner.rms_rotation_deg()
    }
    /// The RMS of the translation residuals, metres.
    #[getter]
    fn rms_translation_m(&self) -> f64 {
        self.inner.rms_translation_m()
    }
    /// The largest rotation residual, degrees.
    #[getter]
    fn max_rotation_deg(&self) -> f64 {
        self.inner.max_rotation_deg()
    }
    /// The largest translation residual, metres.
    #[getter]
    fn max_translation_m(&self) -> f64 {
        self.inner.max_translation_m()
    }
    fn __repr__(&self) -> String {
        let c = &self.inner;
        let t = c.transform.translation.vector;
        format!(
            "HandEyeCalibration(method={:?}, setup={:?}, translation_m=[{:.6}, {:.6}, {:.6}], rotation_deg={:.4}, rms_rotation_deg={:.4}, rms_translation_m={:.6}, axis_spread_deg={:.2}, motions_used={})",
            c.method.name(),
            c.setup.name(),
            t[0],
            t[1],
            t[2],
            c.transform.rotation.angle().to_degrees(),
            c.rms_rotation_deg(),
            c.rms_translation_m(),
            c.axis_spread.spread_deg,
            c.motions_used
        )
    }
}

/// Every method's calibration on the same poses, and how far apart they are.
#[pyclass(name = "HandEyeAgreement", module = "vsinv._core", frozen)]
pub struct PyHandEyeAgreement {
    inner: HandEyeAgreement,
}

#[pymethods]
impl PyHandEyeAgreement {
    /// {method: calibration} of the methods that succeeded ('tsai', 'park', 'daniilidis').
    #[getter]
    fn calibrations<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for c in &self.inner.calibrations {
            d.set_item(c.method.name(), PyHandEyeCalibration { inner: c.clone() })?;
        }
        Ok(d)
    }
    /// {method: reason} of the methods that refused the poses.
    #[getter]
    fn failures<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (method, reason) in &self.inner.failures {
            d.set_item(method.name(), reason)?;
        }
        Ok(d)
    }
    /// Where the camera is: 'eye_in_hand' or 'eye_to_hand' (what every calibration's `matrix` is).
    #[getter]
    fn setup(&self) -> &'static str {
        self.inner.setup.name()
    }
    /// The largest rotation between two methods' transforms, degrees.
    #[getter]
    fn max_rotation_deg(&self) -> f64 {
        self.inner.max_rotation_deg
    }
    /// The largest distance between two methods' translations, metres.
    #[getter]
    fn max_translation_m(&self) -> f64 {
        self.inner.max_translation_m
    }
    fn __repr__(&self) -> String {
        let names: Vec<&str> = self.inner.calibrations.iter().map(|c| c.method.name()).collect();
        format!(
            "HandEyeAgreement(methods={names:?}, setup={:?}, max_rotation_deg={:.4}, max_translation_m={:.6}, failures={})",
            self.inner.setup.name(),
            self.inner.max_rotation_deg,
            self.inner.max_translation_m,
            self.inner.failures.len()
        )
    }
}

/// The camera-to-gripper (setup='eye_in_hand': camera on the flange, target fixed) or
/// camera-to-base (setup='eye_to_hand': camera fixed, target on the flange) transform from
/// (n, 4, 4) gripper-to-base `gripper_poses` and target-to-camera `target_poses` (OpenCV's
/// calibrateHandEye convention), by `method` ('tsai', 'park' or 'daniilidis').
///
/// `gripper_poses`: (n, 4, 4) gripper-to-base poses reported by the robot; `target_poses`:
/// (n, 4, 4) target-to-camera poses (e.g. from solvePnP); `method`: 'tsai' (default), 'park' or
/// 'daniilidis'; `setup`: 'eye_in_hand' (default) or 'eye_to_hand' (the gripper poses are
/// inverted, base-to-gripper, and the same method runs). Raises InvalidInput for a pose that is
/// not a rigid transform (naming the argument and the pose), an unknown method or setup, and
/// DegenerateGeometry (kind 'degenerate_motion') for fewer than 3 poses, no rotation, or
/// rotations about (nearly) parallel axes only.
#[pyfunction]
#[pyo3(
    signature = (gripper_poses, target_poses, method = None, setup = None),
    text_signature = "(gripper_poses, target_poses, method='tsai', setup='eye_in_hand')"
)]
pub fn calibrate_hand_eye(
    py: Python<'_>,
    gripper_poses: &Bound<'_, PyAny>,
    target_poses: &Bound<'_, PyAny>,
    method: Option<&Bound<'_, PyAny>>,
    setup: Option<&Bound<'_, PyAny>>,
) -> PyResult<PyHandEyeCalibration> {
    let (g, c) = (poses_arg(gripper_poses, "gripper_poses")?, poses_arg(target_poses, "target_poses")?);
    let method = method.map(method_arg).transpose()?.unwrap_or(HandEyeMethod::TsaiLenz);
    let setup = setup_arg(setup)?;
    let inner = py.detach(|| hand_eye::calibrate_hand_eye(&g, &c, method, setup))?;
    Ok(PyHandEyeCalibration { inner })
}

/// Runs every method on the same poses, for `setup` 'eye_in_hand' or 'eye_to_hand': their
/// calibrations and how far apart they are.
#[pyfunction]
#[pyo3(
    signature = (gripper_poses, target_poses, setup = None),
    text_signature = "(gripper_poses, target_poses, setup='eye_in_hand')"
)]
pub fn compare_hand_eye_methods(
    py: Python<'_>,
    gripper_poses: &Bound<'_, PyAny>,
    target_poses: &Bound<'_, PyAny>,
    setup: Option<&Bound<'_, PyAny>>,
) -> PyResult<PyHandEyeAgreement> {
    let (g, c) = (poses_arg(gripper_poses, "gripper_poses")?, poses_arg(target_poses, "target_poses")?);
    let setup = setup_arg(setup)?;
    let inner = py.detach(|| hand_eye::compare_hand_eye_methods(&g, &c, setup))?;
    Ok(PyHandEyeAgreement { inner })
}

/// Adds hand-eye calibration.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyHandEyeCalibration>()?;
    m.add_class::<PyHandEyeAgreement>()?;
    m.add_function(wrap_pyfunction!(calibrate_hand_eye, m)?)?;
    m.add_function(wrap_pyfunction!(compare_hand_eye_methods, m)?)?;
    Ok(())
}
