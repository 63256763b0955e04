//! The laws' options, declared once. [`LAW_OPTIONS`] gives each option its name, the laws
//! that read it, its kind and default, its range, its unit, its scenario key and one line of
//! documentation; every layer reads the table:
//!
//! | layer | what it takes from the table |
//! |---|---|
//! | the law ([`Law::from_options`](super::Law::from_options)) | defaults, ranges (errors name the option) |
//! | scenario files (`sim::scenario`, `[control]`) | the keys, which law reads each, the values' checks |
//! | Python (`Servo`, `ImageServo` keyword arguments; `vsinv.laws.LAW_OPTIONS`) | names, kinds, the law check |
//! | the ROS 2 bridge's parameters (`vsinv/ros/params.py`) | names, kinds, choices, docs |
//! | `vsinv replay` flags (`vsinv/cli_replay.py`) | names, kinds, choices, docs |
//! | the reference table of the docs ([`markdown_table`]) | everything |
//!
//! Units are SI (radians, seconds) everywhere but in scenario files, whose angles are in
//! degrees under a key that says so ([`ScenarioKey::Degrees`]: `max_angular_speed_deg`).
//!
//! **Adding a law option** touches these files:
//! 1. `src/servo/law/options.rs`: one entry in [`LAW_OPTIONS`] (a `const` of its own, read by name);
//! 2. `src/servo/law/mod.rs`: the law reads it in [`Law::from_options`](super::Law::from_options)
//!    (and the law's configuration gets the field it sets);
//! 3. `python/vsinv/_core.pyi`: the keyword of `Servo` (and of the law's controller, with its
//!    argument in `src/python/control.rs`, when the controller takes it).
//!
//! `tests/law_options.rs` and `tests/test_law_options.py` go through the table and check that
//! every layer accepts each option's values and refuses the out-of-range ones by name, and that
//! the stub declares every option: they fail until the three files agree.

use crate::core::adaptive_gain::AdaptiveGain;
use crate::core::jacobian::DEFAULT_MIN_STRUCTURE_RATIO;
use crate::error::{Error, Result, Short};

mod given;
mod markdown;
pub use given::LawOptions;
pub use markdown::markdown_table;

/// The laws, by the name scenarios and Python give them.
pub const LAWS: [&str; 3] = ["invariant", "ibvs", "none"];

/// The values an option takes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OptionKind {
    /// A number within the option's [`Range`].
    Number,
    /// On or off.
    Flag,
    /// One of these names.
    Choice(&'static [&'static str]),
    /// ViSP's adaptive gain `(lambda_0, lambda_inf, lambda'_0)`: `lambda_0 >= lambda_inf > 0`,
    /// `lambda'_0 > 0` (scenario files: `{ at_zero, at_infinity, slope_at_zero }`).
    AdaptiveGain,
}

impl OptionKind {
    /// The kind's name, as Python sees it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Number => "number",
            Self::Flag => "flag",
            Self::Choice(_) => "choice",
            Self::AdaptiveGain => "adaptive_gain",
        }
    }
}

/// The value an option has when it is not given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OptionDefault {
    /// This number.
    Number(f64),
    /// On or off.
    Flag(bool),
    /// This choice.
    Choice(&'static str),
    /// Unset: the option's effect is off (no speed limit, a constant gain).
    Unset,
}

/// The numbers a [`OptionKind::Number`] option takes: from `min` to `max`, each end open or
/// closed (an open end at infinity: finite values only).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    /// The lower end.
    pub min: f64,
    /// Whether `min` itself is refused.
    pub min_open: bool,
    /// The upper end.
    pub max: f64,
    /// Whether `max` itself is refused.
    pub max_open: bool,
}

impl Range {
    /// `(0, inf)`: finite and > 0.
    pub const POSITIVE: Self = Self { min: 0.0, min_open: true, max: f64::INFINITY, max_open: true };
    /// `[0, inf)`: finite and >= 0.
    pub const NON_NEGATIVE: Self = Self { min: 0.0, min_open: false, max: f64::INFINITY, max_open: true };
    /// `(0, inf]`: > 0, infinity allowed (a limit that leaves the value free).
    pub const POSITIVE_OR_INFINITE: Self = Self { min: 0.0, min_open: true, max: f64::INFINITY, max_open: false };

    /// Whether `v` is in the range (NaN never is).
    pub fn contains(&self, v: f64) -> bool {
        let above = v > self.min || (!self.min_open && v == self.min);
        let below = v < self.max || (!self.max_open && v == self.max);
        above && below
    }

    /// What the range asks, in words ("must be finite and > 0").
    pub fn requirement(&self) -> String {
        let infinite = self.max == f64::INFINITY;
        match (infinite, self.max_open) {
            (true, true) => format!("must be finite and {} {}", if self.min_open { ">" } else { ">=" }, self.min),
            (true, false) => format!("must be {} {}", if self.min_open { ">" } else { ">=" }, self.min),
            _ => format!("must be in {}", self.interval()),
        }
    }

    /// The range in interval notation: `(0, inf)`, `[0, inf)`, `(0, inf]`.
    pub fn interval(&self) -> String {
        let end = |v: f64| if v.is_infinite() { "inf".to_string() } else { format!("{v}") };
        let (open, close) = (if self.min_open { "(" } else { "[" }, if self.max_open { ")" } else { "]" });
        format!("{open}{}, {}{close}", end(self.min), end(self.max))
    }
}

/// Where scenario files give an option (the `[control]` table).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScenarioKey {
    /// Under the option's name, in its unit.
    Same,
    /// Under this key, in degrees where the option is in radians (deg/s for rad/s): the
    /// README's convention for angles in scenario files.
    Degrees(&'static str),
    /// Not a scenario key (the built-in default applies to every scenario).
    Absent,
}

/// One option of the laws.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OptionSpec {
    /// The name: the Python keyword argument, the ROS parameter, the `--flag` (with dashes).
    pub name: &'static str,
    /// The laws that read it; another law refuses it by name.
    pub laws: &'static [&'static str],
    /// The values it takes.
    pub kind: OptionKind,
    /// Its value when not given.
    pub default: OptionDefault,
    /// The numbers it takes (numbers only).
    pub range: Option<Range>,
    /// Its unit ("" for none).
    pub unit: &'static str,
    /// Where scenario files give it.
    pub scenario: ScenarioKey,
    /// What it does, in one line (with the paper's equation where it is the paper's).
    pub doc: &'static str,
}

impl OptionSpec {
    /// Whether `law` reads the option.
    pub fn reads(&self, law: &str) -> bool {
        self.laws.contains(&law)
    }

    /// Its key in scenario files, if it has one.
    pub fn scenario_key(&self) -> Option<&'static str> {
        match self.scenario {
            ScenarioKey::Same => Some(self.name),
            ScenarioKey::Degrees(key) => Some(key),
            ScenarioKey::Absent => None,
        }
    }

    /// Its unit in scenario files.
    pub fn scenario_unit(&self) -> &'static str {
        match self.scenario {
            ScenarioKey::Degrees(_) if self.unit == "rad/s" => "deg/s",
            ScenarioKey::Degrees(_) => "deg",
            _ => self.unit,
        }
    }

    /// Checks a value of the option (its kind, its range); the error names the option (or
    /// the part of it at fault, `adaptive_gain.at_infinity`).
    pub fn check(&self, value: &OptionValue) -> Result<()> {
        let mismatch =
            || Error::InvalidParameter { name: self.name, reason: format!("expected a {}", self.kind.name()) };
        match (self.kind, value) {
            (OptionKind::Number, OptionValue::Number(v)) => match self.range {
                Some(r) if !r.contains(*v) => Err(Error::InvalidParameter {
                    name: self.name,
                    reason: format!("{}, got {}", r.requirement(), Short(*v)),
                }),
                _ => Ok(()),
            },
            (OptionKind::Flag, OptionValue::Flag(_)) => Ok(()),
            (OptionKind::Choice(names), OptionValue::Choice(c)) if names.contains(&c.as_str()) => Ok(()),
            (OptionKind::Choice(names), OptionValue::Choice(c)) => Err(Error::InvalidParameter {
                name: self.name,
                reason: format!("expected one of {}, got {:?}", quoted(names), clip(c)),
            }),
            (OptionKind::AdaptiveGain, OptionValue::AdaptiveGain(g)) => g.validate(),
            _ => Err(mismatch()),
        }
    }
}

/// A given name cut to 40 characters (it may be anything).
fn clip(s: &str) -> String {
    match s.char_indices().nth(40) {
        Some((i, _)) => format!("{}...", &s[..i]),
        None => s.to_string(),
    }
}

/// `"a", "b" or "c"`.
fn quoted(names: &[&str]) -> String {
    let q: Vec<String> = names.iter().map(|n| format!("{n:?}")).collect();
    match q.as_slice() {
        [first @ .., last] if !first.is_empty() => format!("{} or {last}", first.join(", ")),
        _ => q.join(""),
    }
}

/// A value of an option, in the option's unit.
#[derive(Debug, Clone, PartialEq)]
pub enum OptionValue {
    /// A number.
    Number(f64),
    /// On or off.
    Flag(bool),
    /// A choice's name.
    Choice(String),
    /// An adaptive gain.
    AdaptiveGain(AdaptiveGain),
}

const MOVING: &[&str] = &["invariant", "ibvs"];

/// lambda, the gain of the law.
pub const GAIN: OptionSpec = OptionSpec {
    name: "gain",
    laws: MOVING,
    kind: OptionKind::Number,
    default: OptionDefault::Number(1.0),
    range: Some(Range::POSITIVE),
    unit: "1/s",
    scenario: ScenarioKey::Same,
    doc: "lambda: the rate at which the error decreases, eq. (17) (IBVS: v = -lambda L_hat^+ (p - p*))",
};
/// eta, the gain of the rotation about the optical axis.
pub const GAIN_RZ: OptionSpec = OptionSpec {
    name: "gain_rz",
    laws: &["invariant"],
    kind: OptionKind::Number,
    default: OptionDefault::Number(1.0),
    range: Some(Range::POSITIVE),
    unit: "1/s",
    scenario: ScenarioKey::Same,
    doc: "eta: the gain of the rotation about the optical axis, eq. (24)",
};
/// The feed-forward term of eq. (17).
pub const FEEDFORWARD: OptionSpec = OptionSpec {
    name: "feedforward",
    laws: &["invariant"],
    kind: OptionKind::Flag,
    default: OptionDefault::Flag(true),
    range: None,
    unit: "",
    scenario: ScenarioKey::Same,
    doc: "the feed-forward term J_hat^+ ds*/dt of eq. (17) while the reference moves (path following)",
};
/// The task on the rotation about the optical axis.
pub const RZ_TASK: OptionSpec = OptionSpec {
    name: "rz_task",
    laws: &["invariant"],
    kind: OptionKind::Choice(&["angle", "tau21"]),
    default: OptionDefault::Choice("angle"),
    range: None,
    unit: "",
    scenario: ScenarioKey::Same,
    doc: "the task on the rotation about the optical axis: angle (any start) or tau21 (eq. 24, |rz| < 90 deg)",
};
/// The threshold of degenerate structure.
pub const MIN_STRUCTURE_RATIO: OptionSpec = OptionSpec {
    name: "min_structure_ratio",
    laws: &["invariant"],
    kind: OptionKind::Number,
    default: OptionDefault::Number(DEFAULT_MIN_STRUCTURE_RATIO),
    range: Some(Range::NON_NEGATIVE),
    unit: "",
    scenario: ScenarioKey::Absent,
    doc: "the smallest sigma_5/sigma_1 of the depth-balanced J_hat (below: a degenerate structure)",
};
/// Where IBVS evaluates its interaction matrix.
pub const INTERACTION: OptionSpec = OptionSpec {
    name: "interaction",
    laws: &["ibvs"],
    kind: OptionKind::Choice(&["current", "desired", "mean"]),
    default: OptionDefault::Choice("current"),
    range: None,
    unit: "",
    scenario: ScenarioKey::Same,
    doc: "where the interaction matrix L_hat is evaluated: at the current pixels, the desired ones, or their mean",
};
/// ViSP's adaptive gain.
pub const ADAPTIVE_GAIN: OptionSpec = OptionSpec {
    name: "adaptive_gain",
    laws: MOVING,
    kind: OptionKind::AdaptiveGain,
    default: OptionDefault::Unset,
    range: None,
    unit: "1/s",
    scenario: ScenarioKey::Same,
    doc: "a gain lambda(||e||) from lambda_0 at zero error down to lambda_inf, slope lambda'_0 at zero; replaces gain",
};
/// The largest linear speed.
pub const MAX_LINEAR_SPEED: OptionSpec = OptionSpec {
    name: "max_linear_speed",
    laws: MOVING,
    kind: OptionKind::Number,
    default: OptionDefault::Unset,
    range: Some(Range::POSITIVE_OR_INFINITE),
    unit: "m/s",
    scenario: ScenarioKey::Same,
    doc: "the largest linear speed: the twist is scaled as a whole (its direction kept); unset: free",
};
/// The largest angular speed.
pub const MAX_ANGULAR_SPEED: OptionSpec = OptionSpec {
    name: "max_angular_speed",
    laws: MOVING,
    kind: OptionKind::Number,
    default: OptionDefault::Unset,
    range: Some(Range::POSITIVE_OR_INFINITE),
    unit: "rad/s",
    scenario: ScenarioKey::Degrees("max_angular_speed_deg"),
    doc: "the largest angular speed: the twist is scaled as a whole (its direction kept); unset: free",
};

/// Every option of the laws.
pub const LAW_OPTIONS: &[OptionSpec] = &[
    GAIN,
    GAIN_RZ,
    FEEDFORWARD,
    RZ_TASK,
    MIN_STRUCTURE_RATIO,
    INTERACTION,
    ADAPTIVE_GAIN,
    MAX_LINEAR_SPEED,
    MAX_ANGULAR_SPEED,
];

/// The option of this name.
pub fn option(name: &str) -> Option<&'static OptionSpec> {
    LAW_OPTIONS.iter().find(|o| o.name == name)
}

/// The option under this scenario key.
pub fn option_by_scenario_key(key: &str) -> Option<&'static OptionSpec> {
    LAW_OPTIONS.iter().find(|o| o.scenario_key() == Some(key))
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests;
