//! Dot detection: bright dots on a dark background, or dark dots on a bright one (found as
//! the bright dots of the negative image: see [`Polarity`]). A threshold (Otsu's by default) and
//! 8-connected components (imageproc) find the dots; each centroid is the intensity-weighted
//! mean of its bounding box grown by two pixels, weighted by the grey level above the local
//! background, so that the anti-aliased edge pixels under the threshold still count. Pixel
//! `(u, v)` covers `[u - 0.5, u + 0.5] x [v - 0.5, v + 0.5]` (OpenCV's convention).

use imageproc::contrast::otsu_level;
use imageproc::region_labelling::{Connectivity, connected_components};

use crate::error::{Error, Result};
use crate::vision::image::{GreyBuffer, GreyImage, Pixels, check_image};
use crate::vision::polarity::Polarity;

/// Pixels added around a component's bounding box for its centroid.
const MARGIN: u32 = 2;

/// What [`detect_dots`] keeps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectConfig {
    /// Grey level above which (light dots) or below which (dark dots) a pixel belongs to a
    /// dot (None: Otsu's threshold). Dark dots with threshold `t` are the light dots of the
    /// negative image with threshold `255 - t`.
    pub threshold: Option<u8>,
    /// Smallest dot, pixels above the threshold.
    pub min_area: usize,
    /// Largest dot (None: no limit).
    pub max_area: Option<usize>,
    /// Light dots (the default), dark dots, or decided by the image.
    pub polarity: Polarity,
}

impl Default for DetectConfig {
    fn default() -> Self {
        Self { threshold: None, min_area: 4, max_area: None, polarity: Polarity::Light }
    }
}

/// A detected dot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dot {
    /// Subpixel centroid `(u, v)`.
    pub centroid: [f64; 2],
    /// Pixels above the threshold.
    pub area: f64,
    /// `[u_min, v_min, u_max, v_max]` of the pixels above the threshold (inclusive).
    pub bbox: [u32; 4],
}

/// A rectangle of pixels, inclusive bounds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Window {
    /// First column.
    pub u0: u32,
    /// First row.
    pub v0: u32,
    /// Last column.
    pub u1: u32,
    /// Last row.
    pub v1: u32,
}

impl Window {
    /// The whole image.
    pub fn full<C: Pixels>(image: &GreyBuffer<C>) -> Self {
        Self { u0: 0, v0: 0, u1: image.width() - 1, v1: image.height() - 1 }
    }

    /// The square of half-side `radius` around `(u, v)`, clipped to the image; None when it
    /// falls outside.
    pub fn around<C: Pixels>(image: &GreyBuffer<C>, center: [f64; 2], radius: f64) -> Option<Self> {
        let (w, h) = (f64::from(image.width()), f64::from(image.height()));
        let (u0, u1) = ((center[0] - radius).round().max(0.0), (center[0] + radius).round().min(w - 1.0));
        let (v0, v1) = ((center[1] - radius).round().max(0.0), (center[1] + radius).round().min(h - 1.0));
        (u0 <= u1 && v0 <= v1).then_some(Self { u0: u0 as u32, v0: v0 as u32, u1: u1 as u32, v1: v1 as u32 })
    }

    fn width(&self) -> u32 {
        self.u1 - self.u0 + 1
    }

    fn height(&self) -> u32 {
        self.v1 - self.v0 + 1
    }
}

/// Detects the dots of a whole image, sorted by `(v, u)` of their centroids. A uniform image
/// (all black, say) is an error: nothing can stand out in it.
pub fn detect_dots<C: Pixels>(image: &GreyBuffer<C>, config: &DetectConfig) -> Result<Vec<Dot>> {
    check_image("image", image)?;
    if config.max_area.is_some_and(|m| m < config.min_area) {
        return Err(Error::InvalidParameter { name: "max_area", reason: "must be >= min_area".into() });
    }
    let (lo, hi) = image.pixels().fold((u8::MAX, 0u8), |(lo, hi), p| (lo.min(p[0]), hi.max(p[0])));
    if lo == hi {
        return Err(Error::InvalidImage {
            what: "image".into(),
            reason: format!("uniform image (every pixel is {lo}): no dot can stand out"),
        });
    }
    let whole = Window::full(image);
    let dark = config.polarity.dark_dots(image);
    let threshold = match config.threshold {
        Some(t) if dark => 255 - t,
        Some(t) => t,
        None => automatic_threshold(&crop(image, whole, dark)),
    };
    let mut dots = detect_in(image, whole, threshold, dark, config.min_area, config.max_area);
    dots.sort_by(|a, b| a.centroid[1].total_cmp(&b.centroid[1]).then(a.centroid[0].total_cmp(&b.centroid[0])));
    Ok(dots)
}

/// The dots of a window with a given threshold. Components that touch the window's border
/// (the image's border included) are dropped: they may not be whole, and the centroid of a
/// cut dot is not its centre. `dark`: the dots are dark, found in the negative image (grey
/// level `255 - g`), to which `threshold` then applies.
pub fn detect_in<C: Pixels>(
    image: &GreyBuffer<C>,
    window: Window,
    threshold: u8,
    dark: bool,
    min_area: usize,
    max_area: Option<usize>,
) -> Vec<Dot> {
    let patch = crop(image, window, dark);
    let binary = GreyImage::from_fn(patch.width(), patch.height(), |u, v| {
        image::Luma([u8::from(patch.get_pixel(u, v)[0] > threshold)])
    });
    let labels = connected_components(&binary, Connectivity::Eight, image::Luma([0u8]));
    let stats = component_stats(&labels);
    stats
        .iter()
        .enumerate()
        .filter(|(_, s)| s.area >= min_area && max_area.is_none_or(|m| s.area <= m))
        .filter(|(_, s)| !cut_by_window(s, window))
        .map(|(label, s)| weighted_dot(&patch, &labels, label as u32 + 1, s, window))
        .collect()
}

/// Otsu's threshold, raised to at least [`NOISE_SIGMAS`] noise deviations above the median
/// (the background): when the dots cover little of the image, Otsu's level falls inside the
/// background's noise and would cut it into specks.
fn automatic_threshold(image: &GreyImage) -> u8 {
    let mut histogram = [0usize; 256];
    image.pixels().for_each(|p| histogram[usize::from(p[0])] += 1);
    let median = histogram_median(&histogram);
    let mut deviations = [0usize; 256];
    for (level, &count) in histogram.iter().enumerate() {
        deviations[level.abs_diff(median)] += count;
    }
    // The median absolute deviation of Gaussian noise is 0.6745 sigma.
    let sigma = histogram_median(&deviations) as f64 / 0.6745;
    let floor = (median as f64 + (NOISE_SIGMAS * sigma).max(1.0)).min(254.0) as u8;
    otsu_level(image).max(floor)
}

/// Noise deviations between the background and the automatic threshold.
const NOISE_SIGMAS: f64 = 6.0;

fn histogram_median(histogram: &[usize; 256]) -> usize {
    let half = histogram.iter().sum::<usize>().div_ceil(2);
    let mut seen = 0;
    histogram
        .iter()
        .position(|&c| {
            seen += c;
            seen >= half
        })
        .unwrap_or(0)
}

/// A window of the image, or of its negative (`dark`).
fn crop<C: Pixels>(image: &GreyBuffer<C>, w: Window, dark: bool) -> GreyImage {
    let flip = if dark { 255 } else { 0 };
    GreyImage::from_fn(w.width(), w.height(), |u, v| image::Luma([flip ^ image.get_pixel(u + w.u0, v + w.v0)[0]]))
}

/// Area and bounding box of one label, in window coordinates.
#[derive(Debug, Clone, Copy)]
struct Stats {
    area: usize,
    bbox: [u32; 4],
}

fn component_stats(labels: &image::ImageBuffer<image::Luma<u32>, Vec<u32>>) -> Vec<Stats> {
    let mut stats: Vec<Stats> = Vec::new();
    for (u, v, p) in labels.enumerate_pixels() {
        let label = p[0] as usize;
        if label == 0 {
            continue;
        }
        if stats.len() < label {
            stats.resize(label, Stats { area: 0, bbox: [u32::MAX, u32::MAX, 0, 0] });
        }
        let s = &mut stats[label - 1];
        s.area += 1;
        s.bbox = [s.bbox[0].min(u), s.bbox[1].min(v), s.bbox[2].max(u), s.bbox[3].max(v)];
    }
    stats
}

fn cut_by_window(s: &Stats, w: Window) -> bool {
    s.bbox[0] == 0 || s.bbox[1] == 0 || s.bbox[2] == w.width() - 1 || s.bbox[3] == w.height() - 1
}

/// The intensity-weighted centroid over the grown bounding box, weights above the median of
/// the box's border ring, pixels of other components left out.
fn weighted_dot(
    patch: &GreyImage,
    labels: &image::ImageBuffer<image::Luma<u32>, Vec<u32>>,
    label: u32,
    s: &Stats,
    window: Window,
) -> Dot {
    let (pw, ph) = (patch.width(), patch.height());
    let (u0, v0) = (s.bbox[0].saturating_sub(MARGIN), s.bbox[1].saturating_sub(MARGIN));
    let (u1, v1) = ((s.bbox[2] + MARGIN).min(pw - 1), (s.bbox[3] + MARGIN).min(ph - 1));
    let background = ring_median(patch, [u0, v0, u1, v1]);
    let (mut sum, mut su, mut sv) = (0.0, 0.0, 0.0);
    for v in v0..=v1 {
        for u in u0..=u1 {
            let l = labels.get_pixel(u, v)[0];
            if l != 0 && l != label {
                continue;
            }
            let w = (f64::from(patch.get_pixel(u, v)[0]) - background).max(0.0);
            sum += w;
            su += w * f64::from(u);
            sv += w * f64::from(v);
        }
    }
    let (du, dv) = (f64::from(window.u0), f64::from(window.v0));
    let centroid = if sum > 0.0 {
        [su / sum + du, sv / sum + dv]
    } else {
        [0.5 * f64::from(s.bbox[0] + s.bbox[2]) + du, 0.5 * f64::from(s.bbox[1] + s.bbox[3]) + dv]
    };
    let bbox = [s.bbox[0] + window.u0, s.bbox[1] + window.v0, s.bbox[2] + window.u0, s.bbox[3] + window.v0];
    Dot { centroid, area: s.area as f64, bbox }
}

/// The median grey level of the border pixels of a box.
fn ring_median(patch: &GreyImage, [u0, v0, u1, v1]: [u32; 4]) -> f64 {
    let mut ring: Vec<u8> = Vec::with_capacity(2 * ((u1 - u0 + 1) + (v1 - v0 + 1)) as usize);
    for u in u0..=u1 {
        ring.push(patch.get_pixel(u, v0)[0]);
        ring.push(patch.get_pixel(u, v1)[0]);
    }
    for v in v0..=v1 {
        ring.push(patch.get_pixel(u0, v)[0]);
        ring.push(patch.get_pixel(u1, v)[0]);
    }
    ring.sort_unstable();
    f64::from(ring[ring.len() / 2])
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::core::camera::Intrinsics;
    use crate::core::distortion::Distortion;
    use crate::vision::render::{CameraView, Disc, RenderConfig, Renderer};
    use crate::vision::target::dots::Dots;
    use nalgebra::Isometry3;

    /// Fronto-parallel discs of `radius_px` at subpixel centres (known exactly: the centroid
    /// of a fronto-parallel disc's image is its projected centre).
    fn scene(radius_px: f64, config: RenderConfig) -> (GreyImage, Vec<[f64; 2]>) {
        let k = Intrinsics::pinhole(1000.0, 1000.0, 0.0, 0.0).unwrap();
        let mut state = 12345u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut discs = Vec::new();
        let mut centres = Vec::new();
        for j in 0..4 {
            for i in 0..5 {
                let (u, v) = (40.0 + 60.0 * i as f64 + next(), 40.0 + 60.0 * j as f64 + next());
                discs.push(Disc::new([u * 0.5e-3, v * 0.5e-3, 0.5], [0.0, 0.0, -1.0], radius_px * 0.5e-3).unwrap());
                centres.push([u, v]);
            }
        }
        let (pose, none) = (Isometry3::identity(), Distortion::none());
        let view = CameraView { pose: &pose, intrinsics: &k, distortion: &none, size: (320, 260) };
        let img = Renderer::new(config).unwrap().render(&Dots::new(discs), None, &view, 1).unwrap();
        (img.image, centres)
    }

    fn errors(radius_px: f64, config: RenderConfig) -> Vec<f64> {
        let (img, centres) = scene(radius_px, config);
        let dots = detect_dots(&img, &DetectConfig::default()).unwrap();
        assert_eq!(dots.len(), centres.len());
        let mut errs: Vec<f64> = centres
            .iter()
            .map(|c| {
                dots.iter().map(|d| (d.centroid[0] - c[0]).hypot(d.centroid[1] - c[1])).fold(f64::INFINITY, f64::min)
            })
            .collect();
        errs.sort_by(f64::total_cmp);
        errs
    }

    #[test]
    fn dark_dots_are_the_light_dots_of_the_negative() {
        let (img, centres) = scene(4.0, RenderConfig::default());
        let negative =
            GreyImage::from_fn(img.width(), img.height(), |u, v| image::Luma([255 - img.get_pixel(u, v)[0]]));
        let light = detect_dots(&img, &DetectConfig::default()).unwrap();
        assert_eq!(light.len(), centres.len());
        let dark = DetectConfig { polarity: Polarity::Dark, ..Default::default() };
        assert_eq!(detect_dots(&negative, &dark).unwrap(), light);
        let auto = DetectConfig { polarity: Polarity::Auto, ..Default::default() };
        assert_eq!(detect_dots(&negative, &auto).unwrap(), light);
        assert_eq!(detect_dots(&img, &auto).unwrap(), light);
        let fixed = DetectConfig { threshold: Some(100), ..dark };
        let light_fixed = DetectConfig { threshold: Some(155), ..Default::default() };
        assert_eq!(detect_dots(&negative, &fixed).unwrap(), detect_dots(&img, &light_fixed).unwrap());
    }

    #[test]
    fn centroids_of_rendered_discs_are_subpixel_accurate() {
        for radius in [3.0, 5.0, 8.0] {
            let errs = errors(radius, RenderConfig::default());
            let (median, max) = (errs[errs.len() / 2], errs[errs.len() - 1]);
            assert!(median < 0.05 && max < 0.2, "radius {radius}: median {median}, max {max}");
            let clean = errors(radius, RenderConfig { noise_sigma: 0.0, blur_sigma: 0.0, ..Default::default() });
            assert!(clean[clean.len() - 1] < 0.02, "radius {radius}: {clean:?}");
        }
    }

    #[test]
    fn empty_and_uniform_images_are_errors() {
        let black = GreyImage::new(40, 30);
        assert!(matches!(detect_dots(&black, &DetectConfig::default()), Err(Error::InvalidImage { .. })));
        let grey = GreyImage::from_pixel(40, 30, image::Luma([128]));
        assert!(detect_dots(&grey, &DetectConfig::default()).is_err());
        let mut one = black.clone();
        one.put_pixel(3, 3, image::Luma([200]));
        assert!(detect_dots(&one, &DetectConfig::default()).unwrap().is_empty(), "a 1-pixel speck is not a dot");
        assert!(detect_dots(&GreyImage::new(0, 0), &DetectConfig::default()).is_err());
        let bad = DetectConfig { min_area: 10, max_area: Some(5), ..Default::default() };
        assert!(detect_dots(&black, &bad).is_err());
    }

    #[test]
    fn area_filters_and_threshold_override() {
        let (img, centres) = scene(5.0, RenderConfig::default());
        let all = detect_dots(&img, &DetectConfig::default()).unwrap();
        assert_eq!(all.len(), centres.len());
        let none = DetectConfig { max_area: Some(20), ..Default::default() };
        assert!(detect_dots(&img, &none).unwrap().is_empty());
        let none = DetectConfig { min_area: 200, ..Default::default() };
        assert!(detect_dots(&img, &none).unwrap().is_empty());
        let high = DetectConfig { threshold: Some(250), ..Default::default() };
        assert!(detect_dots(&img, &high).unwrap().is_empty());
    }
}
