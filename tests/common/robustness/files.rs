//! Text inputs: calibration files and scenarios, mutated.
//!
//! The properties of tests/robustness_files.rs (and the census of tests/robustness_census.rs).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::robustness::*;
use proptest::prelude::*;

/// One edit of a text: delete a line, replace a number on it, duplicate it, or truncate.
#[derive(Debug, Clone, Copy)]
enum Edit {
    Delete(usize),
    Replace(usize, usize, usize),
    Duplicate(usize),
    Truncate(usize),
}

fn edits() -> impl Strategy<Value = Vec<Edit>> {
    let edit = prop_oneof![
        1 => any::<usize>().prop_map(Edit::Delete),
        4 => (any::<usize>(), 0usize..8, any::<usize>()).prop_map(|(l, n, r)| Edit::Replace(l, n, r)),
        1 => any::<usize>().prop_map(Edit::Duplicate),
        1 => any::<usize>().prop_map(Edit::Truncate),
    ];
    prop::collection::vec(edit, 0..4)
}

const REPLACEMENTS: &[&str] = &[
    "nan",
    "-nan",
    ".nan",
    "inf",
    "-inf",
    "-.inf",
    "-1",
    "0",
    "-0.0",
    "1e400",
    "1e300",
    "1e-300",
    "text",
    "\"text\"",
    "[]",
    "true",
    "9223372036854775807",
    "-9223372036854775808",
    "99999999999999999999",
    "",
];

/// The byte ranges of the numbers of a line.
fn numbers(line: &str) -> Vec<(usize, usize)> {
    let b = line.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts = b[i].is_ascii_digit() && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_'));
        if !starts {
            i += 1;
            continue;
        }
        let start = if i > 0 && b[i - 1] == b'-' { i - 1 } else { i };
        while i < b.len() && (b[i].is_ascii_digit() || b".eE+-".contains(&b[i])) {
            i += 1;
        }
        out.push((start, i));
    }
    out
}

fn mutate(text: &str, edits: &[Edit]) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    for &e in edits {
        if lines.is_empty() {
            break;
        }
        let n = lines.len();
        match e {
            Edit::Delete(l) => {
                lines.remove(l % n);
            }
            Edit::Duplicate(l) => lines.insert(l % n, lines[l % n].clone()),
            Edit::Replace(l, k, r) => {
                let line = &mut lines[l % n];
                if let Some(&(a, b)) = numbers(line).get(k) {
                    line.replace_range(a..b, REPLACEMENTS[r % REPLACEMENTS.len()]);
                }
            }
            Edit::Truncate(at) => {
                let mut text = lines.join("\n");
                let mut cut = at % (text.len() + 1);
                while !text.is_char_boundary(cut) {
                    cut -= 1;
                }
                text.truncate(cut);
                lines = text.lines().map(str::to_string).collect();
            }
        }
    }
    lines.join("\n")
}

pub fn prop_calibration(cases: u32) {
    run(cases, (0..CALIBRATION_FILES.len(), edits()), |(i, e)| {
        let text = mutate(CALIBRATION_FILES[i], &e);
        let r = vsinv::calibration::parse_calibration(&text, "fuzz.yaml");
        check("calibration::parse_calibration", &r, |c| {
            finite(c.intrinsics.matrix().iter())
                && finite(c.distortion.coefficients())
                && c.image_size.is_none_or(|(w, h)| w > 0 && h > 0)
        })?;
        if let Err(e) = &r {
            prop_assert!(e.to_string().contains("fuzz.yaml"), "{e} does not name the file");
        }
        Ok(())
    });
}

pub fn prop_scenario(cases: u32) {
    let names = vsinv::sim::scenario::BUILTIN;
    run(cases, (0..names.len(), edits(), prop::bool::weighted(0.25)), |(i, e, simulate)| {
        let text = mutate(names[i].1, &e);
        let r = vsinv::sim::Scenario::from_toml(&text);
        check("Scenario::from_toml", &r, |_| true)?;
        let Ok(scenario) = r else { return Ok(()) };
        let config = scenario.to_config();
        check("Scenario::to_config", &config, |c| c.dt > 0.0 && c.dt.is_finite())?;
        let Ok(mut config) = config else { return Ok(()) };
        if simulate {
            config.stop.max_iterations = 3;
            let out = vsinv::sim::simulate(&config, &mut |_, _| true);
            check("sim::simulate (3 iterations)", &out, |o| {
                let s = &o.summary;
                s.iterations <= 3 && s.final_translation_error.is_finite() && s.final_rotation_error.is_finite()
            })?;
        }
        Ok(())
    });
}
