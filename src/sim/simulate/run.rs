//! The state of a run between iterations, and its iteration: observe the world, let the
//! servo session decide and compute, move the robot, record.

use nalgebra::{Isometry3, Vector3, Vector6};

use crate::core::camera::Intrinsics;
use crate::core::se3::pose_error;
use crate::core::stability::stability_verdicts;
use crate::error::fixed_or_short;
use crate::servo::{Servo, ServoStep};
use crate::sim::config::SimulationConfig;
use crate::sim::depth_source::DepthSource;
use crate::sim::error::Result;
use crate::sim::image_loop::{ImageLoop, Tracked, pixel_size};
use crate::sim::outcome::{Outcome, Recording, Status, Summary};
use crate::sim::record_budget::RecordBudget;
use crate::sim::robot::{RobotEvent, RobotMotion};
use crate::sim::scenario::DEPTHS_REMEDY;
use crate::sim::scene::Observation;
use crate::vision::render::Renderer;

use super::pixel_noise::PixelNoise;
use super::prop3::Prop3Figures;
use super::{reference_pixels, start_servo};

/// How a run ends: its status and the reason, in words.
pub(super) type End = (Status, String);

/// The world of a run and the servo session it drives.
pub(super) struct Run<'a> {
    config: &'a SimulationConfig,
    servo: Servo,
    prop1: bool,
    prop2: bool,
    noise: PixelNoise,
    obs: Observation,
    /// The points as the camera delivers them (noisy or tracked, before undistortion).
    pixels: Vec<[f64; 2]>,
    /// Points visible in the scene (and found by the tracker with images).
    visible: Vec<bool>,
    images: Option<ImageLoop>,
    detection: Vec<f64>,
    pose: Isometry3<f64>,
    /// Joint positions: the robot's state.
    joints: Vec<f64>,
    /// Smallest manipulability so far (robots that have one).
    min_manipulability: Option<f64>,
    /// Set when a robot step ends the run (joint limit, singularity).
    robot_end: Option<End>,
    max_line_deviation: f64,
    /// Largest commanded linear (m/s) and angular (rad/s) speeds so far.
    peak_speeds: (f64, f64),
    prop3: Prop3Figures,
    recording: Option<Recording>,
    budget: RecordBudget,
    iteration: usize,
}

impl<'a> Run<'a> {
    /// The run of `config` from its reference; `renderer` (the configuration's `[vision]`
    /// one, None without it) renders the loop's images.
    pub(super) fn new(
        config: &'a SimulationConfig,
        mut obs: Observation,
        reference_depths: Vec<f64>,
        renderer: Option<Renderer>,
    ) -> Result<Self> {
        let mut noise = PixelNoise::new(config.noise.pixel_sigma, config.noise.seed)?;
        let pixels = reference_pixels(config, &mut obs, &mut noise)?;
        let n = pixels.len();
        let servo = start_servo(config, pixels, &reference_depths)?;
        let gain = servo.law().gain();
        let (prop1, prop2, _) = stability_verdicts(&config.camera.schedule()?, &config.estimate.matrix(), 1.0, gain)?;
        let images = match renderer {
            Some(r) => Some(ImageLoop::new(r, &config.scene, pixel_size(config.camera.image, "camera")?)?),
            None => None,
        };
        let (joints, min_manipulability) = config.robot.as_robot().start(&config.start)?;
        Ok(Self {
            config,
            servo,
            prop1,
            prop2,
            noise,
            obs,
            pixels: vec![[0.0; 2]; n],
            visible: vec![false; n],
            images,
            detection: vec![f64::NAN; n],
            pose: config.start,
            recording: config.record.then(|| Recording { n_points: n, n_joints: joints.len(), ..Default::default() }),
            budget: RecordBudget::new(config.record_bytes, n, joints.len(), config.vision.is_some()),
            joints,
            min_manipulability,
            robot_end: None,
            max_line_deviation: 0.0,
            peak_speeds: (0.0, 0.0),
            prop3: Prop3Figures::new(),
            iteration: 0,
        })
    }

    /// One iteration; `Some` when the run ends.
    pub(super) fn iterate(&mut self, progress: &mut dyn FnMut(usize, usize) -> bool) -> Result<Option<End>> {
        let t = self.iteration as f64 * self.config.dt;
        let k = self.config.camera.at(t)?;
        if let Err(e) = self.observe(&k) {
            return Ok(Some((Status::LostFeatures, format!("dot tracking failed: {e}"))));
        }
        self.record_observation(t);
        if let Some(end) = self.robot_end.take() {
            return Ok(Some(end));
        }
        if let Some(end) = self.stop_check(progress) {
            return Ok(Some(end));
        }
        let step = self.servo.control();
        self.after_control(&step, &k);
        // The stop's reason in the scenario's words (the remedy names its key).
        if let Some(status) = step.verdict.status() {
            return Ok(Some((status, step.verdict.reason_with_remedy(DEPTHS_REMEDY).unwrap_or_default())));
        }
        if let Err(end) = self.move_robot(&step.twist) {
            return Ok(Some(end));
        }
        self.iteration += 1;
        Ok(None)
    }

    /// Observes the scene with K(t) (the exact projections with pixel noise, or the dots
    /// tracked in the rendered image) and hands the points to the servo session.
    fn observe(&mut self, k: &Intrinsics) -> Result<()> {
        let (scene, pose, camera) = (&self.config.scene, &self.pose, &self.config.camera);
        scene.observe_through(pose, k, &camera.distortion, camera.image, &mut self.obs);
        self.visible.copy_from_slice(&self.obs.visible);
        match self.images.as_mut() {
            Some(images) => {
                let run =
                    Tracked { pixels: &mut self.pixels, visible: &mut self.visible, detection: &mut self.detection };
                images.observe(pose, k, &camera.distortion, &self.obs, run)?;
            }
            None => {
                self.pixels.copy_from_slice(&self.obs.pixels);
                self.noise.add(&mut self.pixels, &self.visible);
            }
        }
        let depths = matches!(self.config.depths, DepthSource::True).then_some(self.obs.depths.as_slice());
        Ok(self.servo.observe(&self.pixels, Some(&self.visible), depths)?)
    }

    fn record_observation(&mut self, t: f64) {
        // The goal is the identity, so the line from start to goal ends at the origin.
        let position = self.pose.translation.vector;
        let deviation = distance_to_segment(&position, &self.config.start.translation.vector, &Vector3::zeros());
        self.max_line_deviation = self.max_line_deviation.max(deviation);
        let Some(r) = self.recording.as_mut() else { return };
        self.budget.before_row(r, self.iteration);
        let (pose, m, servo) = (&self.pose, self.servo.telemetry(), &self.servo);
        r.time.push(t);
        let h = pose.to_homogeneous();
        r.pose.extend((0..16).map(|i| h[(i / 4, i % 4)]));
        r.joints.extend_from_slice(&self.joints);
        for (p, &v) in servo.pixels().iter().zip(servo.visible()) {
            r.pixels.extend_from_slice(&if v { *p } else { [f64::NAN; 2] });
        }
        r.visible.extend_from_slice(servo.visible());
        r.invariant_error.push(m.invariant_error);
        r.eps_z.push(m.eps_z);
        r.image_error.push(m.image_error);
        r.translation_error.push(pose.translation.vector.norm());
        r.rotation_error.push(pose.rotation.angle());
        if self.images.is_some() {
            r.detection_error.extend_from_slice(&self.detection);
        }
    }

    /// The stop rules, in order: divergence (the world's: the simulator knows the pose), then
    /// the servo session's verdict, then the caller.
    fn stop_check(&mut self, progress: &mut dyn FnMut(usize, usize) -> bool) -> Option<End> {
        let stop = &self.config.stop;
        let distance = self.pose.translation.vector.norm();
        if distance.is_nan() || distance > stop.divergence_distance {
            return Some((Status::Diverged, format!("camera {} m from the goal", fixed_or_short(distance, 2))));
        }
        let verdict = self.servo.verdict();
        if let Some(status) = verdict.status() {
            return Some((status, verdict.reason_with_remedy(DEPTHS_REMEDY).unwrap_or_default()));
        }
        if self.iteration.is_multiple_of(64) && !progress(self.iteration, stop.max_iterations) {
            return Some((Status::MaxIterations, "stopped by the caller".into()));
        }
        None
    }

    /// Prop. 3's figures while the reference moves along a planned path, and the record of
    /// the law's task function.
    fn after_control(&mut self, step: &ServoStep, k: &Intrinsics) {
        let t = self.iteration as f64 * self.config.dt;
        let moving = self.servo.path().is_some_and(|(duration, _)| t < duration);
        if let (true, true, Some(state)) = (step.telemetry.law_ran, moving, self.servo.invariant_state()) {
            let (depths, visible) = (self.servo.depths(), self.servo.visible());
            let (sum, count) = (0..depths.len())
                .filter(|&i| visible[i])
                .fold((0.0, 0.0), |(s, c), i| (s + depths[i] / self.obs.depths[i], c + 1.0));
            let feedforward = self.servo.law().invariant().is_some_and(|c| c.config().feedforward);
            self.prop3.observe(state, k, &self.config.estimate, sum / count, feedforward);
        }
        if let Some(r) = self.recording.as_mut() {
            r.eps.extend_from_slice(&step.telemetry.eps);
            r.tracking_error.push(step.telemetry.tracking_error);
        }
    }

    /// Sends the twist to the robot for one period. A non-finite pose is never taken (the
    /// run ends at the last finite one); a robot event (joint limit, singularity) ends the
    /// run once the image where the robot stopped is recorded.
    fn move_robot(&mut self, twist: &Vector6<f64>) -> std::result::Result<(), End> {
        let (v, w) = (twist.fixed_rows::<3>(0).norm(), twist.fixed_rows::<3>(3).norm());
        self.peak_speeds = (self.peak_speeds.0.max(v), self.peak_speeds.1.max(w));
        let robot = self.config.robot.as_robot();
        let moved: RobotMotion = robot
            .step(&self.pose, &self.joints, twist, self.config.dt)
            .map_err(|e| (Status::Diverged, e.to_string()))?;
        let finite =
            moved.pose.translation.vector.iter().chain(moved.pose.rotation.coords.iter()).all(|v| v.is_finite());
        if !finite {
            return Err((Status::Diverged, "the integrated pose is not finite".into()));
        }
        self.pose = moved.pose;
        self.joints.copy_from_slice(&moved.joints);
        if let (Some(w), Some(m)) = (self.min_manipulability, moved.manipulability) {
            self.min_manipulability = Some(w.min(m));
        }
        if let Some(r) = self.recording.as_mut() {
            r.twist.extend_from_slice(moved.twist.as_slice());
            if let Some(velocities) = &moved.joint_velocities {
                r.joint_velocities.extend_from_slice(velocities);
            }
        }
        self.robot_end = moved.event.map(|event| {
            let status = match event {
                RobotEvent::JointLimit { .. } => Status::JointLimit,
                RobotEvent::Singular { .. } => Status::Singular,
            };
            (status, event.message())
        });
        Ok(())
    }

    pub(super) fn finish(mut self, (status, message): End) -> Outcome {
        // Pad the per-step columns of the last recorded row (no step followed it).
        if let Some(r) = self.recording.as_mut() {
            let rows = r.time.len();
            r.twist.resize(rows * 6, f64::NAN);
            r.eps.resize(rows * 5, f64::NAN);
            r.tracking_error.resize(rows, f64::NAN);
            if self.min_manipulability.is_some() {
                r.joint_velocities.resize(rows * r.n_joints, f64::NAN);
            }
        }
        let summary = self.summary(status, message);
        Outcome { summary, recording: self.recording, reference_pixels: self.servo.reference_pixels().to_vec() }
    }

    fn summary(&self, status: Status, message: String) -> Summary {
        let goal = Isometry3::identity();
        let (final_t, final_r) = pose_error(&goal, &self.pose);
        let stop = &self.config.stop;
        let within_tolerance =
            final_t <= stop.max_translation_uncertainty && final_r <= stop.max_rotation_uncertainty_deg.to_radians();
        let (servo, m) = (&self.servo, self.servo.telemetry());
        Summary {
            status,
            message,
            iterations: self.iteration,
            final_translation_error: final_t,
            final_rotation_error: final_r,
            final_image_error: m.image_error,
            final_invariant_error: m.invariant_error,
            final_tau: m.tau,
            prop1: self.prop1,
            prop2: self.prop2,
            stop_rule: servo.stop_rule(),
            start_error: pose_error(&goal, &self.config.start),
            basis: servo.basis(),
            basis_switches: servo.basis_switches(),
            max_line_deviation: self.max_line_deviation,
            peak_speeds: self.peak_speeds,
            tracking: servo.path().map(|path| self.prop3.summary(servo.law().gain(), path)),
            detection_error: self.images.as_ref().map(ImageLoop::error_summary),
            min_manipulability: self.min_manipulability,
            certainty: servo.certainty(),
            within_tolerance,
        }
    }
}

/// Distance from `p` to the segment `[a, b]`.
fn distance_to_segment(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    let t = if len2 > 0.0 { ((p - a).dot(&ab) / len2).clamp(0.0, 1.0) } else { 0.0 };
    (p - (a + ab * t)).norm()
}
