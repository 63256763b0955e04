//! Pose helpers in Python (4x4 homogeneous matrices of the camera frame in F*), so that users
//! need not write their own SE(3) code: `exp_twist`, `pose_from_position_thetau`,
//! `thetau_from_pose`, `thetau_from_rotations`, `twist_adjoint`.

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;

use super::arrays::{f64_array, from_matrix, mat, pose_arg, vec1};
use super::errors::{PyError, Value, invalid_argument};
use crate::core::se3;
use crate::error::{Error, Short, check_finite, check_finite_matrix, check_overflow};

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
    let pose = pose_arg(pose)?;
    Ok((vec1(py, pose.translation.vector.as_slice()), vec1(py, &se3::thetau_from_pose(&pose))))
}

/// The theta-u vectors (rad, theta in [0, pi]) of rotation matrices `(n, 3, 3)`, shape `(n, 3)` (OpenCV's Rodrigues
/// vectors); `InvalidInput` naming the matrix for one with a non-finite entry or that is not a rotation
/// (orthonormal, det +1, within 1e-6).
#[pyfunction]
pub fn thetau_from_rotations<'py>(
    py: Python<'py>,
    rotations: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let a = f64_array(rotations, "rotations", &[None, Some(3), Some(3)])?;
    let values = a.as_slice()?;
    let mut out = Vec::with_capacity(values.len() / 3);
    for (i, m) in values.chunks_exact(9).enumerate() {
        let tu = se3::thetau_from_rotation(&nalgebra::Matrix3::from_row_slice(m)).map_err(|e| matrix_error(i, &e))?;
        out.extend(tu);
    }
    mat(py, values.len() / 9, 3, out)
}

/// The error of matrix `i` of `rotations`: its message and fields, the matrix named first.
fn matrix_error(i: usize, e: &Error) -> PyErr {
    let reason = match e {
        Error::NonFinitePoint { row, column, .. } => format!("non-finite value at row {row}, column {column}"),
        _ => "not a rotation matrix (orthonormal with det +1, within 1e-6)".to_string(),
    };
    let err = PyError::invalid(format!("rotations[{i}]: {reason}")).argument("rotations").with("index", Value::Int(i));
    match e {
        Error::NonFinitePoint { row, column, .. } => {
            err.kind("non_finite_point").with("row", Value::Int(*row)).with("column", Value::Int(*column)).into()
        }
        _ => err.kind("invalid_parameter").reason(reason).into(),
    }
}

/// The 6x6 twist transform (adjoint) of a pose `(R, t)` (4x4): a twist `(v, w)` in the pose's
/// frame to the same motion's twist in the parent frame, `(R v + t x R w, R w)`; for the
/// camera's pose in the end effector's frame, the camera twist as the end effector's. The
/// rotation block and translation are used as given; the last row is not read.
#[pyfunction]
pub fn twist_adjoint<'py>(py: Python<'py>, pose: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let a = f64_array(pose, "pose", &[Some(4), Some(4)])?;
    let m = nalgebra::Matrix4::from_row_slice(a.as_slice()?);
    check_finite_matrix("pose", &m)?;
    let r = m.fixed_view::<3, 3>(0, 0).into_owned();
    let t = m.fixed_view::<3, 1>(0, 3).into_owned();
    let adjoint = se3::twist_adjoint(&r, &t);
    check_overflow("pose", "adjoint (t x R)", &[adjoint.as_slice()])?;
    from_matrix(py, &adjoint)
}

/// Adds the pose helpers.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(exp_twist, m)?)?;
    m.add_function(wrap_pyfunction!(pose_from_position_thetau, m)?)?;
    m.add_function(wrap_pyfunction!(thetau_from_pose, m)?)?;
    m.add_function(wrap_pyfunction!(thetau_from_rotations, m)?)?;
    m.add_function(wrap_pyfunction!(twist_adjoint, m)?)?;
    Ok(())
}
