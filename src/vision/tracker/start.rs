//! Starting a dot from a click in the first image: a threshold midway between the window's
//! background (its median) and the dot's peak, and the component under the click (or the
//! nearest one). A dot larger than the search window is still found: while the window has no
//! contrast (it lies inside the dot) or the component is cut by the window's edge, the window
//! doubles, and once grown it only accepts the component under the click.

use super::shape::Shape;
use super::window_search::{Component, Level, WindowSearch};
use super::{TrackedDot, TrackerConfig, distance};
use crate::error::{Error, Short, fixed_or_short};
use crate::vision::dots::DIGITISATION_SLACK;
use crate::vision::error::{Result, VisionError};
use crate::vision::image::Window;
use crate::vision::image::{GreyBuffer, Pixels};

/// Grey levels by which a dot must stand out from its background.
pub(super) const MIN_CONTRAST: u8 = 24;

/// Smallest fill ratio of a dot when it starts (as [`detect_dots`]'s default `min_fill`,
/// with the same allowance for small dots): a notched disc, a bar or a ring is not a dot.
///
/// [`detect_dots`]: crate::vision::dots::detect_dots
const MIN_FILL: f64 = 0.95;

/// The most pixels the start search reads for all the clicks of one tracker (the window
/// around a click doubles while no dot is found in it): 2^27, some seconds at most, as
/// [`detect_dots`]'s bound on a whole image.
///
/// [`detect_dots`]: crate::vision::dots::detect_dots
pub const MAX_START_PIXELS: u64 = 1 << 27;

/// The dot around click `i`, or an error naming it; `read` counts the pixels the windows of
/// every click read so far, at most [`MAX_START_PIXELS`].
pub(super) fn initial_dot<C: Pixels>(
    image: &GreyBuffer<C>,
    i: usize,
    click: [f64; 2],
    config: &TrackerConfig,
    dark: bool,
    search: &mut WindowSearch,
    read: &mut u64,
) -> Result<TrackedDot> {
    if !(click[0].is_finite() && click[1].is_finite()) {
        return Err(Error::NonFinitePoint {
            what: "initial_pixels",
            row: i,
            column: usize::from(click[0].is_finite()),
        }
        .into());
    }
    let not_found = |reason: &str| VisionError::InvalidImage {
        what: "initial_pixels".into(),
        reason: format!("point {i} at ({}, {}): {reason}", fixed_or_short(click[0], 1), fixed_or_short(click[1], 1)),
    };
    let (w, h) = (f64::from(image.width()), f64::from(image.height()));
    if click[0] < -0.5 || click[1] < -0.5 || click[0] > w - 0.5 || click[1] > h - 0.5 {
        return Err(not_found("outside the image"));
    }
    let flip = if dark { 255 } else { 0 };
    let mut radius = config.search_radius;
    let mut no_contrast = true;
    loop {
        let window = Window::around(image, click, radius).ok_or_else(|| not_found("outside the image"))?;
        *read += u64::from(window.u1 - window.u0 + 1) * u64::from(window.v1 - window.v0 + 1);
        if *read > MAX_START_PIXELS {
            return Err(not_found(&format!(
                "no dot found within {} px (the start search reads at most {MAX_START_PIXELS} pixels, 2^27, for all \
                 the points)",
                Short(radius / 2.0)
            )));
        }
        let whole =
            window.u0 == 0 && window.v0 == 0 && window.u1 + 1 >= image.width() && window.v1 + 1 >= image.height();
        let (background, peak) = window_levels(image, window, flip);
        if peak.saturating_sub(background) >= MIN_CONTRAST {
            no_contrast = false;
            let level = Level { threshold: background + (peak - background) / 2, flip };
            search.begin(window);
            search.label_all(image, level);
            let grown = radius > config.search_radius;
            match pick(search, click, config.min_area, grown) {
                Some(c) if !c.touches_window || whole => {
                    if c.touches_image {
                        return Err(not_found("the dot is cut by the image's border"));
                    }
                    let fill = c.fill_ratio();
                    if fill < MIN_FILL - DIGITISATION_SLACK / (c.area as f64).sqrt() {
                        return Err(not_found(&format!("not a dot (fill ratio {fill:.3}: not a filled ellipse)")));
                    }
                    let centroid = search.weighted_centroid(image, level, &c).centroid;
                    return Ok(TrackedDot::started(centroid, level.threshold, Shape::of(&c)));
                }
                // Cut by the window: the dot is larger than it.
                Some(_) => {}
                None if !grown => {
                    return Err(not_found(&format!("no dot within {} px", Short(config.search_radius))));
                }
                None => {}
            }
        }
        if whole {
            let why = if no_contrast { "no contrast" } else { "no whole dot under it" };
            return Err(not_found(&format!("no dot around it ({why})")));
        }
        radius *= 2.0;
    }
}

/// The component under the click, or (in the first window only) the nearest to it.
fn pick(search: &WindowSearch, click: [f64; 2], min_area: usize, grown: bool) -> Option<Component> {
    let (u, v) = (click[0].round().max(0.0) as u32, click[1].round().max(0.0) as u32);
    let under = |c: &&Component| c.bbox[0] <= u && u <= c.bbox[2] && c.bbox[1] <= v && v <= c.bbox[3];
    let large = search.components.iter().filter(|c| c.area >= min_area);
    let nearest =
        |a: &&Component, b: &&Component| distance(a.centroid(), click).total_cmp(&distance(b.centroid(), click));
    let covering = large.clone().filter(under).min_by(nearest);
    if grown { covering.copied() } else { covering.or_else(|| large.min_by(nearest)).copied() }
}

/// The median and the largest grey level of a window (of its negative for `flip` 255).
fn window_levels<C: Pixels>(image: &GreyBuffer<C>, w: Window, flip: u8) -> (u8, u8) {
    let mut histogram = [0usize; 256];
    for v in w.v0..=w.v1 {
        for u in w.u0..=w.u1 {
            histogram[usize::from(flip ^ image.get_pixel(u, v)[0])] += 1;
        }
    }
    let total: usize = histogram.iter().sum();
    let mut seen = 0;
    let median = histogram.iter().position(|&n| {
        seen += n;
        seen > total / 2
    });
    let peak = histogram.iter().rposition(|&n| n > 0);
    (median.unwrap_or(0) as u8, peak.unwrap_or(0) as u8)
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use crate::vision::image::GreyImage;
    use crate::vision::tracker::{DotTracker, TrackerConfig};

    /// A disc of radius 15 at (40, 40) on 30, less a notch `notch` px wide and 10 px high on
    /// its right side (0: the whole disc).
    fn notched(notch: u32) -> GreyImage {
        GreyImage::from_fn(80, 80, |u, v| {
            let disc = (f64::from(u) - 40.0).hypot(f64::from(v) - 40.0) < 15.0;
            let cut = u + notch > 55 && (35..45).contains(&v);
            image::Luma([if disc && !cut { 220 } else { 30 }])
        })
    }

    #[test]
    fn a_notched_disc_is_not_a_dot() {
        let whole = DotTracker::new(&notched(0), &[[41.0, 39.0]], TrackerConfig::default()).unwrap();
        let p = whole.positions()[0];
        assert!((p[0] - 40.0).hypot(p[1] - 40.0) < 0.05, "{p:?}");
        for notch in [12, 16] {
            let e = DotTracker::new(&notched(notch), &[[41.0, 39.0]], TrackerConfig::default()).unwrap_err();
            assert!(e.to_string().contains("not a dot"), "{notch}: {e}");
        }
    }

    /// A blank 8200 x 8192 image (the attack: a 40000 x 40000 one ran past 30 s): the windows
    /// around each click double up to the whole image; after the first click or two the
    /// search has read its bound and says so, and a dot is still found within it.
    #[test]
    fn the_start_search_reads_a_bounded_number_of_pixels() {
        use crate::vision::polarity::Polarity;
        let mut blank = GreyImage::new(8200, 8192);
        let t = std::time::Instant::now();
        let clicks: Vec<[f64; 2]> = (0..20).map(|k| [1000.0 + 300.0 * f64::from(k), 4000.0]).collect();
        let e = DotTracker::new(&blank, &clicks, TrackerConfig::default()).unwrap_err().to_string();
        assert!(e.contains("at most 134217728 pixels"), "{e}");
        assert!(t.elapsed().as_secs_f64() < 10.0, "{:?}", t.elapsed());
        // One click in the middle of a blank image: read whole (within the bound), no dot.
        let e = DotTracker::new(&blank, &[[4100.0, 4096.0]], TrackerConfig::default()).unwrap_err().to_string();
        assert!(e.contains("no contrast"), "{e}");
        // A dot far from its click is found by the doubling windows, within the bound.
        for v in 4990..5010 {
            for u in 4990..5010 {
                blank.put_pixel(u, v, image::Luma([255]));
            }
        }
        let tracker = DotTracker::new(&blank, &[[4999.5, 4999.5]], TrackerConfig::default()).unwrap();
        assert!((tracker.positions()[0][0] - 4999.5).abs() < 1e-9);
        // Polarity "auto" labels the whole image: refused above the dot detector's bound.
        let auto = TrackerConfig { polarity: Polarity::Auto, ..TrackerConfig::default() };
        let e = DotTracker::new(&blank, &[[4999.5, 4999.5]], auto).unwrap_err().to_string();
        assert!(e.contains("polarity") && e.contains("at most 67108864 pixels"), "{e}");
        let small = GreyImage::from_fn(64, 64, |u, v| {
            image::Luma([if (28..36).contains(&u) && (28..36).contains(&v) { 255 } else { 0 }])
        });
        assert!(DotTracker::new(&small, &[[31.5, 31.5]], auto).is_ok());
    }
}
