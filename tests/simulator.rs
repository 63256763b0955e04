//! The simulator and the scenario runner: the paper's experiments and the simulator's
//! contracts (visibility, robot limits, noise, stop rules, scenario validation).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use vsinv::Error;
use vsinv::sim::SimError;
use vsinv::sim::scenario::{BUILTIN, Scenario, builtin};
use vsinv::sim::{Outcome, Status, simulate};

fn run(s: &Scenario) -> Outcome {
    simulate(&s.to_config().unwrap(), &mut |_, _| true).unwrap()
}

fn report(o: &Outcome) -> String {
    let s = &o.summary;
    format!(
        "{} after {} it: {:.3} mm, {:.4} deg, image {:.2} px, invariant {:.2e} ({})",
        s.status.as_str(),
        s.iterations,
        s.final_translation_error * 1e3,
        s.final_rotation_error.to_degrees(),
        s.final_image_error,
        s.final_invariant_error,
        s.message
    )
}

fn mm_deg(o: &Outcome) -> (f64, f64) {
    (o.summary.final_translation_error * 1e3, o.summary.final_rotation_error.to_degrees())
}

/// Noise-free 12 -> 6 mm lens change: back within 1 mm and 0.1 degrees.
#[test]
fn lens_change_12_to_6_converges() {
    let o = run(&builtin("lens-12-6").unwrap());
    let (t, r) = mm_deg(&o);
    assert_eq!(o.summary.status, Status::Converged, "{}", report(&o));
    assert!(t < 1.0 && r < 0.1, "{}", report(&o));
    assert!(o.summary.prop1 && o.summary.prop2);
}

/// Every lens change of sec. 5.2 converges with the invariant law, and IBVS with the same
/// lens change ends more than 100 mm away (or loses the object).
#[test]
fn invariant_law_survives_lens_changes_ibvs_does_not() {
    for pair in ["12-12", "12-6", "25-12", "6-12"] {
        let o = run(&builtin(&format!("lens-{pair}")).unwrap());
        let (t, r) = mm_deg(&o);
        assert!(o.summary.status == Status::Converged && t < 1.0 && r < 0.1, "lens-{pair}: {}", report(&o));
        let o = run(&builtin(&format!("ibvs-{pair}")).unwrap());
        let (t, _) = mm_deg(&o);
        if pair == "12-12" {
            assert!(o.summary.status == Status::Converged && t < 1.0, "ibvs-{pair}: {}", report(&o));
        } else {
            assert!(t > 100.0 || o.summary.status == Status::LostFeatures, "ibvs-{pair}: {}", report(&o));
        }
    }
    let o = run(&builtin("ibvs-12-6").unwrap());
    assert!(mm_deg(&o).0 > 100.0, "{}", report(&o));
}

/// 0.5 px of noise on the current images (clean reference, 3D object): within 2 mm and
/// 0.3 degrees, for several seeds.
#[test]
fn noisy_lens_change_ends_within_2mm() {
    let base = builtin("noise-12-6").unwrap();
    assert_eq!(base.noise.pixel_sigma, 0.5);
    assert!(!base.noise.on_reference);
    for seed in 0..8 {
        let mut s = base.clone();
        s.noise.seed = seed;
        let o = run(&s);
        let (t, r) = mm_deg(&o);
        assert!(t < 2.0 && r < 0.3, "seed {seed}: {}", report(&o));
    }
    // Reproducible: the same seed gives the same run.
    assert_eq!(run(&base).summary, run(&base).summary);
}

fn with_start(mut s: Scenario, position: [f64; 3], rotation: [f64; 3]) -> Scenario {
    s.start.as_mut().unwrap().position = position;
    s.start.as_mut().unwrap().rotation_deg = rotation;
    s
}

/// A basis point out of the image from the start (issue 27): the session switches to a basis
/// among the visible points and the run goes on to the goal.
#[test]
fn basis_point_out_of_the_image_switches_the_basis() {
    let mut s = builtin("lens-12-6").unwrap();
    s.object.basis = Some([0, 5, 11]);
    // Translate sideways: the object shifts left in the image and point 0 leaves it first.
    let s = with_start(s, [0.3, 0.0, 0.0], [0.0, 0.0, 0.0]);
    let o = simulate(&s.to_config().unwrap(), &mut |_, _| true).unwrap();
    assert_eq!(o.summary.status, Status::Converged, "{}", report(&o));
    assert!(o.summary.basis_switches >= 1 && !o.summary.basis.contains(&0), "{:?}", o.summary.basis);
    let rec = o.recording.unwrap();
    assert!(!rec.visible[0], "point 0 must be flagged not visible");
    assert!(rec.pixels[0].is_nan());
}

/// An occluded basis point (a plate between the camera and the point): the basis switches
/// and the run converges.
#[test]
fn occluded_basis_point_switches_the_basis() {
    let mut s = builtin("lens-12-6").unwrap();
    s.object.basis = Some([0, 3, 9]);
    // Where the camera centre is after 20 iterations of a clean run.
    let clean = run(&s).recording.unwrap();
    let c = &clean.pose[20 * 16..21 * 16];
    let center = [c[3], c[7], c[11]];
    // A small plate on that line of sight to point 9, 20 cm in front of the point: the start
    // and the reference pose see point 9, the camera loses it on its way back.
    let p = s.object.points[9];
    let d: Vec<f64> = (0..3).map(|i| p[i] - center[i]).collect();
    let len = d.iter().map(|v| v * v).sum::<f64>().sqrt();
    let position = [0, 1, 2].map(|i| p[i] - d[i] / len * 0.2);
    s.object.bodies.push(vsinv::sim::scenario::BodySpec::Cuboid {
        half_extents: [0.004, 0.004, 0.001],
        position,
        rotation_deg: [0.0; 3],
    });
    let o = run(&s);
    assert_eq!(o.summary.status, Status::Converged, "{}", report(&o));
    assert!(o.summary.basis_switches >= 1 && !o.summary.basis.contains(&9), "{:?}", o.summary.basis);
    let rec = o.recording.unwrap();
    let n = rec.n_points;
    assert!((0..rec.len()).any(|row| !rec.visible[row * n + 9]), "point 9 must be hidden on the way");
}

/// Non-basis points may hide for a while: the run carries on with the others.
#[test]
fn occlusion_scenario_recovers_hidden_points() {
    let o = run(&builtin("occlusion").unwrap());
    assert_eq!(o.summary.status, Status::Converged, "{}", report(&o));
    let rec = o.recording.unwrap();
    let n = rec.n_points;
    let seen_first = rec.visible[..n].iter().filter(|v| **v).count();
    let seen_last = rec.visible[rec.visible.len() - n..].iter().filter(|v| **v).count();
    assert!(seen_first < n && seen_first >= 6, "at the start {seen_first} of {n} visible");
    assert_eq!(seen_last, n);
}

/// The Cartesian robot respects its joint position and speed limits.
#[test]
fn cartesian_robot_respects_joint_limits() {
    let mut s = builtin("cartesian-12-6").unwrap();
    // Tighten two limits so that they are hit: z cannot come closer than -0.05 m to the
    // goal's 0 (the goal is out of reach), and the wrist's c axis turns at 15 deg/s at most.
    let mut max = s.robot.joint_max.unwrap();
    max[2] = -0.05;
    s.robot.joint_max = Some(max);
    let mut vel = s.robot.joint_velocity.unwrap();
    vel[5] = 15.0;
    s.robot.joint_velocity = Some(vel);
    s.stop.max_iterations = 400;
    let config = s.to_config().unwrap();
    let vsinv::sim::robot::Robot::Cartesian(vsinv::sim::robot::CartesianRobot { limits }) = config.robot else {
        panic!("not cartesian")
    };
    let o = simulate(&config, &mut |_, _| true).unwrap();
    let rec = o.recording.unwrap();
    let rows = rec.len();
    let mut hit_position = false;
    for r in 0..rows {
        let q = &rec.joints[6 * r..6 * r + 6];
        for (i, qi) in q.iter().enumerate() {
            assert!(*qi >= limits.min[i] - 1e-9 && *qi <= limits.max[i] + 1e-9, "row {r} joint {i} = {qi}");
        }
        hit_position |= (q[2] - limits.max[2]).abs() < 1e-9;
        if r > 0 {
            let p = &rec.joints[6 * (r - 1)..6 * r];
            for i in 0..6 {
                let speed = (q[i] - p[i]).abs() / s.control.dt;
                // The executed twist is held constant in the camera frame over dt, so joint
                // rates drift slightly within a step: allow 0.1 %.
                assert!(speed <= limits.velocity[i] * 1.001, "row {r} joint {i} speed {speed}");
            }
        }
    }
    assert!(hit_position, "the z limit was never reached; the test does not test anything");
    assert_eq!(o.summary.status, Status::MaxIterations);
}

/// Sec. 5.1: a stationary zooming camera: the image error grows while the invariant error
/// stays at zero without noise, and at the noise level with it.
#[test]
fn stationary_zoom_invariant_error_stays_flat() {
    let noisy = builtin("zoom-stationary").unwrap();
    let mut clean = noisy.clone();
    clean.noise.pixel_sigma = 0.0;
    let rec = run(&clean).recording.unwrap();
    assert_eq!(rec.len(), 6);
    let img = &rec.image_error;
    assert!(img.windows(2).all(|w| w[1] > w[0]) && img[5] > 50.0, "image error must grow: {img:?}");
    assert!(rec.invariant_error.iter().all(|&e| e < 1e-9), "{:?}", rec.invariant_error);
    assert!(rec.translation_error.iter().all(|&t| t == 0.0), "the camera must not move");
    let rec = run(&noisy).recording.unwrap();
    assert!(rec.image_error[5] > 50.0);
    assert!(rec.invariant_error.iter().all(|&e| e > 1e-4 && e < 0.03), "{:?}", rec.invariant_error);
}

/// A planar object ends as degenerate with a clear message.
#[test]
fn planar_object_is_degenerate() {
    let o = run(&builtin("planar").unwrap());
    assert_eq!(o.summary.status, Status::Degenerate, "{}", report(&o));
    assert!(o.summary.message.contains("planar"), "{}", o.summary.message);
}

/// A zoom during the servo: Prop. 2 holds over the schedule and the camera converges.
#[test]
fn zoom_during_servo_converges() {
    let o = run(&builtin("zoom-servo").unwrap());
    let (t, r) = mm_deg(&o);
    assert!(o.summary.status == Status::Converged && t < 1.0 && r < 0.1, "{}", report(&o));
    assert!(o.summary.prop2);
}

/// The recording has one row per iteration and consistent shapes.
#[test]
fn recording_shapes() {
    let o = run(&builtin("lens-12-6").unwrap());
    let r = o.recording.unwrap();
    let rows = o.summary.iterations + 1;
    assert_eq!(r.len(), rows);
    assert_eq!(r.pose.len(), rows * 16);
    assert_eq!(r.twist.len(), rows * 6);
    assert_eq!(r.joints.len(), rows * 6);
    assert_eq!(r.pixels.len(), rows * 12 * 2);
    assert_eq!(r.visible.len(), rows * 12);
    assert_eq!(r.eps.len(), rows * 5);
    assert!(r.twist[(rows - 1) * 6].is_nan() && r.twist[0].is_finite());
    assert!((r.translation_error[0] - o.summary.start_error.0).abs() < 1e-12);
}

fn scenario_error(text: &str) -> (String, String) {
    match Scenario::from_toml(text) {
        Err(SimError::Scenario { key, reason }) => (key.to_string(), reason),
        other => panic!("expected a scenario error, got {other:?}"),
    }
}

/// Bad files get an error that names the key and the problem.
#[test]
fn bad_scenarios_name_the_key() {
    let good = BUILTIN.iter().find(|(n, _)| *n == "lens-12-6").unwrap().1;
    let (key, reason) = scenario_error(&good.replace("[control]\n", "[control]\nspeed = 3\n"));
    assert!(key.contains("control") && reason.contains("speed"), "{key}: {reason}");
    let (key, reason) = scenario_error(&good.replace("gain = 1.0", "gain = \"fast\""));
    assert_eq!(key, "control.gain", "{reason}");
    let (key, _) = scenario_error(&good.replace("gain = 1.0", "gain = -1.0"));
    assert_eq!(key, "control.gain");
    let mut few = builtin("lens-12-6").unwrap();
    few.object.points.truncate(5);
    let (key, reason) = scenario_error(&few.to_toml().unwrap());
    assert!(key == "object.points" && reason.contains("at least 6"), "{key}: {reason}");
    let (key, reason) = scenario_error(&good.replace("position = [0.2, -0.15, -0.15]", "position = [0.0, 0.0, 1.5]"));
    assert!(key == "start" && reason.contains("behind the camera"), "{key}: {reason}");
    let (key, _) = scenario_error(&good.replace("[-0.15, -0.12, 0.60]", "[-0.15, -0.12, -0.60]"));
    assert!(key.starts_with("object.points"), "{key}");
    let (key, _) = scenario_error(&good.replace("fku = 600.0", "fku = -600.0"));
    assert_eq!(key, "camera.fku");
    let (key, _) = scenario_error(&good.replace("depths = \"reference\"", "depths = \"guessed\""));
    assert_eq!(key, "control.depths");
    let (key, reason) = scenario_error("name = \"x\"\n");
    assert!(key.is_empty() && reason.contains("missing field"), "{key}: {reason}");
}

/// Scenarios survive a TOML and a JSON round trip unchanged.
#[test]
fn scenario_round_trips() {
    for (name, _) in BUILTIN {
        let s = builtin(name).unwrap();
        assert_eq!(Scenario::from_toml(&s.to_toml().unwrap()).unwrap(), s, "{name}");
        assert_eq!(Scenario::from_json(&s.to_json().unwrap()).unwrap(), s, "{name}");
    }
}

/// The depth-estimator interface: an estimator giving depths up to a scale kappa (here the
/// reference depths times 3) drives the law like any depth source (Prop. 1 holds for any
/// kappa > 0), and a failing estimator ends the run with a clear message.
#[test]
fn depth_estimator_interface() {
    use std::sync::Arc;
    use vsinv::sim::scene::Scene;
    use vsinv::sim::{DepthEstimator, DepthEstimatorFactory, DepthSource};

    struct Scaled(Vec<f64>);
    impl DepthEstimator for Scaled {
        fn estimate(&mut self, _: &[[f64; 2]], _: &[bool], depths: &mut [f64]) -> vsinv::Result<()> {
            depths.copy_from_slice(&self.0);
            Ok(())
        }
    }
    struct ScaledFactory;
    impl DepthEstimatorFactory for ScaledFactory {
        fn start(&self, scene: &Scene, _: &[[f64; 2]]) -> Result<Box<dyn DepthEstimator>, SimError> {
            Ok(Box::new(Scaled(scene.points().iter().map(|p| 3.0 * p[2]).collect())))
        }
    }
    struct Failing;
    impl DepthEstimator for Failing {
        fn estimate(&mut self, _: &[[f64; 2]], _: &[bool], _: &mut [f64]) -> vsinv::Result<()> {
            Err(vsinv::Error::InvalidParameter { name: "depths", reason: "no epipole".into() })
        }
    }
    struct FailingFactory;
    impl DepthEstimatorFactory for FailingFactory {
        fn start(&self, _: &Scene, _: &[[f64; 2]]) -> Result<Box<dyn DepthEstimator>, SimError> {
            Ok(Box::new(Failing))
        }
    }

    let mut config = builtin("lens-12-6").unwrap().to_config().unwrap();
    config.depths = DepthSource::Estimated(Arc::new(ScaledFactory));
    let o = simulate(&config, &mut |_, _| true).unwrap();
    let (t, r) = mm_deg(&o);
    assert!(o.summary.status == Status::Converged && t < 1.0 && r < 0.1, "{}", report(&o));
    config.depths = DepthSource::Estimated(Arc::new(FailingFactory));
    let o = simulate(&config, &mut |_, _| true).unwrap();
    assert_eq!(o.summary.status, Status::Degenerate);
    assert!(o.summary.message.contains("no epipole"), "{}", o.summary.message);
}

/// Sec. 5.3: K_hat 50% off, depths estimated from images only, a planned path: the camera
/// ends within 1 mm and 0.1 degrees, follows the straight line more closely with N = 3000
/// than with N = 500, and with feed-forward the observed max ||eps|| stays below psi/phi.
#[test]
fn path_planning_scenarios() {
    let mut deviation = Vec::new();
    for name in ["path-500", "path-3000", "path-500-feedforward"] {
        let o = run(&builtin(name).unwrap());
        let (t, r) = mm_deg(&o);
        assert!(o.summary.status == Status::Converged && t < 1.0 && r < 0.1, "{name}: {}", report(&o));
        let tracking = o.summary.tracking.expect("a path run reports Prop. 3");
        assert!(tracking.plane_parallax_residual < 1e-9);
        assert!(tracking.sigma > 0.0 && tracking.bound.is_finite());
        if name.ends_with("feedforward") {
            assert!(tracking.max_eps <= tracking.bound, "{tracking:?}");
        }
        eprintln!(
            "{name}: {} | line {:.3} mm | sigma {:.4} psi {:.4} phi {:.4} bound {:.4} max eps {:.4}",
            report(&o),
            o.summary.max_line_deviation * 1e3,
            tracking.sigma,
            tracking.psi,
            tracking.phi,
            tracking.bound,
            tracking.max_eps
        );
        deviation.push(o.summary.max_line_deviation);
    }
    assert!(deviation[1] < deviation[0], "N = 3000 must stay closer to the line: {deviation:?}");
    // Without a path the same start leaves the line much further.
    let mut no_path = builtin("path-500").unwrap();
    no_path.path = None;
    let o = run(&no_path);
    assert!(o.summary.max_line_deviation > 2.0 * deviation[0], "{}", o.summary.max_line_deviation);
}

#[test]
fn rotation_deg_is_the_key_and_the_older_rotation_is_read_as_degrees() {
    let text = builtin("lens-12-6").unwrap().to_toml().unwrap();
    assert!(text.contains("rotation_deg = [") && !text.contains("\nrotation = ["));
    let old = text.replace("rotation_deg = [", "rotation = [");
    let (a, b) = (Scenario::from_toml(&text).unwrap(), Scenario::from_toml(&old).unwrap());
    assert_eq!(a.start, b.start);
    assert_eq!(a.to_config().unwrap().start, b.to_config().unwrap().start);
    let both = text.replace("rotation_deg = [", "rotation = [0.0, 0.0, 0.0]\nrotation_deg = [");
    match Scenario::from_toml(&both) {
        Err(SimError::Scenario { key, reason }) => {
            assert!(key.to_string().starts_with("start") && reason.contains("duplicate"), "{key}: {reason}")
        }
        other => panic!("{other:?}"),
    }
}

/// The law owns what it can do: a planned path (invariant space) under IBVS, or too few
/// points for the invariant law, is refused when the servo session starts, by name.
#[test]
fn the_law_refuses_what_it_cannot_do() {
    use vsinv::core::ibvs::Interaction;
    let mut config = builtin("path-500").unwrap().to_config().unwrap();
    config.law =
        vsinv::sim::Law::Ibvs { gain: 1.0, interaction: Interaction::Current, adaptive_gain: None, twist_limits: None };
    let err = simulate(&config, &mut |_, _| true).unwrap_err();
    assert!(matches!(err, SimError::Core(Error::InvalidParameter { name: "path", .. })), "{err}");
    let mut config = builtin("lens-12-6").unwrap().to_config().unwrap();
    let points: Vec<[f64; 3]> = config.scene.points().iter().take(5).copied().collect();
    config.scene = vsinv::sim::scene::Scene::new(points, Vec::new()).unwrap();
    let err = simulate(&config, &mut |_, _| true).unwrap_err();
    assert!(matches!(err, SimError::Core(Error::TooFewPoints { needed: 6, got: 5, .. })), "{err}");
}
