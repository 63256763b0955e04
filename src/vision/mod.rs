//! Images in the loop (feature `vision`): what the camera sees and what a dot tracker
//! extracts from it.
//!
//! | concept | module |
//! |---|---|
//! | 8-bit grey images, PNG files | [`image`](mod@image) |
//! | rendering the white discs of the feature points (perspective ellipses, anti-aliasing, blur, noise) | [`render`] |
//!
//! Images are row-major `(height, width)` 8-bit grey levels ([`GreyImage`]).

pub mod image;
pub mod render;

pub use self::image::{GreyImage, load_png, save_png};
pub use self::render::{Disc, RenderConfig, Rendered, Renderer};
