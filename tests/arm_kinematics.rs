//! Serial arms from URDF: forward kinematics and geometric Jacobians of the built-in UR5 and
//! Panda against Peter Corke's Robotics Toolbox for Python (fixtures made by
//! `tests/fixtures/make_arm_fixtures.py`) and against finite differences; bad input.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common::Lcg;
use nalgebra::{Isometry3, Matrix4, Matrix6xX, Vector3};
use serde::Deserialize;
use vsinv::Error;
use vsinv::sim::SimError;
use vsinv::sim::arm::{ArmModel, BUILTIN_ARMS, JointKind, builtin_urdf};

#[derive(Deserialize)]
struct Fixture {
    generator: String,
    end_effector: String,
    samples: Vec<Sample>,
}

#[derive(Deserialize)]
struct Sample {
    q: Vec<f64>,
    pose: [[f64; 4]; 4],
    jacob0: Vec<Vec<f64>>,
    flange_pose: Option<[[f64; 4]; 4]>,
}

fn fixture(name: &str) -> Fixture {
    let path = format!("{}/tests/fixtures/arm_{name}.json", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn matrix_error(pose: &Isometry3<f64>, rows: &[[f64; 4]; 4]) -> f64 {
    let expected = Matrix4::from_fn(|r, c| rows[r][c]);
    (pose.to_homogeneous() - expected).abs().max()
}

/// Largest errors (pose, Jacobian) of the model against an rtb fixture.
fn compare_with_rtb(name: &str) -> (f64, f64) {
    let data = fixture(name);
    let arm = ArmModel::builtin(name).unwrap();
    assert_eq!(arm.end_effector(), data.end_effector);
    let flange = ArmModel::builtin_with_end_effector(name, "panda_link8").ok();
    let (mut pose_err, mut jac_err) = (0.0_f64, 0.0_f64);
    for s in &data.samples {
        pose_err = pose_err.max(matrix_error(&arm.fk(&s.q).unwrap(), &s.pose));
        let jac = arm.jacobian_base(&s.q).unwrap();
        let expected = Matrix6xX::from_fn(arm.dof(), |r, c| s.jacob0[r][c]);
        jac_err = jac_err.max((jac - expected).abs().max());
        if let (Some(flange), Some(rows)) = (&flange, &s.flange_pose) {
            pose_err = pose_err.max(matrix_error(&flange.fk(&s.q).unwrap(), rows));
        }
    }
    println!("{name} vs {}: pose {pose_err:.2e}, jacob0 {jac_err:.2e}", data.generator);
    (pose_err, jac_err)
}

#[test]
fn arm_ur5_matches_robotics_toolbox() {
    let (pose, jac) = compare_with_rtb("ur5");
    assert!(pose < 1e-9 && jac < 1e-9, "pose {pose:.2e}, jacobian {jac:.2e}");
}

#[test]
fn arm_panda_matches_robotics_toolbox() {
    assert!(fixture("panda").samples.iter().all(|s| s.flange_pose.is_some()));
    let (pose, jac) = compare_with_rtb("panda");
    assert!(pose < 1e-9 && jac < 1e-9, "pose {pose:.2e}, jacobian {jac:.2e}");
}

fn random_q(arm: &ArmModel, rng: &mut Lcg) -> Vec<f64> {
    let limits = arm.limits();
    (0..arm.dof()).map(|i| rng.uniform(limits.lower[i], limits.upper[i])).collect()
}

/// Central differences of the pose along joint `i`: `(v, w)` in the base frame and in the
/// end-effector frame (rotation by the log of `R(q+h) R(q-h)^T`, resp. `R(q-h)^T R(q+h)`).
fn finite_difference(arm: &ArmModel, q: &[f64], i: usize, h: f64) -> ([f64; 6], [f64; 6]) {
    let (mut qp, mut qm) = (q.to_vec(), q.to_vec());
    qp[i] += h;
    qm[i] -= h;
    let (tp, tm) = (arm.fk(&qp).unwrap(), arm.fk(&qm).unwrap());
    let r = arm.fk(q).unwrap().rotation;
    let v = (tp.translation.vector - tm.translation.vector) / (2.0 * h);
    let w_base = (tp.rotation * tm.rotation.inverse()).scaled_axis() / (2.0 * h);
    let w_ee = (tm.rotation.inverse() * tp.rotation).scaled_axis() / (2.0 * h);
    let v_ee = r.inverse() * v;
    let stack = |a: Vector3<f64>, b: Vector3<f64>| [a.x, a.y, a.z, b.x, b.y, b.z];
    (stack(v, w_base), stack(v_ee, w_ee))
}

#[test]
fn arm_jacobians_match_finite_differences() {
    let mut rng = Lcg(20_250_101);
    for name in BUILTIN_ARMS {
        let arm = ArmModel::builtin(name).unwrap();
        let (mut base_err, mut ee_err) = (0.0_f64, 0.0_f64);
        for _ in 0..50 {
            let q = random_q(&arm, &mut rng);
            let (jb, je) = (arm.jacobian_base(&q).unwrap(), arm.jacobian_end_effector(&q).unwrap());
            for i in 0..arm.dof() {
                let (fd_base, fd_ee) = finite_difference(&arm, &q, i, 1e-6);
                for r in 0..6 {
                    base_err = base_err.max((jb[(r, i)] - fd_base[r]).abs());
                    ee_err = ee_err.max((je[(r, i)] - fd_ee[r]).abs());
                }
            }
        }
        println!("{name}: Jacobian vs central differences: base {base_err:.2e}, end-effector {ee_err:.2e}");
        assert!(base_err < 1e-6 && ee_err < 1e-6, "{name}: base {base_err:.2e}, end-effector {ee_err:.2e}");
    }
}

#[test]
fn arm_links_and_limits() {
    let arm = ArmModel::builtin("panda").unwrap();
    assert_eq!(arm.dof(), 7);
    assert_eq!(arm.base_link(), "panda_link0");
    assert_eq!(arm.joint_names()[6], "panda_joint7");
    assert_eq!(arm.link_names().len(), 10);
    assert!(arm.joints().iter().all(|j| j.kind() == JointKind::Revolute));
    let limits = arm.limits();
    assert_eq!((limits.lower[3], limits.upper[3], limits.velocity[6]), (-3.0718, -0.0698, 2.61));
    let q = [0.1, -0.4, 0.2, -2.0, 0.3, 1.5, 0.7];
    assert_eq!(arm.fk_link(&q, "panda_hand_tcp").unwrap(), arm.fk(&q).unwrap());
    assert_eq!(arm.fk_link(&q, "panda_link0").unwrap(), Isometry3::identity());
    // The TCP is 0.103 m along the flange's z, turned by -pi/4.
    let d = arm.fk_link(&q, "panda_link8").unwrap().inverse() * arm.fk(&q).unwrap();
    assert!((d.translation.vector - Vector3::new(0.0, 0.0, 0.103)).norm() < 1e-12);
    assert!((d.rotation.scaled_axis() + Vector3::z() * std::f64::consts::FRAC_PI_4).norm() < 1e-12);
    arm.check_limits(&q).unwrap();
    let err = arm.check_limits(&[0.1, -0.4, 0.2, 0.5, 0.3, 1.5, 0.7]).unwrap_err();
    assert!(err.to_string().contains("panda_joint4"), "{err}");
}

#[test]
fn arm_from_file_equals_builtin() {
    let path = format!("{}/robots/ur5.urdf", env!("CARGO_MANIFEST_DIR"));
    let from_file = ArmModel::from_urdf_file(&path, "tool0").unwrap();
    let builtin = ArmModel::builtin("ur5").unwrap();
    assert_eq!(from_file.source(), path);
    assert_eq!(builtin.source(), "builtin:ur5");
    let q = [0.3, -1.1, 0.9, -0.4, 1.2, 2.0];
    assert_eq!(from_file.fk(&q).unwrap(), builtin.fk(&q).unwrap());
    let from_str = ArmModel::from_urdf_str(builtin_urdf("ur5").unwrap(), "wrist_3_link").unwrap();
    assert_eq!(from_str.dof(), 6);
    assert_eq!(from_str.end_effector(), "wrist_3_link");
}

#[test]
fn arm_manipulability() {
    let ur5 = ArmModel::builtin("ur5").unwrap();
    // Elbow stretched (q3 = 0): the UR5 is singular.
    let m = ur5.manipulability(&[0.2, -1.0, 0.0, -0.5, 1.2, 0.1]).unwrap();
    println!("ur5 singular: {m:.3e}, regular {:.3e}", ur5.manipulability(&[0.2, -1.0, 1.0, -0.5, 1.2, 0.1]).unwrap());
    assert!(m < 1e-12, "{m}");
    let panda = ArmModel::builtin("panda").unwrap();
    let q = [0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.785];
    let product: f64 = panda.jacobian_end_effector(&q).unwrap().singular_values().iter().product();
    let m = panda.manipulability(&q).unwrap();
    assert!(m > 0.01 && (m - product).abs() < 1e-12 * m.max(1.0), "{m} vs {product}");
}

const TWO_LINKS: &str = r#"<robot name="two">
  <link name="a"/><link name="b"/><link name="c"/>
  <joint name="j1" type="revolute"><parent link="a"/><child link="b"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="b"/><child link="c"/>
    <origin xyz="1 0 0"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" velocity="1"/></joint>
</robot>"#;

fn urdf_message(result: Result<ArmModel, SimError>) -> String {
    match result {
        Err(SimError::Urdf { message, .. }) => message,
        other => panic!("expected a URDF error, got {other:?}"),
    }
}

#[test]
fn arm_bad_urdf_is_an_error() {
    for text in ["", "not xml", "<robot name=\"x\"><link name=\"a\"></robot>", "<robot><joint name=\"j\"/></robot>"] {
        let err = ArmModel::from_urdf_str(text, "a").unwrap_err();
        assert!(matches!(err, SimError::Urdf { ref file, .. } if file == "<string>"), "{text:?}: {err}");
    }
    for (from, to) in
        [(r#"xyz="1 0 0""#, r#"xyz="1 0""#), (r#"xyz="1 0 0""#, r#"xyz="a b c""#), ("\"revolute\"", "\"hinge\"")]
    {
        let text = TWO_LINKS.replacen(from, to, 1);
        assert!(urdf_message(ArmModel::from_urdf_str(&text, "c")).contains("not valid URDF"), "{to}");
    }
    assert!(urdf_message(ArmModel::from_urdf_str(TWO_LINKS, "hand")).contains("no link `hand`"));
    assert!(urdf_message(ArmModel::from_urdf_str(TWO_LINKS, "a")).contains("no actuated joint"));
    let floating = TWO_LINKS.replacen("\"revolute\"", "\"floating\"", 1);
    assert!(urdf_message(ArmModel::from_urdf_str(&floating, "c")).contains("joint `j1` is Floating"));
    let no_limit = TWO_LINKS.replacen(r#"<limit lower="-1" upper="1" velocity="1"/>"#, "", 1);
    assert!(urdf_message(ArmModel::from_urdf_str(&no_limit, "c")).contains("joint `j1`: position limits"));
    let zero_axis = TWO_LINKS.replacen(r#"<axis xyz="0 0 1"/>"#, r#"<axis xyz="0 0 0"/>"#, 1);
    assert!(urdf_message(ArmModel::from_urdf_str(&zero_axis, "c")).contains("joint `j1`: axis"));
    let nan_origin = TWO_LINKS.replacen(r#"<origin xyz="1 0 0"/>"#, r#"<origin xyz="NaN 0 0"/>"#, 1);
    assert!(urdf_message(ArmModel::from_urdf_str(&nan_origin, "c")).contains("joint `j2`"));
    let cycle = TWO_LINKS.replacen(r#"<parent link="a"/>"#, r#"<parent link="c"/>"#, 1);
    assert!(urdf_message(ArmModel::from_urdf_str(&cycle, "c")).contains("cycle"));
    let missing = ArmModel::from_urdf_file("/nonexistent/arm.urdf", "tool0").unwrap_err();
    assert!(matches!(missing, SimError::Urdf { ref file, .. } if file == "/nonexistent/arm.urdf"), "{missing}");
    let unknown = ArmModel::builtin("puma").unwrap_err();
    assert!(matches!(unknown, SimError::Core(Error::InvalidParameter { name: "arm", .. })), "{unknown}");
}

#[test]
fn arm_bad_joints_are_errors() {
    let arm = ArmModel::builtin("ur5").unwrap();
    let short = [0.0; 5];
    assert!(matches!(arm.fk(&short), Err(SimError::Core(Error::Shape { what: "joint positions", .. }))));
    assert!(matches!(arm.jacobian_base(&[0.0; 7]), Err(SimError::Core(Error::Shape { .. }))));
    assert!(matches!(arm.jacobian_end_effector(&short), Err(SimError::Core(Error::Shape { .. }))));
    assert!(matches!(arm.manipulability(&short), Err(SimError::Core(Error::Shape { .. }))));
    assert!(matches!(arm.check_limits(&short), Err(SimError::Core(Error::Shape { .. }))));
    let nan = [0.0, 0.0, f64::NAN, 0.0, 0.0, 0.0];
    assert_eq!(arm.fk(&nan).unwrap_err(), SimError::Core(Error::NonFinite { what: "joint positions", index: 2 }));
    assert!(matches!(arm.jacobian_base(&nan), Err(SimError::Core(Error::NonFinite { index: 2, .. }))));
    assert!(matches!(
        arm.fk_link(&[f64::INFINITY; 6], "tool0"),
        Err(SimError::Core(Error::NonFinite { index: 0, .. }))
    ));
    let err = arm.fk_link(&[0.0; 6], "panda_link8").unwrap_err();
    assert!(
        matches!(err, SimError::Core(Error::InvalidParameter { name: "link", .. }))
            && err.to_string().contains("base_link")
    );
}
