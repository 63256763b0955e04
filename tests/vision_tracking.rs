//! The dot tracker on rendered image sequences: following, losing and re-acquiring a dot,
//! two dots crossing without being swapped, and bad inputs.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use vsinv::nalgebra::Isometry3;
use vsinv::vision::{CameraView, Disc, DotTracker, Dots, GreyImage, RenderConfig, Renderer, TrackerConfig};
use vsinv::{Distortion, Intrinsics};

/// Fronto-parallel discs of radius 5 px at the given pixel centres (1000 px focal, 0.5 m).
fn frame(centres: &[[f64; 2]], index: u64) -> GreyImage {
    let k = Intrinsics::pinhole(1000.0, 1000.0, 0.0, 0.0).unwrap();
    let discs: Vec<Disc> = centres
        .iter()
        .map(|c| Disc::new([c[0] * 0.5e-3, c[1] * 0.5e-3, 0.5], [0.0, 0.0, -1.0], 2.5e-3).unwrap())
        .collect();
    let (pose, none) = (Isometry3::identity(), Distortion::none());
    let view = CameraView { pose: &pose, intrinsics: &k, distortion: &none, size: (240, 160) };
    Renderer::new(RenderConfig::default()).unwrap().render(&Dots::new(discs), None, &view, index).unwrap().image
}

fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

#[test]
fn a_moving_dot_is_followed() {
    let at = |t: usize| [30.3 + 3.0 * t as f64, 50.7 + 1.5 * t as f64];
    let mut tracker = DotTracker::new(&frame(&[at(0)], 0), &[[32.0, 49.0]], TrackerConfig::default()).unwrap();
    assert!(distance(tracker.positions()[0], at(0)) < 0.05);
    for t in 1..30 {
        let r = tracker.track(&frame(&[at(t)], t as u64)).unwrap();
        assert!(r.found[0] && distance(r.pixels[0], at(t)) < 0.05, "frame {t}: {:?} vs {:?}", r.pixels[0], at(t));
    }
}

#[test]
fn a_dot_that_leaves_is_reported_lost_and_found_again() {
    let still = [60.0, 80.0];
    let mut tracker =
        DotTracker::new(&frame(&[still, [200.0, 80.0]], 0), &[still, [200.0, 80.0]], TrackerConfig::default()).unwrap();
    // The second dot leaves the image for a few frames, then comes back near where it was.
    for t in 1..5 {
        let r = tracker.track(&frame(&[still], t)).unwrap();
        assert_eq!(r.found, vec![true, false], "frame {t}");
        assert_eq!(r.pixels[1], tracker.positions()[1]);
    }
    let back = [204.0, 83.0];
    let r = tracker.track(&frame(&[still, back], 9)).unwrap();
    assert_eq!(r.found, vec![true, true]);
    assert!(distance(r.pixels[1], back) < 0.05);
}

#[test]
fn crossing_dots_are_never_swapped() {
    // Dot 0 moves right, dot 1 moves left on a nearby row: their discs merge for a few frames.
    let path = |t: usize| [[40.0 + 4.0 * t as f64, 80.0], [200.0 - 4.0 * t as f64, 83.0]];
    let first = path(0);
    let mut tracker = DotTracker::new(&frame(&first, 0), &first, TrackerConfig::default()).unwrap();
    let mut lost_frames = 0;
    for t in 1..=40 {
        let truth = path(t);
        let r = tracker.track(&frame(&truth, t as u64)).unwrap();
        for i in 0..2 {
            if r.found[i] {
                assert!(
                    distance(r.pixels[i], truth[i]) < 0.2,
                    "frame {t}: dot {i} at {:?}, truth {:?}",
                    r.pixels[i],
                    truth
                );
            } else {
                lost_frames += 1;
            }
        }
    }
    // They did merge (some frames lost), and both are tracked at the end, each on its own dot.
    let end = tracker.positions();
    assert!(lost_frames > 0);
    assert!(distance(end[0], path(40)[0]) < 0.2 && distance(end[1], path(40)[1]) < 0.2);
}

#[test]
fn bad_inputs_are_refused() {
    let img = frame(&[[50.0, 50.0]], 0);
    let cfg = TrackerConfig::default();
    assert!(DotTracker::new(&img, &[], cfg).is_err());
    let err = DotTracker::new(&img, &[[50.0, 50.0], [f64::NAN, 3.0]], cfg).unwrap_err();
    assert!(err.to_string().contains("row 1, column 0"), "{err}");
    let err = DotTracker::new(&img, &[[50.0, 50.0], [150.0, 120.0]], cfg).unwrap_err();
    assert!(err.to_string().contains("point 1"), "{err}");
    let err = DotTracker::new(&img, &[[50.0, 50.0], [52.0, 51.0]], cfg).unwrap_err();
    assert!(err.to_string().contains("points 0 and 1"), "{err}");
    assert!(DotTracker::new(&img, &[[500.0, 50.0]], cfg).is_err());
    let mut tracker = DotTracker::new(&img, &[[50.0, 50.0]], cfg).unwrap();
    assert!(tracker.track(&GreyImage::new(10, 10)).is_err());
    let bad = TrackerConfig { search_radius: f64::NAN, ..cfg };
    assert!(DotTracker::new(&img, &[[50.0, 50.0]], bad).is_err());
}
