//! `Scenario.arm()`: the arm of a scenario's `[robot]` as the kinematic simulator reads it,
//! for a world that moves the arm itself (`vsinv.mujoco`): its placement, start joints and
//! limits, and the kinematic arm's resolution of a camera twist into joint velocities for a
//! Jacobian from that world.

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;

use super::arrays::{f64_array, from_matrix, pose_arg, vec1};
use crate::sim::arm::ArmRobot;

/// The arm of a scenario (`Scenario.arm()`): the built-in model or URDF, its base in F*, the
/// camera's mount on the end effector, the start joints and the limits the kinematic simulator
/// uses, and its resolution of camera twists into joint velocities.
#[pyclass(name = "ScenarioArm", module = "vsinv._core", frozen)]
pub struct PyScenarioArm {
    pub inner: ArmRobot,
}

/// Joint values (n,) of `obj`, finite, one per joint of `arm` (`what` names the argument).
fn joints_of(arm: &ArmRobot, obj: &Bound<'_, PyAny>, what: &'static str) -> PyResult<Vec<f64>> {
    let q = f64_array(obj, what, &[Some(arm.dof())])?.as_slice()?.to_vec();
    crate::error::check_finite(what, &q)?;
    Ok(q)
}

#[pymethods]
impl PyScenarioArm {
    /// `robot.urdf`: the built-in arm's name ('ur5', 'ur5e', 'panda') or the URDF's source.
    #[getter]
    fn model(&self) -> &str {
        self.inner.model.name()
    }
    /// Where the arm's model came from: `builtin:<name>` for a built-in arm, else the path of
    /// the URDF file `robot.urdf` (resolved from the scenario file's folder).
    #[getter]
    fn source(&self) -> &str {
        self.inner.model.source()
    }
    /// The link carrying the camera (`robot.end_effector`, or the model's default).
    #[getter]
    fn end_effector(&self) -> &str {
        self.inner.model.end_effector()
    }
    /// The actuated joints' names, base to end effector.
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.inner.model.joint_names().into_iter().map(String::from).collect()
    }
    /// The arm's base link in F* (4x4, `robot.base`).
    #[getter]
    fn base<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        from_matrix(py, &self.inner.base.to_homogeneous())
    }
    /// The camera in the end effector's frame (4x4, `robot.camera_mount`): where it is.
    #[getter]
    fn mount<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        from_matrix(py, &self.inner.mount.to_homogeneous())
    }
    /// The mount the controller believes (4x4: `camera_mount * mount_error`, or the mount):
    /// camera twists become joint velocities through it.
    #[getter]
    fn believed_mount<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        from_matrix(py, &self.inner.believed_mount.unwrap_or(self.inner.mount).to_homogeneous())
    }
    /// The start joints (rad; m for prismatic joints): `robot.joints`, or solved from `[start]`.
    #[getter]
    fn start<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, &self.inner.start)
    }
    /// Lower joint limits (rad, m).
    #[getter]
    fn lower<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, &self.inner.limits.lower)
    }
    /// Upper joint limits (rad, m).
    #[getter]
    fn upper<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, &self.inner.limits.upper)
    }
    /// Joint speed limits (rad/s, m/s).
    #[getter]
    fn velocity<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, &self.inner.limits.velocity)
    }
    /// The largest damping factor of the least squares (`robot.damping`).
    #[getter]
    fn damping(&self) -> f64 {
        self.inner.damping
    }
    /// A run ends `singular` below this manipulability (`robot.min_manipulability`).
    #[getter]
    fn min_manipulability(&self) -> f64 {
        self.inner.min_manipulability
    }
    /// The camera's pose in F* (4x4) at `joints`: `base * fk(joints) * mount`.
    fn camera_pose<'py>(&self, py: Python<'py>, joints: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let q = joints_of(&self.inner, joints, "joints")?;
        from_matrix(py, &self.inner.camera_pose(&q)?.to_homogeneous())
    }
    /// The manipulability sqrt(det(J J^T)) at `joints` (any frame's Jacobian gives it).
    fn manipulability(&self, joints: &Bound<'_, PyAny>) -> PyResult<f64> {
        let q = joints_of(&self.inner, joints, "joints")?;
        Ok(self.inner.model.manipulability(&q)?)
    }
    /// Joint velocities (n,) for the camera `twist` (6,: in the camera frame the controller
    /// believes) at `joints`, where `jacobian` (6, n) is that camera frame's Jacobian from
    /// elsewhere (MuJoCo's `mj_jacSite`, rows turned into the camera frame): the kinematic arm's
    /// damped least squares, with its joint-centring task on a redundant arm, scaled as a whole
    /// within the joint speed limits; and whether the limits scaled them.
    fn joint_velocities<'py>(
        &self,
        py: Python<'py>,
        jacobian: &Bound<'py, PyAny>,
        joints: &Bound<'py, PyAny>,
        twist: &Bound<'py, PyAny>,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, bool)> {
        let n = self.inner.dof();
        let j = f64_array(jacobian, "jacobian", &[Some(6), Some(n)])?;
        let jac = nalgebra::Matrix6xX::from_row_slice(j.as_slice()?);
        let q = joints_of(&self.inner, joints, "joints")?;
        let v = nalgebra::Vector6::from_column_slice(f64_array(twist, "twist", &[Some(6)])?.as_slice()?);
        let (dq, limited) = self.inner.camera_joint_velocities(&jac, &q, &v)?;
        Ok((vec1(py, dq.as_slice()), limited))
    }
    /// Every link of the chain at `joints`, base link first, end effector last: (name, its pose
    /// in the base link's frame, 4x4), by this arm's own model (`fk` of each link).
    fn link_poses<'py>(
        &self,
        py: Python<'py>,
        joints: &Bound<'py, PyAny>,
    ) -> PyResult<Vec<(String, Bound<'py, PyArray2<f64>>)>> {
        let q = joints_of(&self.inner, joints, "joints")?;
        let model = &self.inner.model;
        let mut out = Vec::new();
        for name in model.link_names() {
            out.push((name.to_string(), from_matrix(py, &model.fk_link(&q, name)?.to_homogeneous())?));
        }
        Ok(out)
    }
    /// Joints within the model's limits that put the end effector at `pose` (4x4, in the arm's
    /// base frame, as `camera_pose` is `base * fk * mount`), by this arm's own model (a user's
    /// URDF, or the built-in): the damped least squares of `kinematics.ik`, from `seed` (one
    /// value per joint; default the middle of the limits), then from spread seeds. Raises
    /// InvalidInput (kind 'unreachable') when no seed reaches the pose.
    #[pyo3(signature = (pose, seed = None))]
    fn ik<'py>(
        &self,
        py: Python<'py>,
        pose: &Bound<'py, PyAny>,
        seed: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let target = pose_arg(pose)?;
        let seed = seed.map(|s| joints_of(&self.inner, s, "seed")).transpose()?;
        let model = &self.inner.model;
        let solution = py.detach(|| model.ik(&target, seed.as_deref()))?;
        Ok(vec1(py, &solution.joints))
    }
    fn __repr__(&self) -> String {
        format!("ScenarioArm(model={:?}, end_effector={:?})", self.inner.model.name(), self.inner.model.end_effector())
    }
}

/// Adds `ScenarioArm`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyScenarioArm>()
}
