//! Which `[control]` keys each law reads: the laws' options of the servo layer's table
//! ([`LAW_OPTIONS`](crate::servo::law::options::LAW_OPTIONS)) under their scenario keys, and
//! the depth source for the laws that move the camera. A key that only another law reads is
//! refused with an error naming the key and both laws, rather than silently ignored (a
//! `rz_task` under `law = "ibvs"` would otherwise look like it did something). A new law
//! option is a new entry of that table, a new law one entry of [`LAWS`].

use std::sync::LazyLock;

use super::scenario_error;
use super::schema::{ControlSpec, LawName};
use crate::servo::law::options::LAW_OPTIONS;
use crate::sim::error::Result;

/// The `[control]` keys of every law: which law, and the period between images (a
/// stationary camera, `law = "none"`, takes one every `dt` too).
pub const COMMON_CONTROL_KEYS: &[&str] = &["law", "dt"];

/// The laws, and whether each moves the camera (and so reads `depths`, the depth source).
const LAWS: [(LawName, bool); 3] = [(LawName::Invariant, true), (LawName::Ibvs, true), (LawName::None, false)];

/// The other `[control]` keys, by the law that reads them.
pub static LAW_KEYS: LazyLock<Vec<(LawName, Vec<&'static str>)>> = LazyLock::new(|| {
    let keys = |law: LawName, moves: bool| {
        let options = LAW_OPTIONS.iter().filter(|o| o.reads(law.name())).filter_map(|o| o.scenario_key());
        moves.then_some("depths").into_iter().chain(options).collect()
    };
    LAWS.iter().map(|&(law, moves)| (law, keys(law, moves))).collect()
});

/// The keys `law` reads besides [`COMMON_CONTROL_KEYS`].
pub fn law_keys(law: LawName) -> Vec<&'static str> {
    LAW_KEYS.iter().find(|(l, _)| *l == law).map(|(_, keys)| keys.clone()).unwrap_or_default()
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
    for key in c.given_keys() {
        if COMMON_CONTROL_KEYS.contains(&key) || own.contains(&key) {
            continue;
        }
        let owners: Vec<&str> =
            LAW_KEYS.iter().filter(|(_, keys)| keys.contains(&key)).map(|(l, _)| l.name()).collect();
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

    /// Every key of `[control]` is common or read by some law, and every law's key is one of
    /// `[control]`: the keys derived from the table and the schema's agree.
    #[test]
    fn the_table_names_exactly_the_schema_keys() {
        let listed: Vec<&str> =
            COMMON_CONTROL_KEYS.iter().chain(LAW_KEYS.iter().flat_map(|(_, keys)| keys.iter())).copied().collect();
        for f in super::super::schema::CONTROL_KEYS.iter() {
            assert!(listed.contains(f), "control.{f} is in the schema but read by no law");
        }
        for k in &listed {
            assert!(super::super::schema::CONTROL_KEYS.contains(k), "control.{k} is listed but not in the schema");
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
