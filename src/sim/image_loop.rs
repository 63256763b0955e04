//! Images in the loop (a scenario's `[vision]` table): the simulator renders what each camera
//! sees of the scenario's target, starts the detector on the start image (the user's clicks,
//! seeded with the projected points) and feeds the detected pixels, with `found` as
//! visibility, to the control law. Detection errors are measured against the true
//! projections of the points. Which target and detector a scenario uses is decided in one
//! place, [`scene_vision`].

use nalgebra::Isometry3;

use crate::core::camera::Intrinsics;
use crate::core::distortion::Distortion;
use crate::error::Error;
use crate::sim::error::Result;
use crate::sim::scene::{ImageSize, Observation, Scene};
use crate::vision::GreyImage;
use crate::vision::detector::{Detection, Detector, Expected};
use crate::vision::image::view_of;
use crate::vision::render::{CameraView, RenderConfig, Renderer};
use crate::vision::target::{Target, TargetPoint};
use crate::vision::targets::{self, SceneObject, SceneVision};

/// The image size of a camera, which vision needs.
pub(crate) fn pixel_size(image: Option<ImageSize>, key: &'static str) -> Result<(u32, u32)> {
    let s = image.ok_or(Error::InvalidParameter { name: key, reason: "[vision] needs width and height".into() })?;
    Ok((s.width.ceil() as u32, s.height.ceil() as u32))
}

/// What the scene's object holds, for the targets' builders.
pub(crate) fn scene_object(scene: &Scene) -> SceneObject<'_> {
    SceneObject { points: scene.points(), normals: scene.normals(), tags: scene.tags() }
}

/// The target of a scene and a fresh detector for it: the entry of [`TARGETS`](crate::vision::TARGETS)
/// that shows the scene's object.
pub(crate) fn scene_vision(scene: &Scene, config: &RenderConfig) -> Result<SceneVision> {
    Ok(targets::scene_vision(&scene_object(scene), config)?)
}

/// What tracking gives the run, per point.
pub(crate) struct Tracked<'a> {
    pub(crate) pixels: &'a mut [[f64; 2]],
    pub(crate) visible: &'a mut [bool],
    pub(crate) detection: &'a mut [f64],
}

/// Rendering and detection through a run.
pub(crate) struct ImageLoop {
    renderer: Renderer,
    target: Box<dyn Target>,
    detector: Box<dyn Detector>,
    started: bool,
    size: (u32, u32),
    frame: u64,
    /// The previous frame's pixels, the memory the next frame is rendered into.
    spare: Vec<u8>,
    /// Every detection error of a found point, pixels.
    pub(crate) errors: Vec<f64>,
    /// The frames rendered and searched only in the detector's windows.
    pub(crate) windowed_frames: u64,
}

impl ImageLoop {
    pub(crate) fn new(renderer: Renderer, scene: &Scene, size: (u32, u32)) -> Result<Self> {
        let vision = scene_vision(scene, renderer.config())?;
        Ok(Self::with(renderer, vision, size))
    }

    /// A loop over any target and detector.
    pub(crate) fn with(renderer: Renderer, vision: SceneVision, size: (u32, u32)) -> Self {
        let SceneVision { target, detector } = vision;
        Self {
            renderer,
            target,
            detector,
            started: false,
            size,
            frame: 0,
            spare: Vec::new(),
            errors: Vec::new(),
            windowed_frames: 0,
        }
    }

    /// The reference image rendered with K* at F*, its points detected around their
    /// projected positions: the reference pixels become the detected ones.
    pub(crate) fn reference(
        renderer: &Renderer,
        scene: &Scene,
        k_star: &Intrinsics,
        distortion: &Distortion,
        size: (u32, u32),
        obs: &mut Observation,
    ) -> Result<GreyImage> {
        let SceneVision { target, mut detector } = scene_vision(scene, renderer.config())?;
        let view = CameraView { pose: &Isometry3::identity(), intrinsics: k_star, distortion, size };
        let rendered = renderer.render(&*target, Some(&obs.visible), &view, 0)?;
        let points = target.points();
        let image = view_of(&rendered.image)?;
        let found = detector.start(&image, &expected(points, &obs.pixels)).map_err(|e| reference_error(&e))?;
        for (i, hit) in per_point(points, &found).into_iter().enumerate() {
            match (hit, obs.pixels.get_mut(i)) {
                (Some(d), Some(pixel)) if d.found => *pixel = d.pixel,
                _ => {
                    let e = crate::vision::VisionError::InvalidImage {
                        what: "reference".into(),
                        reason: format!("point {i} not found"),
                    };
                    return Err(reference_error(&e).into());
                }
            }
        }
        Ok(rendered.image)
    }

    /// Renders the current image with K(t) at `pose` and detects the points (starting the
    /// detector on the first image); `run` gets the detected pixels, `found && visible` as
    /// visibility and each point's detection error (NaN if not found).
    pub(crate) fn observe(
        &mut self,
        pose: &Isometry3<f64>,
        k: &Intrinsics,
        distortion: &Distortion,
        obs: &Observation,
        run: Tracked<'_>,
    ) -> Result<()> {
        self.frame += 1;
        let view = CameraView { pose, intrinsics: k, distortion, size: self.size };
        let (detections, image) = self.render_and_detect(&view, &obs.visible, &obs.pixels)?;
        let hits = per_point(self.target.points(), &detections);
        for i in 0..run.pixels.len() {
            let hit = hits.get(i).copied().flatten();
            run.visible[i] = obs.visible[i] && hit.is_some_and(|d| d.found);
            if let Some(d) = hit {
                run.pixels[i] = d.pixel;
            }
            run.detection[i] = if run.visible[i] {
                let e = (run.pixels[i][0] - obs.pixels[i][0]).hypot(run.pixels[i][1] - obs.pixels[i][1]);
                self.errors.push(e);
                e
            } else {
                f64::NAN
            };
        }
        self.spare = image.into_raw();
        Ok(())
    }

    /// Renders the frame of `view` and detects the points in it. Once the detector is started
    /// and reads only windows ([`Detector::reads`]), only those are rendered; when it needs
    /// more ([`Detector::detect_within`] gives `None`) the whole frame is rendered and searched:
    /// the points are those of the whole frame either way, bit for bit.
    fn render_and_detect(
        &mut self,
        view: &CameraView<'_>,
        visible: &[bool],
        pixels: &[[f64; 2]],
    ) -> Result<(Vec<Detection>, GreyImage)> {
        let spare = std::mem::take(&mut self.spare);
        let (target, frame) = (&*self.target, self.frame);
        let spare = match self.detector.reads().filter(|_| self.started) {
            Some(windows) => {
                let rendered = self.renderer.render_windows_in(target, Some(visible), view, frame, spare, &windows)?;
                if let Some(found) = self.detector.detect_within(&view_of(&rendered.image)?)? {
                    self.windowed_frames += 1;
                    return Ok((found, rendered.image));
                }
                rendered.image.into_raw()
            }
            None => spare,
        };
        let rendered = self.renderer.render_in(target, Some(visible), view, frame, spare)?;
        let image = view_of(&rendered.image)?;
        if !self.started {
            self.detector.start(&image, &expected(self.target.points(), pixels))?;
            self.started = true;
        }
        Ok((self.detector.detect(&image)?, rendered.image))
    }

    /// The median and largest detection error of the found points, pixels (NaN if none).
    pub(crate) fn error_summary(&self) -> (f64, f64) {
        if self.errors.is_empty() {
            return (f64::NAN, f64::NAN);
        }
        let mut sorted = self.errors.clone();
        sorted.sort_by(f64::total_cmp);
        let n = sorted.len();
        let median = if n % 2 == 1 { sorted[n / 2] } else { 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]) };
        (median, sorted[n - 1])
    }
}

/// The target's points expected at `pixels` (one per point, in order).
fn expected(points: &[TargetPoint], pixels: &[[f64; 2]]) -> Vec<Expected> {
    points.iter().zip(pixels).map(|(p, &pixel)| Expected { id: p.id, pixel }).collect()
}

/// The detection of each point of the target, by identity (None: not reported).
fn per_point<'a>(points: &[TargetPoint], detections: &'a [Detection]) -> Vec<Option<&'a Detection>> {
    let by_id: std::collections::HashMap<u32, &Detection> = detections.iter().map(|d| (d.id, d)).collect();
    points.iter().map(|p| by_id.get(&p.id).copied()).collect()
}

fn reference_error(e: &dyn std::fmt::Display) -> Error {
    Error::InvalidParameter { name: "vision", reason: format!("the reference image's dots cannot be detected: {e}") }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use std::sync::{Arc, Mutex};

    use super::*;
    use crate::vision::GreyView;
    use crate::vision::detector::dot_tracking::DotTracking;
    use crate::vision::render::{Canvas, Disc};
    use crate::vision::target::dots::Dots;
    use crate::vision::targets::scene_discs;
    use crate::vision::tracker::TrackerConfig;

    fn scene() -> Scene {
        Scene::new(vec![[-0.03, -0.02, 0.5], [0.03, -0.02, 0.5], [0.03, 0.02, 0.5], [-0.03, 0.02, 0.5]], vec![])
            .unwrap()
    }

    /// The servo camera at F* and what it sees of the scene.
    fn camera() -> (Isometry3<f64>, Intrinsics, Observation) {
        let (pose, k) = (Isometry3::identity(), Intrinsics::pinhole(800.0, 800.0, 160.0, 120.0).unwrap());
        let mut obs = Observation::default();
        scene().observe(&pose, &k, Some(ImageSize { width: 320.0, height: 240.0 }), &mut obs);
        assert!(obs.visible.iter().all(|&v| v));
        (pose, k, obs)
    }

    /// Runs `frames` images through a loop; the run's pixels, visibility and errors.
    fn run(mut images: ImageLoop, frames: usize) -> (Vec<[f64; 2]>, Vec<bool>, Vec<f64>, ImageLoop) {
        let (pose, k, obs) = camera();
        let n = obs.pixels.len();
        let (mut pixels, mut visible, mut detection) = (vec![[0.0; 2]; n], vec![false; n], vec![0.0; n]);
        for _ in 0..frames {
            let tracked = Tracked { pixels: &mut pixels, visible: &mut visible, detection: &mut detection };
            images.observe(&pose, &k, &Distortion::none(), &obs, tracked).unwrap();
        }
        (pixels, visible, detection, images)
    }

    /// A test detector: reports, in reverse order, each expected point moved by (0.3, 0.4),
    /// the point of identity 1 as not found, and a point of an identity the target lacks.
    struct Scripted {
        expected: Vec<Expected>,
        calls: Arc<Mutex<(usize, usize)>>,
    }

    impl Detector for Scripted {
        fn start(&mut self, _: &GreyView<'_>, expected: &[Expected]) -> crate::vision::error::Result<Vec<Detection>> {
            self.calls.lock().unwrap().0 += 1;
            self.expected = expected.to_vec();
            self.detect_all()
        }

        fn detect(&mut self, image: &GreyView<'_>) -> crate::vision::error::Result<Vec<Detection>> {
            assert_eq!(image.dimensions(), (320, 240));
            self.calls.lock().unwrap().1 += 1;
            self.detect_all()
        }
    }

    impl Scripted {
        fn detect_all(&self) -> crate::vision::error::Result<Vec<Detection>> {
            let moved =
                |e: &Expected| Detection { id: e.id, pixel: [e.pixel[0] + 0.3, e.pixel[1] + 0.4], found: e.id != 1 };
            let mut out: Vec<Detection> = self.expected.iter().rev().map(moved).collect();
            out.push(Detection { id: 99, pixel: [0.0, 0.0], found: true });
            Ok(out)
        }
    }

    #[test]
    fn the_loop_feeds_the_run_from_any_detector_by_identity() {
        let config = RenderConfig::default();
        let calls = Arc::new(Mutex::new((0, 0)));
        let detector = Box::new(Scripted { expected: Vec::new(), calls: Arc::clone(&calls) });
        let vision =
            SceneVision { target: Box::new(Dots::new(scene_discs(&scene_object(&scene()), 0.004).unwrap())), detector };
        let (pixels, visible, detection, images) =
            run(ImageLoop::with(Renderer::new(config).unwrap(), vision, (320, 240)), 3);
        let obs = camera().2;
        assert_eq!(*calls.lock().unwrap(), (1, 3), "started once, then one detection per image");
        assert_eq!(visible, [true, false, true, true]);
        for i in [0, 2, 3] {
            assert_eq!(pixels[i], [obs.pixels[i][0] + 0.3, obs.pixels[i][1] + 0.4]);
            assert!((detection[i] - 0.5).abs() < 1e-12);
        }
        assert!(detection[1].is_nan());
        let (median, max) = images.error_summary();
        assert!((median - 0.5).abs() < 1e-12 && (max - 0.5).abs() < 1e-12);
    }

    /// A test target: the scene's dots under identities 30, 20, 10, 0, each drawn twice as
    /// large as the scene's dots.
    struct Renamed(Vec<TargetPoint>, Dots);

    impl Target for Renamed {
        fn points(&self) -> &[TargetPoint] {
            &self.0
        }

        fn draw(&self, canvas: &mut Canvas<'_>, visible: Option<&[bool]>) -> Vec<bool> {
            self.1.draw(canvas, visible)
        }
    }

    #[test]
    fn the_loop_renders_any_target_for_the_dot_tracker() {
        let discs: Vec<Disc> = scene_discs(&scene_object(&scene()), 0.008).unwrap();
        let ids = [30, 20, 10, 0];
        let points = ids.iter().zip(&discs).map(|(&id, d)| TargetPoint { id, position: d.center.into() }).collect();
        let target = Box::new(Renamed(points, Dots::new(discs)));
        let vision = SceneVision { target, detector: Box::new(DotTracking::new(TrackerConfig::default())) };
        let renderer = Renderer::new(RenderConfig::default()).unwrap();
        let (pixels, visible, detection, _) = run(ImageLoop::with(renderer, vision, (320, 240)), 2);
        let obs = camera().2;
        assert_eq!(visible, [true; 4]);
        for i in 0..4 {
            assert!(detection[i] < 0.1, "point {i}: {} px", detection[i]);
            assert!((pixels[i][0] - obs.pixels[i][0]).abs() < 0.1, "point {i}");
        }
    }

    /// The dot tracker seen whole: its windows not declared, so every frame is rendered and
    /// searched whole.
    struct Whole(DotTracking);

    impl Detector for Whole {
        fn start(
            &mut self,
            image: &GreyView<'_>,
            expected: &[Expected],
        ) -> crate::vision::error::Result<Vec<Detection>> {
            self.0.start(image, expected)
        }

        fn detect(&mut self, image: &GreyView<'_>) -> crate::vision::error::Result<Vec<Detection>> {
            self.0.detect(image)
        }
    }

    /// A moving camera (small steps, then a jump of several windows and back): the loop that
    /// renders only the tracker's windows gives the points, visibility and errors of the loop
    /// that renders every frame whole, bit for bit, and renders most frames in windows.
    #[test]
    fn rendering_only_the_trackers_windows_changes_no_detection() {
        let discs = || scene_discs(&scene_object(&scene()), 0.004).unwrap();
        let renderer = || Renderer::new(RenderConfig { noise_sigma: 3.0, ..RenderConfig::default() }).unwrap();
        let tracking = || DotTracking::new(TrackerConfig::default());
        let vision = |detector: Box<dyn Detector>| SceneVision { target: Box::new(Dots::new(discs())), detector };
        let mut windowed = ImageLoop::with(renderer(), vision(Box::new(tracking())), (320, 240));
        let mut whole = ImageLoop::with(renderer(), vision(Box::new(Whole(tracking()))), (320, 240));
        let k = Intrinsics::pinhole(800.0, 800.0, 160.0, 120.0).unwrap();
        let frames = 24;
        for f in 0..frames {
            let x = if (12..15).contains(&f) { 0.03 } else { 0.0005 * f as f64 };
            let pose = Isometry3::translation(x, -0.0003 * f as f64, 0.0);
            let mut obs = Observation::default();
            scene().observe(&pose.inverse(), &k, Some(ImageSize { width: 320.0, height: 240.0 }), &mut obs);
            let n = obs.pixels.len();
            let mut got = (vec![[0.0; 2]; n], vec![false; n], vec![0.0; n]);
            let mut want = got.clone();
            for (images, out) in [(&mut windowed, &mut got), (&mut whole, &mut want)] {
                let tracked = Tracked { pixels: &mut out.0, visible: &mut out.1, detection: &mut out.2 };
                images.observe(&pose, &k, &Distortion::none(), &obs, tracked).unwrap();
            }
            let bits = |d: &[f64]| d.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!((&got.0, &got.1, bits(&got.2)), (&want.0, &want.1, bits(&want.2)), "frame {f}");
        }
        assert_eq!(whole.windowed_frames, 0);
        let w = windowed.windowed_frames;
        assert!(w >= frames - 4 && w < frames - 1, "{w} of {frames} frames in windows");
    }

    #[test]
    fn a_tag_that_is_not_decoded_drops_its_four_corners() {
        use crate::vision::target::tags::{RigTag, TagRig};
        use nalgebra::{Translation3, UnitQuaternion, Vector3};
        // Tag 5 faces the camera; tag 9 beside it is turned away (its back is not drawn).
        let facing = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI);
        let away = UnitQuaternion::identity();
        let tag = |id, x: f64, rotation| RigTag {
            id,
            size: 0.05,
            pose: Isometry3::from_parts(Translation3::new(x, 0.0, 0.5), rotation),
        };
        let rig =
            TagRig::new(crate::vision::TagFamily::Tag36h11, vec![tag(5, -0.04, facing), tag(9, 0.04, away)]).unwrap();
        let points: Vec<[f64; 3]> = rig.points().iter().map(|p| p.position).collect();
        let scene = Scene::new(points, vec![]).unwrap().with_tags(rig).unwrap();
        let config = RenderConfig { noise_sigma: 1.0, ..RenderConfig::default() };
        let (pose, k) = (Isometry3::identity(), Intrinsics::pinhole(800.0, 800.0, 160.0, 120.0).unwrap());
        let mut obs = Observation::default();
        scene.observe(&pose, &k, Some(ImageSize { width: 320.0, height: 240.0 }), &mut obs);
        assert!(obs.visible.iter().all(|&v| v));
        let mut images = ImageLoop::new(Renderer::new(config).unwrap(), &scene, (320, 240)).unwrap();
        let (mut pixels, mut visible, mut detection) = (vec![[0.0; 2]; 8], vec![false; 8], vec![0.0; 8]);
        let tracked = Tracked { pixels: &mut pixels, visible: &mut visible, detection: &mut detection };
        images.observe(&pose, &k, &Distortion::none(), &obs, tracked).unwrap();
        assert_eq!(visible, [true, true, true, true, false, false, false, false]);
        for (i, d) in detection[..4].iter().enumerate() {
            // A 40 px tag (5 px cells), blurred: the detector is within half a pixel.
            assert!(*d < 0.5, "corner {i}: {d} px");
        }
        assert!(detection[4..].iter().all(|d| d.is_nan()));
    }
}
