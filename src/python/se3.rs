//! Pose helpers in Python (4x4 homogeneous matrices of the camera frame in F*), so that users
//! need not write their own SE(3) code: `exp_twist`, `pose_from_position_thetau`,
//! `thetau_from_pose`.

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;

use super::arrays::{f64_array, from_matrix, vec1};
use super::errors::invalid_argument;
use crate::core::se3;
use crate::error::{Short, check_finite};

fn vector<const N: usize>(obj: &Bound<'_, PyAny>, what: &'static str) -> PyResult<[f64; N]> {
    let a = f64_array(obj, what, &[Some(N)])?;
    let v: [f64; N] =
        a.as_slice()?.try_into().map_err(|_| invalid_argument(what, format!("{what}: expected {N} values")))?;
    check_finite(what, &v)?;
    Ok(v)
}

/// The 4x4 rigid motion of holding the camera twist `(vx, vy, vz, wx, wy, wz)` (camera frame)
/// for `dt` seconds: the next pose is `pose @ exp_twist(twist, dt)`.
#[pyfunction]
#[pyo3(signature = (twist, dt = 1.0))]
pub fn exp_twist<'py>(py: Python<'py>, twist: &Bound<'py, PyAny>, dt: f64) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let t: [f64; 6] = vector(twist, "twist")?;
    check_finite("dt", &[dt])?;
    let overflow = || {
        invalid_argument(
            "twist, dt",
            format!("twist, dt: the motion twist * dt overflows (twist {t:?}, dt {})", Short(dt)),
        )
    };
    let m = se3::exp_twist(&t.map(|x| x * dt)).map_err(|_| overflow())?.to_homogeneous();
    from_matrix(py, &m)
}

/// The 4x4 pose with camera centre `position` (metres, F*) and theta-u rotation `thetau`
/// (radians, F*).
#[pyfunction]
pub fn pose_from_position_thetau<'py>(
    py: Python<'py>,
    position: &Bound<'py, PyAny>,
    thetau: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (position, thetau) = (vector(position, "position")?, vector(thetau, "thetau")?);
    let m = se3::pose_from_position_thetau(position, thetau)?.to_homogeneous();
    from_matrix(py, &m)
}

/// `(position (3,), thetau (3,))` of a 4x4 pose: the camera centre and the theta-u rotation
/// vector (radians, theta in [0, pi]).
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn thetau_from_pose<'py>(
    py: Python<'py>,
    pose: &Bound<'py, PyAny>,
) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>)> {
    let a = f64_array(pose, "pose", &[Some(4), Some(4)])?;
    let pose = se3::pose_from_matrix(&nalgebra::Matrix4::from_row_slice(a.as_slice()?))?;
    Ok((vec1(py, pose.translation.vector.as_slice()), vec1(py, &se3::thetau_from_pose(&pose))))
}

/// Adds the pose helpers.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(exp_twist, m)?)?;
    m.add_function(wrap_pyfunction!(pose_from_position_thetau, m)?)?;
    m.add_function(wrap_pyfunction!(thetau_from_pose, m)?)?;
    Ok(())
}
