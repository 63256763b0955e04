//! Inverse kinematics of the built-in arms: round trips `fk(ik(fk(q)))` over random joints
//! within the limits, the limits respected, unreachable poses refused; against an
//! independent solver, roboticstoolbox-python's `ikine_LM` (fixtures made by
//! `tests/fixtures/ik/make_ik_fixtures.py`); and arm scenarios placed by the camera pose.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common::Lcg;
use nalgebra::{Isometry3, Matrix4};
use serde::Deserialize;
use vsinv::core::se3::{pose_error, pose_from_matrix, thetau_from_pose};
use vsinv::sim::SimError;
use vsinv::sim::arm::{ArmModel, DampedLeastSquaresIk, InverseKinematics};
use vsinv::sim::robot::Robot;
use vsinv::sim::scenario::{Scenario, StartSpec, builtin};

/// Random joints within the limits of `arm`.
fn random_joints(arm: &ArmModel, rng: &mut Lcg) -> Vec<f64> {
    let l = arm.limits();
    l.lower.iter().zip(&l.upper).map(|(&lo, &hi)| rng.uniform(lo, hi)).collect()
}

/// fk(ik(fk(q))) = fk(q) from seeds unrelated to q, within the limits.
#[test]
fn round_trips_over_random_joints_within_the_limits() {
    for (name, seed) in [("ur5", 7u64), ("panda", 11)] {
        let arm = ArmModel::builtin(name).unwrap();
        let mut rng = Lcg(seed);
        for case in 0..100 {
            let q = random_joints(&arm, &mut rng);
            let target = arm.fk(&q).unwrap();
            let solution = arm.ik(&target, None).unwrap_or_else(|e| panic!("{name} case {case}: {e}"));
            arm.check_limits(&solution.joints).unwrap();
            let (dt, dr) = pose_error(&arm.fk(&solution.joints).unwrap(), &target);
            assert!(dt < 1e-9 && dr < 1e-9, "{name} case {case}: {dt:e} m, {dr:e} rad");
            assert!((solution.position_residual - dt).abs() < 1e-12, "{name} case {case}");
            assert!(solution.position_residual <= 1e-10 && solution.rotation_residual <= 1e-10);
        }
    }
}

/// A seed next to the true joints of the non-redundant UR5 converges to them, in few
/// iterations (Newton's quadratic convergence at the end).
#[test]
fn a_nearby_seed_returns_the_true_joints() {
    let arm = ArmModel::builtin("ur5").unwrap();
    let mut rng = Lcg(3);
    for case in 0..50 {
        let q = random_joints(&arm, &mut rng);
        let seed: Vec<f64> = q.iter().map(|v| v + rng.uniform(-0.05, 0.05)).collect();
        let l = arm.limits();
        let seed: Vec<f64> = seed.iter().enumerate().map(|(i, v)| v.clamp(l.lower[i], l.upper[i])).collect();
        let s = arm.ik(&arm.fk(&q).unwrap(), Some(&seed)).unwrap();
        assert_eq!(s.seed, 0, "case {case}");
        let gap = q.iter().zip(&s.joints).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(gap < 1e-8, "case {case}: {gap:e}");
        assert!(s.iterations < 20, "case {case}: {} iterations", s.iterations);
    }
}

/// Narrowed limits hold: the solution stays inside them, and a pose reachable only outside
/// them is refused.
#[test]
fn joint_limits_are_respected() {
    let arm = ArmModel::builtin("panda").unwrap();
    let q = [0.3, -0.4, 0.2, -2.0, 0.1, 1.8, 0.5];
    let target = arm.fk(&q).unwrap();
    let mut limits = arm.limits();
    limits.lower[0] = 0.25;
    limits.upper[0] = 0.35;
    let s = DampedLeastSquaresIk::default().solve(&arm, &limits, &target, None).unwrap();
    assert!((0.25..=0.35).contains(&s.joints[0]), "{:?}", s.joints);
    // A folded elbow 0.01 rad from its limit: reached only near the limit, which the active
    // set holds while the other joints make up the rest of the step.
    let folded = [0.314, 0.629, -2.148, -3.061, -2.443, 3.238, 2.193];
    let s = arm.ik(&arm.fk(&folded).unwrap(), None).unwrap();
    arm.check_limits(&s.joints).unwrap();
    // The UR5's base joint narrowed to [1, 1.2] rad: the pose of q0 = 0.1 has its base joint at
    // 0.1 or 3.602 rad (mod 2 pi; the two shoulder solutions of the closed form), both outside.
    let ur5 = ArmModel::builtin("ur5").unwrap();
    let q = [0.1, -1.2, 1.0, -0.5, 1.4, 0.3];
    let mut limits = ur5.limits();
    (limits.lower[0], limits.upper[0]) = (1.0, 1.2);
    let solver = DampedLeastSquaresIk { seeds: 8, ..Default::default() };
    let err = solver.solve(&ur5, &limits, &ur5.fk(&q).unwrap(), None).unwrap_err();
    assert!(matches!(err, SimError::Unreachable { .. }), "{err}");
}

#[test]
fn unreachable_poses_name_the_pose_and_the_residual() {
    let arm = ArmModel::builtin("panda").unwrap();
    let far = Isometry3::translation(0.0, 2.0, 0.3);
    let err = arm.ik(&far, None).unwrap_err();
    let text = err.to_string();
    assert!(text.starts_with("pose: unreachable by panda"), "{text}");
    assert!(text.contains("position [0, 2, 0.3] m"), "{text}");
    let SimError::Unreachable { position_residual, seeds, .. } = err else { unreachable!() };
    assert!(position_residual > 0.8 && seeds == 64, "{text}");
    // Bad seeds are refused by name.
    let err = arm.ik(&far, Some(&[0.0; 6])).unwrap_err().to_string();
    assert!(err.contains("joint positions") && err.contains("7 values"), "{err}");
}

#[derive(Deserialize)]
struct Fixture {
    generator: String,
    arms: std::collections::BTreeMap<String, Vec<Case>>,
}

#[derive(Deserialize)]
struct Case {
    q_true: Vec<f64>,
    pose: [[f64; 4]; 4],
    q_seed: Vec<f64>,
    rtb_q: Vec<f64>,
    rtb_success: bool,
}

fn rtb_fixture() -> Fixture {
    let path = format!("{}/tests/fixtures/ik/ik_rtb.json", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// roboticstoolbox's `ikine_LM` on the same URDF files: both solvers reach the pose rtb's
/// forward kinematics gives; from the same nearby seed, the UR5's joints agree (the Panda is
/// redundant: its solutions form a manifold, only the poses are compared).
#[test]
fn agrees_with_roboticstoolbox_ikine_lm() {
    let fixture = rtb_fixture();
    assert!(fixture.generator.contains("ikine_LM"));
    for (name, cases) in &fixture.arms {
        let arm = ArmModel::builtin(name).unwrap();
        let mut joints_compared = 0;
        for (i, c) in cases.iter().enumerate() {
            let target = pose_from_matrix(&Matrix4::from_fn(|r, k| c.pose[r][k])).unwrap();
            // rtb's forward kinematics: an independent check of the crate's.
            let (dt, dr) = pose_error(&arm.fk(&c.q_true).unwrap(), &target);
            assert!(dt < 1e-12 && dr < 1e-12, "{name} {i}: fk {dt:e} m, {dr:e} rad");
            let s = arm.ik(&target, Some(&c.q_seed)).unwrap_or_else(|e| panic!("{name} {i}: {e}"));
            let (dt, dr) = pose_error(&arm.fk(&s.joints).unwrap(), &target);
            assert!(dt < 1e-9 && dr < 1e-9, "{name} {i}: {dt:e} m, {dr:e} rad");
            if !c.rtb_success {
                continue;
            }
            let (dt, dr) = pose_error(&arm.fk(&c.rtb_q).unwrap(), &target);
            assert!(dt < 1e-6 && dr < 1e-6, "{name} {i}: rtb's solution {dt:e} m, {dr:e} rad");
            if name == "ur5" {
                let gap = c.rtb_q.iter().zip(&s.joints).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
                assert!(gap < 1e-7, "{name} {i}: joints differ by {gap:e} rad");
                joints_compared += 1;
            }
        }
        assert!(name != "ur5" || joints_compared >= 20, "{joints_compared}");
    }
}

/// The arm of `arm-ur5-12-6` placed by its camera's start pose rather than its joints.
fn placed_by_pose(seed: bool) -> (Scenario, Vec<f64>, Isometry3<f64>) {
    let mut s = builtin("arm-ur5-12-6").unwrap();
    let config = s.to_config().unwrap();
    let Robot::Arm(arm) = &config.robot else { panic!("not an arm") };
    let start = config.start;
    let p = start.translation.vector;
    let r = thetau_from_pose(&start).map(f64::to_degrees);
    s.start = Some(StartSpec { position: [p.x, p.y, p.z], rotation_deg: r });
    s.robot.ik_seed = if seed { s.robot.joints.take() } else { None };
    s.robot.joints = None;
    (s, arm.start.clone(), start)
}

#[test]
fn an_arm_scenario_is_placed_by_the_camera_pose() {
    // Seeded by the original joints: the same joints back.
    let (s, joints, start) = placed_by_pose(true);
    let config = s.to_config().unwrap();
    let Robot::Arm(arm) = &config.robot else { panic!("not an arm") };
    let gap = joints.iter().zip(&arm.start).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(gap < 1e-8, "{gap:e}");
    let (dt, dr) = pose_error(&config.start, &start);
    assert!(dt < 1e-9 && dr < 1e-9);
    // Unseeded: some joints within the limits placing the camera there.
    let (s, _, start) = placed_by_pose(false);
    let config = s.to_config().unwrap();
    let Robot::Arm(arm) = &config.robot else { panic!("not an arm") };
    arm.model.check_limits(&arm.start).unwrap();
    let (dt, dr) = pose_error(&arm.camera_pose(&arm.start).unwrap(), &start);
    assert!(dt < 1e-9 && dr < 1e-9);
    let outcome = vsinv::sim::simulate(&config, &mut |_, _| true).unwrap();
    assert_eq!(outcome.summary.status, vsinv::sim::Status::Converged, "{}", outcome.summary.message);
}

fn key_error(s: &Scenario) -> (String, String) {
    match s.to_config() {
        Err(SimError::Scenario { key, reason }) => (key.to_string(), reason),
        other => panic!("expected a scenario error, got {other:?}"),
    }
}

#[test]
fn the_start_is_given_one_way_only() {
    let (mut both, _, _) = placed_by_pose(false);
    both.robot.joints = builtin("arm-ur5-12-6").unwrap().robot.joints;
    let (key, reason) = key_error(&both);
    assert_eq!(key, "start");
    assert!(reason.contains("robot.joints") && reason.contains("start.position"), "{reason}");
    let mut neither = both.clone();
    (neither.start, neither.robot.joints) = (None, None);
    let (key, reason) = key_error(&neither);
    assert_eq!(key, "robot.joints");
    assert!(reason.contains("[start]"), "{reason}");
    let mut seed_with_joints = builtin("arm-ur5-12-6").unwrap();
    seed_with_joints.robot.ik_seed = Some(vec![0.0; 6]);
    assert_eq!(key_error(&seed_with_joints).0, "robot.ik_seed");
    let (mut short_seed, _, _) = placed_by_pose(false);
    short_seed.robot.ik_seed = Some(vec![0.0; 5]);
    assert_eq!(key_error(&short_seed).0, "robot.ik_seed");
    let (mut far, _, _) = placed_by_pose(false);
    far.start.as_mut().unwrap().position = [0.2, -0.15, -3.0];
    let (key, reason) = key_error(&far);
    assert_eq!(key, "start");
    assert!(reason.contains("unreachable by ur5"), "{reason}");
    let mut free = builtin("lens-12-6").unwrap();
    free.robot.ik_seed = Some(vec![0.0; 6]);
    assert_eq!(key_error(&free).0, "robot.ik_seed");
}
