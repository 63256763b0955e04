//! Every law option of the servo layer's table is a scenario key of the laws that read it:
//! accepted in its range and reaching the law's configuration (in radians under a `_deg`
//! key), refused out of it with an error naming the key. Nothing here lists the options: a
//! new entry of the table is tested as it is added.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use vsinv::servo::Law;
use vsinv::servo::law::options::{
    LAW_OPTIONS, LawOptions, OptionDefault, OptionKind, OptionSpec, OptionValue, ScenarioKey,
};
use vsinv::sim::SimError;
use vsinv::sim::scenario::{BUILTIN, Scenario};

/// A value in the option's range (TOML text, and the value in the option's own unit).
fn valid(o: &OptionSpec) -> (String, OptionValue) {
    match (o.kind, o.default) {
        (OptionKind::Number, _) => {
            let r = o.range.unwrap();
            let v = if r.min.is_finite() { r.min + 0.75 } else { 0.75 };
            let given = if matches!(o.scenario, ScenarioKey::Degrees(_)) { v.to_radians() } else { v };
            (format!("{v:?}"), OptionValue::Number(given))
        }
        (OptionKind::Flag, OptionDefault::Flag(d)) => (format!("{}", !d), OptionValue::Flag(!d)),
        (OptionKind::Flag, _) => ("true".into(), OptionValue::Flag(true)),
        (OptionKind::Choice(names), _) => {
            let last = names[names.len() - 1];
            (format!("{last:?}"), OptionValue::Choice(last.into()))
        }
        (OptionKind::AdaptiveGain, _) => {
            let g = vsinv::core::adaptive_gain::AdaptiveGain { at_zero: 4.0, at_infinity: 0.4, slope_at_zero: 30.0 };
            ("{ at_zero = 4.0, at_infinity = 0.4, slope_at_zero = 30.0 }".into(), OptionValue::AdaptiveGain(g))
        }
    }
}

/// Values the option refuses, as TOML text.
fn invalid(o: &OptionSpec) -> Vec<String> {
    match o.kind {
        OptionKind::Number => {
            let r = o.range.unwrap();
            let below = if r.min_open { r.min } else { r.min - 1.0 };
            vec![format!("{below:?}"), "nan".into()]
        }
        OptionKind::Flag => vec!["\"yes\"".into()],
        OptionKind::Choice(_) => vec!["\"bogus\"".into()],
        OptionKind::AdaptiveGain => vec!["{ at_zero = 1.0, at_infinity = 2.0, slope_at_zero = 3.0 }".into()],
    }
}

/// lens-12-6 with its `[control]` table replaced by `law` and `extra`.
fn scenario_text(law: &str, extra: &str) -> String {
    let text = BUILTIN.iter().find(|(n, _)| *n == "lens-12-6").unwrap().1;
    let (head, rest) = text.split_once("[control]\n").unwrap();
    let tail = &rest[rest.find("\n[").unwrap()..];
    format!("{head}[control]\nlaw = \"{law}\"\ndt = 0.04\n{extra}\n{tail}")
}

#[test]
fn every_scenario_key_takes_its_range_and_reaches_the_law() {
    let mut checked = 0;
    for o in LAW_OPTIONS {
        let Some(key) = o.scenario_key() else { continue };
        for law in o.laws {
            let (text, value) = valid(o);
            let scenario = Scenario::from_toml(&scenario_text(law, &format!("{key} = {text}")))
                .unwrap_or_else(|e| panic!("{key} = {text} under {law}: {e}"));
            let mut expected = LawOptions::new();
            expected.set(o.name, value).unwrap();
            let law_given = scenario.to_config().unwrap().law;
            assert_eq!(law_given, Law::from_options(law, &expected).unwrap(), "{key} = {text} under {law}");
            for bad in invalid(o) {
                match Scenario::from_toml(&scenario_text(law, &format!("{key} = {bad}"))) {
                    Err(SimError::Scenario { key: at, reason }) => {
                        assert!(at.to_string().starts_with(&format!("control.{key}")), "{key} = {bad}: {at}: {reason}")
                    }
                    other => panic!("{key} = {bad} under {law}: expected a scenario error, got {other:?}"),
                }
            }
            checked += 1;
        }
    }
    assert!(checked >= LAW_OPTIONS.len(), "{checked} (option, law) pairs");
}

/// The option the scenario files do not take is still a documented decision of the table.
#[test]
fn options_without_a_key_say_so() {
    for o in LAW_OPTIONS.iter().filter(|o| o.scenario == ScenarioKey::Absent) {
        let text = scenario_text(o.laws[0], &format!("{} = {}", o.name, valid(o).0));
        assert!(Scenario::from_toml(&text).is_err(), "{} is refused as an unknown key", o.name);
    }
}
