//! The tracker's component search inside one window: 8-connected components of the pixels
//! above a threshold, grown by scanline flood fill (each row run of a component is visited
//! once), with their binary moments (area, bounding box, first and second moments, summed in
//! closed form per run), and the grey-weighted centroid of one of them. Buffers are kept
//! from call to call: a search allocates nothing once they have reached the largest window.
//! Pixel `(u, v)` covers `[u - 0.5, u + 0.5] x [v - 0.5, v + 0.5]` (OpenCV's convention).

use crate::vision::image::Window;
use crate::vision::image::{GreyBuffer, Pixels};

/// Pixels added around a component's bounding box for its weighted centroid (as
/// [`detect_dots`](crate::vision::dots::detect_dots)).
const MARGIN: u32 = 2;

/// One 8-connected component of a window.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Component {
    /// The stamp its pixels carry in the search's buffer.
    stamp: u32,
    /// Pixels above the threshold.
    pub(super) area: usize,
    /// `[u_min, v_min, u_max, v_max]`, image coordinates, inclusive.
    pub(super) bbox: [u32; 4],
    /// Sums of `u`, `v`, `u^2`, `v^2`, `u v` over its pixels (exact integers in f64).
    moments: [f64; 5],
    /// It reaches the window's first or last row or column: it may be cut.
    pub(super) touches_window: bool,
    /// It reaches the image's border: it is cut.
    pub(super) touches_image: bool,
}

impl Component {
    /// The binary centroid (mean pixel centre).
    pub(super) fn centroid(&self) -> [f64; 2] {
        let n = self.area as f64;
        [self.moments[0] / n, self.moments[1] / n]
    }

    /// The central second moments `[mu20, mu02, mu11]` per pixel (the pixels' covariance,
    /// each pixel counted at its centre).
    pub(super) fn covariance(&self) -> [f64; 3] {
        let n = self.area as f64;
        let [cu, cv] = self.centroid();
        [self.moments[2] / n - cu * cu, self.moments[3] / n - cv * cv, self.moments[4] / n - cu * cv]
    }

    /// The area over that of the ellipse of its second moments, each pixel a unit square
    /// (as [`Component::fill_ratio`](crate::vision::runs::Component::fill_ratio)).
    pub(super) fn fill_ratio(&self) -> f64 {
        let [uu, vv, uv] = self.covariance();
        let det = (uu + 1.0 / 12.0) * (vv + 1.0 / 12.0) - uv * uv;
        self.area as f64 / (4.0 * std::f64::consts::PI * det.max(0.0).sqrt())
    }
}

/// A component's grey-weighted centroid, with the grey levels it was weighted against (of
/// the negative image for dark dots).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Weighted {
    pub(super) centroid: [f64; 2],
    /// The median of the border ring of its grown box.
    pub(super) background: u8,
    /// Its brightest pixel.
    pub(super) peak: u8,
}

/// Reusable buffers and the state of the current window.
#[derive(Debug, Clone, Default)]
pub(super) struct WindowSearch {
    /// Per window pixel, the stamp of the fill that took it (stamps of earlier windows are
    /// all <= `base`).
    stamps: Vec<u32>,
    /// The last stamp given.
    stamp: u32,
    /// Stamps above this one belong to the current window.
    base: u32,
    window: Option<Window>,
    /// Runs waiting for their neighbour rows: `(v, u_first, u_last)`.
    stack: Vec<(u32, u32, u32)>,
    /// The components found by [`WindowSearch::label_all`].
    pub(super) components: Vec<Component>,
    /// 256 bins for the ring median.
    histogram: Vec<usize>,
}

/// What is above the threshold: `flip ^ g > threshold` (`flip` 255 for dark dots).
#[derive(Debug, Clone, Copy)]
pub(super) struct Level {
    pub(super) threshold: u8,
    pub(super) flip: u8,
}

impl Level {
    #[inline]
    fn above(self, g: u8) -> bool {
        (self.flip ^ g) > self.threshold
    }
}

/// Reads one byte per cache line of a rectangle of the image, so that the memory loads of
/// all the dots' rows are issued together (independent loads overlap) instead of one row at
/// a time as the fill reaches them: a new camera image is not in the cache.
pub(super) fn warm_up<C: Pixels>(image: &GreyBuffer<C>, w: Window) {
    const LINE: usize = 64;
    let stride = image.width() as usize;
    let raw: &[u8] = image.as_raw();
    let mut sum = 0u8;
    for v in w.v0..=w.v1 {
        let row = &raw[v as usize * stride + w.u0 as usize..][..(w.u1 - w.u0 + 1) as usize];
        for g in row.iter().step_by(LINE).chain(row.last()) {
            sum = sum.wrapping_add(*g);
        }
    }
    std::hint::black_box(sum);
}

impl WindowSearch {
    /// Starts a new window: earlier fills no longer count.
    pub(super) fn begin(&mut self, window: Window) {
        let len = ((window.u1 - window.u0 + 1) * (window.v1 - window.v0 + 1)) as usize;
        if self.stamps.len() < len {
            self.stamps.resize(len, 0);
        }
        if self.stamp > u32::MAX - (len as u32).saturating_add(2) {
            self.stamps.iter_mut().for_each(|s| *s = 0);
            self.stamp = 0;
        }
        self.base = self.stamp;
        self.window = Some(window);
        self.components.clear();
    }

    fn index(&self, w: Window, u: u32, v: u32) -> usize {
        ((v - w.v0) * (w.u1 - w.u0 + 1) + (u - w.u0)) as usize
    }

    /// The component holding pixel `(u, v)` (already found in this window or grown now), or
    /// None when that pixel is not above the threshold or outside the window.
    pub(super) fn component_at<C: Pixels>(
        &mut self,
        image: &GreyBuffer<C>,
        level: Level,
        u: u32,
        v: u32,
    ) -> Option<Component> {
        let w = self.window?;
        if u < w.u0 || u > w.u1 || v < w.v0 || v > w.v1 || !level.above(image.get_pixel(u, v)[0]) {
            return None;
        }
        let s = self.stamps[self.index(w, u, v)];
        if s > self.base {
            return self.components.iter().find(|c| c.stamp == s).copied();
        }
        let c = self.fill(image, level, w, u, v);
        self.components.push(c);
        Some(c)
    }

    /// Every component of the window (those found already are kept).
    pub(super) fn label_all<C: Pixels>(&mut self, image: &GreyBuffer<C>, level: Level) {
        let Some(w) = self.window else { return };
        let stride = image.width() as usize;
        let raw: &[u8] = image.as_raw();
        for v in w.v0..=w.v1 {
            let row = &raw[v as usize * stride..][..stride];
            let first = self.index(w, w.u0, v);
            for u in w.u0..=w.u1 {
                if level.above(row[u as usize]) && self.stamps[first + (u - w.u0) as usize] <= self.base {
                    let c = self.fill(image, level, w, u, v);
                    self.components.push(c);
                }
            }
        }
    }

    /// Scanline flood fill of the component holding `(u, v)`, inside the window.
    fn fill<C: Pixels>(&mut self, image: &GreyBuffer<C>, level: Level, w: Window, u: u32, v: u32) -> Component {
        self.stamp += 1;
        let mut c = Component {
            stamp: self.stamp,
            area: 0,
            bbox: [u, v, u, v],
            moments: [0.0; 5],
            touches_window: false,
            touches_image: false,
        };
        let run = self.take_run(image, level, w, u, v);
        self.add_run(&mut c, w, image, v, run);
        let stride = image.width() as usize;
        let raw: &[u8] = image.as_raw();
        let span = (w.u1 - w.u0 + 1) as usize;
        while let Some((rv, a, b)) = self.stack.pop() {
            let (lo, hi) = (a.saturating_sub(1).max(w.u0), (b + 1).min(w.u1));
            for nv in [rv.wrapping_sub(1), rv + 1] {
                if nv < w.v0 || nv > w.v1 {
                    continue;
                }
                let row = &raw[nv as usize * stride + w.u0 as usize..][..span];
                let first = (nv - w.v0) as usize * span;
                let mut x = lo;
                while x <= hi {
                    let k = (x - w.u0) as usize;
                    if level.above(row[k]) && self.stamps[first + k] <= self.base {
                        let run = self.take_run(image, level, w, x, nv);
                        self.add_run(&mut c, w, image, nv, run);
                        // The pixel after a run is below the threshold (or outside).
                        x = run.1 + 2;
                    } else {
                        x += 1;
                    }
                }
            }
        }
        c
    }

    /// The row run through `(u, v)` (pixels above the threshold, inside the window), stamped.
    fn take_run<C: Pixels>(&mut self, image: &GreyBuffer<C>, level: Level, w: Window, u: u32, v: u32) -> (u32, u32) {
        let stride = image.width() as usize;
        let row = &image.as_raw()[v as usize * stride..][..stride];
        let (mut a, mut b) = (u, u);
        while a > w.u0 && level.above(row[a as usize - 1]) {
            a -= 1;
        }
        while b < w.u1 && level.above(row[b as usize + 1]) {
            b += 1;
        }
        let first = self.index(w, a, v);
        self.stamps[first..=first + (b - a) as usize].iter_mut().for_each(|s| *s = self.stamp);
        (a, b)
    }

    /// Adds a run's pixels to the component's moments and queues its neighbour rows.
    fn add_run<C: Pixels>(&mut self, c: &mut Component, w: Window, image: &GreyBuffer<C>, v: u32, (a, b): (u32, u32)) {
        let n = u64::from(b - a + 1);
        let sum_u = (u64::from(a) + u64::from(b)) * n / 2;
        let squares = |k: u64| k * (k + 1) * (2 * k + 1) / 6;
        let sum_uu = squares(u64::from(b)) - if a == 0 { 0 } else { squares(u64::from(a) - 1) };
        let fv = f64::from(v);
        c.area += n as usize;
        c.moments[0] += sum_u as f64;
        c.moments[1] += n as f64 * fv;
        c.moments[2] += sum_uu as f64;
        c.moments[3] += n as f64 * fv * fv;
        c.moments[4] += sum_u as f64 * fv;
        c.bbox = [c.bbox[0].min(a), c.bbox[1].min(v), c.bbox[2].max(b), c.bbox[3].max(v)];
        c.touches_window |= a == w.u0 || b == w.u1 || v == w.v0 || v == w.v1;
        c.touches_image |= a == 0 || v == 0 || b + 1 == image.width() || v + 1 == image.height();
        self.stack.push((v, a, b));
    }

    /// The grey-weighted centroid of a component of this window: over its bounding box grown
    /// by [`MARGIN`] (clipped to the window), each pixel weighted by its grey level above the
    /// median of the box's border ring (the local background), pixels of other components
    /// left out. The rule of [`detect_dots`](crate::vision::dots::detect_dots).
    pub(super) fn weighted_centroid<C: Pixels>(
        &mut self,
        image: &GreyBuffer<C>,
        level: Level,
        c: &Component,
    ) -> Weighted {
        let Some(w) = self.window else { return Weighted { centroid: c.centroid(), background: 0, peak: 0 } };
        let (u0, v0) = (c.bbox[0].saturating_sub(MARGIN).max(w.u0), c.bbox[1].saturating_sub(MARGIN).max(w.v0));
        let (u1, v1) = ((c.bbox[2] + MARGIN).min(w.u1), (c.bbox[3] + MARGIN).min(w.v1));
        let background = self.ring_median(image, level.flip, [u0, v0, u1, v1]);
        let background = i64::from(background);
        let stride = image.width() as usize;
        let raw: &[u8] = image.as_raw();
        // Integer weights: the sums are exact (and the same as in f64 for any image that fits
        // in memory).
        let (mut sum, mut su, mut sv) = (0i64, 0i64, 0i64);
        let mut peak = 0u8;
        let len = (u1 - u0 + 1) as usize;
        for v in v0..=v1 {
            let row = &raw[v as usize * stride + u0 as usize..][..len];
            let first = self.index(w, u0, v);
            let stamps = &self.stamps[first..first + len];
            let (mut row_sum, mut row_su) = (0i64, 0i64);
            for (k, (&g, &s)) in row.iter().zip(stamps).enumerate() {
                let other = level.above(g) && s != c.stamp;
                if s == c.stamp {
                    peak = peak.max(level.flip ^ g);
                }
                let weight = if other { 0 } else { (i64::from(level.flip ^ g) - background).max(0) };
                row_sum += weight;
                row_su += weight * k as i64;
            }
            sum += row_sum;
            su += row_su + row_sum * i64::from(u0);
            sv += row_sum * i64::from(v);
        }
        let centroid = if sum > 0 { [su as f64 / sum as f64, sv as f64 / sum as f64] } else { c.centroid() };
        Weighted { centroid, background: u8::try_from(background).unwrap_or(u8::MAX), peak }
    }

    /// The median grey level (of the negative for `flip` 255) of the border pixels of a box,
    /// the corners counted twice (as `detect_dots` does).
    fn ring_median<C: Pixels>(&mut self, image: &GreyBuffer<C>, flip: u8, [u0, v0, u1, v1]: [u32; 4]) -> u8 {
        self.histogram.clear();
        self.histogram.resize(256, 0);
        let mut count = |g: u8| self.histogram[usize::from(flip ^ g)] += 1;
        for u in u0..=u1 {
            count(image.get_pixel(u, v0)[0]);
            count(image.get_pixel(u, v1)[0]);
        }
        for v in v0..=v1 {
            count(image.get_pixel(u0, v)[0]);
            count(image.get_pixel(u1, v)[0]);
        }
        let half = (2 * ((u1 - u0 + 1) + (v1 - v0 + 1))) as usize / 2;
        let mut seen = 0;
        for (g, &n) in self.histogram.iter().enumerate() {
            seen += n;
            if seen > half {
                return g as u8;
            }
        }
        255
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use imageproc::region_labelling::{Connectivity, connected_components};

    use super::*;
    use crate::vision::image::GreyImage;

    /// A pseudo-random image of blobs and specks.
    fn noisy(width: u32, height: u32) -> GreyImage {
        let mut state = 987654321u64;
        GreyImage::from_fn(width, height, |u, v| {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let blob = ((u as f64 / 7.0).sin() * (v as f64 / 5.0).cos() * 120.0 + 120.0) as u8;
            ::image::Luma([blob.saturating_add((state >> 60) as u8 * 8)])
        })
    }

    #[test]
    fn components_and_moments_match_imageproc_labelling() {
        let image = noisy(90, 70);
        let window = Window { u0: 10, v0: 5, u1: 80, v1: 60 };
        for (threshold, flip) in [(150u8, 0u8), (100, 255)] {
            let level = Level { threshold, flip };
            let mut search = WindowSearch::default();
            search.begin(window);
            search.label_all(&image, level);
            // Independent: imageproc's 8-connected labels of the window's binary image.
            let binary = GreyImage::from_fn(71, 56, |u, v| {
                ::image::Luma([u8::from(level.above(image.get_pixel(u + 10, v + 5)[0]))])
            });
            let labels = connected_components(&binary, Connectivity::Eight, ::image::Luma([0u8]));
            let count = labels.pixels().map(|p| p[0]).max().unwrap() as usize;
            assert_eq!(search.components.len(), count);
            for c in &search.components {
                // Its pixels by the search's stamps, and imageproc's label of the first of them.
                let pixels: Vec<[f64; 2]> = (window.v0..=window.v1)
                    .flat_map(|v| (window.u0..=window.u1).map(move |u| (u, v)))
                    .filter(|&(u, v)| search.stamps[search.index(window, u, v)] == c.stamp)
                    .map(|(u, v)| [f64::from(u), f64::from(v)])
                    .collect();
                let label_of = |p: &[f64; 2]| labels.get_pixel(p[0] as u32 - 10, p[1] as u32 - 5)[0];
                let label = label_of(&pixels[0]);
                assert!(label != 0 && pixels.iter().all(|p| label_of(p) == label));
                assert_eq!(labels.pixels().filter(|p| p[0] == label).count(), c.area);
                assert_eq!(pixels.len(), c.area);
                let n = c.area as f64;
                let mean = [pixels.iter().map(|p| p[0]).sum::<f64>() / n, pixels.iter().map(|p| p[1]).sum::<f64>() / n];
                let [cu, cv] = c.centroid();
                assert!((cu - mean[0]).abs() < 1e-9 && (cv - mean[1]).abs() < 1e-9);
                let var_u = pixels.iter().map(|p| (p[0] - mean[0]).powi(2)).sum::<f64>() / n;
                let cov = pixels.iter().map(|p| (p[0] - mean[0]) * (p[1] - mean[1])).sum::<f64>() / n;
                let [mu20, _, mu11] = c.covariance();
                assert!((mu20 - var_u).abs() < 1e-6 && (mu11 - cov).abs() < 1e-6);
            }
        }
    }
}
