//! A spread of points over the image: the strongest keypoint of each cell of a grid, so the
//! points cover the object rather than crowd on its most textured patch, and the invariant
//! law's basis (three points, `core::widest_triangle`) can be wide and well conditioned.

/// Indices of at most `count` of `pixels`, spread over the `width x height` image: a grid of
/// about `count` cells, in each the point of largest `strength`; then, while fewer than
/// `count` are chosen, the strongest of the rest. Distinct pixels only (two keypoints at one
/// pixel, as SIFT reports for two orientations, are one point).
pub fn spread(pixels: &[[f64; 2]], strength: &[f32], width: u32, height: u32, count: usize) -> Vec<usize> {
    if count == 0 || pixels.is_empty() {
        return Vec::new();
    }
    let side = ((f64::from(width) * f64::from(height) / count as f64).sqrt()).max(1.0);
    let cols = (f64::from(width) / side).ceil().max(1.0) as usize;
    let rows = (f64::from(height) / side).ceil().max(1.0) as usize;
    let mut order: Vec<usize> = (0..pixels.len()).collect();
    order.sort_by(|&a, &b| strength.get(b).partial_cmp(&strength.get(a)).unwrap_or(std::cmp::Ordering::Equal));
    let mut taken = vec![false; cols * rows];
    let mut chosen: Vec<usize> = Vec::new();
    let same = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).abs() < 0.5 && (a[1] - b[1]).abs() < 0.5;
    for &i in &order {
        let [u, v] = pixels[i];
        let cell = ((v / side).floor().max(0.0) as usize).min(rows - 1) * cols
            + ((u / side).floor().max(0.0) as usize).min(cols - 1);
        if !taken[cell] && chosen.len() < count {
            taken[cell] = true;
            chosen.push(i);
        }
    }
    for &i in &order {
        if chosen.len() >= count {
            break;
        }
        if !chosen.iter().any(|&c| c == i || same(pixels[c], pixels[i])) {
            chosen.push(i);
        }
    }
    chosen
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    #[test]
    fn the_strongest_of_each_cell_first_then_the_strongest_of_the_rest() {
        // A crowd of strong points in one corner and weak ones elsewhere.
        let mut pixels = Vec::new();
        let mut strength = Vec::new();
        for i in 0..20 {
            pixels.push([5.0 + f64::from(i % 5), 5.0 + f64::from(i / 5)]);
            strength.push(10.0 + i as f32);
        }
        for (u, v) in [(90.0, 10.0), (10.0, 90.0), (90.0, 90.0)] {
            pixels.push([u, v]);
            strength.push(1.0);
        }
        let chosen = spread(&pixels, &strength, 100, 100, 4);
        assert_eq!(chosen.len(), 4);
        // The strongest of the crowd and the three lone corners.
        assert_eq!(chosen[0], 19);
        for lone in 20..23 {
            assert!(chosen.contains(&lone), "{chosen:?}");
        }
        // Asking for more fills up with the strongest of the rest, never a pixel twice.
        let mut twice = pixels.clone();
        twice.push(pixels[18]);
        let mut s2 = strength.clone();
        s2.push(28.5);
        let more = spread(&twice, &s2, 100, 100, 8);
        assert_eq!(more.len(), 8);
        assert!(!(more.contains(&18) && more.contains(&23)), "{more:?}");
        assert!(spread(&pixels, &strength, 100, 100, 0).is_empty());
    }
}
