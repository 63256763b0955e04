//! The widest triangle of a point set, the basis choice of sec. 5.1, in `O(n log n)` instead
//! of the `O(n^3)` exhaustive search, with the exhaustive search's exact selection.
//!
//! The largest triangle has its vertices on the convex hull, so the search is: the hull
//! (Andrew's monotone chain, `O(n log n)`), the largest triangle of the hull's vertices, then
//! the exhaustive search again, but only over the few points that can be a vertex of a
//! triangle as large as that one once rounding is accounted for (the points within a
//! rounding-sized distance of the hull's boundary: hull vertices, points on hull edges,
//! duplicates). The exhaustive search visits those points in the same order and computes
//! each area with the same expression, so it picks the same triangle as a search over all
//! points: the first `(i, j, k)` in lexicographic order among those of largest area.
//!
//! When more than [`EXACT_MAX_BOUNDARY_POINTS`] points lie on the boundary (a regular polygon
//! of many points, many duplicates of a hull vertex), the result is a largest triangle of
//! the hull's vertices (rotating pointers, `O(h^2)` for `h` hull vertices); ties among
//! those are broken by the smallest sorted index triple, which can differ from the
//! exhaustive search's choice. Hulls of more than [`MAX_HULL_POINTS`] vertices are refused.

use super::convex_hull::{convex_hull, cross};
use crate::error::{Error, Result};

/// Up to this many points the search is exhaustive (`O(n^3)`); above, the hull's path, which
/// picks the same triangle (up to 500 points near the boundary, so always below 500 points).
/// 32 is where the two cost the same (`benches/vsinv.rs`, `choose_basis/uniform/n`, one
/// machine: exhaustive 8.5 us at 32 points, the hull's path 7.0 us at 33); with the
/// exhaustive search up to 200 points, 64, 128 and 200 points took 70 us, 0.53 ms and 2.1 ms,
/// the hull's path takes 13, 28 and 40 us.
pub const EXHAUSTIVE_MAX_POINTS: usize = 32;

/// Above [`EXHAUSTIVE_MAX_POINTS`] points, the exhaustive search runs on the points near the
/// hull's boundary when there are at most this many (`O(m^3)`: about 20 ms for 500).
pub const EXACT_MAX_BOUNDARY_POINTS: usize = 500;

/// The largest convex hull (in vertices) the `O(h^2)` search takes: it answers within a
/// second (docs/reference/files-and-limits.md); larger hulls are refused with `InvalidParameter("pixels")`.
pub const MAX_HULL_POINTS: usize = 10_000;

/// Twice the triangle's area, with the expression (and vertex order: `a` has the lowest
/// index) of the exhaustive search, so that equal inputs round equally.
#[inline]
fn twice_area(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs()
}

/// The exhaustive search over `indices` (increasing): twice the largest area and the first
/// triple in lexicographic order that has it (`indices[..3]` when every area is 0).
pub(crate) fn exhaustive(pixels: &[[f64; 2]], indices: &[usize]) -> (f64, [usize; 3]) {
    let mut best = (0.0_f64, [indices[0], indices[1], indices[2]]);
    for (a_pos, &i) in indices.iter().enumerate() {
        for (b_pos, &j) in indices.iter().enumerate().skip(a_pos + 1) {
            let (a, b) = (pixels[i], pixels[j]);
            for &k in &indices[b_pos + 1..] {
                let area = twice_area(a, b, pixels[k]);
                if area > best.0 {
                    best = (area, [i, j, k]);
                }
            }
        }
    }
    best
}

/// The sorted triple of three indices.
fn sorted(mut t: [usize; 3]) -> [usize; 3] {
    t.sort_unstable();
    t
}

/// A largest triangle of a convex polygon's vertices (`hull`, counter-clockwise), by the
/// classic rotating pointers: for each first vertex `i`, the best third vertex moves forward
/// as the second one does, `O(h^2)`. Areas by the exhaustive search's expression on the
/// sorted triple; equal areas keep the smallest sorted triple.
pub(crate) fn largest_hull_triangle(pixels: &[[f64; 2]], hull: &[usize]) -> (f64, [usize; 3]) {
    let h = hull.len();
    let points: Vec<[f64; 2]> = hull.iter().map(|&i| pixels[i]).collect();
    let mut best = (0.0_f64, [0, 1, 2]);
    for (i, &a) in points.iter().enumerate() {
        let mut k = i + 2;
        for j in i + 1..h - 1 {
            let b = points[j];
            let area = |k: usize| cross(a, b, points[k]).abs();
            k = k.max(j + 1);
            let mut at_k = area(k);
            while k + 1 < h {
                let next = area(k + 1);
                if next < at_k {
                    break;
                }
                (k, at_k) = (k + 1, next);
            }
            let better = at_k > best.0
                || (at_k == best.0 && sorted([hull[i], hull[j], hull[k]]) < sorted(best.1.map(|m| hull[m])));
            if better {
                best = (at_k, [i, j, k]);
            }
        }
    }
    let s = sorted(best.1.map(|m| hull[m]));
    (twice_area(pixels[s[0]], pixels[s[1]], pixels[s[2]]), s)
}

/// The widest triangle of `pixels` (finite, at least 3): twice its area and its sorted
/// indices, the exhaustive search's choice (see the module's documentation for when it is
/// not, and the limit on the hull's size).
pub(crate) fn widest_triangle(pixels: &[[f64; 2]]) -> Result<(f64, [usize; 3])> {
    let all: Vec<usize> = (0..pixels.len()).collect();
    if pixels.len() <= EXHAUSTIVE_MAX_POINTS {
        return Ok(exhaustive(pixels, &all));
    }
    let hull = convex_hull(pixels);
    if hull.len() < 3 {
        // All points collinear: every area rounds to (nearly) 0; the caller refuses it.
        return Ok((0.0, sorted([all[0], all[1], all[2]])));
    }
    if hull.len() > MAX_HULL_POINTS {
        return Err(Error::InvalidParameter {
            name: "pixels",
            reason: format!(
                "{} of the points are convex-hull vertices; the widest-triangle search (basis \"auto\") takes at \
                 most {MAX_HULL_POINTS}: give the basis indices",
                hull.len()
            ),
        });
    }
    let (area, triangle) = largest_hull_triangle(pixels, &hull);
    if hull.len() > EXACT_MAX_BOUNDARY_POINTS {
        return Ok((area, triangle));
    }
    match super::boundary_points::near_boundary(pixels, &hull, triangle, area, EXACT_MAX_BOUNDARY_POINTS) {
        Some(candidates) => Ok(exhaustive(pixels, &candidates)),
        None => Ok((area, triangle)),
    }
}

#[cfg(test)]
#[path = "widest_triangle_tests.rs"]
mod tests;
