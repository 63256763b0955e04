//! Dot tracking from image to image, as ViSP users know it: initialised with one
//! approximate pixel per dot (the clicks in the first image), it searches a window around
//! each dot's predicted position (last position plus last displacement), with a threshold
//! learned per dot (midway between its local background and its peak, updated with every
//! image where it is found). The window follows the dot: its half-sides are the dot's half-extents,
//! grown by the largest accepted change of size, plus half the search radius of unpredicted
//! motion and the predicted motion itself (never less than the search radius); it grows
//! while nothing is found, up to `max_search_radius` or the dot's own size.
//!
//! A found component must be the same dot as in the previous image: its area and its
//! principal spreads may change by a bounded factor (the `shape` module). A dot that fails is reported
//! lost and keeps its last position, never returned at a wrong position: when the predicted
//! pixel lies in a component that is too large, cut by the window, or of another shape (the
//! dot merged with a neighbouring region), the dot is lost for that image and no other
//! component is taken in its place. Two dots are never silently swapped: when two tracked
//! dots claim the same component (dots merging as they pass each other) both are reported
//! lost for that image and keep their predicted motion; a component nearer to another dot's
//! prediction than to its own is not taken (overlapping windows), nor one whose box holds
//! another dot's prediction.

mod settings;
mod shape;
mod start;
mod window_search;

pub use self::settings::{
    SettingKind, SettingValue, TRACKER_SETTINGS, TrackerSetting, tracker_setting, tracker_setting_names,
};
pub use self::start::MAX_START_PIXELS;

use self::shape::Shape;
use self::window_search::{Component, Level, WindowSearch};
use crate::error::Error;
use crate::vision::dots::MAX_DOT_PIXELS;
use crate::vision::error::{Result, VisionError};
use crate::vision::image::Window;
use crate::vision::image::{GreyBuffer, Pixels, check_image};
use crate::vision::polarity::Polarity;

/// How the tracker searches.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackerConfig {
    /// Half-side of the search window around a dot's prediction, pixels: the smallest
    /// window, and twice the unpredicted motion allowed around a dot larger than it.
    pub search_radius: f64,
    /// The largest window (grown x2 while a dot is not found), pixels; a dot larger than
    /// it gets a window of its own size.
    pub max_search_radius: f64,
    /// Smallest dot, pixels above the threshold.
    pub min_area: usize,
    /// A component whose area differs from the dot's last area by more than this factor
    /// (beyond an allowance for the boundary pixels), or whose principal spreads differ by
    /// more than its square root, is not that dot.
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
            max_area_ratio: 1.5,
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
                reason: "need 2 <= search_radius <= max_search_radius (finite) and max_area_ratio > 1 (finite)".into(),
            }
            .into())
        }
    }
}

/// What one image gave.
#[derive(Debug, Clone, PartialEq, Default)]
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
    shape: Shape,
    lost_for: usize,
}

/// A component taken for a dot in this image.
#[derive(Debug, Clone, Copy)]
struct Hit {
    centroid: [f64; 2],
    shape: Shape,
    /// Which component (two dots' windows see the same component with the same box and area).
    identity: ([u32; 4], usize),
    /// The dot's threshold for the next image.
    threshold: u8,
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
    /// Buffers kept from image to image.
    search: WindowSearch,
    hits: Vec<Option<Hit>>,
}

impl DotTracker {
    /// Detects each dot in a window around its click in the first image.
    pub fn new<C: Pixels>(image: &GreyBuffer<C>, initial_pixels: &[[f64; 2]], config: TrackerConfig) -> Result<Self> {
        config.validate()?;
        check_image("image", image)?;
        if initial_pixels.is_empty() {
            return Err(Error::TooFewPoints { needed: 1, got: 0, why: "the tracker needs one pixel per dot" }.into());
        }
        check_auto_polarity(image, config.polarity)?;
        let dark = config.polarity.dark_dots(image);
        let mut search = WindowSearch::default();
        let mut dots = Vec::with_capacity(initial_pixels.len());
        let mut read = 0;
        for (i, &click) in initial_pixels.iter().enumerate() {
            dots.push(start::initial_dot(image, i, click, &config, dark, &mut search, &mut read)?);
        }
        check_distinct(&dots)?;
        let positions = dots.iter().map(|d| d.position).collect();
        let hits = vec![None; dots.len()];
        Ok(Self { size: image.dimensions(), config, dark, dots, positions, search, hits })
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
        let mut out = TrackResult::default();
        self.track_into(image, &mut out)?;
        Ok(out)
    }

    /// [`DotTracker::track`] writing into `out` (its vectors are reused: no allocation once
    /// they hold one entry per dot).
    pub fn track_into<C: Pixels>(&mut self, image: &GreyBuffer<C>, out: &mut TrackResult) -> Result<()> {
        self.track_with(image, out, false).map(|_| ())
    }

    /// The windows the next image is searched in first, one per dot: its search window around
    /// its prediction (the largest while the dot is lost), clipped to the image; a dot whose
    /// window falls outside the image has none. A [`DotTracker::track`] that finds each dot
    /// there, or concludes it is lost there, reads no pixel outside them (its larger windows
    /// are read only when a dot is in none of its components).
    pub fn first_windows(&self) -> Vec<Window> {
        self.dots.iter().filter_map(|dot| window_in(self.size, dot.predicted, self.first_half(dot))).collect()
    }

    /// [`DotTracker::track_into`] reading only the pixels of [`DotTracker::first_windows`]
    /// (the others may hold anything, e.g. a frame rendered only there): `Ok(true)` with `out`
    /// as `track_into` gives it, or `Ok(false)`, the tracker unchanged, when a dot needs a
    /// larger window: then track the whole image with `track_into`.
    pub fn track_in_first_windows<C: Pixels>(&mut self, image: &GreyBuffer<C>, out: &mut TrackResult) -> Result<bool> {
        self.track_with(image, out, true)
    }

    /// Tracks into `out`; with `first_only`, stops before a larger window than the first
    /// and returns false, the dots not updated.
    fn track_with<C: Pixels>(
        &mut self,
        image: &GreyBuffer<C>,
        out: &mut TrackResult,
        first_only: bool,
    ) -> Result<bool> {
        if image.dimensions() != self.size {
            return Err(VisionError::InvalidImage {
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
        for dot in &self.dots {
            if let Some(w) = window_around(image, dot.predicted, dot.box_half()) {
                window_search::warm_up(image, w);
            }
        }
        let mut hits = std::mem::take(&mut self.hits);
        let dots = std::mem::take(&mut self.dots);
        let mut within = true;
        for (i, hit) in hits.iter_mut().enumerate() {
            match self.search(image, i, &dots, first_only) {
                Ok(found) => *hit = found,
                Err(Beyond) => {
                    within = false;
                    break;
                }
            }
        }
        self.dots = dots;
        if !within {
            self.hits = hits;
            return Ok(false);
        }
        drop_shared_components(&mut hits);
        drop_hits_over_other_dots(&mut hits, &self.dots);
        for ((dot, hit), position) in self.dots.iter_mut().zip(&hits).zip(self.positions.iter_mut()) {
            dot.update(hit.as_ref());
            *position = dot.position;
        }
        out.pixels.clear();
        out.pixels.extend_from_slice(&self.positions);
        out.found.clear();
        out.found.extend(hits.iter().map(Option::is_some));
        self.hits = hits;
        Ok(true)
    }

    /// The half-sides of a dot's first search window: the largest while it is lost.
    fn first_half(&self, dot: &TrackedDot) -> [f64; 2] {
        let half = dot.window_half(&self.config);
        let limit = half.map(|h| h.max(self.config.max_search_radius));
        if dot.lost_for > 0 { limit } else { half }
    }
}

/// A search that needs a window larger than the first (in [`DotTracker::track_in_first_windows`]).
struct Beyond;

impl DotTracker {
    /// The component taken for a dot in this image, or None (lost). First the component
    /// under the predicted pixel: if it is the dot's size and shape and whole, it is the dot;
    /// if it is larger, cut by the window or of another shape, the dot merged with something
    /// and is lost. Otherwise the nearest component of the dot's size and shape in the
    /// window, the window doubling while there is none.
    fn search<C: Pixels>(
        &mut self,
        image: &GreyBuffer<C>,
        i: usize,
        dots: &[TrackedDot],
        first_only: bool,
    ) -> std::result::Result<Option<Hit>, Beyond> {
        let dot = &dots[i];
        // A component nearer to another dot's prediction is that dot's (taking it would swap).
        let own = |c: &Component| {
            let d = distance(c.centroid(), dot.predicted);
            dots.iter().enumerate().all(|(j, other)| j == i || distance(c.centroid(), other.predicted) >= d)
        };
        let level = Level { threshold: dot.threshold, flip: if self.dark { 255 } else { 0 } };
        let ratio = self.config.max_area_ratio;
        let mut half = self.first_half(dot);
        let limit = dot.window_half(&self.config).map(|h| h.max(self.config.max_search_radius));
        let (w, h) = (f64::from(image.width()), f64::from(image.height()));
        let (pu, pv) = (dot.predicted[0].round(), dot.predicted[1].round());
        let inside = pu >= 0.0 && pv >= 0.0 && pu < w && pv < h;
        loop {
            let Some(window) = window_around(image, dot.predicted, half) else { return Ok(None) };
            self.search.begin(window);
            let under = if inside { self.search.component_at(image, level, pu as u32, pv as u32) } else { None };
            if let Some(c) = under {
                let shape = Shape::of(&c);
                // A speck smaller than the dot may sit on the prediction: look further.
                let smaller =
                    c.area < self.config.min_area || (shape.area < dot.shape.area && !dot.shape.admits(&shape, ratio));
                if !smaller {
                    let whole = !c.touches_window && !c.touches_image;
                    return Ok((whole && dot.shape.admits(&shape, ratio)).then(|| self.hit(image, level, &c, shape)));
                }
            }
            self.search.label_all(image, level);
            let best = self
                .search
                .components
                .iter()
                .filter(|c| c.area >= self.config.min_area && !c.touches_window && !c.touches_image && own(c))
                .map(|c| (*c, Shape::of(c)))
                .filter(|(_, s)| dot.shape.admits(s, ratio))
                .min_by(|a, b| {
                    distance(a.0.centroid(), dot.predicted).total_cmp(&distance(b.0.centroid(), dot.predicted))
                });
            if let Some((c, shape)) = best {
                return Ok(Some(self.hit(image, level, &c, shape)));
            }
            let whole =
                window.u0 == 0 && window.v0 == 0 && window.u1 + 1 >= image.width() && window.v1 + 1 >= image.height();
            if whole || (half[0] >= limit[0] && half[1] >= limit[1]) {
                return Ok(None);
            }
            if first_only {
                return Err(Beyond);
            }
            half = [(2.0 * half[0]).min(limit[0]), (2.0 * half[1]).min(limit[1])];
        }
    }

    /// The dot's centroid, and its threshold for the next image: midway between its local
    /// background and its peak in this image (the light changes through a sequence), kept
    /// while the contrast is too low to learn from.
    fn hit<C: Pixels>(&mut self, image: &GreyBuffer<C>, level: Level, c: &Component, shape: Shape) -> Hit {
        let weighted = self.search.weighted_centroid(image, level, c);
        let (background, peak) = (weighted.background, weighted.peak);
        let threshold = if peak.saturating_sub(background) >= start::MIN_CONTRAST {
            background + (peak - background) / 2
        } else {
            level.threshold
        };
        Hit { centroid: weighted.centroid, shape, identity: (c.bbox, c.area), threshold }
    }
}

/// The rectangle of half-sides `half` around `center`, clipped to the image; None when it
/// falls outside.
fn window_around<C: Pixels>(image: &GreyBuffer<C>, center: [f64; 2], half: [f64; 2]) -> Option<Window> {
    window_in(image.dimensions(), center, half)
}

/// [`window_around`] in an image of `size` (width, height).
fn window_in(size: (u32, u32), center: [f64; 2], half: [f64; 2]) -> Option<Window> {
    let (w, h) = (f64::from(size.0), f64::from(size.1));
    let (u0, u1) = ((center[0] - half[0]).round().max(0.0), (center[0] + half[0]).round().min(w - 1.0));
    let (v0, v1) = ((center[1] - half[1]).round().max(0.0), (center[1] + half[1]).round().min(h - 1.0));
    (u0 <= u1 && v0 <= v1).then_some(Window { u0: u0 as u32, v0: v0 as u32, u1: u1 as u32, v1: v1 as u32 })
}

impl TrackedDot {
    fn started(centroid: [f64; 2], threshold: u8, shape: Shape) -> Self {
        Self { position: centroid, predicted: centroid, velocity: [0.0, 0.0], threshold, shape, lost_for: 0 }
    }

    /// Half-sides of the search window: the dot's half-extent grown by the largest accepted
    /// change of size ([`Shape::admits`]), plus half the search radius of unpredicted motion,
    /// at least the search radius; plus the predicted motion.
    fn window_half(&self, config: &TrackerConfig) -> [f64; 2] {
        let growth = config.max_area_ratio.sqrt();
        let half = |k: usize| {
            let size = 0.5 * self.shape.extent[k] * growth + 0.5 * config.search_radius;
            size.max(config.search_radius) + self.velocity[k].abs()
        };
        [half(0), half(1)]
    }

    /// Half-sides of the dot's box at its prediction, with the centroid's margin.
    fn box_half(&self) -> [f64; 2] {
        [0.5 * self.shape.extent[0] + 3.0, 0.5 * self.shape.extent[1] + 3.0]
    }

    fn update(&mut self, hit: Option<&Hit>) {
        match hit {
            Some(d) => {
                self.velocity = [d.centroid[0] - self.position[0], d.centroid[1] - self.position[1]];
                if self.lost_for > 0 {
                    self.velocity = [0.0, 0.0];
                }
                self.position = d.centroid;
                self.shape = d.shape;
                self.threshold = d.threshold;
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

/// Two clicks on the same dot are an error naming both.
/// Refuses [`Polarity::Auto`] on an image the dot detector would refuse: its rule labels the
/// whole image (some 10 bytes a pixel), where a tracker otherwise reads windows only.
fn check_auto_polarity<C: Pixels>(image: &GreyBuffer<C>, polarity: Polarity) -> Result<()> {
    let pixels = u64::from(image.width()) * u64::from(image.height());
    if polarity != Polarity::Auto || pixels <= MAX_DOT_PIXELS {
        return Ok(());
    }
    Err(Error::InvalidParameter {
        name: "polarity",
        reason: format!(
            "\"auto\" reads the whole image (some 10 bytes a pixel), at most {MAX_DOT_PIXELS} pixels (2^26); this \
             one has {pixels}: give \"dark\" or \"light\""
        ),
    }
    .into())
}

fn check_distinct(dots: &[TrackedDot]) -> Result<()> {
    for (i, a) in dots.iter().enumerate() {
        if let Some(j) = dots[i + 1..].iter().position(|b| distance(a.position, b.position) < 0.5) {
            return Err(VisionError::InvalidImage {
                what: "initial_pixels".into(),
                reason: format!("points {i} and {} found the same dot", i + 1 + j),
            });
        }
    }
    Ok(())
}

/// Two dots that claim the same component are both reported lost.
fn drop_shared_components(hits: &mut [Option<Hit>]) {
    for i in 0..hits.len() {
        let Some(a) = hits[i] else { continue };
        let mut shared = false;
        for other in hits[i + 1..].iter_mut() {
            if other.is_some_and(|b| b.identity == a.identity || distance(a.centroid, b.centroid) < 0.5) {
                *other = None;
                shared = true;
            }
        }
        if shared {
            hits[i] = None;
        }
    }
}

/// A component is not taken when it is nearer to another dot's prediction than to its own
/// dot's (with overlapping windows, dot A must not take B's component: B may be lost in this
/// image), or when its box holds another dot's prediction (that dot may have merged into it).
fn drop_hits_over_other_dots(hits: &mut [Option<Hit>], dots: &[TrackedDot]) {
    for (i, hit) in hits.iter_mut().enumerate() {
        let Some(h) = hit else { continue };
        let own = distance(h.centroid, dots[i].predicted);
        let [u0, v0, u1, v1] = h.identity.0.map(f64::from);
        let over = |p: [f64; 2]| (u0 - 0.5..=u1 + 0.5).contains(&p[0]) && (v0 - 0.5..=v1 + 0.5).contains(&p[1]);
        let taken = dots
            .iter()
            .enumerate()
            .any(|(j, d)| j != i && (distance(h.centroid, d.predicted) < own || over(d.predicted)));
        if taken {
            *hit = None;
        }
    }
}
