//! Images in the loop (feature `vision`): what the camera sees and what a detector finds
//! in it, behind two seams: a [`Target`] (points with identities, drawn by the renderer's
//! primitives) and a [`Detector`] (image in, identities, pixels and found flags out).
//!
//! | concept | module |
//! |---|---|
//! | 8-bit grey images, image files (PNG, PGM/PPM, JPEG) | [`image`](mod@image) |
//! | colour (RGB, BGR, RGBA, BGRA) frames to grey by Rec. 601 luma | [`grey`] |
//! | compressed frames (PNG, JPEG bytes) to grey | [`compressed`] |
//! | what is drawn: the [`Target`] trait | [`target`] |
//! | the targets, declared once: [`TARGETS`] (name, detector, arguments, scenario keys, builders) | [`targets`] |
//! | white discs ([`Dots`]) | [`target::dots`] |
//! | a rig of AprilTags of any [`TagFamily`] ([`TagRig`]) | [`target::tags`] |
//! | the renderer: one entry point, [`Renderer::render`] (canvas, conics, lens, rasterising, noise) | [`render`] |
//! | what is detected: the [`Detector`] trait | [`detector`] |
//! | today's detector: the dot tracker ([`DotTracking`]) | [`detector::dot_tracking`] |
//! | natural keypoints: SIFT, matches across cameras checked by the fundamental matrix, LK tracks | [`features`] |
//! | keypoints as a detector: matched once, tracked, checked, re-detected ([`FeatureTracking`](detector::features::FeatureTracking)) | [`detector::features`] |
//! | AprilTags as a detector: four corners a tag, tracked between frames ([`TagDetector`]) | [`detector::tags`] |
//! | AprilTag detection: ids and corners in OpenCV's order and convention ([`detect_tags`]) | [`tags`] |
//! | dot detection: thresholds, filters, the dots of an image or a window | [`dots`] |
//! | the local threshold: a background model on tiles | [`background`] |
//! | a tile's background, peak and threshold from the tiles around it | [`tile_levels`] |
//! | each tile's median and peak, 32 bytes at a time | [`tile_stats`] |
//! | coarser tiles, for dots wider than a tile's neighbourhood | [`coarse`] |
//! | the runs of dot pixels of rows, from 32-bit masks | [`row_scan`] |
//! | 8-connected components as runs, with moments | [`runs`] |
//! | a dot's subpixel centroid over a local background plane | [`centroid`] |
//! | bright or dark dots, or decided by the image | [`polarity`] |
//! | dot tracking from image to image, never swapping two dots | [`tracker`] |
//! | one pipeline from image to twist: detect, match by identity, step the servo session | [`image_servo`] |
//!
//! Images are row-major `(height, width)` 8-bit grey levels ([`GreyImage`]).
//!
//! # Adding a target type
//!
//! The targets are declared once, in [`TARGETS`] ([`targets`]): each entry names the target,
//! its detector, its arguments and scenario keys, and builds it for the simulator and for real
//! images; every layer (the image loop, `ImageServo`, Python, the CLI, the ROS parameters)
//! reads the table. The files a new target or detector touches are listed in [`targets`].

pub mod background;
pub mod centroid;
pub mod coarse;
pub mod compressed;
pub mod detector;
pub mod dots;
pub mod error;
pub mod features;
pub mod grey;
pub mod image;
pub mod image_servo;
pub mod own_sums;
pub mod polarity;
pub mod render;
pub mod row_scan;
pub mod runs;
pub mod tags;
pub mod target;
pub mod targets;
pub mod tile_levels;
pub mod tile_stats;
pub mod tracker;

pub use self::detector::dot_tracking::DotTracking;
pub use self::detector::tags::TagDetector;
pub use self::detector::{Detection, Detector, Expected};
pub use self::dots::{DetectConfig, Dot, detect_dots};
pub use self::error::VisionError;
pub use self::image::{GreyBuffer, GreyImage, GreyView, load_image, load_png, save_png, view_of};
pub use self::image_servo::{ImageServo, ImageServoConfig, ImageTarget, ImageTargetKind};
pub use self::polarity::Polarity;
pub use self::render::{CameraView, Canvas, Disc, Polygon, RenderConfig, Rendered, Renderer};
pub use self::tags::{
    DEFAULT_DECIMATION, MAX_DECIMATION, TAG_CORNERS_IN_LAYOUT, Tag, TagDecoder, TagFamily, detect_tags,
};
pub use self::target::dots::Dots;
pub use self::target::tags::{RigTag, TagRig};
pub use self::target::{Target, TargetPoint};
pub use self::targets::{TARGETS, TargetSpec};
pub use self::tracker::{DotTracker, TrackResult, TrackerConfig};
