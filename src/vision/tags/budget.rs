//! The work [`TagDecoder`](super::TagDecoder) does on one frame, bounded: a cluttered frame
//! (thousands of small dark squares, a random checkerboard, a wall of tags) is searched only
//! as far as the bound allows, and the answer says it stopped early ([`TagReport`]).
//!
//! Where the time goes (1920 x 1080, a wall of 8,000 small tag16h5 tags, 0.9 s before this
//! bound): `kornia-apriltag`'s gradient clusters, quad fit and decoding (0.58 s, inside one
//! call that cannot be interrupted; its threshold and connected components take 4%), then
//! the corners measured again on the edges (`edges.rs`, 0.3 s for 6,767 decoded candidates
//! of 30 ids, about 45 us each). Both grow with the regions of the thresholded image, not
//! with its pixels. So:
//!
//! - before a level's quads are searched, its regions are counted (the black and white regions
//!   of its threshold large enough to start a quad, labelled for the search itself:
//!   `components.rs`), and a level that would take the frame past [`MAX_SEARCHED_REGIONS`] is
//!   not searched (the coarser levels still are: their regions are fewer);
//! - the decoded candidates are measured best first (fewest bit errors, then the best
//!   decoding margin), an id already measured is not measured again, and at most
//!   [`MAX_MEASURED_CANDIDATES`] are measured.

use super::{Candidate, Tag};

/// The most regions (of the detector's threshold, counted by `regions`) a frame's quad
/// searches read, over all its levels: the detector takes some 15 to 50 us a region (noise
/// the least, small squares and tags the most), so a frame's quad searches take at most some
/// 0.2 s. Ordinary frames hold fewer: ViSP's AprilTag images at most 950 at the default
/// decimation, 3,854 for the photograph enlarged to 1920 x 1080 and searched at decimation 1;
/// a wall of 8,000 small tags or 4,500 dark squares at 1920 x 1080 some 4,500 to 11,000 on
/// its finest level.
pub const MAX_SEARCHED_REGIONS: u64 = 4096;

/// The most decoded candidates whose corners are measured on the edges in one frame (some
/// 45 us each): one per id unless the best is refused, so only a wall of hundreds of
/// distinct tags reaches it.
pub const MAX_MEASURED_CANDIDATES: usize = 512;

/// The tags of one frame and whether the search stopped early (a level not searched, or
/// candidates not measured, because the frame was too cluttered: see the module docs).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TagReport {
    /// The tags found, sorted by id (as [`detect_tags`](super::detect_tags) returns them).
    pub tags: Vec<Tag>,
    /// Whether some of the frame was not searched or some candidates not measured.
    pub stopped_early: bool,
}

/// What is left of one frame's budget.
#[derive(Debug)]
pub(super) struct Budget {
    regions_left: u64,
    pub(super) stopped_early: bool,
}

impl Budget {
    pub(super) fn new() -> Self {
        Self { regions_left: MAX_SEARCHED_REGIONS, stopped_early: false }
    }

    /// Whether a level of `regions` regions is searched (taking them from the budget); a
    /// level refused marks the frame as stopped early.
    pub(super) fn admit(&mut self, regions: u64) -> bool {
        if regions <= self.regions_left {
            self.regions_left -= regions;
            return true;
        }
        self.stopped_early = true;
        false
    }
}

/// The candidates to measure, best first (fewest bit errors, then the best decoding margin;
/// ties in the detector's order), and whether some were left out by the budget: an id is
/// measured again only when its better candidates were all refused by `measure`.
pub(super) fn measure_best_first(
    mut candidates: Vec<Candidate>,
    mut measure: impl FnMut(&[[f64; 2]; 4]) -> Option<[[f64; 2]; 4]>,
) -> (Vec<Tag>, bool) {
    candidates.sort_by(|a, b| a.0.0.cmp(&b.0.0).then(b.0.1.total_cmp(&a.0.1)));
    let mut tags: Vec<Tag> = Vec::new();
    let mut done = std::collections::HashSet::new();
    let mut measured = 0;
    let mut stopped_early = false;
    for (_, id, corners) in candidates {
        if done.contains(&id) {
            continue;
        }
        if measured == MAX_MEASURED_CANDIDATES {
            stopped_early = true;
            break;
        }
        measured += 1;
        if let Some(corners) = measure(&corners) {
            done.insert(id);
            tags.push(Tag { id, corners });
        }
    }
    tags.sort_by_key(|t| t.id);
    (tags, stopped_early)
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::vision::tags::synthetic::{Placement, Rng, draw};
    use crate::vision::tags::{TagDecoder, TagFamily, detect_tags};

    /// The old rule: every candidate measured, then per id the fewest bit errors and the best
    /// margin among those measured.
    fn measure_all(candidates: &[Candidate], measure: impl Fn(&[[f64; 2]; 4]) -> Option<[[f64; 2]; 4]>) -> Vec<Tag> {
        let mut tags: Vec<((u8, f32), Tag)> =
            candidates.iter().filter_map(|(m, id, c)| Some((*m, Tag { id: *id, corners: measure(c)? }))).collect();
        tags.sort_by(|a, b| a.1.id.cmp(&b.1.id).then(a.0.0.cmp(&b.0.0)).then(b.0.1.total_cmp(&a.0.1)));
        tags.dedup_by_key(|t| t.1.id);
        tags.into_iter().map(|(_, t)| t).collect()
    }

    #[test]
    fn best_first_measuring_keeps_what_measuring_all_kept() {
        let mut rng = Rng(3);
        // Refused when the first coordinate's fraction is below 0.3; moved otherwise.
        let measure = |c: &[[f64; 2]; 4]| (c[0][0].fract() >= 0.3).then(|| c.map(|[u, v]| [u + 0.25, v]));
        for n in [0, 1, 5, 40, 300] {
            let candidates: Vec<Candidate> = (0..n)
                .map(|k| {
                    let margin = rng.below(4) as f32 * 10.0; // ties on purpose
                    let corner = [f64::from(k) + rng.unit(), 0.0];
                    ((rng.below(3) as u8, margin), rng.below(12) as u32, [corner; 4])
                })
                .collect();
            let (tags, stopped) = measure_best_first(candidates.clone(), measure);
            assert_eq!(tags, measure_all(&candidates, measure), "{n}");
            assert!(!stopped);
        }
        // More distinct ids than the budget: the best ones are measured, and it says so.
        let many: Vec<Candidate> =
            (0..3000u32).map(|id| ((u8::from(id % 2 == 1), id as f32), id, [[0.5, 0.0]; 4])).collect();
        let mut calls = 0;
        let (tags, stopped) = measure_best_first(many, |c| {
            calls += 1;
            Some(*c)
        });
        assert!(stopped && calls == MAX_MEASURED_CANDIDATES && tags.len() == MAX_MEASURED_CANDIDATES);
        // Even ids (no bit error) first, the best margin (the largest id) first.
        assert!(tags.iter().all(|t| t.id % 2 == 0 && t.id >= 3000 - 2 * MAX_MEASURED_CANDIDATES as u32));
    }

    /// A wall of small tags (tag16h5, 30 ids, 2 px a cell): the search stops early, within
    /// its bound, and what it finds is right.
    #[test]
    fn a_cluttered_frame_is_searched_within_the_bound_and_says_so() {
        let (width, height, step) = (1280u32, 720u32, 16.0);
        let mut placed = Vec::new();
        let mut v = 10.0;
        while v + step < f64::from(height) {
            let mut u = 10.0;
            while u + step < f64::from(width) {
                placed.push(Placement { id: placed.len() % 30, centre: [u, v], cell: 2.0, quarter_turns: 0 });
                u += step;
            }
            v += step;
        }
        let image = draw(TagFamily::Tag16h5, width, height, &placed);
        let mut decoder = TagDecoder::new(TagFamily::Tag16h5);
        let report = decoder.detect_report(&image).unwrap();
        assert!(report.stopped_early, "{} tags drawn", placed.len());
        // Each tag found is one drawn there (an id at a drawn centre).
        for tag in &report.tags {
            let centre = [0, 1].map(|k| tag.corners.iter().map(|c| c[k]).sum::<f64>() / 4.0);
            let near = |p: &&Placement| (p.centre[0] - centre[0]).hypot(p.centre[1] - centre[1]) < 1.0;
            assert!(placed.iter().filter(near).any(|p| p.id as u32 == tag.id), "{tag:?}");
        }
        // An ordinary frame: a few tags, searched whole.
        let few = [(3, [200.0, 150.0]), (7, [600.0, 400.0]), (11, [1000.0, 300.0])].map(|(id, centre)| Placement {
            id,
            centre,
            cell: 8.0,
            quarter_turns: 1,
        });
        let report = decoder.detect_report(&draw(TagFamily::Tag16h5, width, height, &few)).unwrap();
        assert!(!report.stopped_early);
        assert_eq!(report.tags.iter().map(|t| t.id).collect::<Vec<_>>(), [3, 7, 11]);
        assert_eq!(
            report.tags,
            detect_tags(&draw(TagFamily::Tag16h5, width, height, &few), TagFamily::Tag16h5).unwrap()
        );
    }

    #[test]
    fn the_budget_admits_levels_while_they_fit() {
        let mut budget = Budget::new();
        assert!(budget.admit(MAX_SEARCHED_REGIONS - 10) && !budget.stopped_early);
        assert!(!budget.admit(11) && budget.stopped_early);
        assert!(budget.admit(10));
    }
}
