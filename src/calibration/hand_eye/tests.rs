//! Hand-eye calibration against exact data (the closed form: `X` back to rounding), and
//! the refusals.

use nalgebra::{Isometry3, Matrix4, Vector3};

use super::*;
use crate::calibration::error::CalibrationError;
use crate::error::Located;
use HandEyeSetup::{EyeInHand, EyeToHand};

/// The true camera-to-gripper transform of the tests.
fn truth() -> Isometry3<f64> {
    Isometry3::new(Vector3::new(0.04, -0.03, 0.11), Vector3::new(0.2, -0.4, 1.1))
}

/// `n` stations with gripper rotations about varied axes (deterministic), and the exact
/// target poses they imply for `x`.
fn stations(n: usize, x: &Isometry3<f64>) -> (Vec<Matrix4<f64>>, Vec<Matrix4<f64>>) {
    let target_in_base = Isometry3::new(Vector3::new(0.7, 0.1, -0.05), Vector3::new(0.1, 0.05, 0.3));
    let mut gripper = Vec::new();
    let mut target = Vec::new();
    for k in 0..n {
        let s = k as f64;
        let rotation = Vector3::new((1.3 * s).sin(), (0.7 * s + 1.0).cos(), (2.1 * s).sin() * 0.5) * 0.5;
        let g = Isometry3::new(Vector3::new(0.4 + 0.05 * (s * 0.9).sin(), 0.1 * (s * 1.7).cos(), 0.5), rotation);
        gripper.push(g.to_homogeneous());
        target.push(((g * x).inverse() * target_in_base).to_homogeneous());
    }
    (gripper, target)
}

fn assert_close(found: &Isometry3<f64>, expected: &Isometry3<f64>, tol: f64, what: &str) {
    let diff = (found.to_homogeneous() - expected.to_homogeneous()).amax();
    assert!(diff < tol, "{what}: |X - X_true| = {diff:e}");
}

#[test]
fn every_method_recovers_x_from_exact_poses() {
    let x = truth();
    for n in [3, 4, 8, 20] {
        let (g, c) = stations(n, &x);
        for method in HandEyeMethod::ALL {
            let cal = calibrate_hand_eye(&g, &c, method, EyeInHand).unwrap();
            assert_close(&cal.transform, &x, 1e-10, &format!("{method:?} with {n} poses"));
            assert_eq!(cal.residuals.len(), n * (n - 1) / 2);
            assert!(cal.max_rotation_deg() < 1e-8 && cal.max_translation_m() < 1e-10, "{method:?}");
            assert_eq!(cal.method, method);
        }
    }
}

#[test]
fn agreement_of_exact_data_is_rounding() {
    let (g, c) = stations(10, &truth());
    let agreement = compare_hand_eye_methods(&g, &c, EyeInHand).unwrap();
    assert_eq!(agreement.calibrations.len(), 3);
    assert!(agreement.failures.is_empty());
    assert!(agreement.max_rotation_deg < 1e-8 && agreement.max_translation_m < 1e-10, "{agreement:?}");
}

#[test]
fn residuals_see_a_wrong_station() {
    let (g, mut c) = stations(8, &truth());
    // Station 3's target pose off by 1 degree about z and 5 mm.
    let nudge = Isometry3::new(Vector3::new(0.005, 0.0, 0.0), Vector3::new(0.0, 0.0, 1f64.to_radians()));
    c[3] = nudge.to_homogeneous() * c[3];
    let cal = calibrate_hand_eye(&g, &c, HandEyeMethod::ParkMartin, EyeInHand).unwrap();
    let worst = cal.residuals.iter().max_by(|a, b| a.rotation_deg.total_cmp(&b.rotation_deg)).unwrap();
    assert!(worst.first == 3 || worst.second == 3, "{worst:?}");
    assert!(cal.max_rotation_deg() > 0.3 && cal.max_translation_m() > 1e-3);
}

#[test]
fn axis_spread_is_the_angle_between_two_axes() {
    let about = |axis: Vector3<f64>| {
        let r = nalgebra::Rotation3::from_scaled_axis(axis * 0.5).into_inner();
        motions::Rigid { r, t: Vector3::zeros() }
    };
    let still = motions::Rigid { r: nalgebra::Matrix3::identity(), t: Vector3::zeros() };
    let angle = 30f64.to_radians();
    let axes = [Vector3::x(), Vector3::new(angle.cos(), angle.sin(), 0.0)];
    let m: Vec<Motion> =
        axes.iter().map(|a| Motion { first: 0, second: 1, gripper: about(*a), camera: still }).collect();
    let spread = AxisSpread::of(&m);
    assert!((spread.spread_deg - 30.0).abs() < 1e-9, "{spread:?}");
    assert_eq!(spread.rotating_motions, 2);
    let e = spread.eigenvalues;
    assert!((e.iter().sum::<f64>() - 1.0).abs() < 1e-12 && e[2].abs() < 1e-12, "{e:?}");
    assert!((spread.max_rotation_deg - 0.5f64.to_degrees()).abs() < 1e-9);
}

#[test]
fn too_few_and_mismatched_poses_are_refused() {
    let (g, c) = stations(5, &truth());
    let err = calibrate_hand_eye(&g[..2], &c[..2], HandEyeMethod::TsaiLenz, EyeInHand).unwrap_err();
    assert!(matches!(err, CalibrationError::DegenerateMotion { poses: 2, .. }) && err.is_degenerate(), "{err}");
    let err = calibrate_hand_eye(&g, &c[..4], HandEyeMethod::TsaiLenz, EyeInHand).unwrap_err();
    assert!(matches!(err, CalibrationError::Core(Error::Shape { what: "target_poses", .. })), "{err}");
}

#[test]
fn non_rigid_poses_are_refused_naming_argument_and_index() {
    let (g, c) = stations(5, &truth());
    let cases: [(&str, usize, fn(&mut Matrix4<f64>), &str); 5] = [
        ("gripper_poses", 2, |m| m[(1, 3)] = f64::NAN, "non-finite value at row 1, column 3"),
        ("target_poses", 4, |m| m[(0, 0)] *= 1.01, "not orthonormal"),
        ("target_poses", 1, |m| m[(3, 0)] = 0.5, "last row"),
        ("gripper_poses", 0, |m| m.fixed_view_mut::<1, 3>(2, 0).neg_mut(), "reflection"),
        ("gripper_poses", 3, |m| m[(0, 3)] = 1e300, "beyond"),
    ];
    for (what, index, spoil, words) in cases {
        let (mut g, mut c) = (g.clone(), c.clone());
        spoil(if what == "gripper_poses" { &mut g[index] } else { &mut c[index] });
        let err = calibrate_hand_eye(&g, &c, HandEyeMethod::ParkMartin, EyeInHand).unwrap_err();
        match &err {
            CalibrationError::InvalidPose { what: w, index: i, reason } => {
                assert_eq!((*w, *i), (what, index));
                assert!(reason.contains(words), "{err}");
            }
            _ => panic!("{what}[{index}]: {err}"),
        }
        assert!(!err.is_degenerate());
    }
}

#[test]
fn rotations_about_one_axis_are_refused() {
    let x = truth();
    let target_in_base = Isometry3::new(Vector3::new(0.7, 0.0, 0.0), Vector3::zeros());
    let axis = Vector3::new(0.3, -0.5, 0.8).normalize();
    let (mut g, mut c) = (Vec::new(), Vec::new());
    for k in 0..6 {
        let p = Isometry3::new(Vector3::new(0.4, 0.02 * k as f64, 0.5), axis * (0.3 * k as f64));
        g.push(p.to_homogeneous());
        c.push(((p * x).inverse() * target_in_base).to_homogeneous());
    }
    for method in HandEyeMethod::ALL {
        let err = calibrate_hand_eye(&g, &c, method, EyeInHand).unwrap_err();
        assert!(
            matches!(&err, CalibrationError::DegenerateMotion { poses: 6, reason } if reason.contains("parallel")),
            "{err}"
        );
    }
}

#[test]
fn pure_translations_are_refused() {
    let x = truth();
    let target_in_base = Isometry3::new(Vector3::new(0.7, 0.0, 0.0), Vector3::zeros());
    let (mut g, mut c) = (Vec::new(), Vec::new());
    for k in 0..5 {
        let p = Isometry3::new(Vector3::new(0.4 + 0.03 * k as f64, 0.01 * (k * k) as f64, 0.5), Vector3::zeros());
        g.push(p.to_homogeneous());
        c.push(((p * x).inverse() * target_in_base).to_homogeneous());
    }
    let err = compare_hand_eye_methods(&g, &c, EyeInHand).unwrap_err();
    assert!(
        matches!(&err, CalibrationError::DegenerateMotion { reason, .. } if reason.contains("no gripper motion rotates")),
        "{err}"
    );
}

#[test]
fn tsai_without_motions_in_its_band_is_refused_and_the_others_still_compare() {
    let x = truth();
    let target_in_base = Isometry3::new(Vector3::new(0.7, 0.0, 0.0), Vector3::zeros());
    // Rotations of 5 degrees: below Tsai-Lenz's band, enough for Park-Martin and Daniilidis.
    let small = 5f64.to_radians();
    let rotations = [Vector3::zeros(), Vector3::x() * small, Vector3::y() * small, Vector3::z() * small];
    let (mut g, mut c) = (Vec::new(), Vec::new());
    for r in rotations {
        let p = Isometry3::new(Vector3::new(0.4, 0.0, 0.5), r);
        g.push(p.to_homogeneous());
        c.push(((p * x).inverse() * target_in_base).to_homogeneous());
    }
    let err = calibrate_hand_eye(&g, &c, HandEyeMethod::TsaiLenz, EyeInHand).unwrap_err();
    assert!(matches!(&err, CalibrationError::DegenerateMotion { reason, .. } if reason.contains("Tsai-Lenz")), "{err}");
    let agreement = compare_hand_eye_methods(&g, &c, EyeInHand).unwrap();
    assert_eq!(agreement.calibrations.len(), 2);
    assert_eq!(agreement.failures[0].0, HandEyeMethod::TsaiLenz);
    for cal in &agreement.calibrations {
        assert_close(&cal.transform, &x, 1e-9, cal.method.name());
    }
}

#[test]
fn method_names() {
    for method in HandEyeMethod::ALL {
        assert_eq!(HandEyeMethod::from_name(method.name()), Ok(method));
    }
    assert_eq!(HandEyeMethod::from_name("Tsai_Lenz"), Ok(HandEyeMethod::TsaiLenz));
    assert!(matches!(
        HandEyeMethod::from_name("horaud"),
        Err(CalibrationError::Core(Error::InvalidParameter { name: "method", .. }))
    ));
}

/// `n` eye-to-hand stations: the gripper poses of [`stations`], a camera fixed in the base at
/// `camera_in_base` (camera-to-base) and a target on the flange at `target_on_flange`
/// (target-to-flange); the camera sees `C_i = camera_in_base^-1 G_i target_on_flange`.
fn eye_to_hand_stations(
    n: usize,
    camera_in_base: &Isometry3<f64>,
    target_on_flange: &Isometry3<f64>,
) -> (Vec<Matrix4<f64>>, Vec<Matrix4<f64>>) {
    let (gripper, _) = stations(n, &truth());
    let target = gripper
        .iter()
        .map(|g| camera_in_base.inverse().to_homogeneous() * g * target_on_flange.to_homogeneous())
        .collect();
    (gripper, target)
}

fn camera_in_base() -> Isometry3<f64> {
    Isometry3::new(Vector3::new(1.2, -0.3, 0.8), Vector3::new(-1.9, 0.4, 0.7))
}

fn target_on_flange() -> Isometry3<f64> {
    Isometry3::new(Vector3::new(0.0, 0.02, 0.08), Vector3::new(0.05, 0.1, -0.6))
}

#[test]
fn eye_to_hand_recovers_the_camera_in_the_base() {
    let y = camera_in_base();
    for n in [3, 4, 8, 20] {
        let (g, c) = eye_to_hand_stations(n, &y, &target_on_flange());
        for method in HandEyeMethod::ALL {
            let cal = calibrate_hand_eye(&g, &c, method, EyeToHand).unwrap();
            assert_close(&cal.transform, &y, 1e-10, &format!("{method:?} with {n} poses"));
            assert_eq!((cal.setup, cal.method, cal.residuals.len()), (EyeToHand, method, n * (n - 1) / 2));
            assert!(cal.max_rotation_deg() < 1e-8 && cal.max_translation_m() < 1e-10, "{method:?}");
            assert!(cal.axis_spread.spread_deg > 20.0, "{:?}", cal.axis_spread);
        }
        // From 4 stations on, the same data read as eye-in-hand fits nothing: the set-up is not
        // a detail (3 stations are 2 independent motions, whose angles match either way).
        if n >= 4 {
            let wrong = calibrate_hand_eye(&g, &c, HandEyeMethod::ParkMartin, EyeInHand).unwrap();
            assert!(wrong.max_rotation_deg() > 1.0 || wrong.max_translation_m() > 1e-2, "{wrong:?}");
        }
    }
}

#[test]
fn eye_to_hand_is_eye_in_hand_on_the_inverted_gripper_poses() {
    let (g, c) = eye_to_hand_stations(9, &camera_in_base(), &target_on_flange());
    let inverted: Vec<Matrix4<f64>> = g.iter().map(|m| m.try_inverse().unwrap()).collect();
    for method in HandEyeMethod::ALL {
        let to_hand = calibrate_hand_eye(&g, &c, method, EyeToHand).unwrap();
        let in_hand = calibrate_hand_eye(&inverted, &c, method, EyeInHand).unwrap();
        assert_close(&to_hand.transform, &in_hand.transform, 1e-12, method.name());
        assert_eq!(in_hand.setup, EyeInHand);
    }
    let agreement = compare_hand_eye_methods(&g, &c, EyeToHand).unwrap();
    assert_eq!(agreement.setup, EyeToHand);
    assert!(agreement.calibrations.iter().all(|cal| cal.setup == EyeToHand) && agreement.failures.is_empty());
    assert!(agreement.max_rotation_deg < 1e-8 && agreement.max_translation_m < 1e-10, "{agreement:?}");
}

#[test]
fn eye_to_hand_refuses_what_eye_in_hand_refuses() {
    let (y, t) = (camera_in_base(), target_on_flange());
    let axis = Vector3::new(0.3, -0.5, 0.8).normalize();
    let one_axis = |k: usize| Isometry3::new(Vector3::new(0.4, 0.02 * k as f64, 0.5), axis * (0.3 * k as f64));
    let still =
        |k: usize| Isometry3::new(Vector3::new(0.4 + 0.03 * k as f64, 0.01 * (k * k) as f64, 0.5), Vector3::zeros());
    for (pose, words) in
        [(&one_axis as &dyn Fn(usize) -> Isometry3<f64>, "parallel"), (&still, "no gripper motion rotates")]
    {
        let g: Vec<Matrix4<f64>> = (0..6).map(|k| pose(k).to_homogeneous()).collect();
        let c: Vec<Matrix4<f64>> = (0..6).map(|k| (y.inverse() * pose(k) * t).to_homogeneous()).collect();
        let err = compare_hand_eye_methods(&g, &c, EyeToHand).unwrap_err();
        assert!(
            matches!(&err, CalibrationError::DegenerateMotion { poses: 6, reason } if reason.contains(words)),
            "{err}"
        );
    }
    // A spoiled gripper pose is named as given, before the inversion.
    let (mut g, c) = eye_to_hand_stations(5, &y, &t);
    g[2][(1, 3)] = f64::NAN;
    let err = calibrate_hand_eye(&g, &c, HandEyeMethod::TsaiLenz, EyeToHand).unwrap_err();
    assert!(matches!(err, CalibrationError::InvalidPose { what: "gripper_poses", index: 2, .. }), "{err}");
    let err = calibrate_hand_eye(&g[..2], &c[..2], HandEyeMethod::TsaiLenz, EyeToHand).unwrap_err();
    assert!(matches!(err, CalibrationError::DegenerateMotion { poses: 2, .. }), "{err}");
}

#[test]
fn setup_names() {
    for setup in HandEyeSetup::ALL {
        assert_eq!(HandEyeSetup::from_name(setup.name()), Ok(setup));
    }
    assert_eq!(HandEyeSetup::from_name("Eye-To-Hand"), Ok(EyeToHand));
    assert_eq!(HandEyeSetup::default(), EyeInHand);
    assert_eq!((EyeInHand.reference_frame(), EyeToHand.reference_frame()), ("gripper", "base"));
    assert!(matches!(
        HandEyeSetup::from_name("eye_on_hand"),
        Err(CalibrationError::Core(Error::InvalidParameter { name: "setup", .. }))
    ));
}
