//! Image-in-the-loop servoing (sec. 5.2 with images): the built-in vision scenarios converge
//! to the paper's accuracy on tracked centroids, and the detection error is reported.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use vsinv::sim::scenario::builtin;
use vsinv::sim::{Status, Summary, simulate};

fn run(name: &str) -> (Summary, vsinv::sim::Recording) {
    let out = simulate(&builtin(name).unwrap().to_config().unwrap(), &mut |_, _| true).unwrap();
    let s = out.summary;
    let (median, max) = s.detection_error.expect("vision runs report detection errors");
    println!(
        "{name}: {} after {} iterations, {:.3} mm, {:.4} deg; detection error median {median:.3} px, max {max:.3} px",
        s.status.as_str(),
        s.iterations,
        s.final_translation_error * 1e3,
        s.final_rotation_error.to_degrees()
    );
    (s, out.recording.unwrap())
}

#[test]
fn same_lens_through_images_ends_within_1mm_and_0_1_degree() {
    let (s, rec) = run("vision-12-12");
    assert_eq!(s.status, Status::Converged, "{}", s.message);
    assert!(s.final_translation_error < 1e-3 && s.final_rotation_error.to_degrees() < 0.1);
    assert_eq!(rec.detection_error.len(), rec.len() * rec.n_points);
}

#[test]
fn lens_change_through_images_ends_within_2mm_and_0_2_degree() {
    let (s6, _) = run("vision-12-6");
    assert_eq!(s6.status, Status::Converged, "{}", s6.message);
    assert!(s6.final_translation_error < 2e-3 && s6.final_rotation_error.to_degrees() < 0.2);
    // The 6 mm lens sees smaller dots: detection is less precise than with the 12 mm lens
    // (sec. 5.2).
    let (s12, _) = run("vision-12-12");
    assert!(s6.detection_error.unwrap().0 > s12.detection_error.unwrap().0);
}

/// Sec. 5.2 through an AprilTag rig (issue 18, item 5): corners matched by tag identity
/// between the 12 mm reference image and the current one, no clicks; the paper's accuracy.
/// With the same lens the 0.5 px image rule can go unmet (within the pose targets, a pan of
/// about 0.04 deg shifts the image by 1 px, which the invariant features barely see):
/// tags-12-12 then ends by its stall rule, `converged` with the pose the images certify.
#[test]
fn tag_rigs_through_images_reach_the_papers_accuracy() {
    let (s, rec) = run("tags-12-12");
    assert_eq!(s.status, Status::Converged, "{}", s.message);
    assert!(s.message.contains("stalled") || s.message.contains("stop rule met"), "{}", s.message);
    assert!(s.final_translation_error < 1e-3 && s.final_rotation_error.to_degrees() < 0.1);
    // Where the run leaves the image error depends on the noise draw: over the seeds 1-5 it
    // ended at 0.41-0.55 px (0.41 px, the 0.5 px rule met: seed 1, the built-in's); with the
    // edges read over half a cell it was 0.37-1.91 px over seeds 1-6, 0.46-1.50 px with the
    // renderer's earlier noise generator.
    assert!(s.final_image_error < 1.0, "{} px", s.final_image_error);
    assert_eq!(rec.n_points, 12);
    let (s, _) = run("tags-12-6");
    assert_eq!(s.status, Status::Converged, "{}", s.message);
    assert!(s.final_translation_error < 2e-3 && s.final_rotation_error.to_degrees() < 0.2);
    // Never a wrong corner: every corner reported is within a tenth of a pixel of its projection.
    let (_, max) = s.detection_error.unwrap();
    assert!(max < 0.1, "{max} px");
}

#[test]
fn zoomed_reference_through_images_converges() {
    // Sec. 5.2: the reference image is taken with a 25 mm lens, the servo uses 12 mm.
    let (s, _) = run("vision-25-12");
    assert_eq!(s.status, Status::Converged, "{}", s.message);
    assert!(s.final_translation_error < 2e-3 && s.final_rotation_error.to_degrees() < 0.2);
}

#[test]
fn rendered_views_show_the_dots_at_their_projections() {
    use vsinv::sim::{Shot, render_view};
    use vsinv::vision::{DetectConfig, detect_dots};
    let config = builtin("vision-12-6").unwrap().to_config().unwrap();
    for shot in [Shot::Reference, Shot::Servo { time: 0.0 }] {
        let view = render_view(&config, shot, None).unwrap();
        let dots = detect_dots(&view.image, &DetectConfig::default()).unwrap();
        assert_eq!(dots.len(), view.pixels.len(), "{shot:?}");
        for p in &view.pixels {
            let nearest =
                dots.iter().map(|d| (d.centroid[0] - p[0]).hypot(d.centroid[1] - p[1])).fold(f64::MAX, f64::min);
            assert!(nearest < 0.2, "{shot:?}: {nearest} px");
        }
    }
    // The servo camera at the reference pose with the 6 mm lens sees the object smaller.
    let at_goal =
        render_view(&config, Shot::Servo { time: 0.0 }, Some(&vsinv::nalgebra::Isometry3::identity())).unwrap();
    let reference = render_view(&config, Shot::Reference, None).unwrap();
    let spread = |v: &vsinv::sim::View| {
        v.pixels.iter().map(|p| p[0]).fold(f64::MIN, f64::max) - v.pixels.iter().map(|p| p[0]).fold(f64::MAX, f64::min)
    };
    assert!((spread(&at_goal) / spread(&reference) - 0.5).abs() < 1e-9);
    assert!(render_view(&config, Shot::Servo { time: f64::NAN }, None).is_err());
    let mut no_size = config.clone();
    no_size.camera.image = None;
    let err = render_view(&no_size, Shot::Servo { time: 0.0 }, None).unwrap_err().to_string();
    assert!(err.contains("camera") && err.contains("width"), "{err}");
}

#[test]
fn stationary_zoom_through_images_keeps_the_invariant_error_near_zero() {
    // Sec. 5.1 with images: the image error grows with the zoom, the invariant error does not.
    let (s, rec) = run("vision-zoom");
    assert_eq!(rec.len(), 6, "six images");
    assert!(rec.image_error[5] > 50.0 * rec.image_error[0].max(0.1), "{:?}", rec.image_error);
    // The detection noise alone: over the noise seeds 1-40 the largest invariant error of the
    // six images has median 0.85e-3 and maximum 1.15e-3 (1.23e-3 with the renderer's earlier
    // noise generator, which also passed 1e-3 on 7 seeds in 40).
    let max_q = rec.invariant_error.iter().fold(0.0f64, |m, &e| m.max(e));
    assert!(max_q < 1.5e-3, "invariant error {:?}", rec.invariant_error);
    assert!(s.detection_error.unwrap().1 < 0.2);
}

#[test]
fn dot_normals_tilt_the_rendered_discs() {
    use vsinv::sim::{Shot, render_view};
    use vsinv::vision::{DetectConfig, detect_dots};
    let facing = builtin("vision-12-12").unwrap();
    let mut tilted = facing.clone();
    let n = tilted.object.points.len();
    // 60 degrees from the optical axis: each dot's image has half the area.
    let (s, c) = 60f64.to_radians().sin_cos();
    tilted.object.normals = Some(vec![[s, 0.0, -c]; n]);
    let area = |sc: &vsinv::sim::Scenario| {
        let view = render_view(&sc.to_config().unwrap(), Shot::Reference, None).unwrap();
        let dots = detect_dots(&view.image, &DetectConfig::default()).unwrap();
        assert_eq!(dots.len(), n);
        dots.iter().map(|d| d.area).sum::<f64>()
    };
    let ratio = area(&tilted) / area(&facing);
    assert!((ratio - 0.5).abs() < 0.1, "area ratio {ratio}");
    tilted.object.normals = Some(vec![[0.0, 0.0, -1.0]; n - 1]);
    let err = tilted.to_config().unwrap_err().to_string();
    assert!(err.contains("object.normals"), "{err}");
    tilted.object.normals = Some(vec![[0.0, 0.0, 0.0]; n]);
    assert!(tilted.to_config().unwrap_err().to_string().contains("normal 0"));
}
