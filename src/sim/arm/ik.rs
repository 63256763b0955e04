//! Inverse kinematics of an [`ArmModel`]: joint positions that put the end-effector at a
//! pose of the base frame, within the joint limits.
//!
//! [`DampedLeastSquaresIk`] is the Levenberg-Marquardt iteration of Sugihara (2011,
//! "Solvability-unconcerned inverse kinematics by the Levenberg-Marquardt method", IEEE T-RO
//! 27(5)): with the 6-D pose error `e = (p* - p, theta-u of R* R^T)` (base frame) and the
//! base-frame Jacobian `J`, the step is `dq = (J^T J + lambda I)^-1 J^T e` with the damping
//! `lambda = E + w`, `E = e^T e / 2` (large far from the goal, vanishing near it, so the
//! iteration ends with Newton's quadratic convergence) and a bias `w` that grows when a step
//! fails to lower `E` and shrinks when it succeeds. Each step is projected onto the joint
//! limits by an active set (joints driven past a limit are held at it, the others solved
//! again). Seeds: the given one (default: the middle of the limits), then the
//! Halton points of the limits' box (deterministic, well spread), until one converges.

use nalgebra::{DMatrix, DVector, Isometry3, Vector3};

use super::{ArmLimits, ArmModel, ArmRobot};
use crate::sim::error::{Result, SimError};

/// A solution: joints and how far their pose is from the target.
#[derive(Debug, Clone, PartialEq)]
pub struct IkSolution {
    /// Joint positions (rad, m), within the limits.
    pub joints: Vec<f64>,
    /// Distance between the reached and the target positions, metres.
    pub position_residual: f64,
    /// Angle of the rotation between the reached and the target orientations, radians.
    pub rotation_residual: f64,
    /// Iterations of the seed that converged.
    pub iterations: usize,
    /// Which seed converged: 0 for the given one (or the middle of the limits), then the
    /// spread seeds in order.
    pub seed: usize,
}

/// An inverse kinematics solver.
pub trait InverseKinematics {
    /// Joints within `limits` putting the end-effector of `model` at `target` (base frame),
    /// starting from `seed` (one value per joint) when given; [`SimError::Unreachable`] when no
    /// seed converges.
    fn solve(
        &self,
        model: &ArmModel,
        limits: &ArmLimits,
        target: &Isometry3<f64>,
        seed: Option<&[f64]>,
    ) -> Result<IkSolution>;
}

/// Damped least squares (Levenberg-Marquardt) with joint limits and several seeds (module
/// documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct DampedLeastSquaresIk {
    /// Iterations per seed.
    pub max_iterations: usize,
    /// Seeds tried at most, the given one included.
    pub seeds: usize,
    /// Converged when the position residual is below this (metres) ...
    pub position_tolerance: f64,
    /// ... and the rotation residual below this (radians).
    pub rotation_tolerance: f64,
    /// Converged solutions with a lower manipulability are passed over (the next seed is tried).
    pub min_manipulability: f64,
}

impl Default for DampedLeastSquaresIk {
    fn default() -> Self {
        Self {
            max_iterations: 200,
            seeds: 64,
            position_tolerance: 1e-10,
            rotation_tolerance: 1e-10,
            min_manipulability: 0.0,
        }
    }
}

/// Sugihara's bias `w` at the start of each seed; its bounds.
const BIAS_START: f64 = 1e-3;
const BIAS_MIN: f64 = 1e-9;
const BIAS_MAX: f64 = 1e6;
/// Width of the seeds' box for joints without position limits (radians, about 0).
const UNLIMITED_HALF_WIDTH: f64 = std::f64::consts::PI;
/// The first primes: one Halton base per joint (arms with more joints reuse them shifted).
const PRIMES: [u32; 10] = [2, 3, 5, 7, 11, 13, 17, 19, 23, 29];

/// The pose error `(p* - p, theta-u of R* R^T)` in the base frame.
fn pose_error(reached: &Isometry3<f64>, target: &Isometry3<f64>) -> DVector<f64> {
    let dp = target.translation.vector - reached.translation.vector;
    let dr = (target.rotation * reached.rotation.inverse()).scaled_axis();
    DVector::from_column_slice(&[dp.x, dp.y, dp.z, dr.x, dr.y, dr.z])
}

/// The position and rotation residuals of an error vector.
fn residuals(e: &DVector<f64>) -> (f64, f64) {
    (Vector3::new(e[0], e[1], e[2]).norm(), Vector3::new(e[3], e[4], e[5]).norm())
}

/// The `k`-th term (k >= 1) of the van der Corput sequence in base `b`, in (0, 1).
fn van_der_corput(mut k: u64, b: u32) -> f64 {
    let (mut value, mut scale) = (0.0, 1.0 / f64::from(b));
    while k > 0 {
        value += (k % u64::from(b)) as f64 * scale;
        k /= u64::from(b);
        scale /= f64::from(b);
    }
    value
}

/// The box of the seeds: the limits, or `[-pi, pi]` for a joint without them.
fn seed_box(limits: &ArmLimits, i: usize) -> (f64, f64) {
    let (lo, hi) = (limits.lower[i], limits.upper[i]);
    if lo.is_finite() && hi.is_finite() { (lo, hi) } else { (-UNLIMITED_HALF_WIDTH, UNLIMITED_HALF_WIDTH) }
}

/// Seed `k`: the given seed (or the middle of the box) for 0, the `k`-th Halton point of the
/// box after it.
fn seed_joints(limits: &ArmLimits, given: Option<&[f64]>, k: usize) -> Vec<f64> {
    let n = limits.lower.len();
    (0..n)
        .map(|i| {
            let (lo, hi) = seed_box(limits, i);
            match (k, given) {
                (0, Some(q)) => q[i].clamp(limits.lower[i], limits.upper[i]),
                (0, None) => (lo + hi) / 2.0,
                _ => lo + (hi - lo) * van_der_corput(k as u64 + (i / PRIMES.len()) as u64, PRIMES[i % PRIMES.len()]),
            }
        })
        .collect()
}

/// The damped step `dq = (J^T J + lambda I)^-1 J^T e` from `q`, projected on the limits by
/// an active set: a joint the step would carry past a limit is set at it, and the step is
/// solved again for the free joints against the error the clamped motion leaves (so that
/// they make up for it rather than the whole step being cut); at most one pass per joint.
/// `None` when the damped matrix cannot be factorised.
fn projected_step(j: &DMatrix<f64>, e: &DVector<f64>, q: &[f64], limits: &ArmLimits, lambda: f64) -> Option<Vec<f64>> {
    let n = q.len();
    let mut next = q.to_vec();
    let mut free: Vec<usize> = (0..n).collect();
    for _ in 0..n {
        let clamped_motion = DVector::from_fn(n, |i, _| next[i] - q[i]);
        let rest = e - j * clamped_motion;
        let jf = j.select_columns(&free);
        let mut h = jf.transpose() * &jf;
        for k in 0..free.len() {
            h[(k, k)] += lambda;
        }
        let dq = h.cholesky()?.solve(&(jf.transpose() * rest));
        let mut still_free = Vec::with_capacity(free.len());
        for (k, &i) in free.iter().enumerate() {
            next[i] = (q[i] + dq[k]).clamp(limits.lower[i], limits.upper[i]);
            if next[i] == q[i] + dq[k] {
                still_free.push(i);
            }
        }
        if still_free.len() == free.len() || still_free.is_empty() {
            break;
        }
        free = still_free;
    }
    Some(next)
}

/// One seed's run: the joints, the error and the iterations when it stopped.
struct Descent {
    joints: Vec<f64>,
    error: DVector<f64>,
    iterations: usize,
}

impl DampedLeastSquaresIk {
    fn converged(&self, e: &DVector<f64>) -> bool {
        let (dp, dr) = residuals(e);
        dp <= self.position_tolerance && dr <= self.rotation_tolerance
    }

    /// Sugihara's iteration from `q`, projected onto the limits.
    fn descend(
        &self,
        model: &ArmModel,
        limits: &ArmLimits,
        target: &Isometry3<f64>,
        mut q: Vec<f64>,
    ) -> Result<Descent> {
        let n = q.len();
        let mut e = pose_error(&model.fk(&q)?, target);
        let mut bias = BIAS_START;
        for iteration in 0..self.max_iterations {
            if self.converged(&e) {
                return Ok(Descent { joints: q, error: e, iterations: iteration });
            }
            let cost = e.norm_squared() / 2.0;
            let jac = model.jacobian_base(&q)?;
            let j = DMatrix::from_column_slice(6, n, jac.as_slice());
            let Some(next) = projected_step(&j, &e, &q, limits, cost + bias) else { break };
            let next_error = pose_error(&model.fk(&next)?, target);
            if next_error.norm_squared() / 2.0 < cost {
                (q, e, bias) = (next, next_error, (bias / 2.0).max(BIAS_MIN));
            } else {
                bias *= 10.0;
                if bias > BIAS_MAX {
                    break; // stuck against the limits or in a local minimum: next seed
                }
            }
        }
        Ok(Descent { joints: q, error: e, iterations: self.max_iterations })
    }
}

impl InverseKinematics for DampedLeastSquaresIk {
    fn solve(
        &self,
        model: &ArmModel,
        limits: &ArmLimits,
        target: &Isometry3<f64>,
        seed: Option<&[f64]>,
    ) -> Result<IkSolution> {
        crate::error::check_finite("pose", target.to_homogeneous().as_slice())?;
        if let Some(q) = seed {
            model.check_joints(q)?;
        }
        let mut best: Option<(f64, DVector<f64>)> = None;
        for k in 0..self.seeds.max(1) {
            let run = self.descend(model, limits, target, seed_joints(limits, seed, k))?;
            if self.converged(&run.error) && model.manipulability(&run.joints)? >= self.min_manipulability {
                let (position_residual, rotation_residual) = residuals(&run.error);
                return Ok(IkSolution {
                    joints: run.joints,
                    position_residual,
                    rotation_residual,
                    iterations: run.iterations,
                    seed: k,
                });
            }
            let cost = run.error.norm_squared();
            if best.as_ref().is_none_or(|(c, _)| cost < *c) {
                best = Some((cost, run.error));
            }
        }
        let (position_residual, rotation_residual) = best.map_or((f64::NAN, f64::NAN), |(_, e)| residuals(&e));
        Err(SimError::Unreachable {
            arm: model.name().to_string(),
            position: target.translation.vector.into(),
            thetau_deg: crate::core::se3::thetau_from_pose(target).map(f64::to_degrees),
            position_residual,
            rotation_residual,
            seeds: self.seeds.max(1),
        })
    }
}

impl ArmModel {
    /// Joints within the model's limits that put the end-effector at `target` (base frame),
    /// by [`DampedLeastSquaresIk`] with its defaults, from `seed` when given.
    pub fn ik(&self, target: &Isometry3<f64>, seed: Option<&[f64]>) -> Result<IkSolution> {
        DampedLeastSquaresIk::default().solve(self, &self.limits(), target, seed)
    }
}

impl ArmRobot {
    /// Joints within the arm's limits, not below its `min_manipulability`, that put the
    /// camera at `camera` (F*): the end-effector at `base^-1 camera mount^-1`.
    pub fn ik_camera(&self, camera: &Isometry3<f64>, seed: Option<&[f64]>) -> Result<IkSolution> {
        let target = self.base.inverse() * camera * self.mount.inverse();
        let solver = DampedLeastSquaresIk { min_manipulability: self.min_manipulability, ..Default::default() };
        solver.solve(&self.model, &self.limits, &target, seed)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    #[test]
    fn halton_seeds_stay_inside_the_limits_and_differ() {
        let arm = ArmModel::builtin("panda").unwrap();
        let limits = arm.limits();
        let seeds: Vec<Vec<f64>> = (0..20).map(|k| seed_joints(&limits, None, k)).collect();
        for q in &seeds {
            arm.check_limits(q).unwrap();
        }
        assert!(seeds.windows(2).all(|w| w[0] != w[1]));
        assert_eq!(van_der_corput(1, 2), 0.5);
        assert!((van_der_corput(5, 3) - 7.0 / 9.0).abs() < 1e-15);
    }

    #[test]
    fn a_pose_out_of_reach_is_refused_with_its_residual() {
        let arm = ArmModel::builtin("ur5").unwrap();
        let far = Isometry3::translation(3.0, 0.0, 0.5);
        let solver = DampedLeastSquaresIk { seeds: 4, ..Default::default() };
        let err = solver.solve(&arm, &arm.limits(), &far, None).unwrap_err();
        let SimError::Unreachable { position_residual, .. } = err.clone() else { panic!("{err}") };
        // The UR5 reaches about 0.95 m from the shoulder: at least 2 m short.
        assert!(position_residual > 1.9, "{err}");
        assert!(err.to_string().starts_with("pose: unreachable by ur5"), "{err}");
    }
}
