//! Eye-in-hand control of an arm: a camera fixed on the end-effector through `mount`, the
//! arm's base placed in F*. Each step maps the camera twist to the end-effector twist
//! (constant twist transform of the mount), then to joint velocities by damped least squares
//! with a joint-centring task in the null space of redundant arms, saturates them by the
//! joint speed limits (one common scale) and integrates `q += dq dt`.

use nalgebra::{Cholesky, DMatrix, DVector, Dyn, Isometry3, Matrix6, Matrix6xX, Vector6};

use super::{ArmLimits, ArmModel};
use crate::core::se3::twist_transform;
use crate::error::{Error, Short, check_finite, check_finite_matrix};
use crate::sim::error::Result;
use crate::sim::robot::{CameraRobot, RobotEvent, RobotMotion};

/// Default largest damping factor of the least squares (see [`ArmRobot::damping`]).
pub const DEFAULT_DAMPING: f64 = 0.02;
/// Default manipulability below which a run ends `singular`.
pub const DEFAULT_MIN_MANIPULABILITY: f64 = 1e-4;
/// Gain of the joint-centring task on redundant arms, rad/s per unit of the cost gradient.
const CENTRING_GAIN: f64 = 0.5;

/// An arm carrying the camera.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmRobot {
    /// The kinematic chain, base link to end-effector link.
    pub model: ArmModel,
    /// Pose of the arm's base link in F*.
    pub base: Isometry3<f64>,
    /// Pose of the camera in the end-effector frame.
    pub mount: Isometry3<f64>,
    /// The mount the controller believes (a hand-eye calibration's result) when it is not
    /// the true `mount`: camera twists become joint velocities through it, while the camera
    /// moves with the true mount. `None`: the controller knows the true mount.
    pub believed_mount: Option<Isometry3<f64>>,
    /// Joint positions at the start (rad, m).
    pub start: Vec<f64>,
    /// Position and speed limits (the model's unless overridden).
    pub limits: ArmLimits,
    /// Largest damping factor `d`: with `sigma` the smallest singular value of the Jacobian,
    /// the damping is `mu^2 = d^2 - sigma^2` when `sigma < d`, else none (exact solution).
    pub damping: f64,
    /// A run ends `singular` when the manipulability falls below this.
    pub min_manipulability: f64,
}

/// What one arm step did.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmStep {
    /// New joint positions.
    pub joints: Vec<f64>,
    /// Joint velocities applied (after saturation).
    pub velocities: Vec<f64>,
    /// New camera pose in F*.
    pub pose: Isometry3<f64>,
    /// The camera twist the joint velocities produce (camera frame).
    pub twist: Vector6<f64>,
    /// Manipulability at the new joint positions.
    pub manipulability: f64,
    /// Whether the speed limits scaled the motion down.
    pub limited: bool,
    /// Set when the run must end here.
    pub event: Option<RobotEvent>,
}

impl ArmRobot {
    /// An arm with the model's limits and the default damping and singularity threshold.
    pub fn new(model: ArmModel, base: Isometry3<f64>, mount: Isometry3<f64>, start: Vec<f64>) -> Self {
        let limits = model.limits();
        Self {
            model,
            base,
            mount,
            believed_mount: None,
            start,
            limits,
            damping: DEFAULT_DAMPING,
            min_manipulability: DEFAULT_MIN_MANIPULABILITY,
        }
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.model.dof()
    }

    /// Checks the limits, the damping, the threshold and the start joints.
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &'static str, reason: String| Err(Error::InvalidParameter { name, reason }.into());
        let (n, l) = (self.dof(), &self.limits);
        if l.lower.len() != n || l.upper.len() != n || l.velocity.len() != n {
            return bad("robot limits", format!("one value per joint: {n}"));
        }
        if let Some(i) = (0..n).find(|&i| !(l.lower[i] < l.upper[i]) || !(l.velocity[i] > 0.0)) {
            return bad("robot limits", format!("joint {}: needs lower < upper and velocity > 0", self.name(i)));
        }
        if !(self.damping.is_finite() && self.damping > 0.0) {
            return bad("robot.damping", format!("must be finite and > 0, got {}", Short(self.damping)));
        }
        if !(self.min_manipulability.is_finite() && self.min_manipulability >= 0.0) {
            return bad(
                "robot.min_manipulability",
                format!("must be finite and >= 0, got {}", Short(self.min_manipulability)),
            );
        }
        check_finite("robot.base", self.base.to_homogeneous().as_slice())?;
        check_finite("robot.camera_mount", self.mount.to_homogeneous().as_slice())?;
        if let Some(believed) = &self.believed_mount {
            check_finite("robot.mount_error", believed.to_homogeneous().as_slice())?;
        }
        self.check_start()
    }

    /// The start joints: one per joint, inside the limits, not singular.
    fn check_start(&self) -> Result<()> {
        let q = &self.start;
        self.model.fk(q)?;
        if let Some(i) = (0..self.dof()).find(|&i| !(self.limits.lower[i] <= q[i] && q[i] <= self.limits.upper[i])) {
            let (lo, hi) = (self.limits.lower[i], self.limits.upper[i]);
            let reason =
                format!("{} = {} is outside its limits [{}, {}]", self.name(i), Short(q[i]), Short(lo), Short(hi));
            return Err(Error::InvalidParameter { name: "robot.joints", reason }.into());
        }
        let w = self.model.manipulability(q)?;
        if w < self.min_manipulability {
            let reason = format!("manipulability {w:.3e} at the start is below robot.min_manipulability");
            return Err(Error::InvalidParameter { name: "robot.joints", reason }.into());
        }
        Ok(())
    }

    fn name(&self, i: usize) -> &str {
        self.model.joints()[i].name()
    }

    /// Camera pose in F* at joint positions `q`: `base * fk(q) * mount`.
    pub fn camera_pose(&self, q: &[f64]) -> Result<Isometry3<f64>> {
        Ok(self.base * self.model.fk(q)? * self.mount)
    }

    /// The camera twist (camera frame) to the end-effector twist (end-effector frame),
    /// through the mount the controller believes.
    pub fn mount_twist_transform(&self) -> Matrix6<f64> {
        twist_transform(self.believed_mount.as_ref().unwrap_or(&self.mount))
    }

    /// Joint velocities for a camera twist at `q`, before saturation: damped least squares
    /// on the end-effector twist, plus the joint-centring task in the null space when the
    /// arm is redundant.
    pub fn joint_velocities(&self, q: &[f64], camera_twist: &Vector6<f64>) -> Result<DVector<f64>> {
        let jac = self.model.jacobian_end_effector(q)?;
        self.resolve(&jac, q, &(self.mount_twist_transform() * camera_twist))
    }

    /// Joint velocities for a camera twist where `camera_jacobian` (6 x n, rows in the camera
    /// frame the controller believes) is the camera's Jacobian from elsewhere (a physics
    /// engine's): the kinematic arm's damped least squares, joint-centring task on redundant
    /// arms and saturation by the joint speed limits, as [`ArmRobot::step`]; returns the joint
    /// velocities and whether the limits scaled them down.
    pub fn camera_joint_velocities(
        &self,
        camera_jacobian: &Matrix6xX<f64>,
        q: &[f64],
        camera_twist: &Vector6<f64>,
    ) -> Result<(DVector<f64>, bool)> {
        if camera_jacobian.ncols() != self.dof() || q.len() != self.dof() {
            return Err(Error::Shape {
                what: "jacobian",
                expected: format!("(6, {n}) and {n} joints", n = self.dof()),
                got: format!("(6, {}) and {} joints", camera_jacobian.ncols(), q.len()),
            }
            .into());
        }
        check_finite("joints", q)?;
        let mut dq = self.resolve(camera_jacobian, q, camera_twist)?;
        let limited = self.saturate(&mut dq);
        Ok((dq, limited))
    }

    /// `dq = J^T (J J^T + mu^2 I)^-1 v + (I - J^T (J J^T + mu^2 I)^-1 J) z` (six joints or
    /// more); `(J^T J + mu^2 I)^-1 J^T v` below six.
    fn resolve(&self, jac: &Matrix6xX<f64>, q: &[f64], v: &Vector6<f64>) -> Result<DVector<f64>> {
        let j = DMatrix::from_column_slice(6, jac.ncols(), jac.as_slice());
        let z = (jac.ncols() > 6).then(|| self.centring(q));
        damped_least_squares(&j, v, self.damping, z.as_ref())
    }

    /// Minus the gradient of the joint-limit cost `1/2 sum ((q_i - mid_i) / half_i)^2`
    /// (joints without limits contribute nothing).
    fn centring(&self, q: &[f64]) -> DVector<f64> {
        let l = &self.limits;
        DVector::from_fn(q.len(), |i, _| {
            let (mid, half) = ((l.upper[i] + l.lower[i]) / 2.0, (l.upper[i] - l.lower[i]) / 2.0);
            if half.is_finite() { -CENTRING_GAIN * (q[i] - mid) / (half * half) } else { 0.0 }
        })
    }

    /// Scales `dq` as a whole so that every joint is within its speed limit; returns whether
    /// it had to.
    pub fn saturate(&self, dq: &mut DVector<f64>) -> bool {
        let scale = dq.iter().zip(&self.limits.velocity).map(|(v, max)| max / v.abs()).fold(1.0_f64, f64::min);
        if scale < 1.0 {
            *dq *= scale;
        }
        scale < 1.0
    }

    /// Moves the arm from `q` under a camera twist (camera frame) for `dt` seconds.
    pub fn step(&self, q: &[f64], camera_twist: &Vector6<f64>, dt: f64) -> Result<ArmStep> {
        check_finite("twist", camera_twist.as_slice())?;
        let jac = self.model.jacobian_end_effector(q)?;
        let mut dq = self.resolve(&jac, q, &(self.mount_twist_transform() * camera_twist))?;
        let limited = self.saturate(&mut dq);
        let mut joints: Vec<f64> = q.iter().zip(dq.iter()).map(|(q, v)| q + v * dt).collect();
        let clamped = self.clamp(&mut joints);
        let manipulability = self.model.manipulability(&joints)?;
        let singular = (manipulability < self.min_manipulability).then_some(RobotEvent::Singular { manipulability });
        let twist = self.camera_twist(&jac, &dq);
        Ok(ArmStep {
            pose: self.camera_pose(&joints)?,
            joints,
            velocities: dq.as_slice().to_vec(),
            twist,
            manipulability,
            limited,
            event: clamped.or(singular),
        })
    }

    /// The camera twist (camera frame) that `dq` produces where the Jacobian is `jac`.
    fn camera_twist(&self, jac: &Matrix6xX<f64>, dq: &DVector<f64>) -> Vector6<f64> {
        let inverse = twist_transform(&self.mount.inverse());
        inverse * (jac * dq)
    }

    /// Clamps joints to their limits; the first joint that was outside, if any.
    fn clamp(&self, q: &mut [f64]) -> Option<RobotEvent> {
        let mut event = None;
        for (i, qi) in q.iter_mut().enumerate() {
            let (lo, hi) = (self.limits.lower[i], self.limits.upper[i]);
            if *qi < lo || *qi > hi {
                let bound = if *qi < lo { lo } else { hi };
                event.get_or_insert(RobotEvent::JointLimit { joint: self.name(i).to_string(), value: *qi, bound });
                *qi = bound;
            }
        }
        event
    }
}

/// Cholesky factor of `G + mu^2 I` with `mu^2 = d^2 - sigma_min^2` when the smallest
/// eigenvalue `sigma_min^2` of the Gram matrix `G` is below `d^2` (the factorised matrix's
/// smallest eigenvalue is then `d^2`), else of `G` itself.
/// Joint velocities `dq` that give the twist `v` where the Jacobian is `jac` (6 x n, in the
/// twist's frame), by damped least squares with largest damping `damping` (see
/// [`ArmRobot::damping`]): `dq = J^T (J J^T + mu^2 I)^-1 v` with six joints or more,
/// `(J^T J + mu^2 I)^-1 J^T v` below six; with more than six, `null_space` (n joint velocities,
/// the arm's joint-centring task) is added projected on the null space of `J`,
/// `(I - J^T (J J^T + mu^2 I)^-1 J) z`. The kinematic arm's resolution, for a Jacobian from
/// elsewhere (a physics engine's).
pub fn damped_least_squares(
    jac: &DMatrix<f64>,
    v: &Vector6<f64>,
    damping: f64,
    null_space: Option<&DVector<f64>>,
) -> Result<DVector<f64>> {
    let n = jac.ncols();
    if jac.nrows() != 6 || n == 0 {
        return Err(Error::Shape {
            what: "jacobian",
            expected: "(6, n) with n >= 1".into(),
            got: format!("({}, {n})", jac.nrows()),
        }
        .into());
    }
    let d2 = damping * damping;
    if !(damping.is_finite() && damping > 0.0 && d2.is_normal()) {
        let reason = format!("must be finite and > 0 with a finite, normal square, got {}", Short(damping));
        return Err(Error::InvalidParameter { name: "damping", reason }.into());
    }
    check_finite_matrix("jacobian", jac)?;
    check_finite("twist", v.as_slice())?;
    let v = DVector::from_column_slice(v.as_slice());
    let dq = if n < 6 {
        damped_cholesky(jac.transpose() * jac, damping)?.solve(&(jac.transpose() * v))
    } else {
        let chol = damped_cholesky(jac * jac.transpose(), damping)?;
        let dq = jac.transpose() * chol.solve(&v);
        with_null_space(jac, &chol, dq, null_space)?
    };
    if dq.iter().any(|x| !x.is_finite()) {
        let reason = "the joint velocities overflow (a huge twist or Jacobian)".into();
        return Err(Error::InvalidParameter { name: "twist", reason }.into());
    }
    Ok(dq)
}

/// `dq + (I - J^T (J J^T + mu^2 I)^-1 J) z` for a redundant arm (more than six joints).
fn with_null_space(
    jac: &DMatrix<f64>,
    chol: &Cholesky<f64, Dyn>,
    mut dq: DVector<f64>,
    null_space: Option<&DVector<f64>>,
) -> Result<DVector<f64>> {
    let n = jac.ncols();
    if let Some(z) = null_space.filter(|_| n > 6) {
        if z.len() != n {
            return Err(Error::Shape {
                what: "null_space",
                expected: format!("({n},)"),
                got: format!("({},)", z.len()),
            }
            .into());
        }
        check_finite("null_space", z.as_slice())?;
        dq += z - jac.transpose() * chol.solve(&(jac * z));
    }
    Ok(dq)
}

fn damped_cholesky(mut gram: DMatrix<f64>, d: f64) -> Result<Cholesky<f64, Dyn>> {
    check_finite("jacobian", gram.as_slice())?;
    let sigma2 = gram.clone().symmetric_eigenvalues().min().max(0.0);
    let mu2 = (d * d - sigma2).max(0.0);
    for i in 0..gram.nrows() {
        gram[(i, i)] += mu2;
    }
    gram.cholesky().ok_or(
        Error::InvalidParameter {
            name: "damping",
            reason: "the damped least squares matrix is not positive definite".into(),
        }
        .into(),
    )
}

/// The arm behind the robots' one interface: its joints are its state.
impl CameraRobot for ArmRobot {
    fn dof(&self) -> usize {
        self.model.dof()
    }

    /// The arm is valid and `pose` is its camera pose at the start joints.
    fn start(&self, pose: &Isometry3<f64>) -> Result<(Vec<f64>, Option<f64>)> {
        self.validate()?;
        let (dt, dr) = crate::core::se3::pose_error(&self.camera_pose(&self.start)?, pose);
        if dt > 1e-9 || dr > 1e-9 {
            let reason = format!("the start pose is {dt:.3e} m, {dr:.3e} rad from the camera pose at the arm's joints");
            return Err(Error::InvalidParameter { name: "start", reason }.into());
        }
        Ok((self.start.clone(), Some(self.model.manipulability(&self.start)?)))
    }

    fn step(&self, _pose: &Isometry3<f64>, joints: &[f64], twist: &Vector6<f64>, dt: f64) -> Result<RobotMotion> {
        let step = ArmRobot::step(self, joints, twist, dt)?;
        Ok(RobotMotion {
            pose: step.pose,
            joints: step.joints,
            twist: step.twist,
            joint_velocities: Some(step.velocities),
            manipulability: Some(step.manipulability),
            limited: step.limited,
            event: step.event,
        })
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::sim::error::SimError;

    /// A diagonal Jacobian with singular values `s`: the closed form of the damped least squares
    /// is `dq_i = s_i v_i / (s_i^2 + mu^2)` with `mu^2 = max(d^2 - min s^2, 0)`.
    fn closed_form(s: &[f64], v: &Vector6<f64>, d: f64) -> Vec<f64> {
        let min = s.iter().cloned().fold(f64::INFINITY, f64::min);
        let mu2 = (d * d - min * min).max(0.0);
        s.iter().zip(v.iter()).map(|(s, v)| s * v / (s * s + mu2)).collect()
    }

    #[test]
    fn damped_least_squares_is_the_closed_form_on_a_diagonal_jacobian() {
        let v = Vector6::new(0.1, -0.2, 0.3, 0.05, -0.4, 0.25);
        for (s, d) in [([2.0, 1.0, 0.5, 0.3, 0.2, 0.1], 0.02), ([2.0, 1.0, 0.5, 0.3, 0.2, 0.01], 0.05)] {
            let jac = DMatrix::from_diagonal(&DVector::from_column_slice(&s));
            let dq = damped_least_squares(&jac, &v, d, None).unwrap();
            for (got, want) in dq.iter().zip(closed_form(&s, &v, d)) {
                assert!((got - want).abs() < 1e-12, "{got} vs {want}");
            }
        }
    }

    /// A camera Jacobian from elsewhere (here the end effector's turned into the camera frame,
    /// as a physics engine's site Jacobian would be) gives the joint velocities of the kinematic
    /// arm's own step where the damping is inactive, saturated the same way.
    #[test]
    fn camera_joint_velocities_are_the_kinematic_arms() {
        for name in ["ur5", "ur5e", "panda"] {
            let model = ArmModel::builtin(name).unwrap();
            let n = model.dof();
            let q: Vec<f64> = [0.3, -1.1, 1.2, -1.6, 0.7, 1.4, 0.4][..n].to_vec();
            let q = if name == "panda" { vec![0.1, -0.4, 0.05, -2.0, 0.05, 1.7, 0.7] } else { q };
            let mount = crate::core::se3::pose_from_position_thetau([0.01, -0.06, 0.04], [0.1, -0.2, 0.3]).unwrap();
            let arm = ArmRobot::new(model, Isometry3::identity(), mount, q.clone());
            let jac_cam = twist_transform(&mount.inverse()) * arm.model.jacobian_end_effector(&q).unwrap();
            let twist = Vector6::new(0.02, -0.01, 0.03, 0.05, -0.02, 0.04);
            let (dq, limited) = arm.camera_joint_velocities(&jac_cam, &q, &twist).unwrap();
            let mut want = arm.joint_velocities(&q, &twist).unwrap();
            assert!(!arm.saturate(&mut want) && !limited);
            assert!((&dq - &want).amax() < 1e-9, "{name}: {dq} vs {want}");
            let (fast, limited) = arm.camera_joint_velocities(&jac_cam, &q, &(twist * 200.0)).unwrap();
            let scale = fast.iter().zip(&arm.limits.velocity).map(|(v, m)| v.abs() / m).fold(0.0, f64::max);
            assert!(limited && (scale - 1.0).abs() < 1e-12, "{name}: {scale}");
            assert!(arm.camera_joint_velocities(&jac_cam.columns(0, n - 1).into_owned(), &q, &twist).is_err());
        }
    }

    #[test]
    fn damped_least_squares_refuses_bad_inputs_by_name() {
        let v = Vector6::repeat(0.1);
        let name = |r: Result<DVector<f64>>| match r {
            Err(SimError::Core(Error::InvalidParameter { name, .. })) => name.to_string(),
            Err(SimError::Core(Error::Shape { what, .. })) | Err(SimError::Core(Error::NonFinite { what, .. })) => {
                what.to_string()
            }
            Err(SimError::Core(Error::NonFinitePoint { what, .. })) => what.to_string(),
            other => format!("{other:?}"),
        };
        let eye = DMatrix::<f64>::identity(6, 6);
        assert_eq!(name(damped_least_squares(&DMatrix::identity(5, 6), &v, 0.02, None)), "jacobian");
        assert_eq!(name(damped_least_squares(&eye, &v, 0.0, None)), "damping");
        assert_eq!(name(damped_least_squares(&eye, &Vector6::repeat(f64::NAN), 0.02, None)), "twist");
        let mut nan = eye.clone();
        nan[(2, 3)] = f64::NAN;
        assert_eq!(name(damped_least_squares(&nan, &v, 0.02, None)), "jacobian");
        let seven = DMatrix::<f64>::identity(6, 7);
        assert_eq!(name(damped_least_squares(&seven, &v, 0.02, Some(&DVector::zeros(6)))), "null_space");
    }
}
