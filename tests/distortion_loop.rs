//! Lens distortion in the loop: the simulator projects (and renders) through the servo lens's
//! distortion, the controller is fed undistorted points, and camera tables read calibration
//! files.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use vsinv::sim::SimError;
use vsinv::sim::scenario::{Scenario, builtin};
use vsinv::sim::{Status, Summary, simulate};

fn run(scenario: &Scenario) -> Summary {
    let s = simulate(&scenario.to_config().unwrap(), &mut |_, _| true).unwrap().summary;
    println!(
        "{}: {} after {} iterations, {:.3} mm, {:.4} deg{}",
        scenario.name,
        s.status.as_str(),
        s.iterations,
        s.final_translation_error * 1e3,
        s.final_rotation_error.to_degrees(),
        s.detection_error.map_or(String::new(), |(m, x)| format!(", detection error {m:.3}/{x:.3} px")),
    );
    s
}

/// `lens-12-6-barrel` with the controller unaware of the distortion.
fn unknown_distortion() -> Scenario {
    let text = builtin("lens-12-6-barrel").unwrap().to_toml().unwrap();
    let text = text.replace(
        "[start]",
        "[estimate]\nfku = 600.0\nfkv = 600.0\nu0 = 416.0\nv0 = 312.0\ndistortion = [0.0, 0.0, 0.0, 0.0, 0.0]\n\n[start]",
    );
    Scenario::from_toml(&text).unwrap()
}

#[test]
fn strong_barrel_distortion_known_converges_within_1mm_and_0_1_degree() {
    let scenario = builtin("lens-12-6-barrel").unwrap();
    let config = scenario.to_config().unwrap();
    assert!(!config.camera.distortion.is_identity() && config.estimate_distortion == config.camera.distortion);
    let s = run(&scenario);
    assert_eq!(s.status, Status::Converged, "{}", s.message);
    assert!(s.final_translation_error < 1e-3 && s.final_rotation_error.to_degrees() < 0.1);
}

#[test]
fn unknown_distortion_is_never_reported_converged() {
    let s = run(&unknown_distortion());
    assert_ne!(s.status, Status::Converged, "{}", s.message);
    // It settles where the distorted invariants are closest to the reference ones: centimetres away.
    assert!(s.final_translation_error > 5e-3, "{}", s.final_translation_error);
}

#[test]
fn distortion_through_images_converges() {
    // K_hat is the calibration: undistorting with a wrong K (vision-12-6's estimate) leaves the
    // points off the pinhole model, and the run stops about 1 degree away.
    let text = without_table(&builtin("vision-12-6").unwrap().to_toml().unwrap(), "[estimate]");
    let text = text.replacen("[camera]\n", "[camera]\ndistortion = [-0.30, 0.10, 0.0005, -0.0008, -0.02]\n", 1);
    let scenario = Scenario::from_toml(&text).unwrap();
    assert!(!scenario.to_config().unwrap().camera.distortion.is_identity());
    let s = run(&scenario);
    assert_eq!(s.status, Status::Converged, "{}", s.message);
    assert!(s.final_translation_error < 2e-3 && s.final_rotation_error.to_degrees() < 0.2);
}

/// TOML text without one of its tables.
fn without_table(text: &str, header: &str) -> String {
    let start = text.find(header).unwrap();
    let end = start + text[start..].find("\n[").unwrap() + 1;
    format!("{}{}", &text[..start], &text[end..])
}

/// A scratch directory of this test process.
fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("vsinv-distortion-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

const BARREL_OPENCV_YAML: &str = "%YAML:1.0
---
image_width: 832
image_height: 624
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 600., 0., 416., 0., 600., 312., 0., 0., 1. ]
distortion_coefficients: !!opencv-matrix
   rows: 1
   cols: 5
   dt: d
   data: [ -0.30, 0.10, 0.0005, -0.0008, -0.02 ]
";

/// `lens-12-6-barrel` with its `[camera]` table replaced by `camera_table`, written next to
/// the calibration file.
fn with_camera_table(dir: &std::path::Path, camera_table: &str) -> Result<Scenario, SimError> {
    std::fs::write(dir.join("barrel.yaml"), BARREL_OPENCV_YAML).unwrap();
    let text = without_table(&builtin("lens-12-6-barrel").unwrap().to_toml().unwrap(), "[camera]");
    let path = dir.join("scenario.toml");
    std::fs::write(&path, format!("{text}\n{camera_table}")).unwrap();
    Scenario::from_toml_file(&path)
}

#[test]
fn a_calibration_file_gives_the_same_run_as_its_numbers() {
    let dir = scratch("file");
    let from_file = with_camera_table(&dir, "[camera]\ncalibration = \"barrel.yaml\"\n").unwrap();
    let numbers = builtin("lens-12-6-barrel").unwrap();
    let (a, b) = (from_file.to_config().unwrap(), numbers.to_config().unwrap());
    assert_eq!(a.camera, b.camera);
    assert_eq!(a.estimate_distortion, b.estimate_distortion);
    let (sa, sb) = (run(&from_file), run(&numbers));
    assert_eq!((sa.status, sa.iterations), (sb.status, sb.iterations));
    assert_eq!(sa.final_translation_error, sb.final_translation_error);
}

#[test]
fn calibration_errors_name_the_key() {
    let dir = scratch("errors");
    let key_of = |table: &str| match with_camera_table(&dir, table) {
        Err(SimError::Scenario { key, reason }) => (key.to_string(), reason),
        other => panic!("{other:?}"),
    };
    let (key, reason) = key_of("[camera]\ncalibration = \"barrel.yaml\"\nfku = 600.0\n");
    assert_eq!(key, "camera.fku", "{reason}");
    let (key, reason) = key_of("[camera]\ncalibration = \"missing.yaml\"\n");
    assert_eq!(key, "camera.calibration");
    assert!(reason.contains("missing.yaml"), "{reason}");
    let (key, _) = key_of("[camera]\ncalibration = \"barrel.yaml\"\nskew_deg = 80.0\n");
    assert_eq!(key, "camera.skew_deg");
    let (key, reason) = key_of("[camera]\nfkv = 600.0\nu0 = 416.0\nv0 = 312.0\n");
    assert_eq!(key, "camera.fku", "{reason}");
    let (key, _) = key_of("[camera]\nfku = 600.0\nfkv = 600.0\nu0 = 416.0\nv0 = 312.0\ndistortion = [0.1, 0.0, 0.0]\n");
    assert_eq!(key, "camera.distortion");
    let (key, _) =
        key_of("[camera]\nfku = 600.0\nfkv = 600.0\nu0 = 416.0\nv0 = 312.0\ndistortion = [0.1, nan, 0.0, 0.0]\n");
    assert_eq!(key, "camera.distortion[1]");
    let (key, reason) = key_of(
        "[camera]\nfku = 600.0\nfkv = 600.0\nu0 = 416.0\nv0 = 312.0\ndistortion = [0.1, 0.0, 0.0, 0.0]\nzoom = { times = [0.0, 1.0], fku = [600.0, 500.0], fkv = [600.0, 500.0] }\n",
    );
    assert!(key == "camera" && reason.contains("distortion"), "{key}: {reason}");
}

/// The fisheye camera table of `lens-12-fisheye` with other numbers.
fn fisheye_table(extra: &str) -> String {
    format!("[camera]\nfku = 300.0\nfkv = 300.0\nu0 = 416.0\nv0 = 312.0\nwidth = 832\nheight = 624\n{extra}")
}

#[test]
fn a_fisheye_lens_known_converges_with_the_invariant_law() {
    let scenario = builtin("lens-12-fisheye").unwrap();
    let config = scenario.to_config().unwrap();
    assert_eq!(config.camera.distortion.model(), vsinv::core::distortion::DistortionModel::Equidistant);
    assert_eq!(config.estimate_distortion, config.camera.distortion);
    let s = run(&scenario);
    assert_eq!(s.status, Status::Converged, "{}", s.message);
    assert!(s.final_translation_error < 1e-3 && s.final_rotation_error.to_degrees() < 0.1);
    // Fed the fisheye's pixels as if they were a pinhole's, the law settles centimetres away.
    let text = scenario.to_toml().unwrap().replace(
        "[start]",
        "[estimate]\nfku = 300.0\nfkv = 300.0\nu0 = 416.0\nv0 = 312.0\ndistortion = [0.0, 0.0, 0.0, 0.0]\n\n[start]",
    );
    let s = run(&Scenario::from_toml(&text).unwrap());
    assert_ne!(s.status, Status::Converged, "{}", s.message);
    assert!(s.final_translation_error > 5e-3, "{}", s.final_translation_error);
}

#[test]
fn a_fisheye_lens_through_images_converges() {
    // vision-12-6 with its servo camera a fisheye (f = 450 px, so that the 3 mm dots stay
    // about 2 px wide): the simulator renders through the lens, the tracker follows the dots,
    // and the session undistorts them with the calibration.
    let text = without_table(&builtin("vision-12-6").unwrap().to_toml().unwrap(), "[estimate]");
    let camera = "[camera]\nfku = 450.0\nfkv = 450.0\nu0 = 416.0\nv0 = 312.0\nwidth = 832\nheight = 624\n\
                  distortion = [-0.04, 0.01, -0.003, 0.0005]\ndistortion_model = \"equidistant\"\n\n";
    let text = without_table(&text, "[camera]").replacen("[start]", &format!("{camera}[start]"), 1);
    let scenario = Scenario::from_toml(&text).unwrap();
    assert_eq!(scenario.to_config().unwrap().camera.distortion.coefficients(), &[-0.04, 0.01, -0.003, 0.0005]);
    let s = run(&scenario);
    assert_eq!(s.status, Status::Converged, "{}", s.message);
    assert!(s.final_translation_error < 2e-3 && s.final_rotation_error.to_degrees() < 0.2);
}

#[test]
fn fisheye_keys_are_checked_naming_the_key() {
    let dir = scratch("fisheye");
    let key_of = |extra: &str| match with_camera_table(&dir, &fisheye_table(extra)) {
        Err(vsinv::sim::SimError::Scenario { key, reason }) => (key.to_string(), reason),
        other => panic!("{other:?}"),
    };
    let (key, reason) = key_of("distortion = [0.1, 0.0, 0.0, 0.0, 0.0]\ndistortion_model = \"equidistant\"\n");
    assert_eq!(key, "camera.distortion");
    assert!(reason.contains("equidistant model takes 4"), "{reason}");
    let (key, _) = key_of("distortion = [0.1, nan, 0.0, 0.0]\ndistortion_model = \"equidistant\"\n");
    assert_eq!(key, "camera.distortion[1]");
    let (key, reason) = key_of("distortion = [0.1, 0.0, 0.0, 0.0]\ndistortion_model = \"fisheye\"\n");
    assert_eq!(key, "camera.distortion_model");
    assert!(reason.contains("unknown distortion model \"fisheye\"") && reason.contains("equidistant"), "{reason}");
    let (key, reason) = key_of("distortion_model = \"equidistant\"\n");
    assert_eq!(key, "camera.distortion_model");
    assert!(reason.contains("needs camera.distortion"), "{reason}");
    let (key, _) = match with_camera_table(
        &dir,
        "[camera]\ncalibration = \"barrel.yaml\"\ndistortion_model = \"equidistant\"\n",
    ) {
        Err(vsinv::sim::SimError::Scenario { key, reason }) => (key.to_string(), reason),
        other => panic!("{other:?}"),
    };
    assert_eq!(key, "camera.distortion_model");
    // A fisheye calibration file is read as one.
    std::fs::write(
        dir.join("fisheye.yaml"),
        "image_width: 832\nimage_height: 624\ncamera_matrix: {rows: 3, cols: 3, data: [300, 0, 416, 0, 300, 312, 0, 0, 1]}\n\
         distortion_model: equidistant\ndistortion_coefficients: {rows: 1, cols: 4, data: [-0.04, 0.01, -0.003, 0.0005]}\n",
    )
    .unwrap();
    let from_file = with_camera_table(&dir, "[camera]\ncalibration = \"fisheye.yaml\"\n").unwrap();
    assert_eq!(from_file.to_config().unwrap().camera, builtin("lens-12-fisheye").unwrap().to_config().unwrap().camera);
}
