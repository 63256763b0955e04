//! What a tracked dot looks like, and whether a component can be the same dot one image
//! later: its area and its two principal spreads (the square roots of the eigenvalues of the
//! pixels' covariance, i.e. of the normalised central second moments) may each change by a
//! bounded factor between two images. A dot that merges with a neighbouring region, doubles
//! its area, or stretches into a bar fails; the motion and perspective of a real dot from one
//! image to the next do not. Pixel quantisation gets an allowance: a dot's boundary pixels
//! come and go with noise, so small dots may change more than large ones.

use super::window_search::Component;

/// Area and principal spreads of a dot (binary, pixels above its threshold).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Shape {
    /// Pixels above the threshold.
    pub(super) area: f64,
    /// Standard deviations of the pixels along the major and minor principal axes, pixels.
    pub(super) spreads: [f64; 2],
    /// Width and height of the bounding box, pixels.
    pub(super) extent: [f64; 2],
}

impl Shape {
    pub(super) fn of(c: &Component) -> Self {
        let [a, b, m] = c.covariance();
        // Eigenvalues of [[a, m], [m, b]].
        let (mean, half_gap) = (0.5 * (a + b), (0.25 * (a - b) * (a - b) + m * m).sqrt());
        let spreads = [(mean + half_gap).max(0.0).sqrt(), (mean - half_gap).max(0.0).sqrt()];
        let extent = [f64::from(c.bbox[2] - c.bbox[0] + 1), f64::from(c.bbox[3] - c.bbox[1] + 1)];
        Self { area: c.area as f64, spreads, extent }
    }

    /// Whether `next` can be this dot one image later: its area within a factor
    /// `max_area_ratio` of this one and each principal spread within its square root (the
    /// linear factor of that area change), beyond the quantisation allowances.
    pub(super) fn admits(&self, next: &Shape, max_area_ratio: f64) -> bool {
        // Boundary pixels: about the perimeter of a disc of that area, half of which may
        // flip with noise and subpixel motion.
        let area_slack = (std::f64::consts::PI * self.area).sqrt() + 1.0;
        let (small, large) = (self.area.min(next.area), self.area.max(next.area));
        let area_ok = large <= small * max_area_ratio + area_slack;
        let linear = max_area_ratio.sqrt();
        let spreads_ok = self.spreads.iter().zip(&next.spreads).all(|(&s, &n)| {
            let (small, large) = (s.min(n), s.max(n));
            large <= small * linear + SPREAD_SLACK
        });
        area_ok && spreads_ok
    }
}

/// Pixels a principal spread may change by beyond the area's linear factor (the spread of
/// a one-pixel-wide line of pixels is 0.29 px: one row of boundary pixels).
const SPREAD_SLACK: f64 = 0.5;

#[cfg(test)]
mod tests {
    use super::*;

    fn shape(area: f64, spreads: [f64; 2]) -> Shape {
        Shape { area, spreads, extent: [0.0, 0.0] }
    }

    #[test]
    fn area_and_spread_changes_are_bounded() {
        // A disc of radius 8: area 201, spreads r / 2 = 4.
        let disc = shape(201.0, [4.0, 4.0]);
        assert!(disc.admits(&shape(215.0, [4.1, 4.0]), 1.5));
        assert!(!disc.admits(&shape(402.0, [5.7, 5.7]), 1.5), "twice the area");
        assert!(!disc.admits(&shape(260.0, [8.0, 4.0]), 1.5), "stretched into a bar");
        assert!(!shape(402.0, [5.7, 5.7]).admits(&disc, 1.5), "half the area");
        // Small dots get the quantisation allowance: area 9 to 16 is noise at that size.
        assert!(shape(9.0, [0.8, 0.8]).admits(&shape(16.0, [1.1, 1.1]), 1.5));
    }
}
