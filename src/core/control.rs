//! The invariant control laws of sec. 4: the five-dof task-function law (eqs. 14, 17) and
//! the law for the rotation about the optical axis (eq. 24).

use nalgebra::{Matrix2x6, Matrix3, Matrix5, Vector2, Vector3, Vector5, Vector6};

use crate::core::adaptive_gain::AdaptiveGain;
use crate::core::camera::{Intrinsics, normalised_interaction_unchecked};
use crate::core::invariant::{BasisFrame, RzReference, non_basis_indices, validate_basis};
use crate::core::jacobian::{
    DEFAULT_MIN_STRUCTURE_RATIO, MIN_POINTS, balanced_ratio, check_point_count, combined_interaction,
};
use crate::core::rz_task::{RzTask, linearise};
use crate::core::saturation::TwistLimits;
use crate::core::uncertainty::{ImageNoise, Measurement, PoseUncertainty, invariant_pose_uncertainty};
use crate::error::{
    Error, Result, check_finite_points, check_finite_rows, check_overflow, check_positive, check_step_inputs,
};

/// A visual-servoing control law: current pixels and depth estimates in, camera twist
/// `(vx, vy, vz, wx, wy, wz)` (camera frame) out. Implemented by [`InvariantController`] and
/// [`crate::IbvsController`], so a simulator or a robot loop can run either.
pub trait Controller {
    /// One control step with every point in view.
    fn step(&mut self, pixels: &[[f64; 2]], depths: &[f64]) -> Result<Vector6<f64>>;
    /// One control step using only the points flagged visible (the others' pixels and
    /// depths are ignored). Fails with `TooFewPoints` when too few remain.
    fn step_visible(&mut self, pixels: &[[f64; 2]], depths: &[f64], visible: &[bool]) -> Result<Vector6<f64>>;
}

impl Controller for InvariantController {
    fn step(&mut self, pixels: &[[f64; 2]], depths: &[f64]) -> Result<Vector6<f64>> {
        self.step_masked(pixels, depths, None)
    }
    fn step_visible(&mut self, pixels: &[[f64; 2]], depths: &[f64], visible: &[bool]) -> Result<Vector6<f64>> {
        self.step_masked(pixels, depths, Some(visible))
    }
}

/// Tuning of an [`InvariantController`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InvariantControllerConfig {
    /// lambda of eq. (17), 1/s.
    pub gain: f64,
    /// eta of eq. (24), 1/s.
    pub gain_rz: f64,
    /// Whether to add the feed-forward term `J_hat^+ ds*/dt` of eq. (17) when the reference
    /// moves (sec. 5.3 drops it to show it is not needed for stability).
    pub feedforward: bool,
    /// Threshold on `sigma_5/sigma_1` of the depth-balanced `J_hat` (degenerate structure).
    pub min_structure_ratio: f64,
    /// The task on the rotation about the optical axis (default: the general case, any start
    /// angle; [`RzTask::Tau21`] is the paper's eq. 24).
    pub rz_task: RzTask,
    /// A gain that depends on the invariant error `x = ||s - s*||`: when set, lambda is
    /// `lambda(x)` instead of `gain`, and eta is `gain_rz lambda(x) / lambda(0)`.
    pub adaptive_gain: Option<AdaptiveGain>,
    /// Largest linear and angular speeds: the twist is scaled as a whole to meet them.
    pub twist_limits: Option<TwistLimits>,
}

impl InvariantControllerConfig {
    /// Checks the gains, the adaptive gain, the speed limits and the structure threshold
    /// (what [`InvariantController::new`] checks besides the pixels and the basis).
    pub fn validate(&self) -> Result<()> {
        check_positive("gain", self.gain)?;
        check_positive("gain_rz", self.gain_rz)?;
        if let Some(g) = &self.adaptive_gain {
            g.validate()?;
        }
        if let Some(l) = &self.twist_limits {
            l.validate()?;
        }
        if !(self.min_structure_ratio.is_finite() && self.min_structure_ratio >= 0.0) {
            return Err(Error::InvalidParameter {
                name: "min_structure_ratio",
                reason: "must be finite and >= 0".into(),
            });
        }
        Ok(())
    }
}

impl Default for InvariantControllerConfig {
    fn default() -> Self {
        Self {
            gain: 1.0,
            gain_rz: 1.0,
            feedforward: true,
            min_structure_ratio: DEFAULT_MIN_STRUCTURE_RATIO,
            rz_task: RzTask::Angle,
            adaptive_gain: None,
            twist_limits: None,
        }
    }
}

/// What the last successful control step measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlState {
    /// The twist sent to the camera (vx, vy, vz, wx, wy, wz), camera frame.
    pub twist: Vector6<f64>,
    /// Task function eps of eq. (14).
    pub eps: Vector5<f64>,
    /// Task function eps_z = det(Q*) tau_21 (sec. 4.2), pixels^2 units.
    pub eps_z: f64,
    /// `||s - s*(t)||` in the invariant space.
    pub invariant_error: f64,
    /// `T = Q Q*^-1` (eq. 21).
    pub t: Matrix3<f64>,
    /// The coefficient `a_hat` of `w_z` in the rz task's derivative (eq. 24).
    pub a_hat: f64,
    /// `J_hat^+ ds*/dt` (zero for a still reference), whether or not the law adds it: the
    /// disturbance `b(t)` of eq. (19) is `(A - I)` times it with feed-forward, minus it without.
    pub reference_rate_term: Vector5<f64>,
    /// The lambda used (`gain`, or the adaptive gain at the invariant error).
    pub gain: f64,
    /// The factor the twist limits scaled the law's twist by (1: within the limits).
    pub saturation: f64,
}

impl ControlState {
    /// tau_11 of eq. (21).
    pub fn tau11(&self) -> f64 {
        self.t[(0, 0)]
    }
    /// tau_21 of eq. (21).
    pub fn tau21(&self) -> f64 {
        self.t[(1, 0)]
    }
    /// tau_22 of eq. (21).
    pub fn tau22(&self) -> f64 {
        self.t[(1, 1)]
    }
}

/// Visual servoing in the invariant space (sec. 4): from the current pixels and per-point
/// depth estimates (any common positive scale), the camera twist that drives the invariant
/// points `s` to `s*(t)` (eq. 17) and `tau_21` to zero (eq. 24).
///
/// The reference image may come from another camera: only the estimated intrinsics of the
/// *current* camera, `K_hat`, enter the Jacobian, and any `K_hat` with positive focal terms
/// stabilises the law locally (Prop. 1).
#[derive(Debug, Clone)]
pub struct InvariantController {
    reference_pixels: Vec<[f64; 2]>,
    k_hat: Intrinsics,
    k: Matrix3<f64>,
    k_inv: Matrix3<f64>,
    basis: [usize; 3],
    others: Vec<usize>,
    n: usize,
    reference: RzReference,
    s_star: Vec<Vector3<f64>>,
    s_star_rate: Vec<Vector3<f64>>,
    reference_moves: bool,
    config: InvariantControllerConfig,
    structure_checked: bool,
    state: Option<ControlState>,
}

impl InvariantController {
    /// A controller for the reference image `reference_pixels` (n >= 6 points), estimated
    /// current intrinsics `k_hat` and the basis points (see [`crate::choose_basis`]).
    pub fn new(
        reference_pixels: &[[f64; 2]],
        k_hat: Intrinsics,
        basis: [usize; 3],
        config: InvariantControllerConfig,
    ) -> Result<Self> {
        check_finite_points("reference_pixels", reference_pixels)?;
        let n = reference_pixels.len();
        check_point_count(n, MIN_POINTS)?;
        config.validate()?;
        let basis = validate_basis(basis, n)?;
        let frame = BasisFrame::new(reference_pixels, basis, "reference")?;
        let others = non_basis_indices(n, basis);
        let s_star: Vec<_> = others.iter().map(|&i| frame.transform(reference_pixels[i])).collect();
        let k = k_hat.matrix();
        let k_inv = k.try_inverse().ok_or_else(|| Error::InvalidIntrinsics { reason: "K_hat is singular".into() })?;
        Ok(Self {
            reference_pixels: reference_pixels.to_vec(),
            k_hat,
            k,
            k_inv,
            basis,
            s_star_rate: vec![Vector3::zeros(); others.len()],
            others,
            n,
            reference: RzReference::new(&frame),
            s_star,
            reference_moves: false,
            config,
            structure_checked: false,
            state: None,
        })
    }

    /// Number of points.
    pub fn num_points(&self) -> usize {
        self.n
    }
    /// The basis indices.
    pub fn basis(&self) -> [usize; 3] {
        self.basis
    }
    /// Indices of the non-basis points, in the order of `s`.
    pub fn non_basis(&self) -> &[usize] {
        &self.others
    }
    /// The reference image the controller was built from (`s*` of a still reference).
    pub fn reference_pixels(&self) -> &[[f64; 2]] {
        &self.reference_pixels
    }
    /// The estimated intrinsics used in the Jacobian.
    pub fn k_hat(&self) -> &Intrinsics {
        &self.k_hat
    }
    /// The tuning.
    pub fn config(&self) -> &InvariantControllerConfig {
        &self.config
    }
    /// The current reference `s*(t)`, one invariant point per non-basis point.
    pub fn reference_invariants(&self) -> &[Vector3<f64>] {
        &self.s_star
    }
    /// The derivative `ds*/dt` given to [`set_reference`](Self::set_reference), `None` for a
    /// still reference.
    pub fn reference_rate(&self) -> Option<&[Vector3<f64>]> {
        self.reference_moves.then_some(self.s_star_rate.as_slice())
    }
    /// The state measured by the last successful step.
    pub fn state(&self) -> Option<&ControlState> {
        self.state.as_ref()
    }

    /// Replaces the estimated intrinsics (e.g. a zoom read-out).
    pub fn set_k_hat(&mut self, k_hat: Intrinsics) -> Result<()> {
        let k = k_hat.matrix();
        self.k_inv = k.try_inverse().ok_or_else(|| Error::InvalidIntrinsics { reason: "K_hat is singular".into() })?;
        self.k = k;
        self.k_hat = k_hat;
        Ok(())
    }

    /// Sets a time-varying reference `s*(t)` and its derivative `ds*/dt` (sec. 3, eq. 17),
    /// each one invariant point (3 values summing to 1, resp. 0) per non-basis point.
    /// `rate = None` means a still reference.
    pub fn set_reference(&mut self, s_star: &[[f64; 3]], rate: Option<&[[f64; 3]]>) -> Result<()> {
        let m = self.others.len();
        let shape = |what: &'static str, got: usize| Error::Shape {
            what,
            expected: format!("{m} invariant points (one per non-basis point)"),
            got: format!("{got}"),
        };
        if s_star.len() != m {
            return Err(shape("s_star", s_star.len()));
        }
        check_finite_rows("s_star", s_star)?;
        if let Some(bad) = s_star.iter().position(|q| (q[0] + q[1] + q[2] - 1.0).abs() > 1e-6) {
            return Err(Error::InvalidParameter {
                name: "s_star",
                reason: format!("invariant point {bad} does not sum to 1 (q1 + q2 + q3 = 1 in the invariant space)"),
            });
        }
        if let Some(r) = rate {
            if r.len() != m {
                return Err(shape("rate", r.len()));
            }
            check_finite_rows("rate", r)?;
        }
        for (j, q) in s_star.iter().enumerate() {
            self.s_star[j] = Vector3::from(*q);
            self.s_star_rate[j] = rate.map_or_else(Vector3::zeros, |r| Vector3::from(r[j]));
        }
        self.reference_moves = rate.is_some();
        Ok(())
    }

    /// One control step: the twist `(mu, w_z)` of eqs. (17) and (24) for the current pixels
    /// and depth estimates `zeta_hat = kappa zeta` (any common kappa > 0).
    pub fn step(&mut self, pixels: &[[f64; 2]], depths: &[f64]) -> Result<Vector6<f64>> {
        self.step_masked(pixels, depths, None)
    }

    /// A step with some points hidden: the three basis points and at least three others must
    /// be visible; hidden points drop out of `s` and `J_hat`.
    pub fn step_visible(&mut self, pixels: &[[f64; 2]], depths: &[f64], visible: &[bool]) -> Result<Vector6<f64>> {
        self.step_masked(pixels, depths, Some(visible))
    }

    fn step_masked(&mut self, pixels: &[[f64; 2]], depths: &[f64], visible: Option<&[bool]>) -> Result<Vector6<f64>> {
        self.check_step(pixels, depths, visible)?;
        let frame = BasisFrame::new(pixels, self.basis, "current")?;
        // Work in normalised coordinates: the pixel interaction matrices are K[0..2, 0..2]
        // times the normalised ones, so `J_k = Q^-1[:, 0..2] K[0..2, 0..2] M_k` with
        // `M_k = L_k - q_1k L_1 - q_2k L_2 - q_3k L_3` in normalised coordinates (sec. 4.1).
        let lx_basis = self.basis.map(|i| self.normalised_interaction(pixels, depths, i));
        let normal = self.normal_equations(pixels, depths, visible, &frame, &lx_basis);
        let (eps, rate_term) = self.solve_five_dof(&normal, mean_visible(depths, visible))?;
        let invariant_error = normal.err2.sqrt();
        let gain = self.config.adaptive_gain.map_or(self.config.gain, |g| g.value(invariant_error));
        // mu = -lambda eps + J_hat^+ ds*/dt  (eq. 17).
        let mut mu = -gain * eps;
        if self.config.feedforward && self.reference_moves {
            mu += rate_term;
        }
        let t = self.reference.t_matrix(&frame);
        let gain_rz = self.config.adaptive_gain.map_or(self.config.gain_rz, |g| self.config.gain_rz * gain / g.at_zero);
        let (wz, eps_z, a_hat) = self.rz_velocity(&t, &lx_basis, &mu, gain_rz)?;
        let mut twist = Vector6::new(mu[0], mu[1], mu[2], mu[3], mu[4], wz);
        let saturation = self.config.twist_limits.map_or(1.0, |l| l.apply(&mut twist));
        let values = [twist.as_slice(), eps.as_slice(), t.as_slice(), &[eps_z, invariant_error, a_hat, gain]];
        check_overflow("pixels, depths", "twist and task functions", &values)?;
        self.state = Some(ControlState {
            twist,
            eps,
            eps_z,
            invariant_error,
            t,
            a_hat,
            reference_rate_term: rate_term,
            gain,
            saturation,
        });
        Ok(twist)
    }

    /// Sizes, finiteness, depths, and that the basis and three more points are visible.
    fn check_step(&self, pixels: &[[f64; 2]], depths: &[f64], visible: Option<&[bool]>) -> Result<()> {
        check_point_total(pixels.len(), self.n)?;
        check_step_inputs(pixels, depths, visible)?;
        let Some(v) = visible else { return Ok(()) };
        let others_seen = self.others.iter().filter(|&&i| v[i]).count();
        let basis_seen = self.basis.iter().all(|&b| v[b]);
        if !basis_seen || others_seen < MIN_POINTS - 3 {
            return Err(Error::TooFewPoints {
                needed: MIN_POINTS,
                got: 3 * usize::from(basis_seen) + others_seen,
                why: "the three basis points and three more must be visible",
            });
        }
        Ok(())
    }

    /// The interaction matrix of point `i` in normalised coordinates.
    #[inline]
    fn normalised_interaction(&self, pixels: &[[f64; 2]], depths: &[f64], i: usize) -> Matrix2x6<f64> {
        let m = self.k_inv * Vector3::new(pixels[i][0], pixels[i][1], 1.0);
        normalised_interaction_unchecked(m.x, m.y, depths[i])
    }

    /// `J^T J`, `J^T (s - s*)` and `J^T ds*/dt` accumulated point by point (only the upper
    /// triangle of the symmetric `J^T J` is summed), with `||s - s*||^2`.
    #[inline]
    fn normal_equations(
        &self,
        pixels: &[[f64; 2]],
        depths: &[f64],
        visible: Option<&[bool]>,
        frame: &BasisFrame,
        lx_basis: &[Matrix2x6<f64>; 3],
    ) -> NormalEquations {
        let a = frame.q_inv.fixed_columns::<2>(0) * self.k.fixed_view::<2, 2>(0, 0);
        let gram = a.tr_mul(&a);
        let mut upper = [0.0; 15];
        let (mut jte, mut jtr, mut err2) = (Vector5::zeros(), Vector5::zeros(), 0.0);
        for (j, &idx) in self.others.iter().enumerate() {
            if !visible.is_none_or(|v| v[idx]) {
                continue;
            }
            let q = frame.transform(pixels[idx]);
            let e = q - self.s_star[j];
            err2 += e.norm_squared();
            let m_k = combined_interaction(&self.normalised_interaction(pixels, depths, idx), lx_basis, &q);
            add_gram_upper(&mut upper, &m_k, &(gram * m_k));
            add_projected(&mut jte, &m_k, &a.tr_mul(&e));
            if self.reference_moves {
                add_projected(&mut jtr, &m_k, &a.tr_mul(&self.s_star_rate[j]));
            }
        }
        NormalEquations { jtj: symmetric_from_upper(&upper), jte, jtr, err2 }
    }

    /// eps = J_hat^+ (s - s*) (eq. 14) and J_hat^+ ds*/dt, by Cholesky on `J^T J`; refuses a
    /// degenerate structure (planar object, equal depths) at the first step and on rank loss.
    #[inline]
    fn solve_five_dof(&mut self, normal: &NormalEquations, mean_depth: f64) -> Result<(Vector5<f64>, Vector5<f64>)> {
        let jtj = &normal.jtj;
        // Eigenvalues of a non-finite matrix may not terminate: refuse an overflow first.
        check_overflow("pixels, depths", "normal equations", &[jtj.as_slice(), normal.jte.as_slice()])?;
        let threshold = self.config.min_structure_ratio;
        let degenerate = |jtj: &Matrix5<f64>| {
            let ratio = balanced_ratio(jtj, mean_depth);
            (ratio < threshold.max(1e-7)).then_some(Error::DegenerateStructure { ratio, threshold })
        };
        if !self.structure_checked {
            if let Some(err) = degenerate(jtj) {
                return Err(err);
            }
            self.structure_checked = true;
        }
        let Some(chol) = jtj.cholesky() else {
            return Err(Error::DegenerateStructure { ratio: balanced_ratio(jtj, mean_depth), threshold });
        };
        // A pivot that lost almost all of its diagonal means rank loss since the first step.
        let l = chol.l_dirty();
        if (0..5).any(|i| l[(i, i)] * l[(i, i)] < 1e-14 * jtj[(i, i)])
            && let Some(err) = degenerate(jtj)
        {
            return Err(err);
        }
        let rate_term = if self.reference_moves { chol.solve(&normal.jtr) } else { Vector5::zeros() };
        Ok((chol.solve(&normal.jte), rate_term))
    }

    /// The rz law: `w_z = -(eta e + c_hat^T mu) / a_hat` (eq. 24) for the configured task `e`
    /// (see [`rz_task`](crate::core::rz_task)); returns `(w_z, eps_z, a_hat)`, with
    /// `eps_z = det(Q*) tau_21` whichever the task.
    #[inline]
    fn rz_velocity(
        &self,
        t: &Matrix3<f64>,
        lx_basis: &[Matrix2x6<f64>; 3],
        mu: &Vector5<f64>,
        gain_rz: f64,
    ) -> Result<(f64, f64, f64)> {
        let r = &self.reference;
        let task = linearise(self.config.rz_task, t, &r.q_star_inv, r.det_q_star, &self.k, lx_basis)?;
        let wz = -(gain_rz * task.value + task.c.dot(mu)) / task.a;
        Ok((wz, r.det_q_star * t[(1, 0)], task.a))
    }

    /// The pose uncertainty that pixel noise leaves at `pixels` (the current image, or the
    /// average of `noise.averaged_images` images) under the invariant stop rule, with this
    /// controller's reference image, basis and K_hat ([`crate::core::uncertainty`]).
    pub fn pose_uncertainty(
        &self,
        pixels: &[[f64; 2]],
        depths: &[f64],
        visible: Option<&[bool]>,
        noise: ImageNoise,
    ) -> Result<PoseUncertainty> {
        check_point_total(pixels.len(), self.n)?;
        let m = Measurement { pixels, depths, reference_pixels: &self.reference_pixels, visible, k_hat: &self.k_hat };
        invariant_pose_uncertainty(&m, self.basis, noise)
    }

    /// The stop rule for different cameras (sec. 5.2): `||s - s*|| < invariant_tol`,
    /// `|tau_21| < tau21_tol`, and `tau_11 > 0`, `tau_22 > 0`, which rule out the attracting
    /// equilibrium at rz = pi (correction 8). False before the first step.
    pub fn converged(&self, invariant_tol: f64, tau21_tol: f64) -> bool {
        self.state.as_ref().is_some_and(|s| {
            s.invariant_error < invariant_tol && s.tau21().abs() < tau21_tol && s.tau11() > 0.0 && s.tau22() > 0.0
        })
    }
}

/// Fails unless an image has the reference image's `n` points.
pub(crate) fn check_point_total(got: usize, n: usize) -> Result<()> {
    if got == n {
        return Ok(());
    }
    Err(Error::Shape {
        what: "pixels",
        expected: format!("{n} points (as in the reference image)"),
        got: format!("{got} points"),
    })
}

/// The normal equations of the five-dof task for one image.
struct NormalEquations {
    jtj: Matrix5<f64>,
    jte: Vector5<f64>,
    jtr: Vector5<f64>,
    err2: f64,
}

/// Adds the upper triangle of `M^T W` (row-major, 15 entries) for a 2x6 `M` and `W = G M`.
#[inline]
fn add_gram_upper(upper: &mut [f64; 15], m: &Matrix2x6<f64>, w: &Matrix2x6<f64>) {
    let mut t = 0;
    for r in 0..5 {
        let (m0, m1) = (m[(0, r)], m[(1, r)]);
        for c in r..5 {
            upper[t] += m0 * w[(0, c)] + m1 * w[(1, c)];
            t += 1;
        }
    }
}

/// The symmetric 5x5 matrix whose upper triangle is `upper` (row-major).
#[inline]
fn symmetric_from_upper(upper: &[f64; 15]) -> Matrix5<f64> {
    let mut m = Matrix5::zeros();
    let mut t = 0;
    for r in 0..5 {
        for c in r..5 {
            m[(r, c)] = upper[t];
            m[(c, r)] = upper[t];
            t += 1;
        }
    }
    m
}

/// Adds `M[:, 0..5]^T h` for a 2x6 `M`.
#[inline]
fn add_projected(acc: &mut Vector5<f64>, m: &Matrix2x6<f64>, h: &Vector2<f64>) {
    for r in 0..5 {
        acc[r] += m[(0, r)] * h.x + m[(1, r)] * h.y;
    }
}

/// The mean depth of the points in use.
fn mean_visible(depths: &[f64], visible: Option<&[bool]>) -> f64 {
    let seen = |i: &usize| visible.is_none_or(|v| v[*i]);
    let (sum, count) = (0..depths.len()).filter(seen).fold((0.0, 0usize), |(s, c), i| (s + depths[i], c + 1));
    sum / count as f64
}
