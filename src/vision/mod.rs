//! Images in the loop (feature `vision`): what the camera sees and what a dot tracker
//! extracts from it.
//!
//! | concept | module |
//! |---|---|
//! | 8-bit grey images, PNG files | [`image`](mod@image) |
//! | dot detection: threshold, connected components, subpixel centroids | [`dots`] |
//! | rendering the white discs of the feature points (perspective ellipses, anti-aliasing, blur, noise) | [`render`] |
//! | dot tracking from image to image, never swapping two dots | [`tracker`] |
//!
//! Images are row-major `(height, width)` 8-bit grey levels ([`GreyImage`]).

pub mod dots;
pub mod image;
pub mod render;
pub mod tracker;

pub use self::dots::{DetectConfig, Dot, detect_dots};
pub use self::image::{GreyBuffer, GreyImage, load_png, save_png};
pub use self::render::{CameraView, Disc, RenderConfig, Rendered, Renderer};
pub use self::tracker::{DotTracker, TrackResult, TrackerConfig};
