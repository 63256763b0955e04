//! Deep nesting in every reader (issue 28, finding 2): a URDF of 20,000 nested elements (a
//! 140 KB file) overflowed the stack of the URDF parser and killed the process, and 200,000
//! levels ran past 30 s. Every reader (URDF, calibration YAML and XML, scenario TOML and
//! JSON) must refuse deep nesting with the package's error, quickly, naming the limit and
//! never quoting the file. The tests run on a 2 MiB thread stack (Rust's default for test
//! threads), so a reader that recurses per level would crash the test binary.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::time::{Duration, Instant};

use vsinv::calibration::CalibrationError;
use vsinv::calibration::load_calibration;
use vsinv::sim::SimError;
use vsinv::sim::arm::{ArmModel, MAX_URDF_DEPTH, MAX_URDF_NODES};
use vsinv::sim::scenario::Scenario;

const SECRET: &str = "SECRETMARKER0123456789";
const HANG_BOUND: Duration = Duration::from_secs(5);

fn nested_urdf(levels: usize) -> String {
    format!(
        "<?xml version=\"1.0\"?>\n<robot name=\"r\"><link name=\"base\">{}{SECRET}{}</link></robot>\n",
        "<x>".repeat(levels),
        "</x>".repeat(levels)
    )
}

/// Runs `f` on a thread of a 2 MiB stack; its error's text and the seconds taken.
fn refused<T: Send + 'static, E: Send + 'static>(f: impl FnOnce() -> Result<T, E> + Send + 'static) -> (E, Duration) {
    let t = Instant::now();
    let out = std::thread::Builder::new().stack_size(2 << 20).spawn(f).unwrap().join().unwrap();
    let Err(e) = out else { panic!("accepted") };
    (e, t.elapsed())
}

fn assert_refused(e: &impl std::fmt::Display, took: Duration, needle: &str) {
    let text = e.to_string();
    assert!(text.contains(needle), "{text}");
    assert!(!text.contains(SECRET), "the error quotes the file: {text}");
    assert!(took < HANG_BOUND, "{took:?}: {text}");
}

#[test]
fn deeply_nested_urdf_is_refused_at_every_size() {
    for levels in [MAX_URDF_DEPTH, 20_000, 200_000] {
        let text = nested_urdf(levels);
        let (e, took) = refused(move || ArmModel::from_urdf_str(&text, "base"));
        assert!(matches!(e, SimError::Urdf { .. }), "{e}");
        // Past the node limit, the node count is what refuses it first.
        let limit = if 2 * levels + 4 > MAX_URDF_NODES as usize { "XML nodes" } else { "nested more than 64 deep" };
        assert_refused(&e, took, limit);
        assert_refused(&e, took, "(the limit of a URDF's");
    }
}

#[test]
fn deeply_nested_urdf_file_is_refused() {
    let dir = std::env::temp_dir().join(format!("vsinv-nesting-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("deep.urdf");
    std::fs::write(&path, nested_urdf(20_000)).unwrap();
    let p = path.clone();
    let (e, took) = refused(move || ArmModel::from_urdf_file(&p, "base"));
    assert_refused(&e, took, "deep.urdf");
    assert_refused(&e, took, "(the limit of a URDF's nesting)");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn urdf_element_count_is_bounded() {
    // Flat, well under the 8 MiB limit, but over the node limit: refused before parsing.
    let text = format!("<robot name=\"r\"><link name=\"base\"/>{}</robot>", "<x/>".repeat(MAX_URDF_NODES as usize));
    assert!(text.len() < 1 << 20);
    let (e, took) = refused(move || ArmModel::from_urdf_str(&text, "base"));
    assert_refused(&e, took, &format!("more than {MAX_URDF_NODES} XML nodes"));
}

#[test]
fn urdf_at_the_limits_still_parses() {
    // A real arm with extra elements nested to the limit and padding up to near the node count.
    let ur5 = vsinv::sim::arm::builtin_urdf("ur5").unwrap();
    let deep = format!("<gazebo>{}{}</gazebo>", "<x>".repeat(MAX_URDF_DEPTH - 2), "</x>".repeat(MAX_URDF_DEPTH - 2));
    let pad = "<gazebo/>".repeat(MAX_URDF_NODES as usize / 4);
    let text = ur5.replacen("</robot>", &format!("{deep}{pad}</robot>"), 1);
    let t = Instant::now();
    let arm = ArmModel::from_urdf_str(&text, "tool0").unwrap();
    assert_eq!(arm.dof(), 6);
    assert!(t.elapsed() < HANG_BOUND, "{:?}", t.elapsed());
}

fn temp_file(name: &str, text: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("vsinv-nesting-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn calibration_readers_refuse_deep_nesting() {
    let n = 200_000;
    let cases = [
        ("seq.yaml", format!("image_width: 640\nx: {}{SECRET}{}\n", "[".repeat(n), "]".repeat(n))),
        ("map.yaml", format!("image_width: 640\nx: {}{SECRET}{}\n", "{a: ".repeat(n), "}".repeat(n))),
        ("deep.xml", format!("<opencv_storage>{}{SECRET}{}</opencv_storage>", "<x>".repeat(n), "</x>".repeat(n))),
    ];
    for (name, text) in cases {
        let text: String = text.chars().take(1 << 20).collect(); // within the size limit
        let path = temp_file(name, &text);
        let (e, took) = refused(move || load_calibration(&path));
        assert!(matches!(e, CalibrationError::File { .. }), "{name}: {e}");
        assert_refused(&e, took, name);
    }
}

#[test]
fn scenario_readers_refuse_deep_nesting() {
    let n = 1_000_000;
    let toml_arrays = format!("name = 'x'\nq = {}{}\n", "[".repeat(n), "]".repeat(n));
    let toml_tables = format!("name = 'x'\nq = {}1{}\n", "{a=".repeat(n), "}".repeat(n));
    // Every key is known or refused, so deep values are refused at their key or by serde_json's
    // recursion limit (128): either way an error, quickly, without a crash.
    let json = format!("{{\"name\": \"x\", \"object\": {{\"points\": {}{}}}}}", "[".repeat(n), "]".repeat(n));
    for text in [toml_arrays, toml_tables] {
        let (e, took) = refused(move || Scenario::from_toml(&text));
        assert_refused(&e, took, "recurs");
    }
    let (e, took) = refused(move || Scenario::config_from_json(&json));
    assert_refused(&e, took, "object.points");
}
