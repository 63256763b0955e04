//! A gain that depends on the size of the error, as ViSP's `vpAdaptiveGain`:
//! `lambda(x) = (lambda_0 - lambda_inf) exp(-lambda'_0 x / (lambda_0 - lambda_inf)) + lambda_inf`,
//! with `x = ||e||` the norm of the law's error. A large gain `lambda_0` near the goal ends the
//! exponential decay of the error sooner, a small one `lambda_inf` far from it keeps the first
//! commands moderate; `lambda'_0` is the slope of `lambda` at `x = 0` (in absolute value).

use crate::error::{Error, Result, Short, check_positive};

/// The parameters of `lambda(x)`; `lambda_0 >= lambda_inf > 0`, `lambda'_0 > 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize), serde(deny_unknown_fields))]
pub struct AdaptiveGain {
    /// `lambda_0`: the gain at a zero error (1/s).
    pub at_zero: f64,
    /// `lambda_inf`: the gain for a very large error (1/s).
    pub at_infinity: f64,
    /// `lambda'_0`: the slope of `-lambda(x)` at `x = 0` (1/s per unit of error).
    pub slope_at_zero: f64,
}

impl AdaptiveGain {
    /// Checked parameters.
    pub fn new(at_zero: f64, at_infinity: f64, slope_at_zero: f64) -> Result<Self> {
        let gain = Self { at_zero, at_infinity, slope_at_zero };
        gain.validate()?;
        Ok(gain)
    }

    /// Checks `lambda_0 >= lambda_inf > 0` and `lambda'_0 > 0`, all finite.
    pub fn validate(&self) -> Result<()> {
        check_positive("adaptive_gain.at_zero", self.at_zero)?;
        check_positive("adaptive_gain.at_infinity", self.at_infinity)?;
        check_positive("adaptive_gain.slope_at_zero", self.slope_at_zero)?;
        if self.at_infinity > self.at_zero {
            return Err(Error::InvalidParameter {
                name: "adaptive_gain.at_infinity",
                reason: format!(
                    "the gain for a large error ({}) must not exceed the gain at zero error ({})",
                    Short(self.at_infinity),
                    Short(self.at_zero)
                ),
            });
        }
        Ok(())
    }

    /// `lambda(x)` for an error norm `x >= 0`. Contract: for validated parameters and any
    /// `x >= 0` (`+inf` included) the result is finite and in `[lambda_inf, lambda_0]`; a NaN
    /// `x` gives NaN (the controllers pass norms of errors they have checked to be finite).
    #[inline]
    pub fn value(&self, error_norm: f64) -> f64 {
        let span = self.at_zero - self.at_infinity;
        if span <= 0.0 {
            return self.at_zero;
        }
        span * (-self.slope_at_zero * error_norm / span).exp() + self.at_infinity
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn limits_and_slope_at_zero() {
        let g = AdaptiveGain::new(4.0, 0.4, 30.0).unwrap();
        assert!((g.value(0.0) - 4.0).abs() < 1e-15);
        assert!((g.value(1e6) - 0.4).abs() < 1e-15);
        let h = 1e-7;
        let slope = (g.value(h) - g.value(0.0)) / h;
        assert!((slope + 30.0).abs() < 1e-4, "{slope}");
        // Decreasing in x.
        assert!(g.value(0.01) > g.value(0.02) && g.value(0.02) > g.value(0.5));
    }

    #[test]
    fn a_constant_gain_is_allowed_and_bad_parameters_are_refused() {
        let g = AdaptiveGain::new(1.0, 1.0, 5.0).unwrap();
        assert_eq!(g.value(0.3), 1.0);
        assert!(AdaptiveGain::new(0.5, 1.0, 5.0).is_err());
        assert!(AdaptiveGain::new(1.0, 0.0, 5.0).is_err());
        assert!(AdaptiveGain::new(1.0, 0.5, f64::NAN).is_err());
    }

    /// The documented contract (issue 16 sweep): finite and within the limits for x >= 0.
    #[test]
    fn value_is_within_the_limits_for_every_norm() {
        let g = AdaptiveGain::new(4.0, 0.4, 30.0).unwrap();
        for x in [0.0, 5e-324, 1e-300, 0.5, 1e300, f64::MAX, f64::INFINITY] {
            let v = g.value(x);
            assert!(v.is_finite() && (0.4..=4.0).contains(&v), "{x}: {v}");
        }
        assert!(g.value(f64::NAN).is_nan());
    }
}
