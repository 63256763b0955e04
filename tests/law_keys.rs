//! The `[control]` table is read per law: each law accepts its own keys and refuses every key
//! that only other laws read, naming the key and the laws (issue 17); every built-in
//! scenario still parses.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use vsinv::sim::SimError;
use vsinv::sim::scenario::{BUILTIN, COMMON_CONTROL_KEYS, LAW_KEYS, LawName, Scenario, builtin, law_keys};

/// A valid value of each law-specific `[control]` key, as TOML.
const SAMPLES: &[(&str, &str)] = &[
    ("gain", "0.8"),
    ("gain_rz", "0.9"),
    ("depths", "\"true\""),
    ("feedforward", "false"),
    ("interaction", "\"mean\""),
    ("rz_task", "\"tau21\""),
    ("max_linear_speed", "0.25"),
    ("max_angular_speed_deg", "60.0"),
    ("adaptive_gain", "{ at_zero = 4.0, at_infinity = 0.4, slope_at_zero = 30.0 }"),
];

/// Every law-specific key of [`LAW_KEYS`], once.
fn all_law_keys() -> Vec<&'static str> {
    let mut keys: Vec<&str> = LAW_KEYS.iter().flat_map(|(_, keys)| keys.iter().copied()).collect();
    keys.sort_unstable();
    keys.dedup();
    keys
}

fn sample(key: &str) -> &'static str {
    SAMPLES.iter().find(|(k, _)| *k == key).unwrap_or_else(|| panic!("no sample value for control.{key}")).1
}

/// lens-12-6 with its `[control]` table replaced by `law` and `extra`.
fn scenario_text(law: LawName, extra: &str) -> String {
    let text = BUILTIN.iter().find(|(n, _)| *n == "lens-12-6").unwrap().1;
    let (head, rest) = text.split_once("[control]\n").unwrap();
    let tail = &rest[rest.find("\n[").unwrap()..];
    format!("{head}[control]\nlaw = \"{}\"\ndt = 0.04\n{extra}\n{tail}", law.name())
}

#[test]
fn every_builtin_scenario_parses() {
    for (name, text) in BUILTIN {
        let scenario = Scenario::from_toml(text).unwrap_or_else(|e| panic!("{name}: {e}"));
        match scenario.world.engine {
            vsinv::sim::scenario::Engine::Kinematic => {
                builtin(name).unwrap().to_config().unwrap_or_else(|e| panic!("{name}: {e}"));
            }
            // Run from Python through MuJoCo: this simulator refuses them by the key.
            _ => assert!(builtin(name).unwrap().to_config().unwrap_err().to_string().contains("world.engine")),
        }
    }
}

#[test]
fn each_law_reads_its_own_keys() {
    for (law, keys) in LAW_KEYS.iter() {
        for key in keys {
            let text = scenario_text(*law, &format!("{key} = {}", sample(key)));
            Scenario::from_toml(&text).unwrap_or_else(|e| panic!("{key} under {law:?}: {e}"));
        }
        let all: Vec<String> = keys.iter().map(|k| format!("{k} = {}", sample(k))).collect();
        Scenario::from_toml(&scenario_text(*law, &all.join("\n"))).unwrap_or_else(|e| panic!("{law:?}: {e}"));
    }
}

#[test]
fn a_key_of_another_law_is_refused_by_name() {
    let mut refused = 0;
    for (law, _) in LAW_KEYS.iter() {
        for key in all_law_keys().into_iter().filter(|k| !law_keys(*law).contains(k)) {
            let text = scenario_text(*law, &format!("{key} = {}", sample(key)));
            let (at, reason) = match Scenario::from_toml(&text) {
                Err(SimError::Scenario { key, reason }) => (key.to_string(), reason),
                other => panic!("control.{key} under {law:?}: expected a scenario error, got {other:?}"),
            };
            assert_eq!(at, format!("control.{key}"), "{reason}");
            let owners: Vec<&str> =
                LAW_KEYS.iter().filter(|(_, keys)| keys.contains(&key)).map(|(l, _)| l.name()).collect();
            for owner in owners {
                assert!(reason.contains(owner), "control.{key} under {law:?}: {reason}");
            }
            let this = format!("this scenario's law (control.law) is {}", law.name());
            assert!(reason.contains("belongs to the") && reason.contains(&this), "{reason}");
            refused += 1;
        }
    }
    // invariant refuses interaction; ibvs refuses gain_rz, feedforward, rz_task; none all 9.
    assert_eq!(refused, 1 + 3 + 9);
}

/// The examples of issue 17, word for word.
#[test]
fn the_messages_read_well() {
    let e = Scenario::from_toml(&scenario_text(LawName::Invariant, "interaction = \"current\"")).unwrap_err();
    assert_eq!(
        e.to_string(),
        "scenario: control.interaction: belongs to the ibvs law; this scenario's law (control.law) is invariant"
    );
    let e = Scenario::from_toml(&scenario_text(LawName::None, "gain = 1.0")).unwrap_err();
    assert!(e.to_string().contains("control.gain: belongs to the invariant and ibvs laws"), "{e}");
}

/// The common keys are read by every law; a scenario built in code is checked too.
#[test]
fn common_keys_and_scenarios_built_in_code() {
    assert_eq!(COMMON_CONTROL_KEYS, ["law", "dt"]);
    for (law, _) in LAW_KEYS.iter() {
        Scenario::from_toml(&scenario_text(*law, "")).unwrap_or_else(|e| panic!("{law:?}: {e}"));
    }
    let mut s = builtin("vision-12-6").unwrap();
    s.control.law = LawName::Ibvs;
    match s.to_config() {
        Err(SimError::Scenario { key, .. }) => assert_eq!(key.to_string(), "control.gain_rz"),
        other => panic!("expected control.gain_rz to be refused, got {other:?}"),
    }
    s.control.remove_option("gain_rz");
    s.control.remove_option("rz_task");
    s.to_config().expect("IBVS without the invariant law's keys");
    // lens-12-6 gives only keys both laws read: its law can be switched as it is.
    let mut s = builtin("lens-12-6").unwrap();
    s.control.law = LawName::Ibvs;
    s.to_config().expect("lens-12-6 under IBVS");
}
