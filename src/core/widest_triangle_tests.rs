//! The fast widest-triangle search against the exhaustive one it replaces.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use super::*;
use crate::core::convex_hull::cross;

/// The exhaustive search as `choose_basis` did it before (an independent copy).
fn reference(pixels: &[[f64; 2]]) -> (f64, [usize; 3]) {
    let n = pixels.len();
    let mut best = (0.0_f64, [0, 1, 2]);
    for i in 0..n {
        for j in i + 1..n {
            for k in j + 1..n {
                let (a, b, c) = (pixels[i], pixels[j], pixels[k]);
                let area = ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs();
                if area > best.0 {
                    best = (area, [i, j, k]);
                }
            }
        }
    }
    best
}

/// splitmix64: a small deterministic generator, uniform in [0, 1).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn below(&mut self, n: usize) -> usize {
        ((self.next() * n as f64) as usize).min(n - 1)
    }
}

/// Point sets of `n` points of several shapes, including degenerate ones.
fn point_set(kind: usize, n: usize, rng: &mut Rng) -> Vec<[f64; 2]> {
    let tau = std::f64::consts::TAU;
    let mut px: Vec<[f64; 2]> = (0..n)
        .map(|i| match kind {
            0 => [640.0 * rng.next(), 480.0 * rng.next()],
            1 => {
                let (r, t) = (200.0 * rng.next().sqrt(), tau * rng.next());
                [320.0 + r * t.cos(), 240.0 + r * t.sin()]
            }
            // Integer pixels: exact areas, many ties.
            2 => [rng.below(9) as f64, rng.below(7) as f64],
            // A rectangle's border with points on its edges, and inside.
            3 => match rng.below(5) {
                0 => [rng.below(100) as f64, 0.0],
                1 => [rng.below(100) as f64, 60.0],
                2 => [0.0, rng.below(60) as f64],
                3 => [100.0, rng.below(60) as f64],
                _ => [1.0 + rng.below(98) as f64, 1.0 + rng.below(58) as f64],
            },
            // Duplicates of a few points (a hull vertex many times).
            4 => [[0.0, 0.0], [10.0, 0.0], [0.0, 10.0], [3.0, 3.0], [7.0, 1.0]][rng.below(5)],
            // A regular hexagon (ties among its triangles) and points inside.
            5 if i % 4 == 0 => {
                let t = tau * (rng.below(6) as f64) / 6.0;
                [100.0 * t.cos(), 100.0 * t.sin()]
            }
            5 => [50.0 * (rng.next() - 0.5), 50.0 * (rng.next() - 0.5)],
            // Collinear but for one point.
            6 if i == n / 2 => [3.0, 7.5],
            6 => {
                let t = rng.next();
                [1.0 + 2.0 * t, 5.0 + 3.0 * t]
            }
            // Far from the origin, small spread (rounding of the differences matters).
            7 => [1e6 + rng.next(), -2e5 + rng.next()],
            _ => [0.0, 0.0],
        })
        .collect();
    if kind == 1 {
        // Shuffle the hull's vertices to the end, so that a wrong order of candidates shows.
        px.reverse();
    }
    px
}

/// How many points lie on the boundary of the hull (within 1e-9 of an edge's line).
fn on_boundary(px: &[[f64; 2]]) -> usize {
    let hull = convex_hull(px);
    if hull.len() < 3 {
        return px.len();
    }
    let edge_distance = |p: [f64; 2], m: usize| {
        let (a, b) = (px[hull[m]], px[hull[(m + 1) % hull.len()]]);
        cross(a, b, p) / (b[0] - a[0]).hypot(b[1] - a[1])
    };
    px.iter().filter(|&&p| (0..hull.len()).any(|m| edge_distance(p, m) <= 1e-9)).count()
}

/// The fast search against the exhaustive one: the same triangle (same area bits, same
/// indices) when at most `EXACT_MAX_BOUNDARY_POINTS` points lie on the hull's boundary, else a
/// triangle of the same area up to rounding.
fn check_against_reference(px: &[[f64; 2]], what: &str) {
    let (area, triangle) = widest_triangle(px).unwrap();
    let (want_area, want) = reference(px);
    assert!(triangle[0] < triangle[1] && triangle[1] < triangle[2], "{what}: {triangle:?}");
    if on_boundary(px) <= EXACT_MAX_BOUNDARY_POINTS {
        assert_eq!(area.to_bits(), want_area.to_bits(), "{what}");
        if want_area > 0.0 {
            assert_eq!(triangle, want, "{what}");
        }
    } else {
        assert!((area - want_area).abs() <= 1e-12 * want_area, "{what}: {area} vs {want_area}");
    }
}

#[test]
fn fast_search_picks_the_exhaustive_searchs_triangle() {
    let mut rng = Rng(16);
    let mut exact = 0;
    for kind in 0..9 {
        for seed in 0..8 {
            let n = EXHAUSTIVE_MAX_POINTS + 1 + rng.below(230);
            let px = point_set(kind, n, &mut rng);
            check_against_reference(&px, &format!("kind {kind}, seed {seed}, n {n}"));
            exact += usize::from(on_boundary(&px) <= EXACT_MAX_BOUNDARY_POINTS);
        }
    }
    // Most sets take the exact path (the claim is tested, not skipped).
    assert!(exact >= 48, "{exact} of 72 sets on the exact path");
}

#[test]
fn a_thousand_points_pick_the_exhaustive_searchs_triangle() {
    let mut rng = Rng(1000);
    for kind in [0, 1, 2, 7] {
        let px = point_set(kind, 1000, &mut rng);
        check_against_reference(&px, &format!("kind {kind}"));
        // The exact path, not the fallback, chose it: the boundary filter kept few points.
        let hull = convex_hull(&px);
        let mut sorted_hull = hull.clone();
        sorted_hull.sort_unstable();
        let (area, triangle) = exhaustive(&px, &sorted_hull);
        let near = crate::core::boundary_points::near_boundary(&px, &hull, triangle, area, EXACT_MAX_BOUNDARY_POINTS);
        let count = near.as_ref().map(Vec::len);
        assert!(
            count.is_some_and(|c| c >= hull.len() && c <= on_boundary(&px)),
            "kind {kind}: {count:?} near, hull {}",
            hull.len()
        );
    }
}

#[test]
fn below_the_threshold_the_search_is_the_exhaustive_one() {
    let mut rng = Rng(7);
    for kind in 0..9 {
        let px = point_set(kind, EXHAUSTIVE_MAX_POINTS, &mut rng);
        let (area, triangle) = widest_triangle(&px).unwrap();
        assert_eq!((area.to_bits(), triangle), (reference(&px).0.to_bits(), reference(&px).1), "kind {kind}");
    }
}

#[test]
fn hull_is_the_set_of_extreme_points() {
    let mut rng = Rng(3);
    for kind in 0..9 {
        let px = point_set(kind, 150, &mut rng);
        let hull = convex_hull(&px);
        // Every point is on the inner side of (or on) every edge of a counter-clockwise hull.
        for m in 0..hull.len().max(3).min(hull.len()) {
            let (a, b) = (px[hull[m]], px[hull[(m + 1) % hull.len()]]);
            assert!(px.iter().all(|&p| cross(a, b, p) >= -1e-9), "kind {kind}");
        }
        // Each vertex is strictly convex, and no two vertices are equal points.
        for m in 0..hull.len() {
            let h = hull.len();
            if h >= 3 {
                assert!(cross(px[hull[m]], px[hull[(m + 1) % h]], px[hull[(m + 2) % h]]) > 0.0, "kind {kind}");
            }
        }
    }
}

#[test]
fn rotating_pointers_find_the_largest_hull_triangle() {
    let mut rng = Rng(11);
    let tau = std::f64::consts::TAU;
    for seed in 0..40 {
        // Convex polygons: points on an ellipse, random or regular (many ties).
        let h = 3 + rng.below(120);
        let regular = seed % 3 == 0;
        let px: Vec<[f64; 2]> = (0..h)
            .map(|i| {
                let t = if regular { tau * i as f64 / h as f64 } else { tau * rng.next() };
                [300.0 * t.cos(), 120.0 * t.sin()]
            })
            .collect();
        let hull = convex_hull(&px);
        let (area, _) = largest_hull_triangle(&px, &hull);
        let mut sorted_hull = hull.clone();
        sorted_hull.sort_unstable();
        let (want, _) = exhaustive(&px, &sorted_hull);
        assert!((area - want).abs() <= 1e-12 * want, "seed {seed}: {area} vs {want}");
    }
}

#[test]
fn many_points_on_the_hull_give_a_largest_triangle() {
    // 600 points on a circle: more boundary points than the exhaustive search takes.
    let tau = std::f64::consts::TAU;
    let px: Vec<[f64; 2]> =
        (0..600).map(|i| [100.0 * (tau * i as f64 / 600.0).cos(), 100.0 * (tau * i as f64 / 600.0).sin()]).collect();
    let (area, triangle) = widest_triangle(&px).unwrap();
    let (want, _) = reference(&px);
    assert!((area - want).abs() <= 1e-12 * want, "{area} vs {want}");
    assert!(triangle[0] < triangle[1] && triangle[1] < triangle[2]);
}

#[test]
fn a_huge_hull_is_refused_naming_the_argument_and_the_limit() {
    let n = MAX_HULL_POINTS + 1;
    let tau = std::f64::consts::TAU;
    let px: Vec<[f64; 2]> =
        (0..n).map(|i| [1e4 * (tau * i as f64 / n as f64).cos(), 1e4 * (tau * i as f64 / n as f64).sin()]).collect();
    let err = widest_triangle(&px).unwrap_err();
    let text = err.to_string();
    assert!(matches!(err, Error::InvalidParameter { name: "pixels", .. }), "{text}");
    assert!(text.contains(&MAX_HULL_POINTS.to_string()), "{text}");
}

#[test]
fn all_points_equal_or_collinear_give_a_zero_area() {
    let same = vec![[5.0, 5.0]; 300];
    assert_eq!(widest_triangle(&same).unwrap().0, 0.0);
    let line: Vec<[f64; 2]> = (0..300).map(|i| [i as f64, 2.0 * i as f64]).collect();
    assert_eq!(widest_triangle(&line).unwrap().0, 0.0);
}
