//! The task on the rotation about the optical axis (sec. 4.2, eqs. 21-24), in the paper's
//! form and in the general case the paper leaves out.
//!
//! With `T = Q Q*^-1` (eq. 21), the paper drives `eps_z = det(Q*) tau_21` to zero with
//! `w_z = -(eta eps_z + c_hat^T mu) / a_hat` (eq. 24), which holds for `-pi/2 < rz < pi/2`
//! only: `tau_21` is proportional to `sin rz`, so it also vanishes at `rz = pi`, an attracting
//! equilibrium of the law, and `a` (proportional to `cos rz`) vanishes at `+-pi/2`
//! (correction 8).
//!
//! The general case ([`RzTask::Angle`], the default) drives the angle
//! `phi = atan2(tau_21, (tau_11 + tau_22) / 2)` to zero instead. The upper-left 2x2 block of
//! `T` is `A R(rz) B` for a rotation `rz` about the optical axis, `A` and `B` upper triangular
//! with positive diagonals (from `K` and `K*^-1`): `tau_21 = a22 b11 sin rz`, and
//! `(tau_11 + tau_22) / 2` is `cos rz` times a positive factor plus cross terms that vanish
//! with the skew and the principal-point offsets. So `phi` is zero only at `rz = 0`, is `+-pi`
//! at `rz = pi`, and follows `rz`'s sign on `(-pi, pi)`. With `S = tau_21` and
//! `C = (tau_11 + tau_22) / 2`, both linear in the basis pixels,
//! `dphi/dt = (C dS/dt - S dC/dt) / (S^2 + C^2) = a w_z + c^T mu`; for `K = K*` and a pure
//! rotation, `|a| = a22 b11 / (S^2 + C^2) > 0` for every `rz` (its sign is fixed: rolling the
//! camera rolls the image the other way): the law
//! `w_z = -(eta phi + c^T mu) / a` has no singularity at `+-pi/2` and no equilibrium at `pi`.

use nalgebra::{Matrix2x6, Matrix3, Vector5, Vector6};

use crate::error::{Error, Result};

/// Which scalar task controls the rotation about the optical axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize), serde(rename_all = "lowercase"))]
pub enum RzTask {
    /// `phi = atan2(tau_21, (tau_11 + tau_22) / 2)`: any start in `(-pi, pi)`.
    #[default]
    Angle,
    /// The paper's `eps_z = det(Q*) tau_21` (eq. 24): starts in `(-pi/2, pi/2)` only.
    Tau21,
}

impl std::str::FromStr for RzTask {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "angle" => Ok(Self::Angle),
            "tau21" => Ok(Self::Tau21),
            _ => Err(Error::InvalidParameter {
                name: "rz_task",
                reason: format!("expected \"angle\" or \"tau21\", got {s:?}"),
            }),
        }
    }
}

/// The rz task's value and its derivative `a w_z + c^T mu` for the current image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RzLinearised {
    /// The task's value (`phi` or `eps_z`).
    pub value: f64,
    /// The coefficient of `w_z` (`a_hat` of eq. 24).
    pub a: f64,
    /// The coefficients of `mu` (`c_hat` of eq. 24).
    pub c: Vector5<f64>,
}

/// Pixel-velocity rows of the three basis points from their normalised interaction matrices
/// and `K_hat`: `du = K00 Lx + K01 Ly`, `dv = K11 Ly`.
fn pixel_rows(k: &Matrix3<f64>, lx_basis: &[Matrix2x6<f64>; 3]) -> ([Vector6<f64>; 3], [Vector6<f64>; 3]) {
    let du = lx_basis.map(|l| (l.row(0) * k[(0, 0)] + l.row(1) * k[(0, 1)]).transpose());
    let dv = lx_basis.map(|l| (l.row(1) * k[(1, 1)]).transpose());
    (du, dv)
}

fn combine(weights: [f64; 3], rows: &[Vector6<f64>; 3]) -> Vector6<f64> {
    rows[0] * weights[0] + rows[1] * weights[1] + rows[2] * weights[2]
}

/// Linearises `task` at the current image: `t` is `T = Q Q*^-1`, `q_star_inv` is `Q*^-1`,
/// `k` is `K_hat`, `lx_basis` the basis points' normalised interaction matrices.
pub fn linearise(
    task: RzTask,
    t: &Matrix3<f64>,
    q_star_inv: &Matrix3<f64>,
    det_q_star: f64,
    k: &Matrix3<f64>,
    lx_basis: &[Matrix2x6<f64>; 3],
) -> Result<RzLinearised> {
    let (du, dv) = pixel_rows(k, lx_basis);
    let w0 = [q_star_inv[(0, 0)], q_star_inv[(1, 0)], q_star_inv[(2, 0)]];
    let w1 = [q_star_inv[(0, 1)], q_star_inv[(1, 1)], q_star_inv[(2, 1)]];
    // S = tau_21 = sum_j v_j Q*^-1[j, 0];  C = (tau_11 + tau_22)/2.
    let d_s = combine(w0, &dv);
    let (row, value, scale) = match task {
        RzTask::Tau21 => {
            let scale: f64 = (0..3).map(|j| (w0[j] * dv[j][5]).abs()).sum::<f64>() * det_q_star.abs();
            (d_s * det_q_star, det_q_star * t[(1, 0)], scale)
        }
        RzTask::Angle => {
            let (s, c) = (t[(1, 0)], 0.5 * (t[(0, 0)] + t[(1, 1)]));
            let r2 = s * s + c * c;
            if !(r2 > 0.0) {
                return Err(Error::RzSingular { a_hat: f64::NAN });
            }
            let d_c = (combine(w0, &du) + combine(w1, &dv)) * 0.5;
            let scale = (c.abs() * d_s[5].abs() + s.abs() * d_c[5].abs()) / r2;
            ((d_s * c - d_c * s) / r2, s.atan2(c), scale)
        }
    };
    let a = row[5];
    if !(value.is_finite() && row.iter().all(|v| v.is_finite())) || a.abs() <= 1e-9 * scale {
        return Err(Error::RzSingular { a_hat: a });
    }
    Ok(RzLinearised { value, a, c: Vector5::new(row[0], row[1], row[2], row[3], row[4]) })
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::core::camera::{Intrinsics, normalised_interaction};
    use crate::core::invariant::{BasisFrame, RzReference};
    use crate::core::jacobian::rz_from_interactions;
    use crate::core::se3::{exp_twist, pose_from_position_thetau};
    use nalgebra::{Isometry3, Point3};

    const POINTS: [[f64; 3]; 3] = [[-0.15, -0.12, 0.6], [0.15, -0.1, 0.66], [0.02, 0.14, 0.56]];

    /// Pixels and depths of the basis points seen from `pose` (camera frame in F*).
    fn view(pose: &Isometry3<f64>, k: &Intrinsics) -> ([[f64; 2]; 3], [f64; 3]) {
        let mut px = [[0.0; 2]; 3];
        let mut z = [0.0; 3];
        for (i, p) in POINTS.iter().enumerate() {
            let (pix, depth) = k.project(&pose.inverse_transform_point(&Point3::from(*p))).unwrap();
            px[i] = pix;
            z[i] = depth;
        }
        (px, z)
    }

    fn task_at(task: RzTask, pose: &Isometry3<f64>, k: &Intrinsics, k_star: &Intrinsics) -> RzLinearised {
        let (star, _) = view(&Isometry3::identity(), k_star);
        let reference = RzReference::new(&BasisFrame::new(&star, [0, 1, 2], "reference").unwrap());
        let (px, z) = view(pose, k);
        let t = reference.t_matrix(&BasisFrame::new(&px, [0, 1, 2], "current").unwrap());
        let k_inv = k.matrix().try_inverse().unwrap();
        let lx = [0, 1, 2].map(|i| {
            let m = k_inv * nalgebra::Vector3::new(px[i][0], px[i][1], 1.0);
            normalised_interaction(m.x, m.y, z[i]).unwrap()
        });
        linearise(task, &t, &reference.q_star_inv, reference.det_q_star, &k.matrix(), &lx).unwrap()
    }

    fn cameras() -> (Intrinsics, Intrinsics) {
        (
            Intrinsics::new(640.0, 600.0, 400.0, 300.0, 1.5).unwrap(),
            Intrinsics::pinhole(1200.0, 1200.0, 416.0, 312.0).unwrap(),
        )
    }

    #[test]
    fn tau21_task_is_the_papers_eq_24() {
        let (k, k_star) = cameras();
        let pose = pose_from_position_thetau([0.02, -0.01, -0.05], [0.1, -0.05, 0.4]).unwrap();
        let lin = task_at(RzTask::Tau21, &pose, &k, &k_star);
        let (star, _) = view(&Isometry3::identity(), &k_star);
        let reference = RzReference::new(&BasisFrame::new(&star, [0, 1, 2], "reference").unwrap());
        let (px, z) = view(&pose, &k);
        let k_inv = k.matrix().try_inverse().unwrap();
        let lx = [0, 1, 2].map(|i| {
            let m = k_inv * nalgebra::Vector3::new(px[i][0], px[i][1], 1.0);
            normalised_interaction(m.x, m.y, z[i]).unwrap()
        });
        let (a, c) = rz_from_interactions(&reference, &lx);
        let k11 = k.matrix()[(1, 1)];
        assert!((lin.a - a * k11).abs() < 1e-9 * a.abs() * k11);
        assert!((lin.c - c * k11).norm() < 1e-9 * c.norm() * k11);
        let v = nalgebra::Vector3::new(px[0][1], px[1][1], px[2][1]);
        assert!((lin.value - reference.eps_z(&v)).abs() < 1e-9 * lin.value.abs().max(1.0));
    }

    #[test]
    fn angle_task_derivative_matches_finite_differences() {
        let (k, k_star) = cameras();
        let pose = pose_from_position_thetau([0.03, -0.02, -0.08], [0.15, -0.1, 2.5]).unwrap();
        let lin = task_at(RzTask::Angle, &pose, &k, &k_star);
        let h = 1e-6;
        for axis in 0..6 {
            let mut twist = [0.0; 6];
            twist[axis] = h;
            let plus = task_at(RzTask::Angle, &(pose * exp_twist(&twist).unwrap()), &k, &k_star).value;
            twist[axis] = -h;
            let minus = task_at(RzTask::Angle, &(pose * exp_twist(&twist).unwrap()), &k, &k_star).value;
            let numeric = (plus - minus) / (2.0 * h);
            let analytic = if axis == 5 { lin.a } else { lin.c[axis] };
            assert!((numeric - analytic).abs() < 1e-6 * (1.0 + analytic.abs()), "axis {axis}: {numeric} vs {analytic}");
        }
    }

    #[test]
    fn angle_is_the_roll_for_a_square_camera_and_never_singular() {
        let k = Intrinsics::pinhole(800.0, 800.0, 400.0, 300.0).unwrap();
        for deg in (-179..=179).step_by(7) {
            let rz = f64::from(deg).to_radians();
            let lin = task_at(RzTask::Angle, &pose_from_position_thetau([0.0; 3], [0.0, 0.0, rz]).unwrap(), &k, &k);
            // The camera rolled by rz sees the image rolled by -rz.
            assert!((lin.value + rz).abs() < 1e-9, "{deg}: {}", lin.value);
            assert!((lin.a + 1.0).abs() < 1e-9, "{deg}: a = {}", lin.a);
        }
    }
}
