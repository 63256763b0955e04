//! Twist saturation: separate maxima for the linear and the angular speed, met by scaling the
//! whole twist by one factor, so that its direction (and the path of the error it commands)
//! is kept and only the time along it changes.

use nalgebra::Vector6;

use crate::error::{Error, Result, Short};

/// The largest commanded speeds: `||v|| <= linear` (m/s) and `||w|| <= angular` (rad/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwistLimits {
    /// Largest linear speed, m/s.
    pub linear: f64,
    /// Largest angular speed, rad/s.
    pub angular: f64,
}

impl TwistLimits {
    /// Checked limits (> 0; `f64::INFINITY` leaves that part free).
    pub fn new(linear: f64, angular: f64) -> Result<Self> {
        let limits = Self { linear, angular };
        limits.validate()?;
        Ok(limits)
    }

    /// Checks both maxima are > 0 (infinite allowed, NaN not).
    pub fn validate(&self) -> Result<()> {
        for (name, value) in [("max_linear_speed", self.linear), ("max_angular_speed", self.angular)] {
            if !(value > 0.0) {
                return Err(Error::InvalidParameter { name, reason: format!("must be > 0, got {}", Short(value)) });
            }
        }
        Ok(())
    }

    /// The factor in (0, 1] that brings `twist = (v, w)` within both maxima. Contract: the
    /// twist is finite (the controllers' twists are checked, the simulator's robots refuse
    /// non-finite ones). For a finite twist the factor is in [0, 1]: 0 only when a norm
    /// overflows (entries beyond about 1e154), where the scaled twist is zero; a NaN entry
    /// gives 1 (no limit applies) and is left to the caller's finiteness check.
    #[inline]
    pub fn scale(&self, twist: &Vector6<f64>) -> f64 {
        let v = twist.fixed_rows::<3>(0).norm();
        let w = twist.fixed_rows::<3>(3).norm();
        let mut s: f64 = 1.0;
        if v > self.linear {
            s = s.min(self.linear / v);
        }
        if w > self.angular {
            s = s.min(self.angular / w);
        }
        s
    }

    /// Scales `twist` within the maxima; returns the factor applied (1 when within).
    #[inline]
    pub fn apply(&self, twist: &mut Vector6<f64>) -> f64 {
        let s = self.scale(twist);
        if s < 1.0 {
            *twist *= s;
        }
        s
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// The documented contract (issue 16 sweep).
    #[test]
    fn factor_for_extreme_twists() {
        let limits = TwistLimits::new(0.25, 1.0).unwrap();
        let mut huge = Vector6::new(1e200, 1e200, 0.0, 0.0, 0.0, 0.0);
        assert_eq!(limits.apply(&mut huge), 0.0);
        assert!(huge.iter().all(|v| *v == 0.0));
        let mut big = Vector6::new(1e100, 0.0, 0.0, 0.0, 0.0, 1e100);
        let s = limits.apply(&mut big);
        assert!(s > 0.0 && s < 1.0 && big.iter().all(|v| v.is_finite()));
        assert_eq!(limits.scale(&Vector6::repeat(f64::NAN)), 1.0);
    }

    #[test]
    fn scales_the_whole_twist_by_the_tighter_limit() {
        let limits = TwistLimits::new(0.25, 60f64.to_radians()).unwrap();
        let mut t = Vector6::new(0.3, 0.0, -0.4, 0.0, 0.0, -422f64.to_radians());
        let before = t;
        let s = limits.apply(&mut t);
        // ||v|| = 0.5 asks for 0.5, ||w|| = 422 deg/s for 60/422: the angular limit binds.
        assert!((s - 60.0 / 422.0).abs() < 1e-12);
        assert!((t.fixed_rows::<3>(3).norm() - 60f64.to_radians()).abs() < 1e-12);
        assert!(t.fixed_rows::<3>(0).norm() <= 0.25);
        assert!((t.normalize() - before.normalize()).norm() < 1e-12);
        let mut small = Vector6::new(0.01, 0.0, 0.0, 0.0, 0.1, 0.0);
        assert_eq!(limits.apply(&mut small), 1.0);
        assert_eq!(small, Vector6::new(0.01, 0.0, 0.0, 0.0, 0.1, 0.0));
    }

    #[test]
    fn bad_limits_are_refused() {
        assert!(TwistLimits::new(0.0, 1.0).is_err());
        assert!(TwistLimits::new(-1.0, 1.0).is_err());
        let free_rotation = TwistLimits::new(1.0, f64::INFINITY).unwrap();
        assert_eq!(free_rotation.scale(&Vector6::new(0.5, 0.0, 0.0, 0.0, 0.0, 100.0)), 1.0);
        assert!(TwistLimits::new(f64::NAN, 1.0).is_err());
    }
}
