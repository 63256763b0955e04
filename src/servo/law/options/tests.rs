use super::*;
use crate::core::control::InvariantControllerConfig;
use crate::core::ibvs::Interaction;
use crate::core::rz_task::RzTask;
use crate::servo::Law;

/// The table's defaults are the core's own defaults: a law built from no option is the
/// configuration the core builds by default.
#[test]
fn defaults_are_the_cores() {
    let none = LawOptions::new();
    assert_eq!(Law::from_options("invariant", &none).unwrap(), Law::Invariant(InvariantControllerConfig::default()));
    let ibvs = Law::Ibvs { gain: 1.0, interaction: Interaction::default(), adaptive_gain: None, twist_limits: None };
    assert_eq!(Law::from_options("ibvs", &none).unwrap(), ibvs);
    assert_eq!(Law::from_options("none", &none).unwrap(), Law::Observe);
}

#[test]
fn names_are_unique_and_laws_known() {
    for (i, o) in LAW_OPTIONS.iter().enumerate() {
        let before = &LAW_OPTIONS[..i];
        assert!(before.iter().all(|p| p.name != o.name), "{} twice", o.name);
        let key = o.scenario_key();
        assert!(key.is_none() || before.iter().all(|p| p.scenario_key() != key), "{key:?} twice");
        assert!(!o.laws.is_empty() && o.laws.iter().all(|l| LAWS.contains(l)), "{}: {:?}", o.name, o.laws);
        assert_eq!(o.range.is_some(), o.kind == OptionKind::Number, "{}: a range for numbers only", o.name);
        assert!(!o.doc.is_empty(), "{}", o.name);
    }
}

/// Each default is a value the option accepts, of its kind.
#[test]
fn defaults_are_valid_values() {
    for o in LAW_OPTIONS {
        let value = match (o.kind, o.default) {
            (OptionKind::Number, OptionDefault::Number(v)) => OptionValue::Number(v),
            (OptionKind::Flag, OptionDefault::Flag(v)) => OptionValue::Flag(v),
            (OptionKind::Choice(_), OptionDefault::Choice(c)) => OptionValue::Choice(c.into()),
            (_, OptionDefault::Unset) => continue,
            other => panic!("{}: default {other:?} of another kind", o.name),
        };
        o.check(&value).unwrap_or_else(|e| panic!("{}: {e}", o.name));
    }
}

#[test]
fn ranges_take_their_ends_as_declared() {
    let cases = [
        (Range::POSITIVE, [(0.0, false), (1e-300, true), (f64::INFINITY, false), (f64::NAN, false), (-1.0, false)]),
        (Range::NON_NEGATIVE, [(0.0, true), (-1e-300, false), (f64::INFINITY, false), (f64::NAN, false), (3.0, true)]),
        (
            Range::POSITIVE_OR_INFINITE,
            [(0.0, false), (f64::INFINITY, true), (f64::NAN, false), (2.0, true), (-2.0, false)],
        ),
    ];
    for (range, values) in cases {
        for (v, inside) in values {
            assert_eq!(range.contains(v), inside, "{} contains {v}", range.interval());
        }
    }
    assert_eq!(Range::POSITIVE.requirement(), "must be finite and > 0");
    assert_eq!(Range::NON_NEGATIVE.requirement(), "must be finite and >= 0");
    assert_eq!(Range::POSITIVE_OR_INFINITE.requirement(), "must be > 0");
    assert_eq!(Range::POSITIVE_OR_INFINITE.interval(), "(0, inf]");
}

/// A value out of range, of another kind, or an unknown choice is refused naming the option.
#[test]
fn bad_values_are_refused_by_name() {
    let mut o = LawOptions::new();
    for (name, value) in [
        ("gain", OptionValue::Number(0.0)),
        ("gain_rz", OptionValue::Number(f64::NAN)),
        ("min_structure_ratio", OptionValue::Number(-1e-9)),
        ("max_linear_speed", OptionValue::Number(-0.1)),
        ("rz_task", OptionValue::Choice("spin".into())),
        ("feedforward", OptionValue::Number(1.0)),
    ] {
        match o.set(name, value) {
            Err(Error::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
            other => panic!("{name}: {other:?}"),
        }
    }
    let bad_gain = AdaptiveGain { at_zero: 1.0, at_infinity: 2.0, slope_at_zero: 1.0 };
    match o.set("adaptive_gain", OptionValue::AdaptiveGain(bad_gain)) {
        Err(Error::InvalidParameter { name, .. }) => assert_eq!(name, "adaptive_gain.at_infinity"),
        other => panic!("{other:?}"),
    }
    assert!(o.given().next().is_none(), "nothing refused is kept");
}

/// Given options reach the law's configuration; an option of another law is refused.
#[test]
fn given_options_reach_the_law() {
    let mut o = LawOptions::new();
    o.set("gain", OptionValue::Number(0.5)).unwrap();
    o.set("gain_rz", OptionValue::Number(2.0)).unwrap();
    o.set("rz_task", OptionValue::Choice("tau21".into())).unwrap();
    o.set("max_angular_speed", OptionValue::Number(0.25)).unwrap();
    let Law::Invariant(c) = Law::from_options("invariant", &o).unwrap() else { panic!("not invariant") };
    assert_eq!((c.gain, c.gain_rz, c.rz_task), (0.5, 2.0, RzTask::Tau21));
    let limits = c.twist_limits.unwrap();
    assert_eq!((limits.linear, limits.angular), (f64::INFINITY, 0.25));
    match Law::from_options("ibvs", &o) {
        Err(Error::InvalidParameter { name, reason }) => {
            assert_eq!(name, "gain_rz");
            assert!(reason.contains("\"ibvs\""), "{reason}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn the_markdown_table_has_a_row_per_option() {
    let md = markdown_table();
    assert_eq!(md.lines().count(), LAW_OPTIONS.len() + 2);
    for o in LAW_OPTIONS {
        assert!(md.contains(&format!("| `{}` |", o.name)), "{}", o.name);
    }
    assert!(md.contains("`max_angular_speed_deg` (deg/s)"), "{md}");
}

/// Every choice the table offers is one the law's own parser reads (`RzTask`, `Interaction`).
#[test]
fn every_choice_builds_its_law() {
    for o in LAW_OPTIONS {
        let OptionKind::Choice(names) = o.kind else { continue };
        for name in names {
            let mut given = LawOptions::new();
            given.set(o.name, OptionValue::Choice((*name).into())).unwrap();
            for law in o.laws {
                Law::from_options(law, &given).unwrap_or_else(|e| panic!("{} = {name} under {law}: {e}", o.name));
            }
        }
    }
}
