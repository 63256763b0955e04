//! 8-connected components of the pixels above a threshold, as runs: each row's horizontal
//! runs of dot pixels, runs of neighbouring rows that touch (8-connectivity: overlapping or
//! diagonal) joined by union-find, then per component its area, bounding box and first and
//! second moments, summed run by run in closed form. The rows are scanned in parallel
//! ([`row_scan`](super::row_scan)); no
//! memory per pixel (a label image) is needed: the runs are the labels.

use rayon::prelude::*;

use crate::vision::background::TileThresholds;
use crate::vision::image::{GreyBuffer, Pixels};
pub use crate::vision::row_scan::Run;
use crate::vision::row_scan::scan_rows;

/// Rows scanned by one parallel task.
const BAND: usize = 64;

/// A connected component: area, bounding box and moments of its pixels' centres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Component {
    /// Pixels.
    pub area: u64,
    /// `[u_min, v_min, u_max, v_max]`, inclusive.
    pub bbox: [u32; 4],
    sum_u: u128,
    sum_v: u128,
    sum_uu: u128,
    sum_vv: u128,
    sum_uv: u128,
}

impl Component {
    fn new(run: &Run) -> Self {
        let mut c = Self {
            area: 0,
            bbox: [run.u0, run.v, run.u1 - 1, run.v],
            sum_u: 0,
            sum_v: 0,
            sum_uu: 0,
            sum_vv: 0,
            sum_uv: 0,
        };
        c.add(run);
        c
    }

    fn add(&mut self, run: &Run) {
        let (a, b, v) = (u128::from(run.u0), u128::from(run.u1), u128::from(run.v));
        let n = b - a;
        // Sums of u and u^2 over a..b: f(b) - f(a) with f(x) = sum of the first x values.
        let su = (b * (b - 1) - a * a.saturating_sub(1)) / 2;
        let squares = |x: u128| if x == 0 { 0 } else { (x - 1) * x * (2 * x - 1) / 6 };
        self.area += n as u64;
        self.sum_u += su;
        self.sum_v += v * n;
        self.sum_uu += squares(b) - squares(a);
        self.sum_vv += v * v * n;
        self.sum_uv += v * su;
        self.bbox =
            [self.bbox[0].min(run.u0), self.bbox[1].min(run.v), self.bbox[2].max(run.u1 - 1), self.bbox[3].max(run.v)];
    }

    /// The covariance `[s_uu, s_uv, s_vv]` of the pixels' centres, exact sums (integers) up
    /// to the last division.
    pub fn covariance(&self) -> [f64; 3] {
        let n = u128::from(self.area);
        let n2 = (self.area as f64) * (self.area as f64);
        let central = |sxy: u128, sx: u128, sy: u128| (n * sxy) as f64 / n2 - (sx * sy) as f64 / n2;
        [
            central(self.sum_uu, self.sum_u, self.sum_u),
            central(self.sum_uv, self.sum_u, self.sum_v),
            central(self.sum_vv, self.sum_v, self.sum_v),
        ]
    }

    /// The area over the area of the ellipse of the same second moments (`4 pi sqrt(det)`,
    /// each pixel counted as a unit square: `1/12` added to each variance): 1 for a filled
    /// ellipse, less for anything else (0.955 for a square, less for a ring, a bar with a
    /// bump, two touching discs).
    pub fn fill_ratio(&self) -> f64 {
        let [uu, uv, vv] = self.covariance();
        let det = (uu + 1.0 / 12.0) * (vv + 1.0 / 12.0) - uv * uv;
        self.area as f64 / (4.0 * std::f64::consts::PI * det.max(0.0).sqrt())
    }
}

/// The runs of an image, by row, with the component of each.
#[derive(Debug, Clone, Default)]
pub struct Labelling {
    runs: Vec<Run>,
    /// Runs of row `v`: `runs[row_start[v]..row_start[v + 1]]`.
    row_start: Vec<usize>,
    /// The component of each run.
    component_of: Vec<u32>,
    /// The components, in the raster order of their first pixel.
    pub components: Vec<Component>,
    /// The smallest and largest grey level of the image.
    pub range: [u8; 2],
    /// The labelled image's width and height.
    size: [u32; 2],
}

impl Labelling {
    /// The runs of row `v`, with their components (none for a row outside the image).
    pub fn row(&self, v: u32) -> (&[Run], &[u32]) {
        let start = |v: usize| self.row_start.get(v).copied();
        match (start(v as usize), start(v as usize + 1)) {
            (Some(a), Some(b)) => (&self.runs[a..b], &self.component_of[a..b]),
            _ => (&[], &[]),
        }
    }

    /// The width and height of the image labelled.
    pub fn size(&self) -> [u32; 2] {
        self.size
    }
}

/// The components of the pixels whose level (grey level, or `255 - g` when `dark`) is above
/// their tile's threshold.
pub fn label<C: Pixels>(image: &GreyBuffer<C>, thresholds: &TileThresholds, dark: bool) -> Labelling {
    let (width, height) = (image.width() as usize, image.height() as usize);
    let data: &[u8] = image.as_raw();
    let bands: Vec<(Vec<Run>, [u8; 2])> = (0..height.div_ceil(BAND))
        .into_par_iter()
        .map(|band| {
            let mut runs = Vec::new();
            let rows = band * BAND..((band + 1) * BAND).min(height);
            let range = scan_rows(data, width, rows, thresholds, dark, &mut runs);
            (runs, range)
        })
        .collect();
    let range = bands.iter().fold([u8::MAX, 0], |[lo, hi], (_, [a, b])| [lo.min(*a), hi.max(*b)]);
    let runs: Vec<Run> = bands.into_iter().flat_map(|(runs, _)| runs).collect();
    let mut row_start = vec![0usize; height + 1];
    for r in &runs {
        row_start[r.v as usize + 1] += 1;
    }
    for v in 0..height {
        row_start[v + 1] += row_start[v];
    }
    let mut parent: Vec<u32> = (0..runs.len() as u32).collect();
    for v in 1..height {
        join_rows(&runs, row_start[v - 1]..row_start[v], row_start[v]..row_start[v + 1], &mut parent);
    }
    let (component_of, components) = components(&runs, &mut parent);
    Labelling { runs, row_start, component_of, components, range, size: [image.width(), image.height()] }
}

fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let grand = parent[parent[i as usize] as usize];
        parent[i as usize] = grand;
        i = grand;
    }
    i
}

/// Joins the touching runs of two consecutive rows (the root is the run met first in raster
/// order).
fn join_rows(runs: &[Run], above: std::ops::Range<usize>, below: std::ops::Range<usize>, parent: &mut [u32]) {
    let (mut i, mut j) = (above.start, below.start);
    while i < above.end && j < below.end {
        let (a, b) = (runs[i], runs[j]);
        if a.u0 <= b.u1 && b.u0 <= a.u1 {
            let (ra, rb) = (find(parent, i as u32), find(parent, j as u32));
            let (low, high) = (ra.min(rb), ra.max(rb));
            parent[high as usize] = low;
        }
        if a.u1 < b.u1 {
            i += 1;
        } else {
            j += 1;
        }
    }
}

/// The component of each run and the components' statistics.
fn components(runs: &[Run], parent: &mut [u32]) -> (Vec<u32>, Vec<Component>) {
    let mut component_of = vec![0u32; runs.len()];
    let mut components: Vec<Component> = Vec::new();
    for (i, run) in runs.iter().enumerate() {
        let root = find(parent, i as u32) as usize;
        if root == i {
            component_of[i] = components.len() as u32;
            components.push(Component::new(run));
        } else {
            component_of[i] = component_of[root];
            components[component_of[root] as usize].add(run);
        }
    }
    (component_of, components)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::vision::image::GreyImage;
    use imageproc::region_labelling::{Connectivity, connected_components};

    /// The components of imageproc's labelling: area and bounding box per label.
    fn reference(binary: &GreyImage) -> Vec<(u64, [u32; 4])> {
        let labels = connected_components(binary, Connectivity::Eight, image::Luma([0u8]));
        let mut out: Vec<(u64, [u32; 4])> = Vec::new();
        for (u, v, p) in labels.enumerate_pixels() {
            let l = p[0] as usize;
            if l == 0 {
                continue;
            }
            if out.len() < l {
                out.resize(l, (0, [u32::MAX, u32::MAX, 0, 0]));
            }
            let (a, b) = &mut out[l - 1];
            *a += 1;
            *b = [b[0].min(u), b[1].min(v), b[2].max(u), b[3].max(v)];
        }
        out
    }

    #[test]
    fn components_match_imageproc_on_random_images() {
        let mut state = 99u64;
        for density in [0.2, 0.45, 0.6] {
            let binary = GreyImage::from_fn(150, 97, |_, _| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                image::Luma([if ((state >> 11) as f64 / (1u64 << 53) as f64) < density { 255 } else { 0 }])
            });
            let t = TileThresholds::uniform(&binary, 128);
            let ours: Vec<(u64, [u32; 4])> =
                label(&binary, &t, false).components.iter().map(|c| (c.area, c.bbox)).collect();
            let mut theirs = reference(&binary);
            let mut ours_sorted = ours.clone();
            ours_sorted.sort_by_key(|c| (c.1[1], c.1[0], c.0));
            theirs.sort_by_key(|c| (c.1[1], c.1[0], c.0));
            assert_eq!(ours_sorted, theirs, "density {density}");
        }
    }

    #[test]
    fn moments_and_fill_ratio_in_closed_form() {
        // A 7 x 4 rectangle at (10, 20): variances (n^2 - 1) / 12; fill ratio of a square
        // pi / (4 pi sqrt(1/144)) ... for a w x h rectangle: 3 / pi.
        let binary = GreyImage::from_fn(40, 40, |u, v| {
            image::Luma([if (10..17).contains(&u) && (20..24).contains(&v) { 255 } else { 0 }])
        });
        let l = label(&binary, &TileThresholds::uniform(&binary, 0), false);
        assert_eq!(l.components.len(), 1);
        let c = l.components[0];
        assert_eq!((c.area, c.bbox), (28, [10, 20, 16, 23]));
        let [uu, uv, vv] = c.covariance();
        assert!((uu - 48.0 / 12.0).abs() < 1e-12 && uv.abs() < 1e-12 && (vv - 15.0 / 12.0).abs() < 1e-12);
        assert!((c.fill_ratio() - 3.0 / std::f64::consts::PI).abs() < 1e-12);
        // A disc of radius 20: close to 1.
        let disc = GreyImage::from_fn(60, 60, |u, v| {
            image::Luma([if (f64::from(u) - 30.2).hypot(f64::from(v) - 29.7) < 20.0 { 255 } else { 0 }])
        });
        let fill = label(&disc, &TileThresholds::uniform(&disc, 0), false).components[0].fill_ratio();
        assert!((fill - 1.0).abs() < 0.01, "{fill}");
    }
}
