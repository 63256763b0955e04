//! The options given to a law: checked against [`LAW_OPTIONS`](super::LAW_OPTIONS) as they are given, read with
//! the table's defaults for the others.

use super::{ADAPTIVE_GAIN, MAX_ANGULAR_SPEED, MAX_LINEAR_SPEED, OptionDefault, OptionSpec, OptionValue, clip, option};
use crate::core::adaptive_gain::AdaptiveGain;
use crate::core::saturation::TwistLimits;
use crate::error::{Error, Result};

/// The options given to a law, each checked when given; the others take the table's default.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LawOptions {
    given: Vec<(&'static str, OptionValue)>,
}

impl LawOptions {
    /// No option given: every option at its default.
    pub fn new() -> Self {
        Self::default()
    }

    /// Gives option `name` (in its unit) after checking it; the error names it.
    pub fn set(&mut self, name: &str, value: OptionValue) -> Result<()> {
        let spec = option(name).ok_or_else(|| Error::InvalidParameter {
            name: "law options",
            reason: format!("{:?} is not an option of any law", clip(name)),
        })?;
        spec.check(&value)?;
        self.given.retain(|(n, _)| *n != spec.name);
        self.given.push((spec.name, value));
        Ok(())
    }

    /// The names of the options given.
    pub fn given(&self) -> impl Iterator<Item = &'static str> + '_ {
        self.given.iter().map(|(n, _)| *n)
    }

    fn value(&self, spec: &OptionSpec) -> Option<&OptionValue> {
        self.given.iter().find(|(n, _)| *n == spec.name).map(|(_, v)| v)
    }

    /// A number option's value (its default when not given; NaN for an unset one).
    pub fn number(&self, spec: &OptionSpec) -> f64 {
        match (self.value(spec), spec.default) {
            (Some(&OptionValue::Number(v)), _) | (None, OptionDefault::Number(v)) => v,
            _ => f64::NAN,
        }
    }

    /// A number option's value when given or defaulted, None when unset.
    pub fn opt_number(&self, spec: &OptionSpec) -> Option<f64> {
        Some(self.number(spec)).filter(|v| !v.is_nan())
    }

    /// A flag option's value (its default when not given).
    pub fn flag(&self, spec: &OptionSpec) -> bool {
        match (self.value(spec), spec.default) {
            (Some(&OptionValue::Flag(v)), _) | (None, OptionDefault::Flag(v)) => v,
            _ => false,
        }
    }

    /// A choice option's value (its default when not given).
    pub fn choice(&self, spec: &OptionSpec) -> &str {
        match (self.value(spec), spec.default) {
            (Some(OptionValue::Choice(c)), _) => c,
            (None, OptionDefault::Choice(c)) => c,
            _ => "",
        }
    }

    /// The adaptive gain, if given.
    pub fn adaptive_gain(&self) -> Option<AdaptiveGain> {
        match self.value(&ADAPTIVE_GAIN) {
            Some(OptionValue::AdaptiveGain(g)) => Some(*g),
            _ => None,
        }
    }

    /// The speed limits, if either is given (the other then free).
    pub fn twist_limits(&self) -> Result<Option<TwistLimits>> {
        let (v, w) = (self.opt_number(&MAX_LINEAR_SPEED), self.opt_number(&MAX_ANGULAR_SPEED));
        if v.is_none() && w.is_none() {
            return Ok(None);
        }
        TwistLimits::new(v.unwrap_or(f64::INFINITY), w.unwrap_or(f64::INFINITY)).map(Some)
    }

    /// Refuses an option `law` does not read, naming it.
    pub fn check_law(&self, law: &str) -> Result<()> {
        match self.given.iter().find(|(n, _)| option(n).is_some_and(|o| !o.reads(law))) {
            Some((name, _)) => {
                Err(Error::InvalidParameter { name, reason: format!("not an argument of the {law:?} law") })
            }
            None => Ok(()),
        }
    }
}
