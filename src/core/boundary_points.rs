//! The points that can be a vertex of a widest triangle once rounding is accounted for:
//! those within a rounding-sized distance of the convex hull's boundary, found in
//! `O(n log h)` (used by [`super::widest_triangle`]).
//!
//! Why only those: let `T = |qr| h_p` be twice the area of a triangle `p q r` and `A` twice
//! the largest area. Moving `p` away from the line `qr` until it reaches the boundary moves
//! it by at least `d(p)`, its distance to the boundary, and the area stays at most `A`, so
//! `|qr| d(p) <= A - T`. A triangle whose computed area ties or beats the largest one has
//! `T >= A - 2E` (`E`: the rounding of one computed area), and `|qr| >= T / D` (`D`: the
//! diameter), so `d(p) <= 2 E D / (A - 2E)`.

use super::convex_hull::{Edge, deep_inside, extreme_octagon};

const EPS: f64 = f64::EPSILON;

/// The hull's edges in angular order around an interior point `centre`, and each start
/// vertex's angle (increasing, within `[angles[0], angles[0] + 2 pi)`).
struct Fan {
    centre: [f64; 2],
    edges: Vec<Edge>,
    angles: Vec<f64>,
}

impl Fan {
    fn new(pixels: &[[f64; 2]], hull: &[usize], centre: [f64; 2]) -> Option<Self> {
        let angle = |p: [f64; 2]| (p[1] - centre[1]).atan2(p[0] - centre[0]);
        let h = hull.len();
        let first = (0..h).min_by(|&a, &b| angle(pixels[hull[a]]).total_cmp(&angle(pixels[hull[b]])))?;
        let vertex = |m: usize| pixels[hull[(first + m) % h]];
        let edges: Vec<Edge> = (0..h).map(|m| Edge::new(vertex(m), vertex(m + 1))).collect();
        let angles: Vec<f64> = (0..h).map(|m| angle(vertex(m))).collect();
        angles.windows(2).all(|w| w[0] < w[1]).then_some(Self { centre, edges, angles })
    }

    fn angle_of(&self, p: [f64; 2]) -> f64 {
        (p[1] - self.centre[1]).atan2(p[0] - self.centre[0])
    }

    /// The edge whose angular sector (seen from the centre) holds the direction `phi`.
    fn sector(&self, phi: f64) -> usize {
        let tau = std::f64::consts::TAU;
        let mut phi = phi;
        while phi < self.angles[0] {
            phi += tau;
        }
        while phi >= self.angles[0] + tau {
            phi -= tau;
        }
        self.angles.partition_point(|&a| a <= phi).saturating_sub(1)
    }

    /// Whether some edge whose sector meets `[phi - alpha, phi + alpha]` passes within
    /// `tol` of `p`.
    fn near_an_edge(&self, p: [f64; 2], alpha: f64, tol: f64) -> bool {
        let phi = self.angle_of(p);
        let (mut m, last) = (self.sector(phi - alpha), self.sector(phi + alpha));
        for _ in 0..self.edges.len() {
            if self.edges[m].inner_distance(p) <= tol {
                return true;
            }
            if m == last {
                break;
            }
            m = (m + 1) % self.edges.len();
        }
        false
    }
}

/// The indices (increasing) of the points that can be a vertex of a triangle whose computed
/// twice-area ties or beats `twice_area`, the largest over the hull's vertices (`triangle`
/// is one that has it). `None` when there are more than `max` of them or the point set is
/// too flat for the rounding bound to exclude anything.
pub(crate) fn near_boundary(
    pixels: &[[f64; 2]],
    hull: &[usize],
    triangle: [usize; 3],
    twice_area: f64,
    max: usize,
) -> Option<Vec<usize>> {
    let span = |axis: usize| {
        let (lo, hi) = hull.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &i| {
            (lo.min(pixels[i][axis]), hi.max(pixels[i][axis]))
        });
        hi - lo
    };
    let diameter_sq = span(0).powi(2) + span(1).powi(2);
    let diameter = diameter_sq.sqrt();
    // Rounding of one computed twice-area (generous: the expression's bound is ~8 EPS D^2).
    let area_rounding = 64.0 * EPS * diameter_sq;
    if !(diameter_sq.is_finite() && twice_area > 8.0 * area_rounding) {
        return None;
    }
    let tol = 4.0 * 2.0 * area_rounding * diameter / (twice_area - 2.0 * area_rounding) + 64.0 * EPS * diameter;
    let [a, b, c] = triangle.map(|i| pixels[i]);
    let centre = [(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0];
    let fan = Fan::new(pixels, hull, centre)?;
    let depth = fan.edges.iter().map(|e| e.inner_distance(centre)).fold(f64::INFINITY, f64::min);
    if !(depth > 4.0 * tol) {
        return None;
    }
    // A point within tol of the boundary sees its nearest boundary point within this angle.
    let alpha = 2.0 * (tol / depth).asin() + 1e-9;
    // The octagon of extreme points lies inside the hull: points deeper than tol in it are
    // deeper than tol in the hull (a cheap first test).
    let octagon = extreme_octagon(pixels);
    let mut near = Vec::new();
    for (i, &p) in pixels.iter().enumerate() {
        if !deep_inside(&octagon, p, tol) && fan.near_an_edge(p, alpha, tol) {
            if near.len() == max {
                return None;
            }
            near.push(i);
        }
    }
    Some(near)
}
