//! Dot detection: bright dots on a dark background, or dark dots on a bright one (found as
//! the bright dots of the negative image: see [`Polarity`]).
//!
//! [`detect_dots`] (a whole image): a local threshold ([`background`](super::background): a
//! pixel is a dot pixel when it stands out of the background around it), 8-connected
//! components as runs ([`runs`](super::runs)), then shape and size filters (area range, fill
//! ratio: a dot is a filled ellipse; contrast) and the subpixel centroid of each dot over a
//! local background plane ([`centroid`](super::centroid)).
//!
//! [`detect_in`] (a window, a given threshold: the dot tracker): imageproc's components and
//! the intensity-weighted centroid over the grown bounding box above the median of its border
//! ring. Pixel `(u, v)` covers `[u - 0.5, u + 0.5] x [v - 0.5, v + 0.5]` (OpenCV's convention).

use imageproc::region_labelling::{Connectivity, connected_components};
use rayon::prelude::*;

use crate::error::Error;
use crate::vision::background::TileThresholds;
use crate::vision::centroid::{MARGIN, near_or_grown_centroid};
use crate::vision::error::{Result, VisionError};
pub use crate::vision::image::Window;
use crate::vision::image::{GreyBuffer, GreyImage, MAX_IMAGE_PIXELS, Pixels, check_image};
use crate::vision::polarity::Polarity;
use crate::vision::runs::{Component, label};

/// What [`detect_dots`] keeps. The defaults find the dots of real camera images (ViSP's
/// grid36 and mire-2) and of rendered ones.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectConfig {
    /// Grey level above which (light dots) or below which (dark dots) a pixel belongs to a
    /// dot, the same over the whole image (None, the default: the local threshold of
    /// [`TileThresholds::local`]). Dark dots with threshold `t` are the light dots of the
    /// negative image with threshold `255 - t`.
    pub threshold: Option<u8>,
    /// Smallest dot, pixels above the threshold (default 8: a disc 3.2 px across).
    pub min_area: usize,
    /// Largest dot (None, the default: no limit).
    pub max_area: Option<usize>,
    /// Light dots (the default), dark dots, or decided by the image.
    pub polarity: Polarity,
    /// Smallest fill ratio: the dot's area over that of the ellipse of its second moments
    /// (1 for a filled ellipse, 0.955 for a square; default 0.95), in `[0, 1]`. A dot of `A`
    /// pixels is allowed [`DIGITISATION_SLACK`]` / sqrt(A)` less: its digitised outline, about
    /// `sqrt(A)` pixels of `A`, moves the ratio by that much (0.04 at 25 px, 0.006 at 1000 px).
    pub min_fill: f64,
    /// Smallest contrast, grey levels (default 20): the local threshold is at least this far
    /// above the local background, and a dot's pixels must be this far above the background
    /// plane around it on average.
    pub min_contrast: u8,
    /// Largest clutter around a dot (default 0.15): the RMS deviation of the ring around the
    /// dot (its bounding box grown by 2 px) from the background plane fitted to it, over the
    /// dot's contrast. A dot stands on a plain background (a printed disc, a marker); a bright
    /// speck of a textured scene does not. Non-negative (infinity: no check).
    pub max_ring_residual: f64,
}

impl Default for DetectConfig {
    fn default() -> Self {
        Self {
            threshold: None,
            min_area: 8,
            max_area: None,
            polarity: Polarity::Light,
            min_fill: 0.95,
            min_contrast: 20,
            max_ring_residual: 0.15,
        }
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

/// The most pixels [`detect_dots`] reads: 2^26 (8192 x 8192), a quarter of
/// [`MAX_IMAGE_PIXELS`]. The detector takes about 16 bytes a pixel (local thresholds, labels,
/// runs; measured on stripes, 13 on noise) and some 0.1 s a megapixel, so at most about
/// 1 GiB and several seconds.
pub const MAX_DOT_PIXELS: u64 = MAX_IMAGE_PIXELS >> 2;

/// Detects the dots of a whole image, sorted by `(v, u)` of their centroids. A uniform image
/// (all black, say) is an error: nothing can stand out in it; so is an image of more than
/// [`MAX_DOT_PIXELS`], refused before anything is allocated.
pub fn detect_dots<C: Pixels>(image: &GreyBuffer<C>, config: &DetectConfig) -> Result<Vec<Dot>> {
    check_image("image", image)?;
    let pixels = u64::from(image.width()) * u64::from(image.height());
    if pixels > MAX_DOT_PIXELS {
        return Err(VisionError::InvalidImage {
            what: "image".into(),
            reason: format!(
                "{} x {} pixels: too large for the dot detector (at most {MAX_DOT_PIXELS} pixels, 2^26: \
                 its memory, about 16 bytes a pixel)",
                image.height(),
                image.width()
            ),
        });
    }
    check_config(config)?;
    crate::parallel::install(|| dots_of(image, config))?
}

/// [`detect_dots`] of a checked image and configuration, on the calling thread's rayon pool;
/// a uniform image (found by the labelling's pass: no pass of its own) is an error.
fn dots_of<C: Pixels>(image: &GreyBuffer<C>, config: &DetectConfig) -> Result<Vec<Dot>> {
    let dark = config.polarity.dark_dots(image);
    let thresholds = match config.threshold {
        Some(t) if dark => TileThresholds::uniform(image, 255 - t),
        Some(t) => TileThresholds::uniform(image, t),
        None => TileThresholds::local(image, dark, config.min_contrast),
    };
    let labelling = label(image, &thresholds, dark);
    if let [lo, hi] = labelling.range
        && lo == hi
    {
        return Err(VisionError::InvalidImage {
            what: "image".into(),
            reason: format!("uniform image (every pixel is {lo}): no dot can stand out"),
        });
    }
    let whole = Window::full(image);
    let mut dots: Vec<Dot> = labelling
        .components
        .par_iter()
        .enumerate()
        .filter(|(_, c)| keeps_shape(c, config, whole))
        .filter_map(|(index, c)| {
            let plain = |residual: f64, contrast: f64| residual <= config.max_ring_residual * contrast;
            // A dot whose near surround is not plain (a shaded sphere's limb) is measured again
            // against a ring farther out, where its surround may be plain.
            let keep_near = |residual, contrast| c.area < GROWN_MIN_AREA || plain(residual, contrast);
            let weighted = near_or_grown_centroid(image, &labelling, index as u32, dark, keep_near);
            let plain = plain(weighted.ring_residual, weighted.contrast);
            (weighted.contrast >= f64::from(config.min_contrast).max(f64::MIN_POSITIVE) && plain).then_some(Dot {
                centroid: weighted.centroid,
                area: c.area as f64,
                bbox: c.bbox,
            })
        })
        .collect();
    dots.sort_by(|a, b| a.centroid[1].total_cmp(&b.centroid[1]).then(a.centroid[0].total_cmp(&b.centroid[0])));
    Ok(dots)
}

fn check_config(config: &DetectConfig) -> Result<()> {
    if config.max_area.is_some_and(|m| m < config.min_area) {
        return Err(Error::InvalidParameter { name: "max_area", reason: "must be >= min_area".into() }.into());
    }
    if !(0.0..=1.0).contains(&config.min_fill) {
        return Err(Error::InvalidParameter {
            name: "min_fill",
            reason: format!("must be in [0, 1], got {:?}", config.min_fill),
        }
        .into());
    }
    if config.max_ring_residual.is_nan() || config.max_ring_residual < 0.0 {
        let reason = format!("must be >= 0, got {:?}", config.max_ring_residual);
        return Err(Error::InvalidParameter { name: "max_ring_residual", reason }.into());
    }
    Ok(())
}

/// How much lower than `min_fill` the fill ratio of a dot of `A` pixels may be, times
/// `sqrt(A)`: the pixels along a digitised outline are a fraction of order `1 / sqrt(A)` of the
/// area, and each moves the ratio (rendered discs, blurred, measure about `1 - 0.35 /
/// sqrt(A)`: 0.931 at 26 px, 0.965 at 100 px; the slack keeps those of `min_fill - 0.02` and
/// up).
pub const DIGITISATION_SLACK: f64 = 0.2;

/// Smallest dot measured against a grown ring when its near ring is not plain (pixels above
/// the threshold): a sphere's shading spreads past its lit part when it is several pixels
/// across; a speck that small in clutter is clutter (ViSP's mire-2 poster has many).
const GROWN_MIN_AREA: u64 = 100;

/// Area range, whole and filled like an ellipse. Whole: its box grown by the centroid's
/// [`MARGIN`] lies inside the image, so that the anti-aliased edge the centroid weighs is all
/// there; a dot nearer the border may be cut (its edge pixels under the threshold) and its
/// centroid would lean away from the border (issue 27, item 4: by 0.09 px for a disc of 7.5 px
/// radius whose last edge pixel is the image's last column).
fn keeps_shape(c: &Component, config: &DetectConfig, whole: Window) -> bool {
    let area = c.area as usize;
    let cut = c.bbox[0] < whole.u0 + MARGIN
        || c.bbox[1] < whole.v0 + MARGIN
        || c.bbox[2] + MARGIN > whole.u1
        || c.bbox[3] + MARGIN > whole.v1;
    let min_fill = config.min_fill - DIGITISATION_SLACK / (c.area as f64).sqrt();
    area >= config.min_area && config.max_area.is_none_or(|m| area <= m) && !cut && c.fill_ratio() >= min_fill
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
        assert!(matches!(detect_dots(&black, &DetectConfig::default()), Err(VisionError::InvalidImage { .. })));
        let grey = GreyImage::from_pixel(40, 30, image::Luma([128]));
        assert!(detect_dots(&grey, &DetectConfig::default()).is_err());
        let mut one = black.clone();
        one.put_pixel(3, 3, image::Luma([200]));
        assert!(detect_dots(&one, &DetectConfig::default()).unwrap().is_empty(), "a 1-pixel speck is not a dot");
        assert!(detect_dots(&GreyImage::new(0, 0), &DetectConfig::default()).is_err());
        let bad = DetectConfig { min_area: 10, max_area: Some(5), ..Default::default() };
        assert!(detect_dots(&black, &bad).is_err());
    }

    /// A disc of radius `r` and height `a` at `centre` (8 x 8 supersampled coverage) on the
    /// plane `g0 + gu u + gv v`.
    fn disc_on_gradient(centre: [f64; 2], r: f64, a: f64, [g0, gu, gv]: [f64; 3]) -> GreyImage {
        GreyImage::from_fn(64, 64, |u, v| {
            let mut inside = 0;
            for i in 0..8 {
                for j in 0..8 {
                    let (x, y) =
                        (f64::from(u) - 0.4375 + f64::from(i) / 8.0, f64::from(v) - 0.4375 + f64::from(j) / 8.0);
                    inside += i32::from((x - centre[0]).hypot(y - centre[1]) < r);
                }
            }
            let g = g0 + gu * f64::from(u) + gv * f64::from(v) + a * f64::from(inside) / 64.0;
            image::Luma([g.round().clamp(0.0, 255.0) as u8])
        })
    }

    #[test]
    fn a_lighting_gradient_does_not_pull_the_centroid() {
        // Closed form: the true centre is where the disc is drawn. The plane fitted to the
        // ring cancels the gradient; the ring's median (detect_in) leaves the bright side's
        // background in the weights.
        let centre = [31.3, 32.6];
        let image = disc_on_gradient(centre, 6.0, 120.0, [20.0, 1.5, 0.8]);
        let dots = detect_dots(&image, &DetectConfig::default()).unwrap();
        assert_eq!(dots.len(), 1);
        let plane = (dots[0].centroid[0] - centre[0]).hypot(dots[0].centroid[1] - centre[1]);
        let level = (20.0 + 1.5 * centre[0] + 0.8 * centre[1] + 60.0) as u8;
        let median = detect_in(&image, Window::full(&image), level, false, 4, None);
        assert_eq!(median.len(), 1);
        let median = (median[0].centroid[0] - centre[0]).hypot(median[0].centroid[1] - centre[1]);
        assert!(plane < 0.03, "plane model: {plane} px");
        assert!(median > 3.0 * plane && median > 0.05, "median {median} px vs plane {plane} px");
        // No gradient: both exact.
        let flat = disc_on_gradient(centre, 6.0, 120.0, [40.0, 0.0, 0.0]);
        let d = detect_dots(&flat, &DetectConfig::default()).unwrap()[0].centroid;
        assert!((d[0] - centre[0]).hypot(d[1] - centre[1]) < 0.02, "{d:?}");
    }

    #[test]
    fn a_dot_wider_than_the_tile_neighbourhood_is_found_at_its_centre() {
        // A disc 220 px across (the local threshold's neighbourhood is 160 px: its inside is
        // thresholded at a coarser level; its own pixels are summed in lanes) on a lighting
        // gradient, 4 x 4 supersampled coverage: found alone, at the closed-form centre.
        let centre = [161.3, 158.6];
        let image = GreyImage::from_fn(320, 320, |u, v| {
            let mut inside = 0;
            for i in 0..4 {
                for j in 0..4 {
                    let (x, y) = (f64::from(u) - 0.375 + f64::from(i) / 4.0, f64::from(v) - 0.375 + f64::from(j) / 4.0);
                    inside += i32::from((x - centre[0]).hypot(y - centre[1]) < 110.0);
                }
            }
            let g = 20.0 + 0.2 * f64::from(u) + 0.1 * f64::from(v) + 150.0 * f64::from(inside) / 16.0;
            image::Luma([g.round() as u8])
        });
        for dark in [false, true] {
            let (image, polarity) = if dark {
                (GreyImage::from_fn(320, 320, |u, v| image::Luma([255 - image.get_pixel(u, v)[0]])), Polarity::Dark)
            } else {
                (image.clone(), Polarity::Light)
            };
            let dots = detect_dots(&image, &DetectConfig { polarity, ..Default::default() }).unwrap();
            assert_eq!(dots.len(), 1, "dark {dark}: {dots:?}");
            let d = dots[0].centroid;
            assert!((d[0] - centre[0]).hypot(d[1] - centre[1]) < 0.02, "dark {dark}: {d:?}");
        }
    }

    #[test]
    fn background_noise_around_a_dot_does_not_weigh_on_its_centroid() {
        // A disc on a background with +-3 levels of checkerboard noise (ring RMS 3): a pixel of
        // the box at 5 levels above the background is noise and leaves the centroid as it is;
        // at 40 levels it is part of the dot's edge and counts.
        let centre = [31.3, 32.6];
        let mut image = disc_on_gradient(centre, 6.0, 150.0, [40.0, 0.0, 0.0]);
        for (u, v, g) in image.enumerate_pixels_mut() {
            if g.0[0] == 40 {
                g.0[0] = if (u + v) % 2 == 0 { 43 } else { 37 };
            }
        }
        let centroid = |image: &GreyImage| detect_dots(image, &DetectConfig::default()).unwrap()[0].centroid;
        let before = centroid(&image);
        assert!((before[0] - centre[0]).hypot(before[1] - centre[1]) < 0.02, "{before:?}");
        // (25, 26): inside the box grown around the disc (bounding box 26..37 x 27..38), off it.
        for (bump, moves) in [(45u8, false), (80, true)] {
            let mut bumped = image.clone();
            bumped.put_pixel(25, 26, image::Luma([bump]));
            let after = centroid(&bumped);
            assert_eq!(after != before, moves, "a pixel at {bump}: {before:?} -> {after:?}");
        }
    }

    #[test]
    fn shape_and_contrast_filters() {
        // A filled disc, a ring (fill ratio about 0.5), a bar with a bump, and a faint disc.
        let mut image = GreyImage::from_pixel(160, 64, image::Luma([30]));
        for v in 0..64u32 {
            for u in 0..160u32 {
                let (x, y) = (f64::from(u), f64::from(v));
                let disc = (x - 20.0).hypot(y - 32.0) < 8.0;
                let ring = ((x - 60.0).hypot(y - 32.0) - 8.0).abs() < 1.5;
                let bar = ((80..120).contains(&u) && (30..34).contains(&v))
                    || ((96..104).contains(&u) && (22..42).contains(&v));
                let faint = (x - 140.0).hypot(y - 32.0) < 8.0;
                let g = if disc || ring || bar {
                    220
                } else if faint {
                    45
                } else {
                    30
                };
                image.put_pixel(u, v, image::Luma([g]));
            }
        }
        let found = |config: DetectConfig| -> Vec<u32> {
            let mut columns: Vec<u32> =
                detect_dots(&image, &config).unwrap().iter().map(|d| d.centroid[0].round() as u32).collect();
            columns.sort_unstable();
            columns
        };
        let fixed = DetectConfig { threshold: Some(40), ..Default::default() };
        assert_eq!(found(fixed), vec![20], "ring, bar and faint disc rejected");
        assert_eq!(found(DetectConfig { min_fill: 0.0, ..fixed }), vec![20, 60, 100]);
        assert_eq!(found(DetectConfig { min_contrast: 5, ..fixed }), vec![20, 140]);
        assert_eq!(found(DetectConfig::default()), vec![20]);
        for bad in [-0.1, 1.5, f64::NAN] {
            let e = detect_dots(&image, &DetectConfig { min_fill: bad, ..Default::default() }).unwrap_err();
            assert!(matches!(e, VisionError::Core(Error::InvalidParameter { name: "min_fill", .. })), "{e}");
        }
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

    #[test]
    fn an_image_larger_than_the_dot_bound_is_refused_before_reading() {
        // 8192 x 8193 (just over 2^26 pixels): zero-filled, never read (a uniform image would
        // otherwise be refused as uniform, after a pass over it).
        let big = GreyImage::new(8192, 8193);
        let err = detect_dots(&big, &DetectConfig::default()).unwrap_err().to_string();
        assert!(err.contains("too large for the dot detector") && err.contains("67108864"), "{err}");
        let fits = GreyImage::new(8192, 8192);
        let err = detect_dots(&fits, &DetectConfig::default()).unwrap_err().to_string();
        assert!(err.contains("uniform"), "{err}");
    }
}
