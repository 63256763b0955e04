//! Eye-in-hand control of an arm: the built-in lens changes on a UR5 and a Panda, the
//! damped least squares mapping, the mount's twist transform, and the statuses
//! `joint_limit` and `singular`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3, Vector6};
use vsinv::sim::SimError;
use vsinv::sim::arm::{ArmModel, ArmRobot};
use vsinv::sim::robot::Robot;
use vsinv::sim::scenario::{Scenario, builtin};
use vsinv::sim::{Outcome, Status, simulate};

fn run(s: &Scenario) -> Outcome {
    simulate(&s.to_config().unwrap(), &mut |_, _| true).unwrap()
}

fn arm_of(s: &Scenario) -> std::sync::Arc<ArmRobot> {
    match s.to_config().unwrap().robot {
        Robot::Arm(arm) => arm,
        other => panic!("not an arm: {other:?}"),
    }
}

fn pose(p: [f64; 3], r_deg: [f64; 3]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(p[0], p[1], p[2]),
        UnitQuaternion::from_scaled_axis(Vector3::from(r_deg.map(f64::to_radians))),
    )
}

/// The measured figures of a run, as in the table of docs/results/built-in-scenarios.md.
fn report(o: &Outcome, arm: &ArmRobot) -> String {
    let s = &o.summary;
    let r = o.recording.as_ref().unwrap();
    format!(
        "{} after {} it: {:.3} mm, {:.4} deg, min manipulability {:.4}, peak {:.3} m/s {:.1} deg/s, \
         joint margin {:.1} deg, joint speed / limit {:.3} ({})",
        s.status.as_str(),
        s.iterations,
        s.final_translation_error * 1e3,
        s.final_rotation_error.to_degrees(),
        s.min_manipulability.unwrap_or(f64::NAN),
        s.peak_speeds.0,
        s.peak_speeds.1.to_degrees(),
        joint_margin(&r.joints, arm).to_degrees(),
        speed_fraction(&r.joint_velocities, arm),
        s.message
    )
}

/// Smallest distance of a recorded joint position from its limits.
fn joint_margin(joints: &[f64], arm: &ArmRobot) -> f64 {
    let (n, l) = (arm.dof(), &arm.limits);
    joints
        .chunks(n)
        .flat_map(|q| (0..n).map(move |i| (q[i] - l.lower[i]).min(l.upper[i] - q[i])))
        .fold(f64::INFINITY, f64::min)
}

/// Largest joint speed over its limit.
fn speed_fraction(dq: &[f64], arm: &ArmRobot) -> f64 {
    let v = &arm.limits.velocity;
    dq.chunks(arm.dof())
        .flat_map(|dq| dq.iter().zip(v).map(|(a, b)| a.abs() / b))
        .filter(|f| f.is_finite())
        .fold(0.0, f64::max)
}

fn check_builtin(name: &str) {
    let s = builtin(name).unwrap();
    let arm = arm_of(&s);
    let o = run(&s);
    let (sum, r) = (&o.summary, o.recording.as_ref().unwrap());
    println!("{name}: {}", report(&o, &arm));
    assert_eq!(sum.status, Status::Converged, "{}", report(&o, &arm));
    assert!(sum.final_translation_error < 1e-3 && sum.final_rotation_error.to_degrees() < 0.1);
    let n = arm.dof();
    assert_eq!((r.n_joints, r.joints.len(), r.joint_velocities.len()), (n, r.len() * n, r.len() * n));
    assert!(joint_margin(&r.joints, &arm) > 0.0);
    for dq in r.joint_velocities.chunks(n).take(r.len() - 1) {
        assert!(dq.iter().zip(&arm.limits.velocity).all(|(v, max)| v.abs() <= max * (1.0 + 1e-12)), "{dq:?}");
    }
    assert!(sum.peak_speeds.0 <= 0.25 + 1e-12 && sum.peak_speeds.1.to_degrees() <= 60.0 + 1e-9);
    assert!(sum.min_manipulability.unwrap() > arm.min_manipulability);
}

#[test]
fn ur5_lens_change_converges_within_limits() {
    check_builtin("arm-ur5-12-6");
}

#[test]
fn panda_lens_change_converges_within_limits() {
    check_builtin("arm-panda-12-6");
}

/// Far from singularities (no damping) and on a six-joint arm (no null-space task), the
/// joint velocities give exactly the requested end-effector twist; on the Panda the
/// null-space task leaves it unchanged too.
#[test]
fn damped_least_squares_is_exact_away_from_singularities() {
    for name in ["arm-ur5-12-6", "arm-panda-12-6"] {
        let arm = arm_of(&builtin(name).unwrap());
        let q = &arm.start;
        let twist = Vector6::new(0.05, -0.02, 0.03, 0.2, -0.1, 0.3);
        let dq = arm.joint_velocities(q, &twist).unwrap();
        let jac = arm.model.jacobian_end_effector(q).unwrap();
        let wanted = arm.mount_twist_transform() * twist;
        assert!((jac * &dq - wanted).abs().max() < 1e-9, "{name}");
    }
}

/// The mount's twist transform against finite differences of `fk(q) * mount`.
#[test]
fn mount_twist_transform_matches_finite_differences() {
    let model = ArmModel::builtin("ur5").unwrap();
    let mount = pose([0.03, -0.06, 0.04], [10.0, -20.0, 35.0]);
    let arm = ArmRobot::new(model, Isometry3::identity(), mount, vec![0.3, -1.2, 1.1, -0.6, 1.4, 0.2]);
    let q = arm.start.clone();
    let camera_twist = Vector6::new(0.04, -0.01, 0.02, 0.3, -0.2, 0.1);
    let dq = arm.joint_velocities(&q, &camera_twist).unwrap();
    let h = 1e-7;
    let ahead: Vec<f64> = q.iter().zip(dq.iter()).map(|(q, v)| q + h * v).collect();
    let rel = arm.camera_pose(&q).unwrap().inverse() * arm.camera_pose(&ahead).unwrap();
    let fd_v = rel.translation.vector / h;
    let fd_w = rel.rotation.scaled_axis() / h;
    for i in 0..3 {
        assert!((fd_v[i] - camera_twist[i]).abs() < 1e-6, "{fd_v} vs {camera_twist}");
        assert!((fd_w[i] - camera_twist[3 + i]).abs() < 1e-6, "{fd_w} vs {camera_twist}");
    }
}

/// Narrowed limits on the UR5's wrist_3 (it turns from 15 to about -80 degrees on the way).
#[test]
fn a_joint_driven_into_its_limit_ends_the_run() {
    let mut s = builtin("arm-ur5-12-6").unwrap();
    let mut min = vec![-360.0; 6];
    min[5] = -20.0;
    s.robot.joint_min = Some(min);
    s.robot.joint_max = Some(vec![360.0; 6]);
    let o = run(&s);
    assert_eq!(o.summary.status, Status::JointLimit, "{}", o.summary.message);
    assert!(o.summary.message.contains("wrist_3_joint"), "{}", o.summary.message);
    let r = o.recording.unwrap();
    let last = r.joints[r.joints.len() - 1];
    assert!((last + 20f64.to_radians()).abs() < 1e-12, "{last}");
}

/// The lens change's start pose reached by a UR5 whose wrist is almost aligned (wrist_2
/// at `wrist_deg`): the base is placed so that the camera starts where it does in
/// `lens-12-6`. The servo turns wrist_2 towards 0: the threshold 1e-3 (the start has 2.4e-3)
/// stops it on the way.
fn near_wrist_singularity(wrist_deg: f64) -> Scenario {
    let mut s = builtin("arm-ur5-12-6").unwrap();
    let mut q = s.robot.joints.clone().unwrap();
    q[4] = wrist_deg;
    let arm = arm_of(&s);
    let q_rad: Vec<f64> = q.iter().map(|v| v.to_radians()).collect();
    let start = pose([0.2, -0.15, -0.15], [-19.33, -4.86, 77.28]);
    let base = start * (arm.model.fk(&q_rad).unwrap() * arm.mount).inverse();
    let t = base.translation.vector;
    let r = base.rotation.scaled_axis().map(f64::to_degrees);
    s.robot.base = Some(vsinv::sim::scenario::PoseSpec { position: [t.x, t.y, t.z], rotation_deg: [r.x, r.y, r.z] });
    s.robot.joints = Some(q);
    s
}

#[test]
fn a_start_near_a_singularity_ends_singular() {
    let mut s = near_wrist_singularity(-2.0);
    s.robot.min_manipulability = Some(1e-3);
    let o = run(&s);
    assert_eq!(o.summary.status, Status::Singular, "{}", o.summary.message);
    assert!(o.summary.min_manipulability.unwrap() < 1e-3);
}

fn key_error(s: &Scenario) -> (String, String) {
    match s.to_config() {
        Err(SimError::Scenario { key, reason }) => (key.to_string(), reason),
        other => panic!("expected a scenario error, got {other:?}"),
    }
}

/// A change to a scenario.
type Edit = Box<dyn Fn(&mut Scenario)>;

#[test]
fn bad_arm_keys_name_the_key() {
    let base = builtin("arm-ur5-12-6").unwrap();
    let cases: Vec<(&str, Edit)> = vec![
        ("robot.joints", Box::new(|s| s.robot.joints = Some(vec![0.0; 5]))),
        ("robot.joints", Box::new(|s| s.robot.joints.as_mut().unwrap()[1] = -400.0)),
        ("robot.joints", Box::new(|s| s.robot.joints = None)),
        ("robot.urdf", Box::new(|s| s.robot.urdf = Some("kuka".into()))),
        ("robot.urdf", Box::new(|s| s.robot.urdf = None)),
        ("robot.end_effector", Box::new(|s| s.robot.end_effector = Some("flange".into()))),
        ("robot.damping", Box::new(|s| s.robot.damping = Some(0.0))),
        ("robot.min_manipulability", Box::new(|s| s.robot.min_manipulability = Some(-1.0))),
        ("robot.joint_max", Box::new(|s| s.robot.joint_max = Some(vec![1.0; 7]))),
        ("robot.joint_velocity", Box::new(|s| s.robot.joint_velocity = Some(vec![0.0; 6]))),
        ("robot.base.position[0]", Box::new(|s| s.robot.base.as_mut().unwrap().position[0] = f64::NAN)),
        (
            "start",
            Box::new(|s| {
                s.start =
                    Some(vsinv::sim::scenario::StartSpec { position: [0.2, -0.15, -0.15], rotation_deg: [0.0; 3] })
            }),
        ),
    ];
    for (key, edit) in cases {
        let mut s = base.clone();
        edit(&mut s);
        let (k, reason) = key_error(&s);
        assert_eq!(k, key, "{reason}");
    }
    let mut free = builtin("lens-12-6").unwrap();
    free.robot.damping = Some(0.1);
    assert_eq!(key_error(&free).0, "robot.damping");
}

/// A relative URDF path starts at the scenario file's directory.
#[test]
fn urdf_files_resolve_against_the_scenario_directory() {
    let dir = std::env::temp_dir().join(format!("vsinv-arm-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("robots")).unwrap();
    std::fs::write(dir.join("robots/my.urdf"), vsinv::sim::arm::builtin_urdf("ur5").unwrap()).unwrap();
    let text = include_str!("../scenarios/arm-ur5-12-6.toml").replace("urdf = \"ur5\"", "urdf = \"robots/my.urdf\"");
    std::fs::write(dir.join("s.toml"), &text).unwrap();
    let s = Scenario::from_toml_file(dir.join("s.toml")).unwrap();
    assert_eq!(arm_of(&s).model.source(), dir.join("robots/my.urdf").display().to_string());
    let err = Scenario::from_toml(&text).unwrap_err().to_string();
    assert!(err.contains("robot.urdf"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}
