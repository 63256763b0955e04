//! `[control]`: the law, the control period, the depth source, and the laws' options, whose
//! keys, kinds and checks are those of the servo layer's table
//! ([`LAW_OPTIONS`](crate::servo::law::options::LAW_OPTIONS)): a new option there is a new
//! key here, with nothing to add.

use std::fmt;
use std::sync::LazyLock;

use serde::de::{self, DeserializeSeed, MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::{DepthsName, LawName};
use crate::core::adaptive_gain::AdaptiveGain;
use crate::error::Error;
use crate::servo::law::options::{LAW_OPTIONS, LawOptions, OptionKind, OptionSpec, OptionValue, ScenarioKey};
use crate::sim::error::{Result, SimError};

fn default_dt() -> f64 {
    0.04
}

/// Every key of `[control]`: the law, the period, the depth source, then the laws' options.
pub static CONTROL_KEYS: LazyLock<Vec<&'static str>> = LazyLock::new(|| {
    let options = LAW_OPTIONS.iter().filter_map(OptionSpec::scenario_key);
    ["law", "dt", "depths"].into_iter().chain(options).collect()
});

/// `[control]`. Each law reads its own keys ([`LAW_KEYS`](super::super::LAW_KEYS)): a key of
/// another law is refused.
#[derive(Debug, Clone, PartialEq)]
pub struct ControlSpec {
    /// Which law (default: the invariant law).
    pub law: LawName,
    /// Control period, s.
    pub dt: f64,
    /// Depths given to the law (default: the reference depths).
    pub depths: Option<DepthsName>,
    /// The laws' options given, as written (degrees under a `_deg` key), in the table's order.
    pub options: Vec<(&'static OptionSpec, OptionValue)>,
}

impl Default for ControlSpec {
    fn default() -> Self {
        Self { law: LawName::Invariant, dt: default_dt(), depths: None, options: Vec::new() }
    }
}

impl ControlSpec {
    /// The depths given to the law.
    pub fn depths(&self) -> DepthsName {
        self.depths.unwrap_or(DepthsName::Reference)
    }

    /// The value given under a scenario key, if any.
    pub fn option(&self, key: &str) -> Option<&OptionValue> {
        self.options.iter().find(|(o, _)| o.scenario_key() == Some(key)).map(|(_, v)| v)
    }

    /// Gives the option under scenario key `key` (unchecked: [`Self::law_options`] checks).
    pub fn set_option(&mut self, key: &str, value: OptionValue) -> Result<()> {
        let spec = crate::servo::law::options::option_by_scenario_key(key)
            .ok_or_else(|| super::super::scenario_error(&format!("control.{key}"), "not a key of [control]"))?;
        self.remove_option(key);
        self.options.push((spec, value));
        let index = |o: &OptionSpec| LAW_OPTIONS.iter().position(|p| p.name == o.name);
        self.options.sort_by_key(|(o, _)| index(o));
        Ok(())
    }

    /// Takes back the option under scenario key `key`.
    pub fn remove_option(&mut self, key: &str) {
        self.options.retain(|(o, _)| o.scenario_key() != Some(key));
    }

    /// The scenario keys given (law, dt and those of the options and the depth source).
    pub fn given_keys(&self) -> Vec<&'static str> {
        let depths = self.depths.map(|_| "depths");
        let options = self.options.iter().filter_map(|(o, _)| o.scenario_key());
        ["law", "dt"].into_iter().chain(depths).chain(options).collect()
    }

    /// The options in the law's units (radians for a `_deg` key), each checked; an error names
    /// the scenario key (`control.max_angular_speed_deg`, `control.adaptive_gain.at_zero`).
    pub fn law_options(&self) -> Result<LawOptions> {
        let mut out = LawOptions::new();
        for (spec, value) in &self.options {
            spec.check(value).map_err(|e| keyed(spec, e))?;
            let value = match (spec.scenario, value) {
                (ScenarioKey::Degrees(_), OptionValue::Number(v)) => OptionValue::Number(v.to_radians()),
                _ => value.clone(),
            };
            out.set(spec.name, value).map_err(|e| keyed(spec, e))?;
        }
        Ok(out)
    }
}

/// An option's error under its scenario key.
fn keyed(spec: &OptionSpec, e: Error) -> SimError {
    let key = spec.scenario_key().unwrap_or(spec.name);
    match e {
        Error::InvalidParameter { name, reason } => {
            let rest = name.strip_prefix(spec.name).unwrap_or_default();
            super::super::scenario_error(&format!("control.{key}{rest}"), reason)
        }
        other => super::super::scenario_error(&format!("control.{key}"), other.to_string()),
    }
}

impl Serialize for ControlSpec {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(None)?;
        map.serialize_entry("law", &self.law)?;
        map.serialize_entry("dt", &self.dt)?;
        if let Some(d) = &self.depths {
            map.serialize_entry("depths", d)?;
        }
        for (spec, value) in &self.options {
            let key = spec.scenario_key().unwrap_or(spec.name);
            match value {
                OptionValue::Number(v) => map.serialize_entry(key, v)?,
                OptionValue::Flag(v) => map.serialize_entry(key, v)?,
                OptionValue::Choice(v) => map.serialize_entry(key, v)?,
                OptionValue::AdaptiveGain(v) => map.serialize_entry(key, v)?,
            }
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for ControlSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        d.deserialize_map(ControlVisitor)
    }
}

struct ControlVisitor;

impl<'de> Visitor<'de> for ControlVisitor {
    type Value = ControlSpec;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("the [control] table")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> std::result::Result<ControlSpec, A::Error> {
        let mut c = ControlSpec::default();
        let mut seen: Vec<String> = Vec::new();
        while let Some(key) = map.next_key::<String>()? {
            if seen.contains(&key) {
                return Err(de::Error::custom(format_args!("duplicate field `{key}`")));
            }
            match key.as_str() {
                "law" => c.law = map.next_value()?,
                "dt" => c.dt = map.next_value()?,
                "depths" => c.depths = map.next_value()?,
                _ => {
                    let Some(spec) = crate::servo::law::options::option_by_scenario_key(&key) else {
                        return Err(de::Error::unknown_field(&key, CONTROL_KEYS.as_slice()));
                    };
                    if let Some(value) = map.next_value_seed(ValueSeed(spec))? {
                        c.options.push((spec, value));
                    }
                }
            }
            seen.push(key);
        }
        let index = |o: &OptionSpec| LAW_OPTIONS.iter().position(|p| p.name == o.name);
        c.options.sort_by_key(|(o, _)| index(o));
        Ok(c)
    }
}

/// Reads an option's value as its kind says (None: null, as a Python None becomes).
struct ValueSeed(&'static OptionSpec);

impl<'de> DeserializeSeed<'de> for ValueSeed {
    type Value = Option<OptionValue>;

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> std::result::Result<Self::Value, D::Error> {
        Ok(match self.0.kind {
            OptionKind::Number => Option::<f64>::deserialize(d)?.map(OptionValue::Number),
            OptionKind::Flag => Option::<bool>::deserialize(d)?.map(OptionValue::Flag),
            OptionKind::Choice(names) => match Option::<String>::deserialize(d)? {
                Some(s) if names.contains(&s.as_str()) => Some(OptionValue::Choice(s)),
                Some(s) => return Err(de::Error::unknown_variant(&s, names)),
                None => None,
            },
            OptionKind::AdaptiveGain => Option::<AdaptiveGain>::deserialize(d)?.map(OptionValue::AdaptiveGain),
        })
    }
}
