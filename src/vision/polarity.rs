//! Which dots are looked for: bright dots on a dark background (`light`, the default), dark
//! dots on a bright background (`dark`), or whichever the image shows (`auto`). Dark dots are
//! found as light dots of the negative image (grey level `255 - g`), so that both give the
//! same centroids bit for bit.

use imageproc::contrast::otsu_level;
use imageproc::region_labelling::{Connectivity, connected_components};

use crate::vision::image::{GreyBuffer, GreyImage, Pixels};

/// The polarity of the dots.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "lowercase"))]
pub enum Polarity {
    /// Bright dots on a dark background.
    #[default]
    Light,
    /// Dark dots on a bright background.
    Dark,
    /// Decided per image by [`Polarity::dark_dots`]'s rule.
    Auto,
}

impl Polarity {
    /// The names, as Python and the scenario files spell them.
    pub const NAMES: [&'static str; 3] = ["light", "dark", "auto"];

    /// The polarity of a name (`"light"`, `"dark"` or `"auto"`).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "light" => Some(Self::Light),
            "dark" => Some(Self::Dark),
            "auto" => Some(Self::Auto),
            _ => None,
        }
    }

    /// The name of a polarity.
    pub fn name(self) -> &'static str {
        match self {
            Self::Light => "light",
            Self::Dark => "dark",
            Self::Auto => "auto",
        }
    }

    /// Whether the dots of `image` are dark: `Auto` decides by the image. Otsu's threshold
    /// splits the image into bright and dark pixels; the side holding the largest
    /// 8-connected region is the background (the paper around the dots, the wall around a
    /// target), and the dots are of the other side. A tie gives light dots.
    pub fn dark_dots<C: Pixels>(self, image: &GreyBuffer<C>) -> bool {
        match self {
            Self::Light => false,
            Self::Dark => true,
            Self::Auto => {
                let owned = GreyImage::from_fn(image.width(), image.height(), |u, v| *image.get_pixel(u, v));
                let threshold = otsu_level(&owned);
                largest_region(&owned, threshold, true) > largest_region(&owned, threshold, false)
            }
        }
    }
}

/// The area of the largest 8-connected region of pixels above `threshold` (`bright`) or at or
/// below it.
fn largest_region(image: &GreyImage, threshold: u8, bright: bool) -> usize {
    let binary = GreyImage::from_fn(image.width(), image.height(), |u, v| {
        ::image::Luma([u8::from((image.get_pixel(u, v)[0] > threshold) == bright)])
    });
    let labels = connected_components(&binary, Connectivity::Eight, ::image::Luma([0u8]));
    let mut areas: Vec<usize> = Vec::new();
    for p in labels.pixels() {
        let label = p[0] as usize;
        if label == 0 {
            continue;
        }
        if areas.len() < label {
            areas.resize(label, 0);
        }
        areas[label - 1] += 1;
    }
    areas.into_iter().max().unwrap_or(0)
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    #[test]
    fn names_and_auto() {
        for name in Polarity::NAMES {
            assert_eq!(Polarity::from_name(name).unwrap().name(), name);
        }
        assert!(Polarity::from_name("bright").is_none());
        // A dark square on a bright page, and its negative.
        let page = GreyImage::from_fn(40, 30, |u, v| {
            ::image::Luma([if (10..20).contains(&u) && (10..20).contains(&v) { 20 } else { 200 }])
        });
        assert!(Polarity::Auto.dark_dots(&page));
        let negative = GreyImage::from_fn(40, 30, |u, v| ::image::Luma([255 - page.get_pixel(u, v)[0]]));
        assert!(!Polarity::Auto.dark_dots(&negative));
        assert!(Polarity::Dark.dark_dots(&negative) && !Polarity::Light.dark_dots(&page));
    }
}
