//! The quad search of one level of the pyramid ([`LevelSearch`]): the level decimated as the
//! AprilTag detector decimates it, thresholded by its adaptive threshold (`threshold.rs`, the
//! same pixels as kornia-apriltag's), its regions labelled
//! (`components.rs`) and counted for the frame's budget, and only then, when the budget admits
//! them, their gradient clusters gathered (`clusters.rs`), fitted by quads and decoded by
//! `kornia-apriltag`'s public stages.
//!
//! The stages are `kornia-apriltag`'s `AprilTagDecoder::decode`, with the same points in the
//! same order (so the same quads and codes, checked below against it), but its regions are
//! labelled here, once: the budget's count reads them instead of thresholding the level a
//! second time.

use kornia_apriltag::DecodeTagsConfig;
use kornia_apriltag::decoder::{Detection, decode_tags, dedup_detections};
use kornia_apriltag::family::{TagFamily as Layout, TagFamilyKind};
use kornia_apriltag::quad::fit_quads;
use kornia_apriltag::utils::Pixel;
use kornia_image::{Image, ImageSize};

use super::clusters::Clusters;
use super::components::Components;
use super::threshold::{TILE, Threshold};
use super::{MIN_WHITE_BLACK_DIFFERENCE, THRESHOLD_SPLIT, TagFamily, decimated_side, decoder_error, face};
use crate::vision::error::Result;

/// The fewest points of a cluster the quad fit reads (the AprilTag library's `fit_quad` and
/// kornia-apriltag's `fit_single_quad` return no quad for fewer); the most is four times the
/// level's width and height (kornia-apriltag's `fit_quads`).
const MIN_QUAD_POINTS: usize = 24;

/// The buffers and settings of one level's search (kept while the level's size and decimation
/// stay the same).
pub(super) struct LevelSearch {
    size: ImageSize,
    decimation: usize,
    config: DecodeTagsConfig,
    families: Vec<(TagFamilyKind, Layout)>,
    decimated: Vec<u8>,
    binary: Image<Pixel, 1>,
    threshold: Threshold,
}

/// The labelling and clusters, shared by the levels (one level is searched at a time).
#[derive(Default)]
pub(super) struct Scratch {
    components: Components,
    clusters: Clusters,
}

impl LevelSearch {
    /// The search of a level of `size` decimated by `decimation` for `family`'s tags.
    pub(super) fn new(family: TagFamily, size: ImageSize, decimation: usize) -> Result<Self> {
        // The family data the faces are drawn from (`face.rs`), repaired where kornia's is not.
        let kind = TagFamilyKind::Custom(std::sync::Arc::new(face::layout(family)?.clone()));
        let mut config = DecodeTagsConfig::new(vec![kind.clone()]).map_err(decoder_error)?;
        config.downscale_factor = decimation;
        config.min_tag_width = (family.border_cells() as usize / decimation.max(1)).max(3);
        config.threshold_split = THRESHOLD_SPLIT;
        config.min_white_black_difference = MIN_WHITE_BLACK_DIFFERENCE;
        let layout = Layout::try_from(&kind).map_err(decoder_error)?;
        let searched = decimated_size(size, decimation);
        Ok(Self {
            size,
            decimation,
            config,
            families: vec![(kind, layout)],
            decimated: Vec::new(),
            binary: Image::from_size_val(searched, Pixel::Skip).map_err(decoder_error)?,
            threshold: Threshold::default(),
        })
    }

    /// Whether this search reads a level of `size` decimated by `decimation`.
    pub(super) fn fits(&self, size: ImageSize, decimation: usize) -> bool {
        self.size == size && self.decimation == decimation
    }

    /// Thresholds `source` (decimated) and labels its regions into `scratch`: the regions
    /// large enough to start a quad (see `components.rs`); none when the searched image is
    /// smaller than a threshold tile.
    pub(super) fn regions(&mut self, source: &Image<u8, 1>, scratch: &mut Scratch) -> Result<u64> {
        let searched = self.binary.size();
        if searched.width < TILE || searched.height < TILE {
            scratch.components.label(&[], 1);
            return Ok(0);
        }
        let d = self.decimation.max(1);
        let (width, binary) = (searched.width, self.binary.as_slice_mut());
        let (split, least) = (THRESHOLD_SPLIT, MIN_WHITE_BLACK_DIFFERENCE);
        if d == 1 {
            self.threshold.apply(source.as_slice(), width, binary, least, split);
        } else {
            // One pixel of each `d x d` block, its top-left (the AprilTag library's decimation).
            let pixels = &mut self.decimated;
            pixels.clear();
            for row in source.as_slice().chunks_exact(source.width()).step_by(d).take(searched.height) {
                pixels.extend(row.iter().step_by(d));
            }
            self.threshold.apply(pixels, width, binary, least, split);
        }
        Ok(scratch.components.label(self.binary.as_slice(), searched.width))
    }

    /// The tags decoded in `source` from the regions [`Self::regions`] labelled last, their
    /// quads in `source`'s pixels (centres at `+0.5`).
    pub(super) fn decode(&mut self, source: &Image<u8, 1>, scratch: &mut Scratch) -> Vec<Detection> {
        let Scratch { components, clusters } = scratch;
        let (width, height) = (self.binary.width(), self.binary.height());
        // The quad fit returns no quad for the other clusters (and copies each before it looks).
        clusters.find(self.binary.as_slice(), width, components, MIN_QUAD_POINTS..=4 * (width + height));
        let mut quads = fit_quads(&self.binary, std::slice::from_ref(&clusters.map), &self.config);
        // The edges are refined over the decimation and one pixel, as the AprilTag library does.
        let refine_range = self.decimation as f32 + 1.0;
        let config = &self.config;
        let decoded = decode_tags(
            source,
            &mut quads,
            &self.families,
            config.refine_edges_enabled,
            config.decode_sharpening,
            refine_range,
        );
        dedup_detections(decoded)
    }
}

/// The size of an image of `size` decimated by `d` ([`decimated_side`]).
fn decimated_size(size: ImageSize, d: usize) -> ImageSize {
    ImageSize { width: decimated_side(size.width, d), height: decimated_side(size.height, d) }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use kornia_apriltag::AprilTagDecoder;

    use super::*;
    use crate::vision::tags::synthetic::{Placement, Rng, draw};

    /// A detection as a comparable record: id, bit errors, margin and quad (bits).
    fn record(d: &Detection) -> (u16, u8, u32, Vec<u32>) {
        let quad = d.quad.corners.iter().flat_map(|c| [c.x.to_bits(), c.y.to_bits()]).collect();
        (d.id, d.hamming, d.decision_margin.to_bits(), quad)
    }

    /// Tags of `family` drawn with clutter (dark squares and bars) and noise.
    fn cluttered(family: TagFamily, width: u32, height: u32, rng: &mut Rng) -> Image<u8, 1> {
        let tags: Vec<Placement> = (0..4)
            .map(|k| Placement {
                id: k * 3 + 1,
                centre: [f64::from(width) * (0.2 + 0.2 * k as f64), f64::from(height) * (0.3 + 0.12 * k as f64)],
                cell: 2.5 + 1.5 * k as f64 + rng.unit(),
                quarter_turns: k as u32,
            })
            .collect();
        let image = draw(family, width, height, &tags);
        let mut pixels = image.into_raw();
        for _ in 0..40 {
            let (u, v, side) = (rng.below(width as usize), rng.below(height as usize), 3 + rng.below(12));
            let level = rng.below(120) as u8;
            for y in v..(v + side).min(height as usize) {
                for x in u..(u + side * (1 + rng.below(3))).min(width as usize) {
                    pixels[y * width as usize + x] = level;
                }
            }
        }
        for p in &mut pixels {
            *p = p.saturating_add(rng.below(9) as u8).saturating_sub(4);
        }
        Image::new(ImageSize { width: width as usize, height: height as usize }, pixels).unwrap()
    }

    /// The same detections, bit for bit, as `kornia-apriltag`'s whole detector with the same
    /// settings, on cluttered noisy images of several families and decimations.
    #[test]
    fn decodes_what_kornias_detector_decodes() {
        let mut rng = Rng(13);
        let mut decoded = 0;
        for family in [TagFamily::Tag36h11, TagFamily::Tag16h5, TagFamily::TagStandard41h12, TagFamily::TagCircle21h7] {
            for (width, height) in [(320, 240), (257, 199)] {
                let image = cluttered(family, width, height, &mut rng);
                for decimation in [1, 2, 3] {
                    let mut search = LevelSearch::new(family, image.size(), decimation).unwrap();
                    let mut scratch = Scratch::default();
                    search.regions(&image, &mut scratch).unwrap();
                    let mut ours: Vec<_> = search.decode(&image, &mut scratch).iter().map(record).collect();
                    let mut kornia = AprilTagDecoder::new(search.config.clone(), image.size()).unwrap();
                    let mut theirs: Vec<_> = kornia.decode(&image).unwrap().iter().map(record).collect();
                    ours.sort_by(|a, b| a.partial_cmp(b).unwrap());
                    theirs.sort_by(|a, b| a.partial_cmp(b).unwrap());
                    assert_eq!(ours, theirs, "{family:?} {width} x {height} decimation {decimation}");
                    decoded += ours.len();
                }
            }
        }
        assert!(decoded >= 24, "{decoded} detections compared");
    }

    /// A level smaller than a threshold tile has no regions and decodes nothing.
    #[test]
    fn a_level_smaller_than_a_tile_has_no_regions() {
        let image = Image::<u8, 1>::from_size_val(ImageSize { width: 9, height: 30 }, 0).unwrap();
        let mut search = LevelSearch::new(TagFamily::Tag36h11, image.size(), 3).unwrap();
        let mut scratch = Scratch::default();
        assert_eq!(search.regions(&image, &mut scratch).unwrap(), 0);
        assert!(search.decode(&image, &mut scratch).is_empty());
    }
}
