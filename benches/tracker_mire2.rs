//! `DotTracker::track` on ViSP's mire-2 sequence (Debian's `visp-images-data`, read from the
//! package's folder, never copied): the five dots of the first frame tracked through the 500
//! frames after it, best of several passes, as `benches/vpdot2/vpdot2_mire2.cpp` times ViSP's
//! vpDot2 on the same frames and clicks. `benches/tracker_mire2.py` runs both and prints the
//! ratio (`make bench`). Prints a skip message when the dataset is not installed.
//!
//! Usage: `cargo bench --bench tracker_mire2 [-- DIR]`

#![allow(clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::time::Instant;

use vsinv::vision::{DotTracker, GreyImage, TrackResult, TrackerConfig, load_image};

/// Approximate clicks on the five dots of frame 1 (u, v): OpenCV's blob centroids (85.4, 178.9),
/// (215.3, 166.6), (159.6, 212.8), (242.5, 248.0) and (93.1, 266.0) moved by about 2 px.
const CLICKS: [[f64; 2]; 5] = [[87.0, 181.0], [213.0, 168.0], [162.0, 210.0], [244.0, 246.0], [91.0, 268.0]];

const PASSES: usize = 10;

fn frames(dir: &Path) -> Vec<GreyImage> {
    (1..)
        .map(|k| dir.join(format!("image.{k:04}.pgm")))
        .take_while(|p| p.is_file())
        .map(|p| load_image(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display())))
        .collect()
}

fn main() {
    let dir = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with('-'))
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/usr/share/visp-images-data/ViSP-images/mire-2"));
    let frames = frames(&dir);
    if frames.len() < 2 {
        println!("mire-2 not found under {} (apt-get install visp-images-data): skipped", dir.display());
        return;
    }
    let mut best = f64::INFINITY;
    let mut out = TrackResult::default();
    let mut lost_frames = 0;
    for _ in 0..PASSES {
        let mut tracker = DotTracker::new(&frames[0], &CLICKS, TrackerConfig::default()).expect("start on frame 1");
        lost_frames = 0;
        let start = Instant::now();
        for frame in &frames[1..] {
            tracker.track_into(frame, &mut out).expect("track");
            lost_frames += usize::from(out.found.iter().any(|f| !f));
        }
        best = best.min(start.elapsed().as_secs_f64() * 1e6 / (frames.len() - 1) as f64);
    }
    println!(
        "vsinv DotTracker (Rust): {} dots, {} frames, {best:.2} us/frame (best of {PASSES}), frames with a lost dot: {lost_frames}",
        CLICKS.len(),
        frames.len() - 1
    );
}
