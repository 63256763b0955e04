//! Which `[control]` keys each law reads. [`LAW_KEYS`] is the one declaration: a key that
//! only another law reads is refused with an error naming the key and both laws, rather than
//! silently ignored (a `rz_task` under `law = "ibvs"` would otherwise look like it did
//! something). Adding a law is one entry in that table.

use super::scenario_error;
use super::schema::{ControlSpec, LawName};
use crate::error::Result;

/// The `[control]` keys of every law: which law, and the period between images (a
/// stationary camera, `law = "none"`, takes one every `dt` too).
pub const COMMON_CONTROL_KEYS: &[&str] = &["law", "dt"];

/// The other `[control]` keys, by the law that reads them.
pub const LAW_KEYS: &[(LawName, &[&str])] = &[
    (
        LawName::Invariant,
        &[
            "gain",
            "gain_rz",
            "depths",
            "feedforward",
            "rz_task",
            "max_linear_speed",
            "max_angular_speed_deg",
            "adaptive_gain",
        ],
    ),
    (LawName::Ibvs, &["gain", "depths", "interaction", "max_linear_speed", "max_angular_speed_deg", "adaptive_gain"]),
    (LawName::None, &[]),
];

/// The keys `law` reads besides [`COMMON_CONTROL_KEYS`] (none for a law missing from
/// [`LAW_KEYS`], which then refuses every other key).
pub fn law_keys(law: LawName) -> &'static [&'static str] {
    LAW_KEYS.iter().find(|(l, _)| *l == law).map_or(&[], |(_, keys)| keys)
}

/// The keys a `[control]` table gives: those its serialisation writes (every law-specific
/// key is optional, written only when given).
fn given_keys(c: &ControlSpec) -> Result<Vec<String>> {
    match serde_json::to_value(c) {
        Ok(serde_json::Value::Object(map)) => Ok(map.keys().cloned().collect()),
        Ok(_) => Err(scenario_error("control", "is not a table")),
        Err(e) => Err(scenario_error("control", e.to_string())),
    }
}

/// "the ibvs law", "the invariant and ibvs laws".
fn laws_phrase(laws: &[&str]) -> String {
    match laws {
        [] => "no law".to_string(),
        [one] => format!("the {one} law"),
        [first @ .., last] => format!("the {} and {last} laws", first.join(", ")),
    }
}

/// Refuses a `[control]` key that the scenario's law does not read, naming the key, the
/// laws that read it and the scenario's law.
pub(super) fn check_law_keys(c: &ControlSpec) -> Result<()> {
    let own = law_keys(c.law);
    for key in given_keys(c)? {
        if COMMON_CONTROL_KEYS.contains(&key.as_str()) || own.contains(&key.as_str()) {
            continue;
        }
        let owners: Vec<&str> =
            LAW_KEYS.iter().filter(|(_, keys)| keys.contains(&key.as_str())).map(|(l, _)| l.name()).collect();
        let reason =
            format!("belongs to {}; this scenario's law (control.law) is {}", laws_phrase(&owners), c.law.name());
        return Err(scenario_error(&format!("control.{key}"), reason));
    }
    Ok(())
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::core::adaptive_gain::AdaptiveGain;

    /// Every key of [`ControlSpec`] is common or read by some law, and every key of the
    /// table is one of its fields: the table and the schema agree.
    #[test]
    fn the_table_names_exactly_the_schema_keys() {
        let all = ControlSpec {
            gain: Some(1.0),
            gain_rz: Some(1.0),
            depths: Some(super::super::schema::DepthsName::Reference),
            feedforward: Some(true),
            interaction: Some(Default::default()),
            rz_task: Some(Default::default()),
            max_linear_speed: Some(1.0),
            max_angular_speed_deg: Some(1.0),
            adaptive_gain: Some(AdaptiveGain { at_zero: 2.0, at_infinity: 1.0, slope_at_zero: 1.0 }),
            ..Default::default()
        };
        let fields = given_keys(&all).unwrap();
        let listed: Vec<&str> =
            COMMON_CONTROL_KEYS.iter().chain(LAW_KEYS.iter().flat_map(|(_, keys)| keys.iter())).copied().collect();
        for f in &fields {
            assert!(listed.contains(&f.as_str()), "control.{f} is in the schema but read by no law");
        }
        for k in &listed {
            assert!(fields.iter().any(|f| f == k), "control.{k} is listed but not in the schema");
        }
        for law in [LawName::Invariant, LawName::Ibvs, LawName::None] {
            assert!(LAW_KEYS.iter().any(|(l, _)| *l == law), "{law:?} is missing from LAW_KEYS");
        }
    }

    #[test]
    fn laws_are_named_in_prose() {
        assert_eq!(laws_phrase(&["ibvs"]), "the ibvs law");
        assert_eq!(laws_phrase(&["invariant", "ibvs"]), "the invariant and ibvs laws");
        assert_eq!(laws_phrase(&["a", "b", "c"]), "the a, b and c laws");
    }
}
