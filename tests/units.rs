//! The units convention (docs/reference/conventions.md): SI everywhere, and in scenario files
//! angles in degrees only under keys whose names end in `_deg`; joint vectors, which mix
//! degrees (revolute joints) and metres (prismatic ones) joint by joint, are the stated
//! exception. Checked over every key of the schema as the "Scenario files" page describes it
//! (`readme::readme_scenario_block`, which `readme::readme_scenario_block_names_every_key`
//! holds to name every key), commented-out keys included.

use super::readme::readme_scenario_block;

/// The joint vectors of `[robot]`: degrees or metres per joint (the stated exception).
const JOINT_KEYS: [&str; 5] = ["joint_min", "joint_max", "joint_velocity", "joints", "ik_seed"];

/// One `key = value  # comment` of the block, with the comment lines that continue it.
struct KeyLine {
    key: String,
    value: String,
    comment: String,
}

fn key_lines(block: &str) -> Vec<KeyLine> {
    let mut out: Vec<KeyLine> = Vec::new();
    for line in block.lines() {
        let text = line.trim_start().trim_start_matches('#').trim_start();
        let (code, comment) = text.split_once(" #").map_or((text, ""), |(c, m)| (c, m.trim()));
        let key = code
            .split_once('=')
            .map(|(k, _)| k.trim())
            .filter(|k| k.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_') && !k.is_empty());
        match key {
            Some(k) => out.push(KeyLine {
                key: k.into(),
                value: code.split_once('=').map_or("", |(_, v)| v).trim().into(),
                comment: comment.into(),
            }),
            // A line of comment only, indented past the keys: it continues the last key's comment.
            None if line.starts_with("    ") && line.trim_start().starts_with('#') => {
                if let Some(last) = out.last_mut() {
                    last.comment.push(' ');
                    last.comment.push_str(line.trim_start().trim_start_matches('#').trim());
                }
            }
            None => {}
        }
    }
    out
}

fn numeric(value: &str) -> bool {
    value.trim_start_matches('[').starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '.')
}

fn says_degrees(comment: &str) -> bool {
    comment.split(|c: char| !c.is_ascii_alphabetic()).any(|w| w == "deg" || w == "degrees" || w == "degree")
}

fn says_radians(comment: &str) -> bool {
    comment.split(|c: char| !c.is_ascii_alphabetic()).any(|w| w == "rad" || w == "radians" || w == "radian")
}

#[test]
fn scenario_angles_are_degrees_under_deg_keys_only() {
    let lines = key_lines(&readme_scenario_block());
    assert!(lines.len() > 80, "the block's keys were not read: {}", lines.len());
    for l in lines.iter().filter(|l| numeric(&l.value)) {
        let joint = JOINT_KEYS.contains(&l.key.as_str());
        if says_degrees(&l.comment) {
            assert!(
                l.key.ends_with("_deg") || joint,
                "{} is in degrees but its key does not end in _deg: {}",
                l.key,
                l.comment
            );
        }
        assert!(!says_radians(&l.comment), "{} is in radians in a scenario file: {}", l.key, l.comment);
    }
    // Each _deg key is described as degrees where the block describes it.
    for l in lines.iter().filter(|l| l.key.ends_with("_deg")) {
        let described = lines.iter().any(|m| m.key == l.key && says_degrees(&m.comment));
        assert!(described, "{} ends in _deg but is never described as degrees", l.key);
    }
    // The exception is the joint vectors, each described, and stated by the conventions.
    for key in JOINT_KEYS {
        assert!(lines.iter().any(|l| l.key == key), "{key} not in the block");
    }
    let conventions = include_str!("../docs/reference/conventions.md");
    assert!(conventions.contains("joint values are degrees for revolute joints and metres for prismatic ones"));
    assert!(conventions.contains("Scenario files give angles in degrees, and their keys say so"));
}

#[test]
fn the_checks_can_fail() {
    let bad = "[x]\nyaw = 30.0                      # degrees\nspin = 1.0   # rad/s\nok_deg = 2.0  # degrees\n";
    let lines = key_lines(bad);
    let yaw = lines.iter().find(|l| l.key == "yaw").unwrap();
    assert!(says_degrees(&yaw.comment) && !yaw.key.ends_with("_deg"));
    assert!(says_radians(&lines.iter().find(|l| l.key == "spin").unwrap().comment));
    assert!(!says_degrees("metres, F*") && !says_radians("a radius, metres"));
}
