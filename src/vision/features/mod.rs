//! Natural keypoints as a target (issue 32, item 1): no markers, no clicks. The reference
//! image (taken with any camera) and the first frame (taken with another) are matched by
//! their descriptors, the matches checked by a geometry that needs neither camera's
//! intrinsics (the fundamental matrix, RANSAC); then the points are tracked from frame to
//! frame by pyramidal Lucas-Kanade with a forward-backward check, and each frame's tracks are
//! checked again against the reference by the fundamental matrix. A point failing a check is
//! not visible (never a wrong position); when too few remain, the frame is matched afresh.
//!
//! # Why kornia-rs, in the Rust layer
//!
//! The issue allowed OpenCV's SIFT behind an optional Python extra, or kornia-rs in Rust.
//! kornia-rs 0.2 is already in vsinv's build (`kornia-apriltag` depends on `kornia-imgproc`
//! and `kornia-3d`), and those two crates hold all three pieces:
//! - `kornia_imgproc::features::sift_detect_and_compute`: a port of OpenCV's SIFT (images as
//!   `f32` in 0..255, OpenCV's contrast and edge thresholds, the `firstOctave = -1` doubling),
//!   with a brute-force L2 matcher (Lowe's ratio, mutual check);
//! - `kornia_3d::pose::ransac_fundamental`: the 8-point fundamental matrix in RANSAC with a
//!   local optimisation and DEGENSAC's recovery of a dominant plane;
//! - `kornia_imgproc::optical_flow_pyr_lk`: pyramidal Lucas-Kanade (21 x 21 windows, as
//!   OpenCV's default), on precomputed pyramids.
//!
//! So the whole target lives where the other detectors live: `ImageServo`, `vsinv replay`
//! and the ROS bridge get it without an optional dependency, and the per-frame work stays in
//! Rust. OpenCV is used by the tests only, as the independent computation
//! (`cv2.calcOpticalFlowPyrLK`, SIFT + `findFundamentalMat`). The price, measured by
//! `benches/features_tracking.py`: kornia's tracks agree with OpenCV's to 1e-4 px (median) but
//! take about 5 times OpenCV's time at 640 x 480 and 11 times at 1920 x 1080 (forward and
//! backward, 150 points, both pyramids built at each call). A servo session builds one pyramid
//! a frame and keeps it: a whole tracked step at 640 x 480 takes about 8 ms, under the issue's
//! 10 ms (docs/results/performance.md).
//!
//! | concept | module |
//! |---|---|
//! | keypoints and descriptors of an image (SIFT) | [`keypoints`] |
//! | a spread of points over the image (one per cell, the strongest) | [`spread`] |
//! | matches across two cameras, checked by the fundamental matrix | [`matching`] |
//! | a match refined to a fraction of a pixel (the reference's patch, warped, aligned) | [`refine`] |
//! | the reference blurred as the frame is (measured on the first frame's matches) | [`blur`] |
//! | frame-to-frame tracks, forward-backward checked | [`flow`] |
//! | the pyramid's filters (kornia's, vectorised) | [`pyramid`] |

pub mod blur;
pub mod flow;
pub mod keypoints;
pub mod matching;
pub mod pyramid;
pub mod refine;
pub mod spread;
