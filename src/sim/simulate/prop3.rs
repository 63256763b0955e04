//! Prop. 3's figures observed along a planned path: the simulator knows K(t) and the true
//! depths, so it can evaluate A(t), b(t) and the bound `psi / phi` that a robot cannot.

use nalgebra::Matrix5;

use crate::core::camera::Intrinsics;
use crate::core::control::ControlState;
use crate::core::stability::a_matrix;
use crate::sim::outcome::Tracking;

/// The extremes of Prop. 3's quantities while the reference moves.
pub(super) struct Prop3Figures {
    sigma_min: f64,
    max_b: f64,
    max_eps: f64,
}

impl Prop3Figures {
    pub(super) fn new() -> Self {
        Self { sigma_min: f64::INFINITY, max_b: 0.0, max_eps: 0.0 }
    }

    /// A(t) from K(t), K_hat and kappa(t), b(t) and `||eps(t)||` after a step of the law.
    pub(super) fn observe(
        &mut self,
        state: &ControlState,
        k: &Intrinsics,
        estimate: &Intrinsics,
        kappa: f64,
        ff: bool,
    ) {
        if let Ok(a) = a_matrix(&k.matrix(), &estimate.matrix(), kappa) {
            self.sigma_min = self.sigma_min.min((a + a.transpose()).symmetric_eigenvalues().min());
            let r = state.reference_rate_term;
            let b = if ff { (a - Matrix5::identity()) * r } else { -r };
            self.max_b = self.max_b.max(b.norm());
        }
        self.max_eps = self.max_eps.max(state.eps.norm());
    }

    /// The figures, with the law's gain and the path's duration and plane + parallax residual.
    pub(super) fn summary(&self, gain: f64, (duration, residual): (f64, f64)) -> Tracking {
        let phi = gain * self.sigma_min;
        let psi = 2.0 * self.max_b;
        Tracking {
            sigma: self.sigma_min,
            psi,
            phi,
            bound: if phi > 0.0 { psi / phi } else { f64::INFINITY },
            max_eps: self.max_eps,
            duration,
            plane_parallax_residual: residual,
        }
    }
}
