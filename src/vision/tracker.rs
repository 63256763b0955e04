//! Dot tracking from image to image, as ViSP users know it: initialised with one
//! approximate pixel per dot (the clicks in the first image), it searches a window around
//! each dot's predicted position (last position plus last displacement), grown while the
//! dot is lost, with a threshold learned per dot. A dot that is not found is reported so,
//! never invented, and two dots are never silently swapped: when two tracked dots claim the
//! same component (dots merging as they pass each other), both are reported lost for that
//! image and keep their predicted motion.

use crate::error::{Error, Result, Short, fixed_or_short};
use crate::vision::dots::{Dot, Window, detect_in};
use crate::vision::image::{GreyBuffer, Pixels, check_image};
use crate::vision::polarity::Polarity;

/// How the tracker searches.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackerConfig {
    /// Half-side of the search window around a dot's prediction, pixels.
    pub search_radius: f64,
    /// The largest window (grown x2 while a dot is not found), pixels.
    pub max_search_radius: f64,
    /// Smallest dot, pixels above the threshold.
    pub min_area: usize,
    /// A component whose area differs from the dot's last area by more than this factor is
    /// not that dot.
    pub max_area_ratio: f64,
    /// Light dots (the default), dark dots, or decided by the first image (the whole image,
    /// by [`Polarity::dark_dots`]'s rule).
    pub polarity: Polarity,
}

impl Default for TrackerConfig {
    fn default() -> Self {
        Self {
            search_radius: 20.0,
            max_search_radius: 80.0,
            min_area: 4,
            max_area_ratio: 2.5,
            polarity: Polarity::Light,
        }
    }
}

impl TrackerConfig {
    fn validate(&self) -> Result<()> {
        let ok = self.search_radius.is_finite()
            && self.search_radius >= 2.0
            && self.max_search_radius.is_finite()
            && self.max_search_radius >= self.search_radius
            && self.max_area_ratio.is_finite()
            && self.max_area_ratio > 1.0;
        if ok {
            Ok(())
        } else {
            Err(Error::InvalidParameter {
                name: "tracker",
                reason: "need 2 <= search_radius <= max_search_radius (finite) and max_area_ratio > 1".into(),
            })
        }
    }
}

/// What one image gave.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackResult {
    /// Per dot: the centroid found, or the last known position when not found.
    pub pixels: Vec<[f64; 2]>,
    /// Per dot: found in this image.
    pub found: Vec<bool>,
}

#[derive(Debug, Clone, Copy)]
struct TrackedDot {
    position: [f64; 2],
    predicted: [f64; 2],
    velocity: [f64; 2],
    threshold: u8,
    area: f64,
    lost_for: usize,
}

/// Tracks a fixed set of dots through images of one size.
#[derive(Debug, Clone)]
pub struct DotTracker {
    size: (u32, u32),
    config: TrackerConfig,
    /// The dots are dark (the polarity, decided on the first image for `Auto`).
    dark: bool,
    dots: Vec<TrackedDot>,
    positions: Vec<[f64; 2]>,
}

impl DotTracker {
    /// Detects each dot in a window around its click in the first image.
    pub fn new<C: Pixels>(image: &GreyBuffer<C>, initial_pixels: &[[f64; 2]], config: TrackerConfig) -> Result<Self> {
        config.validate()?;
        check_image("image", image)?;
        if initial_pixels.is_empty() {
            return Err(Error::TooFewPoints { needed: 1, got: 0, why: "the tracker needs one pixel per dot" });
        }
        let dark = config.polarity.dark_dots(image);
        let mut dots = Vec::with_capacity(initial_pixels.len());
        for (i, &click) in initial_pixels.iter().enumerate() {
            dots.push(initial_dot(image, i, click, &config, dark)?);
        }
        check_distinct(&dots)?;
        let positions = dots.iter().map(|d| d.position).collect();
        Ok(Self { size: image.dimensions(), config, dark, dots, positions })
    }

    /// Whether the tracked dots are dark (for `Auto`: as decided on the first image).
    pub fn dark(&self) -> bool {
        self.dark
    }

    /// Number of dots.
    pub fn len(&self) -> usize {
        self.dots.len()
    }

    /// Whether there is no dot (never, once built).
    pub fn is_empty(&self) -> bool {
        self.dots.is_empty()
    }

    /// The last known position of every dot.
    pub fn positions(&self) -> &[[f64; 2]] {
        &self.positions
    }

    /// Finds the dots in the next image.
    pub fn track<C: Pixels>(&mut self, image: &GreyBuffer<C>) -> Result<TrackResult> {
        if image.dimensions() != self.size {
            return Err(Error::InvalidImage {
                what: "image".into(),
                reason: format!(
                    "{} x {} (height x width), the tracker was started on {} x {}",
                    image.height(),
                    image.width(),
                    self.size.1,
                    self.size.0
                ),
            });
        }
        let mut found: Vec<Option<Dot>> = self.dots.iter().map(|d| self.search(image, d)).collect();
        drop_shared_components(&mut found);
        for (dot, hit) in self.dots.iter_mut().zip(&found) {
            dot.update(hit.as_ref());
        }
        self.positions = self.dots.iter().map(|d| d.position).collect();
        Ok(TrackResult { pixels: self.positions.clone(), found: found.iter().map(Option::is_some).collect() })
    }

    /// The component nearest to the dot's prediction in a window grown until one is found.
    fn search<C: Pixels>(&self, image: &GreyBuffer<C>, dot: &TrackedDot) -> Option<Dot> {
        let mut radius = if dot.lost_for > 0 { self.config.max_search_radius } else { self.config.search_radius };
        loop {
            let window = Window::around(image, dot.predicted, radius)?;
            let candidates = detect_in(image, window, dot.threshold, self.dark, self.config.min_area, None);
            let ratio = self.config.max_area_ratio;
            let best = candidates
                .into_iter()
                .filter(|c| c.area <= dot.area * ratio && c.area * ratio >= dot.area)
                .min_by(|a, b| distance(a.centroid, dot.predicted).total_cmp(&distance(b.centroid, dot.predicted)));
            // A window that already covers the image cannot grow: stop (a huge max_search_radius
            // would otherwise rescan the whole image about log2(radius) times).
            let whole =
                window.u0 == 0 && window.v0 == 0 && window.u1 + 1 >= image.width() && window.v1 + 1 >= image.height();
            if best.is_some() || radius >= self.config.max_search_radius || whole {
                return best;
            }
            radius = (2.0 * radius).min(self.config.max_search_radius);
        }
    }
}

impl TrackedDot {
    fn update(&mut self, hit: Option<&Dot>) {
        match hit {
            Some(d) => {
                self.velocity = [d.centroid[0] - self.position[0], d.centroid[1] - self.position[1]];
                if self.lost_for > 0 {
                    self.velocity = [0.0, 0.0];
                }
                self.position = d.centroid;
                self.area = d.area;
                self.lost_for = 0;
            }
            None => self.lost_for += 1,
        }
        // While lost (for a few images), keep moving the prediction: two crossing dots keep
        // their own way through the images where they merge.
        let moving = self.lost_for <= 5;
        let base = if self.lost_for == 0 { self.position } else { self.predicted };
        let step = if moving { self.velocity } else { [0.0, 0.0] };
        self.predicted = [base[0] + step[0], base[1] + step[1]];
    }
}

fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// The dot around a click: a threshold midway between the window's background and its
/// peak (in the negative image for dark dots), the component nearest the click.
fn initial_dot<C: Pixels>(
    image: &GreyBuffer<C>,
    i: usize,
    click: [f64; 2],
    config: &TrackerConfig,
    dark: bool,
) -> Result<TrackedDot> {
    if !(click[0].is_finite() && click[1].is_finite()) {
        return Err(Error::NonFinitePoint {
            what: "initial_pixels",
            row: i,
            column: usize::from(click[0].is_finite()),
        });
    }
    let not_found = |reason: &str| Error::InvalidImage {
        what: "initial_pixels".into(),
        reason: format!("point {i} at ({}, {}): {reason}", fixed_or_short(click[0], 1), fixed_or_short(click[1], 1)),
    };
    let (w, h) = (f64::from(image.width()), f64::from(image.height()));
    if click[0] < -0.5 || click[1] < -0.5 || click[0] > w - 0.5 || click[1] > h - 0.5 {
        return Err(not_found("outside the image"));
    }
    let window = Window::around(image, click, config.search_radius).ok_or_else(|| not_found("outside the image"))?;
    // The threshold is midway between the window's background (its median) and the dot's
    // peak; a window without contrast has no dot.
    let (background, peak) = window_levels(image, window, dark);
    if peak.saturating_sub(background) < MIN_CONTRAST {
        return Err(not_found(&format!("no dot within {} px (no contrast)", Short(config.search_radius))));
    }
    let threshold = background + (peak - background) / 2;
    let best = detect_in(image, window, threshold, dark, config.min_area, None)
        .into_iter()
        .min_by(|a, b| distance(a.centroid, click).total_cmp(&distance(b.centroid, click)))
        .ok_or_else(|| not_found(&format!("no dot within {} px", Short(config.search_radius))))?;
    Ok(TrackedDot {
        position: best.centroid,
        predicted: best.centroid,
        velocity: [0.0, 0.0],
        threshold,
        area: best.area,
        lost_for: 0,
    })
}

/// Grey levels by which a dot must stand out from its background.
const MIN_CONTRAST: u8 = 24;

/// The median and the largest grey level of a window (of its negative for dark dots).
fn window_levels<C: Pixels>(image: &GreyBuffer<C>, w: Window, dark: bool) -> (u8, u8) {
    let flip = if dark { 255 } else { 0 };
    let mut values: Vec<u8> =
        (w.v0..=w.v1).flat_map(|v| (w.u0..=w.u1).map(move |u| flip ^ image.get_pixel(u, v)[0])).collect();
    values.sort_unstable();
    (values[values.len() / 2], values[values.len() - 1])
}

/// Two clicks on the same dot are an error naming both.
fn check_distinct(dots: &[TrackedDot]) -> Result<()> {
    for (i, a) in dots.iter().enumerate() {
        if let Some(j) = dots[i + 1..].iter().position(|b| distance(a.position, b.position) < 0.5) {
            return Err(Error::InvalidImage {
                what: "initial_pixels".into(),
                reason: format!("points {i} and {} found the same dot", i + 1 + j),
            });
        }
    }
    Ok(())
}

/// Two dots that claim the same component are both reported lost.
fn drop_shared_components(found: &mut [Option<Dot>]) {
    let mut shared = vec![false; found.len()];
    for i in 0..found.len() {
        for j in i + 1..found.len() {
            if let (Some(a), Some(b)) = (&found[i], &found[j])
                && distance(a.centroid, b.centroid) < 0.5
            {
                shared[i] = true;
                shared[j] = true;
            }
        }
    }
    for (f, s) in found.iter_mut().zip(shared) {
        if s {
            *f = None;
        }
    }
}
