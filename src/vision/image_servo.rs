//! [`ImageServo`]: one pipeline from image to twist. The reference image (taken with any
//! camera: no K* is needed, sec. 2) is searched once for the target's points; then every
//! frame of the servo camera is searched by a [`Detector`], its points are matched to the
//! reference by identity, and the [`Servo`] session (which undistorts them with K_hat and the
//! believed lens) steps the law. A point the detector does not report, or reports lost, is
//! not visible for that step: the session never receives a wrong position.

use crate::core::camera::Intrinsics;
use crate::core::distortion::{Distortion, undistort_point};
use crate::error::{Error, check_finite_points};
use crate::servo::{Servo, ServoConfig, ServoDepths, ServoReference, ServoStep};
use crate::vision::detector::dot_tracking::DotTracking;
use crate::vision::detector::tags::TagDetector;
use crate::vision::detector::{Detection, Detector, Expected};
use crate::vision::error::{Result, VisionError};
use crate::vision::image::{GreyBuffer, GreyView, Pixels, view_of};
use crate::vision::tags::{TagDecoder, TagFamily};
use crate::vision::tracker::TrackerConfig;

/// What the pipeline looks for in the images, and how it is found.
#[derive(Debug, Clone, PartialEq)]
pub enum ImageTarget {
    /// Dots, tracked from frame to frame: approximate pixels of each dot (clicks) in the
    /// reference image, and in the first frame (None: near the reference's, which suits a
    /// first view close to the reference one). Dot `i` has identity `i`.
    Dots {
        /// One approximate pixel per dot in the reference image.
        reference_points: Vec<[f64; 2]>,
        /// One approximate pixel per dot in the first frame (None: the reference's).
        first_points: Option<Vec<[f64; 2]>>,
        /// The tracker's settings, for the reference image and for the frames.
        tracker: TrackerConfig,
    },
    /// AprilTags of one family, decoded afresh in every image: the corners of the tags
    /// `ids` (None: of every tag decoded in the reference image), corner `c` of tag `t`
    /// under identity `4 t + c`. No clicks: tags match by identity between any two cameras.
    Tags {
        /// The tag family.
        family: TagFamily,
        /// The tags to servo on (each must be decoded in the reference image).
        ids: Option<Vec<u32>>,
        /// The quad search's decimation (`1..=8`, [`TagDecoder::with_decimation`]); None:
        /// the detector's default.
        decimation: Option<u32>,
    },
}

/// What the pipeline needs of a target on real images: a detector, the hints it starts with in
/// the reference image and in the first frame, and which reference points to keep. A target
/// type implements it next to its [`Target`](crate::vision::Target) (its entry of
/// [`TARGETS`](crate::vision::TARGETS) builds it from the arguments); [`ImageTarget`] implements
/// it for dots and tags.
pub trait ImageTargetKind: Send + Sync + std::fmt::Debug {
    /// A detector of this target, not started: for the reference image, or for the frames
    /// (`frames`).
    fn detector(&self, frames: bool) -> Result<Box<dyn Detector>>;

    /// The hints for the reference image (none: the detector needs no help).
    fn reference_hints(&self) -> Vec<Expected> {
        Vec::new()
    }

    /// The hints for the first frame, given the reference points found.
    fn first_hints(&self, _reference: &[Detection]) -> Vec<Expected> {
        Vec::new()
    }

    /// The reference points the target keeps (default: all found).
    fn select(&self, found: Vec<Detection>) -> Result<Vec<Detection>> {
        Ok(found)
    }

    /// Checks the target's own values before the reference image is searched.
    fn validate(&self) -> Result<()> {
        Ok(())
    }

    /// Layers of convex hull the session's basis choice sets aside
    /// ([`ServoConfig::basis_inset`](crate::servo::ServoConfig::basis_inset); default 0).
    fn basis_inset(&self) -> usize {
        0
    }

    /// The frames' detector, given the reference image and the points kept in it (default:
    /// [`detector`](Self::detector) of the frames, which needs neither; the keypoint target
    /// matches the frames to the reference image's descriptors).
    fn frames_detector(&self, _reference: &GreyView<'_>, _kept: &[Detection]) -> Result<Box<dyn Detector>> {
        self.detector(true)
    }
}

impl ImageTargetKind for ImageTarget {
    /// A detector of this target, not started (an error for a decimation out of range). In
    /// the reference image every dot must start; in the frames (`frames`), a dot that cannot
    /// start is not visible.
    fn detector(&self, frames: bool) -> Result<Box<dyn Detector>> {
        Ok(match self {
            ImageTarget::Dots { tracker, .. } if frames => Box::new(DotTracking::partial(*tracker)),
            ImageTarget::Dots { tracker, .. } => Box::new(DotTracking::new(*tracker)),
            ImageTarget::Tags { family, decimation: None, .. } => Box::new(TagDetector::new(*family)),
            ImageTarget::Tags { family, decimation: Some(d), .. } => {
                Box::new(TagDetector::with_decoder(TagDecoder::with_decimation(*family, *d)?))
            }
        })
    }

    /// The hints for the reference image: every dot's click, identities `0, 1, ...`.
    fn reference_hints(&self) -> Vec<Expected> {
        match self {
            ImageTarget::Dots { reference_points, .. } => hints(reference_points),
            ImageTarget::Tags { .. } => Vec::new(),
        }
    }

    /// The hints for the first frame, given the reference points found.
    fn first_hints(&self, reference: &[Detection]) -> Vec<Expected> {
        match self {
            ImageTarget::Dots { first_points: Some(points), .. } => hints(points),
            ImageTarget::Dots { first_points: None, .. } => {
                reference.iter().map(|d| Expected { id: d.id, pixel: d.pixel }).collect()
            }
            ImageTarget::Tags { .. } => Vec::new(),
        }
    }

    /// The reference points the target keeps: for tags with `ids`, the corners of those tags,
    /// each of which must be there.
    fn select(&self, found: Vec<Detection>) -> Result<Vec<Detection>> {
        let ImageTarget::Tags { ids: Some(ids), .. } = self else { return Ok(found) };
        if let Some(missing) = ids.iter().find(|&&t| !found.iter().any(|d| d.id / 4 == t)) {
            return Err(VisionError::InvalidImage {
                what: "reference_image".into(),
                reason: format!("tag {missing} (of the target's ids) is not decoded in it"),
            });
        }
        Ok(found.into_iter().filter(|d| ids.contains(&(d.id / 4))).collect())
    }

    /// Checks the hints: finite pixels, and as many in the first frame as in the reference.
    fn validate(&self) -> Result<()> {
        let ImageTarget::Dots { reference_points, first_points, .. } = self else { return Ok(()) };
        check_finite_points("reference_points", reference_points)?;
        let Some(first) = first_points else { return Ok(()) };
        check_finite_points("first_points", first)?;
        if first.len() != reference_points.len() {
            return Err(Error::Shape {
                what: "first_points",
                expected: format!("{} points (one per reference point)", reference_points.len()),
                got: format!("{} points", first.len()),
            }
            .into());
        }
        Ok(())
    }
}

fn hints(points: &[[f64; 2]]) -> Vec<Expected> {
    (0u32..).zip(points).map(|(id, &pixel)| Expected { id, pixel }).collect()
}

/// How the pipeline is set up besides its target.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageServoConfig {
    /// The servo session: the law, K_hat and the servo camera's believed lens, stop rules.
    pub servo: ServoConfig,
    /// The reference camera's own intrinsics and lens, to undistort the reference points
    /// (None: its pixels are taken as they are, a pinhole camera).
    pub reference_lens: Option<(Intrinsics, Distortion)>,
    /// Depths of the points at the reference pose, when known (IBVS and the reference depth
    /// source need them).
    pub reference_depths: Option<Vec<f64>>,
}

impl ImageServoConfig {
    /// A pipeline over `servo` with a pinhole reference camera and no reference depths.
    pub fn new(servo: ServoConfig) -> Self {
        Self { servo, reference_lens: None, reference_depths: None }
    }
}

/// The pipeline from image to twist. See the module documentation.
pub struct ImageServo {
    servo: Servo,
    detector: Box<dyn Detector>,
    ids: Vec<u32>,
    first: Vec<Expected>,
    started: bool,
    pixels: Vec<[f64; 2]>,
    found: Vec<bool>,
}

impl std::fmt::Debug for ImageServo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ImageServo").field("ids", &self.ids).field("started", &self.started).finish_non_exhaustive()
    }
}

impl ImageServo {
    /// Finds `target` in the reference image (every point must be found there) and sets up
    /// the session servoing to it.
    pub fn new<C: Pixels>(
        reference: &GreyBuffer<C>,
        target: &dyn ImageTargetKind,
        config: ImageServoConfig,
        depths: ServoDepths,
    ) -> Result<Self> {
        target.validate()?;
        let reference = view_of(reference)?;
        let found = reference_points(&reference, target.detector(false)?.as_mut(), &target.reference_hints())
            .map_err(|e| hints_named(e, "reference_points"))?;
        let found = target.select(found)?;
        let first = target.first_hints(&found);
        let mut config = config;
        config.servo.basis_inset = config.servo.basis_inset.max(target.basis_inset());
        Self::with_detector(&found, target.frames_detector(&reference, &found)?, first, config, depths)
    }

    /// The pipeline over any detector: `reference` holds the reference image's points (their
    /// identities and pixels; all found), `first` the hints the detector is started with on
    /// the first frame.
    pub fn with_detector(
        reference: &[Detection],
        detector: Box<dyn Detector>,
        first: Vec<Expected>,
        config: ImageServoConfig,
        depths: ServoDepths,
    ) -> Result<Self> {
        let ids = distinct_ids(reference)?;
        let mut pixels: Vec<[f64; 2]> = reference.iter().map(|d| d.pixel).collect();
        if let Some((k, distortion)) = &config.reference_lens {
            for p in &mut pixels {
                *p = undistort_point(*p, k, distortion)?;
            }
        }
        let n = pixels.len();
        let servo_reference = ServoReference { pixels, depths: config.reference_depths };
        let servo = Servo::new(config.servo, servo_reference, depths)?;
        Ok(Self { servo, detector, ids, first, started: false, pixels: vec![[0.0; 2]; n], found: vec![false; n] })
    }

    /// One frame: detect (the first frame starts the detector on its hints), match by
    /// identity, step the session. A first-frame hint outside the image is not an error: its
    /// point is not visible (the session works with the others, switching its basis if need
    /// be). A frame in which the detector cannot start is an error and the next frame starts
    /// it again.
    pub fn step<C: Pixels>(&mut self, image: &GreyBuffer<C>) -> Result<ServoStep> {
        let image = view_of(image)?;
        let basis = self.servo.basis().map(|i| self.ids[i]);
        self.detector.favour(&basis);
        let detections = if self.started {
            self.detector.detect(&image)?
        } else {
            // A hint outside the image, like any dot that cannot start, is left out by the
            // frames' detector (`DotTracking::partial`): its point is not visible.
            // The frames' detector leaves out each dot that cannot start, so it fails only when
            // none can: a first frame without the target (blank, dark, out of focus) is a lost
            // target, no point found, and the servo's verdict lost_features with a zero twist.
            let d = match self.detector.start(&image, &self.first) {
                Err(VisionError::InvalidImage { what, .. }) if what == "initial_pixels" => Vec::new(),
                other => other.map_err(|e| hints_named(e, "first_points"))?,
            };
            self.started = true;
            d
        };
        self.found.fill(false);
        for d in detections.iter().filter(|d| d.found) {
            if let Some(i) = self.ids.iter().position(|&id| id == d.id) {
                self.pixels[i] = d.pixel;
                self.found[i] = true;
            }
        }
        Ok(self.servo.step(&self.pixels, Some(&self.found), None)?)
    }

    /// The points' identities, in the session's order.
    pub fn ids(&self) -> &[u32] {
        &self.ids
    }

    /// The last frame's pixels (distorted, as detected; the last known where not found).
    pub fn pixels(&self) -> &[[f64; 2]] {
        &self.pixels
    }

    /// Per point: found in the last frame.
    pub fn found(&self) -> &[bool] {
        &self.found
    }

    /// Whether the detector's search of the last frame stopped at its bound on its work (a
    /// cluttered frame, [`Detector::stopped_early`]): a point not found may be in view.
    pub fn stopped_early(&self) -> bool {
        self.detector.stopped_early()
    }

    /// The servo session (its reference pixels, basis, telemetry, certainty).
    pub fn servo(&self) -> &Servo {
        &self.servo
    }
}

/// A detector's error about its hints (the tracker's `initial_pixels`) under the name the
/// pipeline's caller gave them.
fn hints_named(error: VisionError, name: &'static str) -> VisionError {
    match error {
        VisionError::InvalidImage { what, reason } if what == "initial_pixels" => {
            VisionError::InvalidImage { what: name.into(), reason }
        }
        VisionError::Core(Error::NonFinitePoint { what: "initial_pixels", row, column }) => {
            Error::NonFinitePoint { what: name, row, column }.into()
        }
        other => other,
    }
}

/// The points of the reference image: each hint's point must be found.
fn reference_points(image: &GreyView<'_>, detector: &mut dyn Detector, hints: &[Expected]) -> Result<Vec<Detection>> {
    let found: Vec<Detection> = detector.start(image, hints)?.into_iter().filter(|d| d.found).collect();
    if found.is_empty() {
        return Err(VisionError::InvalidImage {
            what: "reference_image".into(),
            reason: "the target was not found in it".into(),
        });
    }
    Ok(found)
}

/// The identities of the reference points; two points under one identity are an error.
fn distinct_ids(reference: &[Detection]) -> Result<Vec<u32>> {
    let ids: Vec<u32> = reference.iter().map(|d| d.id).collect();
    for (i, id) in ids.iter().enumerate() {
        if ids[..i].contains(id) {
            return Err(VisionError::InvalidImage {
                what: "reference_image".into(),
                reason: format!("point identity {id} found twice (point {i} and an earlier one)"),
            });
        }
    }
    Ok(ids)
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

    use super::*;
    use crate::core::camera::project_points;
    use crate::servo::{Law, Status, Verdict};
    use crate::vision::image::GreyImage;
    use crate::vision::render::{CameraView, RenderConfig, Renderer};
    use crate::vision::target::dots::Dots;

    /// Eight dots on two planes (a non-planar object), 0.5 m in front of the reference camera.
    fn object() -> Vec<[f64; 3]> {
        vec![
            [-0.06, -0.05, 0.5],
            [0.06, -0.05, 0.5],
            [0.06, 0.05, 0.5],
            [-0.06, 0.05, 0.5],
            [-0.03, -0.02, 0.44],
            [0.03, -0.02, 0.44],
            [0.03, 0.03, 0.46],
            [-0.02, 0.03, 0.46],
        ]
    }

    fn render(pose: &Isometry3<f64>, k: &Intrinsics) -> GreyImage {
        let dots = Dots::facing_reference(&object(), 0.004).unwrap();
        let none = Distortion::none();
        let view = CameraView { pose, intrinsics: k, distortion: &none, size: (640, 480) };
        let config = RenderConfig { noise_sigma: 0.0, ..RenderConfig::default() };
        Renderer::new(config).unwrap().render(&dots, None, &view, 0).unwrap().image
    }

    fn clicks(pose: &Isometry3<f64>, k: &Intrinsics) -> Vec<[f64; 2]> {
        let camera: Vec<[f64; 3]> = object()
            .iter()
            .map(|p| {
                let c = pose.inverse_transform_point(&nalgebra::Point3::new(p[0], p[1], p[2]));
                [c.x, c.y, c.z]
            })
            .collect();
        project_points(&camera, k).unwrap().0.iter().map(|p| [p[0] + 1.5, p[1] - 1.0]).collect()
    }

    /// A reference through a 12 mm lens, frames through a 6 mm lens (the paper's zoom): the
    /// pipeline's twists, integrated, bring the camera back to the reference pose.
    #[test]
    fn servoes_through_images_of_another_lens() {
        let k_ref = Intrinsics::pinhole(1600.0, 1600.0, 320.0, 240.0).unwrap();
        let k = Intrinsics::pinhole(800.0, 800.0, 320.0, 240.0).unwrap();
        let start = Isometry3::from_parts(
            Translation3::new(0.02, -0.01, -0.05),
            UnitQuaternion::from_euler_angles(0.05, -0.04, 0.1),
        );
        let target = ImageTarget::Dots {
            reference_points: clicks(&Isometry3::identity(), &k_ref),
            first_points: Some(clicks(&start, &k)),
            tracker: TrackerConfig::default(),
        };
        let mut servo_config = ServoConfig::new(Law::Invariant(Default::default()), k);
        servo_config.stop.max_iterations = 600;
        let config = ImageServoConfig {
            reference_depths: Some(object().iter().map(|p| p[2]).collect()),
            ..ImageServoConfig::new(servo_config)
        };
        let mut pipeline =
            ImageServo::new(&render(&Isometry3::identity(), &k_ref), &target, config, ServoDepths::Reference).unwrap();
        let mut pose = start;
        let status = loop {
            let step = pipeline.step(&render(&pose, &k)).unwrap();
            if let Verdict::Stop { status, reason, .. } = step.verdict {
                assert_eq!(status, Status::Converged, "{reason} after {} steps", pipeline.servo().iterations());
                break status;
            }
            assert!(pipeline.found().iter().all(|&f| f));
            let (v, w) = (step.twist.fixed_rows::<3>(0), step.twist.fixed_rows::<3>(3));
            let motion = Isometry3::new(Vector3::from(v) * 0.04, Vector3::from(w) * 0.04);
            pose *= motion;
        };
        assert_eq!(status, Status::Converged);
        assert!(pose.translation.vector.norm() < 1e-3, "{:?}", pose.translation);
        assert!(pose.rotation.angle() < 0.1f64.to_radians(), "{}", pose.rotation.angle());
    }

    /// A detector that reports fixed detections, to check matching by identity.
    struct Scripted(Vec<Vec<Detection>>);

    impl Detector for Scripted {
        fn start(&mut self, _: &GreyView<'_>, _: &[Expected]) -> Result<Vec<Detection>> {
            Ok(self.0.remove(0))
        }
        fn detect(&mut self, _: &GreyView<'_>) -> Result<Vec<Detection>> {
            Ok(self.0.remove(0))
        }
    }

    #[test]
    fn points_are_matched_by_identity_and_missing_ones_are_not_visible() {
        let d = |id, u: f64, v: f64, found| Detection { id, pixel: [u, v], found };
        let reference =
            [d(7, 100.0, 100.0, true), d(3, 300.0, 120.0, true), d(9, 200.0, 300.0, true), d(4, 150.0, 250.0, true)];
        let frames = vec![
            // Reordered, one extra identity (ignored).
            vec![
                d(9, 201.0, 301.0, true),
                d(42, 5.0, 5.0, true),
                d(7, 101.0, 101.0, true),
                d(4, 151.0, 251.0, true),
                d(3, 301.0, 121.0, true),
            ],
            // 3 missing, 4 reported lost.
            vec![d(7, 102.0, 102.0, true), d(9, 202.0, 302.0, true), d(4, 999.0, 999.0, false)],
        ];
        let k = Intrinsics::pinhole(800.0, 800.0, 320.0, 240.0).unwrap();
        let config = ImageServoConfig::new(ServoConfig::new(Law::Observe, k));
        let mut pipeline = ImageServo::with_detector(
            &reference,
            Box::new(Scripted(frames)),
            Vec::new(),
            config,
            ServoDepths::Constant(0.5),
        )
        .unwrap();
        let image = GreyImage::new(4, 4);
        pipeline.step(&image).unwrap();
        assert_eq!(pipeline.ids(), [7, 3, 9, 4]);
        assert_eq!(pipeline.pixels(), [[101.0, 101.0], [301.0, 121.0], [201.0, 301.0], [151.0, 251.0]]);
        assert_eq!(pipeline.found(), [true; 4]);
        pipeline.step(&image).unwrap();
        assert_eq!(pipeline.found(), [true, false, true, false]);
        assert_eq!(
            pipeline.pixels()[3],
            [151.0, 251.0],
            "a lost point keeps its last position, never the reported one"
        );
        let twice = [d(7, 1.0, 1.0, true), d(7, 2.0, 2.0, true), d(1, 3.0, 9.0, true)];
        let config = ImageServoConfig::new(ServoConfig::new(Law::Observe, k));
        let err = ImageServo::with_detector(
            &twice,
            Box::new(Scripted(vec![])),
            Vec::new(),
            config,
            ServoDepths::Constant(0.5),
        );
        assert!(matches!(err, Err(VisionError::InvalidImage { .. })));
    }

    /// Tags: the reference's corners by identity, no clicks; a tag left out of a frame drops
    /// its four corners; `ids` keeps the tags asked for, and one missing from the reference
    /// image is an error.
    #[test]
    fn tags_match_by_identity_and_a_missing_tag_drops_its_corners() {
        use crate::vision::tags::synthetic::{Placement, corners, draw};
        let family = TagFamily::Tag36h11;
        let place = |id, u, v, cell| Placement { id, centre: [u, v], cell, quarter_turns: 0 };
        let reference_tags = [place(3, 90.0, 80.0, 8.0), place(7, 230.0, 90.0, 8.0), place(12, 150.0, 190.0, 8.0)];
        let frame_tags = [place(3, 95.0, 84.0, 7.0), place(7, 228.0, 95.0, 7.0), place(12, 148.0, 185.0, 7.0)];
        let reference = draw(family, 320, 260, &reference_tags);
        let k = Intrinsics::pinhole(800.0, 800.0, 160.0, 130.0).unwrap();
        let config = || ImageServoConfig::new(ServoConfig::new(Law::Observe, k));
        let target = ImageTarget::Tags { family, ids: None, decimation: None };
        let mut pipeline = ImageServo::new(&reference, &target, config(), ServoDepths::Constant(0.5)).unwrap();
        assert_eq!(pipeline.ids(), [12, 13, 14, 15, 28, 29, 30, 31, 48, 49, 50, 51]);
        let want: Vec<[f64; 2]> = reference_tags.iter().flat_map(|p| corners(family, p)).collect();
        for (got, want) in pipeline.servo().reference_pixels().iter().zip(&want) {
            assert!((got[0] - want[0]).hypot(got[1] - want[1]) < 0.5, "{got:?} vs {want:?}");
        }
        pipeline.step(&draw(family, 320, 260, &frame_tags)).unwrap();
        assert!(pipeline.found().iter().all(|&f| f));
        let want: Vec<[f64; 2]> = frame_tags.iter().flat_map(|p| corners(family, p)).collect();
        for (got, want) in pipeline.pixels().iter().zip(&want) {
            assert!((got[0] - want[0]).hypot(got[1] - want[1]) < 0.5, "{got:?} vs {want:?}");
        }
        let before = pipeline.pixels().to_vec();
        pipeline.step(&draw(family, 320, 260, &[frame_tags[0], frame_tags[2]])).unwrap();
        assert_eq!(pipeline.found(), [true, true, true, true, false, false, false, false, true, true, true, true]);
        assert_eq!(pipeline.pixels()[4..8], before[4..8], "a missing tag keeps its last corners, not visible");
        let some = ImageTarget::Tags { family, ids: Some(vec![12, 3]), decimation: None };
        let pipeline = ImageServo::new(&reference, &some, config(), ServoDepths::Constant(0.5)).unwrap();
        assert_eq!(pipeline.ids(), [12, 13, 14, 15, 48, 49, 50, 51]);
        let absent = ImageTarget::Tags { family, ids: Some(vec![3, 5]), decimation: None };
        let err = ImageServo::new(&reference, &absent, config(), ServoDepths::Constant(0.5)).unwrap_err();
        assert!(err.to_string().contains("tag 5"), "{err}");
    }

    /// The target's decimation reaches the detector: every decimation finds the same tags,
    /// one out of `1..=8` is refused by name.
    #[test]
    fn a_tags_target_takes_a_decimation() {
        use crate::vision::tags::synthetic::{Placement, draw};
        let family = TagFamily::Tag36h11;
        let tags = [Placement { id: 3, centre: [90.0, 80.0], cell: 8.0, quarter_turns: 0 }];
        let reference = draw(family, 200, 160, &tags);
        let k = Intrinsics::pinhole(800.0, 800.0, 100.0, 80.0).unwrap();
        let config = || ImageServoConfig::new(ServoConfig::new(Law::Observe, k));
        for decimation in [None, Some(1), Some(3)] {
            let target = ImageTarget::Tags { family, ids: None, decimation };
            let pipeline = ImageServo::new(&reference, &target, config(), ServoDepths::Constant(0.5)).unwrap();
            assert_eq!(pipeline.ids(), [12, 13, 14, 15], "{decimation:?}");
        }
        for bad in [0, 9] {
            let target = ImageTarget::Tags { family, ids: None, decimation: Some(bad) };
            let err = ImageServo::new(&reference, &target, config(), ServoDepths::Constant(0.5)).unwrap_err();
            assert!(matches!(err, VisionError::Core(Error::InvalidParameter { name: "decimation", .. })), "{err}");
        }
    }
}
