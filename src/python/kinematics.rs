//! Forward and inverse kinematics of the built-in arms in Python: `fk(arm, joints)` and
//! `ik(arm, pose, seed=None)` with poses of the end-effector in the arm's base frame (4x4), and
//! the kinematic arm's damped least squares for any Jacobian (`damped_least_squares`).

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;

use super::arrays::{f64_array, from_matrix, pose_arg, vec1};
use super::errors::invalid_argument;
use crate::sim::arm::{ArmModel, BUILTIN_ARMS, DEFAULT_DAMPING, IkSolution};

/// A built-in arm by name (its default end-effector).
fn builtin_arm(arm: &Bound<'_, PyAny>) -> PyResult<ArmModel> {
    let name: String = arm.extract().map_err(|_| {
        invalid_argument(
            "arm",
            format!("arm: expected a built-in arm name ({}), got {}", BUILTIN_ARMS.join(", "), type_name(arm)),
        )
    })?;
    Ok(ArmModel::builtin(&name)?)
}

fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type().name().map_or_else(|_| "an object".into(), |n| n.to_string())
}

/// One float per joint of `model`, read from `obj` (`what` names it).
fn joints_arg(obj: &Bound<'_, PyAny>, what: &'static str, model: &ArmModel) -> PyResult<Vec<f64>> {
    let a = f64_array(obj, what, &[None])?;
    let q = a.as_slice()?.to_vec();
    if q.len() != model.dof() {
        let reason = format!(
            "{what}: expected {} values (joints {}), got {}",
            model.dof(),
            model.joint_names().join(", "),
            q.len()
        );
        return Err(invalid_argument(what, reason));
    }
    crate::error::check_finite(what, &q)?;
    Ok(q)
}

/// A solution of [`ik`]: the joints (radians; metres for prismatic joints) and how far their
/// pose is from the target.
#[pyclass(name = "IkSolution", module = "vsinv._core", frozen)]
struct PyIkSolution {
    inner: IkSolution,
}

#[pymethods]
impl PyIkSolution {
    /// Joint positions (rad; m for prismatic joints), base to end-effector.
    #[getter]
    fn joints<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, &self.inner.joints)
    }

    /// Distance between the reached and the target positions, metres.
    #[getter]
    fn position_residual(&self) -> f64 {
        self.inner.position_residual
    }

    /// Angle between the reached and the target orientations, radians.
    #[getter]
    fn rotation_residual(&self) -> f64 {
        self.inner.rotation_residual
    }

    /// Iterations of the seed that converged.
    #[getter]
    fn iterations(&self) -> usize {
        self.inner.iterations
    }

    /// The seed that converged: 0 for the given one (or the middle of the limits), then the
    /// spread seeds in order.
    #[getter]
    fn seed(&self) -> usize {
        self.inner.seed
    }

    fn __repr__(&self) -> String {
        let s = &self.inner;
        format!(
            "IkSolution(joints={:?}, position_residual={:.3e}, rotation_residual={:.3e}, iterations={}, seed={})",
            s.joints, s.position_residual, s.rotation_residual, s.iterations, s.seed
        )
    }
}

/// The 4x4 pose of the end-effector of the built-in `arm` ('ur5', 'ur5e': `tool0`, 'panda': `panda_hand_tcp`) in the arm's
/// base frame (its URDF root link: `base_link`, `panda_link0`) at `joints` (rad), one value per joint within the
/// joint limits (InvalidInput naming the first joint outside).
#[pyfunction]
fn fk<'py>(
    py: Python<'py>,
    arm: &Bound<'py, PyAny>,
    joints: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let model = builtin_arm(arm)?;
    let q = joints_arg(joints, "joints", &model)?;
    // Within the joint limits (1e300 rad is no pose of the arm).
    model.check_limits(&q).map_err(|e| match e {
        crate::sim::SimError::Core(crate::Error::InvalidParameter { reason, .. }) => {
            invalid_argument("joints", format!("joints: {reason}"))
        }
        e => e.into(),
    })?;
    from_matrix(py, &model.fk(&q)?.to_homogeneous())
}

/// Joints within the limits of the built-in `arm` ('ur5', 'ur5e', 'panda') that put its end-effector at `pose`: a 4x4
/// float64 rigid motion of the end-effector frame ('ur5', 'ur5e': `tool0`, 'panda': `panda_hand_tcp`) in the arm's base
/// frame (the URDF root link), as :func:`fk` returns. Damped least squares (Levenberg-Marquardt, Sugihara 2011)
/// projected on the joint limits, from `seed` (one value per joint; default the middle of the limits), then from up
/// to 63 spread seeds until one converges to 1e-10 m and 1e-10 rad. A redundant arm (the Panda) returns one of its
/// solutions. Raises InvalidInput (kind 'unreachable', argument 'pose', `residual` the best position residual) when
/// no seed reaches the pose.
#[pyfunction]
#[pyo3(signature = (arm, pose, seed = None))]
fn ik(
    py: Python<'_>,
    arm: &Bound<'_, PyAny>,
    pose: &Bound<'_, PyAny>,
    seed: Option<&Bound<'_, PyAny>>,
) -> PyResult<PyIkSolution> {
    let model = builtin_arm(arm)?;
    let target = pose_arg(pose)?;
    let seed = seed.map(|s| joints_arg(s, "seed", &model)).transpose()?;
    let inner = py.detach(|| model.ik(&target, seed.as_deref()))?;
    Ok(PyIkSolution { inner })
}

/// Joint velocities (n,) that give `twist` (6,: vx, vy, vz, wx, wy, wz) where the arm's Jacobian
/// is `jacobian` (6, n: rows in the twist's frame, a column per joint), by the kinematic arm's
/// damped least squares: the damping grows as the smallest singular value of the Jacobian falls
/// below `damping`; with more than six joints `null_space` (n,) is added projected on the
/// Jacobian's null space. For a Jacobian from elsewhere (MuJoCo's `mj_jacSite`).
#[pyfunction]
#[pyo3(signature = (jacobian, twist, damping = DEFAULT_DAMPING, null_space = None))]
fn damped_least_squares<'py>(
    py: Python<'py>,
    jacobian: &Bound<'py, PyAny>,
    twist: &Bound<'py, PyAny>,
    damping: f64,
    null_space: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let j = f64_array(jacobian, "jacobian", &[Some(6), None])?;
    let n = j.shape()[1];
    let jac = nalgebra::DMatrix::from_row_slice(6, n, j.as_slice()?);
    let v = nalgebra::Vector6::from_column_slice(f64_array(twist, "twist", &[Some(6)])?.as_slice()?);
    let z = match null_space {
        Some(z) => Some(nalgebra::DVector::from_column_slice(f64_array(z, "null_space", &[Some(n)])?.as_slice()?)),
        None => None,
    };
    let dq = crate::sim::arm::damped_least_squares(&jac, &v, damping, z.as_ref())?;
    Ok(vec1(py, dq.as_slice()))
}

/// Adds `fk`, `ik`, `damped_least_squares` and `IkSolution`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyIkSolution>()?;
    m.add_function(wrap_pyfunction!(damped_least_squares, m)?)?;
    m.add_function(wrap_pyfunction!(fk, m)?)?;
    m.add_function(wrap_pyfunction!(ik, m)?)?;
    Ok(())
}
