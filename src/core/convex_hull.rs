//! The convex hull of a point set (for [`super::widest_triangle`]): Andrew's monotone chain,
//! `O(n log n)`, after the Akl-Toussaint heuristic has set aside the points well inside the
//! octagon of the extreme points in eight directions (most points of a typical set).

const EPS: f64 = f64::EPSILON;

/// One edge of a counter-clockwise convex polygon: its start, direction and length.
pub(crate) struct Edge {
    pub start: [f64; 2],
    pub dir: [f64; 2],
    pub len: f64,
}

impl Edge {
    pub fn new(a: [f64; 2], b: [f64; 2]) -> Self {
        let dir = [b[0] - a[0], b[1] - a[1]];
        Self { start: a, dir, len: dir[0].hypot(dir[1]) }
    }

    /// Distance from the edge's line, positive on the polygon's side. Rounding is at most a
    /// few `EPS |p - start|`, whatever the edge's length.
    #[inline]
    pub fn inner_distance(&self, p: [f64; 2]) -> f64 {
        (self.dir[0] * (p[1] - self.start[1]) - self.dir[1] * (p[0] - self.start[0])) / self.len
    }
}

/// `(a - o) x (b - o)`: positive when `o, a, b` turn counter-clockwise.
#[inline]
pub(crate) fn cross(o: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
}

/// The octagon of the extreme points in the directions of x, y, x + y and x - y, as edges
/// (counter-clockwise, zero-length ones dropped): a convex polygon inside the hull.
pub(crate) fn extreme_octagon(pixels: &[[f64; 2]]) -> Vec<Edge> {
    let keys: [fn([f64; 2]) -> f64; 8] = [
        |p| p[1],         // lowest
        |p| p[1] - p[0],  // lower right
        |p| -p[0],        // rightmost
        |p| -p[0] - p[1], // upper right
        |p| -p[1],        // highest
        |p| p[0] - p[1],  // upper left
        |p| p[0],         // leftmost
        |p| p[0] + p[1],  // lower left
    ];
    let corners: Vec<[f64; 2]> = keys
        .iter()
        .map(|key| pixels.iter().copied().min_by(|&a, &b| key(a).total_cmp(&key(b))).unwrap_or([0.0, 0.0]))
        .collect();
    let mut edges: Vec<Edge> =
        (0..8).map(|m| Edge::new(corners[m], corners[(m + 1) % 8])).filter(|e| e.len > 0.0).collect();
    // Degenerate octagons (fewer than 3 distinct corners, or not convex) set nothing aside.
    let convex = edges.len() >= 3
        && (0..edges.len()).all(|m| {
            let (e, f) = (&edges[m], &edges[(m + 1) % edges.len()]);
            e.dir[0] * f.dir[1] - e.dir[1] * f.dir[0] >= 0.0
        });
    if !convex {
        edges.clear();
    }
    edges
}

/// Whether `p` is farther than `margin` inside the convex polygon `edges` (never, when
/// `edges` is empty).
#[inline]
pub(crate) fn deep_inside(edges: &[Edge], p: [f64; 2], margin: f64) -> bool {
    !edges.is_empty() && edges.iter().all(|e| e.inner_distance(p) > margin)
}

/// The strict convex hull's vertices (no collinear ones), counter-clockwise, as indices;
/// among equal points the lowest index stands for them. Fewer than 3 when all points are
/// collinear.
pub(crate) fn convex_hull(pixels: &[[f64; 2]]) -> Vec<usize> {
    let octagon = extreme_octagon(pixels);
    let span = octagon.iter().map(|e| e.len).sum::<f64>();
    // Points this far inside the octagon cannot be hull vertices, rounding included.
    let margin = 64.0 * EPS * span;
    let mut order: Vec<([f64; 2], usize)> =
        pixels.iter().enumerate().filter(|&(_, &p)| !deep_inside(&octagon, p, margin)).map(|(i, &p)| (p, i)).collect();
    order.sort_unstable_by(|(p, a), (q, b)| p[0].total_cmp(&q[0]).then(p[1].total_cmp(&q[1])).then(a.cmp(b)));
    order.dedup_by(|later, first| later.0 == first.0);
    if order.len() < 3 {
        return order.into_iter().map(|(_, i)| i).collect();
    }
    let mut hull: Vec<([f64; 2], usize)> = Vec::with_capacity(2 * order.len());
    let chain = |hull: &mut Vec<([f64; 2], usize)>, point: ([f64; 2], usize), floor: usize| {
        while hull.len() >= floor + 2 && cross(hull[hull.len() - 2].0, hull[hull.len() - 1].0, point.0) <= 0.0 {
            hull.pop();
        }
        hull.push(point);
    };
    for &point in &order {
        chain(&mut hull, point, 0);
    }
    let lower = hull.len() - 1;
    for &point in order.iter().rev().skip(1) {
        chain(&mut hull, point, lower);
    }
    hull.pop();
    hull.into_iter().map(|(_, i)| i).collect()
}
