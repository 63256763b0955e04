//! The "Scenario files" page's block (docs/reference/scenario-files.md, once the README's
//! section) is the one description of the scenario keys: it must parse as a valid scenario and
//! name every key of the schema.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::BTreeSet;

use vsinv::sim::Scenario;

pub(crate) fn readme_scenario_block() -> String {
    let page = include_str!("../docs/reference/scenario-files.md");
    let section = page.split("# Scenario files").nth(1).expect("the page has a 'Scenario files' title");
    let block = section.split("```toml\n").nth(1).expect("a toml block in that section");
    block.split("\n```").next().expect("a closed toml block").to_string()
}

/// Every dotted key path of a TOML value (array entries share their parent's path).
fn key_paths(value: &toml::Value, prefix: &str, out: &mut BTreeSet<String>) {
    match value {
        toml::Value::Table(t) => {
            for (k, v) in t {
                let path = if prefix.is_empty() { k.clone() } else { format!("{prefix}.{k}") };
                out.insert(path.clone());
                key_paths(v, &path, out);
            }
        }
        toml::Value::Array(items) => items.iter().for_each(|v| key_paths(v, prefix, out)),
        _ => {}
    }
}

#[test]
fn readme_scenario_block_is_a_valid_scenario() {
    let text = readme_scenario_block();
    let scenario = Scenario::from_toml(&text).unwrap_or_else(|e| panic!("README scenario block: {e}"));
    assert_eq!(scenario.name, "my-run");
    scenario.to_config().expect("the README's scenario converts to a simulation");
}

#[test]
fn readme_scenario_block_names_every_key() {
    let text = readme_scenario_block();
    let scenario = Scenario::from_toml(&text).expect("valid");
    let mut documented = BTreeSet::new();
    key_paths(&toml::Value::Table(toml::from_str(&text).expect("toml")), "", &mut documented);
    // The serialised scenario writes every key of the schema that this scenario uses,
    // defaults included: each must be in the README.
    let written = toml::Value::Table(toml::from_str(&scenario.to_toml().expect("to toml")).expect("toml"));
    let mut schema = BTreeSet::new();
    key_paths(&written, "", &mut schema);
    let missing: Vec<_> = schema.difference(&documented).collect();
    assert!(missing.is_empty(), "keys of the schema missing from the README's block: {missing:?}");
}

/// The block is one scenario with one law, so the keys of the other laws are shown commented
/// out: every `[control]` key of every law must still be described there.
#[test]
fn readme_scenario_block_describes_every_law_key() {
    use vsinv::sim::scenario::{COMMON_CONTROL_KEYS, LAW_KEYS};
    let text = readme_scenario_block();
    let control = text.split("\n[control]").nth(1).and_then(|s| s.split("\n[").next()).expect("a [control] table");
    let keys = COMMON_CONTROL_KEYS.iter().chain(LAW_KEYS.iter().flat_map(|(_, keys)| keys.iter()));
    for key in keys {
        let described = control.lines().any(|l| l.trim_start_matches(['#', ' ']).starts_with(&format!("{key} =")));
        assert!(described, "control.{key} is not described in the README's [control] table");
    }
}
