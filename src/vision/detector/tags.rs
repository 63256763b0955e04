//! AprilTags as a [`Detector`]: each corner of each decoded tag is a point, with identity
//! `4 * tag_id + corner` (corner 0..3 in the order of [`Tag::corners`](crate::vision::Tag)).
//! The detector needs no help: the expected pixels are ignored, and every image is read
//! afresh. A tag that is not decoded (out of view, too small, occluded) is not reported: its
//! four corners are missing from the list, never reported at a wrong place.

use crate::error::{Error, Result};
use crate::vision::detector::{Detection, Detector, Expected};
use crate::vision::image::GreyImage;
use crate::vision::tags::{Tag, TagDecoder, TagFamily};

/// Tags of one family, found in each image.
#[derive(Debug)]
pub struct TagDetector {
    decoder: TagDecoder,
}

impl TagDetector {
    /// A detector of `family`'s tags.
    pub fn new(family: TagFamily) -> Self {
        Self { decoder: TagDecoder::new(family) }
    }

    /// A detector reading tags with `decoder` (e.g. [`TagDecoder::with_decimation`]).
    pub fn with_decoder(decoder: TagDecoder) -> Self {
        Self { decoder }
    }

    /// The identity of corner `corner` (0..3) of tag `tag_id`: `4 * tag_id + corner`;
    /// `None` when it does not fit a `u32` or `corner > 3`.
    pub fn corner_id(tag_id: u32, corner: u32) -> Option<u32> {
        if corner > 3 {
            return None;
        }
        tag_id.checked_mul(4)?.checked_add(corner)
    }

    /// The tags in an image, as [`detect_tags`](crate::vision::detect_tags) (buffers reused).
    pub fn tags(&mut self, image: &GreyImage) -> Result<Vec<Tag>> {
        self.decoder.detect(image)
    }
}

impl Detector for TagDetector {
    /// The corners in the first image; `expected` is not needed and ignored.
    fn start(&mut self, image: &GreyImage, _expected: &[Expected]) -> Result<Vec<Detection>> {
        self.detect(image)
    }

    /// The corners of the tags decoded in `image`, sorted by identity, all found.
    fn detect(&mut self, image: &GreyImage) -> Result<Vec<Detection>> {
        let mut out = Vec::new();
        for tag in self.decoder.detect(image)? {
            for (corner, &pixel) in (0u32..).zip(&tag.corners) {
                let id = Self::corner_id(tag.id, corner).ok_or_else(|| Error::InvalidParameter {
                    name: "tag id",
                    reason: format!("tag {} has no corner identity in u32", tag.id),
                })?;
                out.push(Detection { id, pixel, found: true });
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::vision::tags::synthetic::{Placement, corners, draw};

    const FAMILY: TagFamily = TagFamily::Tag36h11;

    #[test]
    fn reports_four_corners_a_tag_under_their_identities() {
        let a = Placement { id: 3, centre: [60.0, 60.0], cell: 6.0, quarter_turns: 1 };
        let b = Placement { id: 0, centre: [150.0, 70.0], cell: 7.0, quarter_turns: 0 };
        let image = draw(FAMILY, 220, 130, &[a, b]);
        let mut detector = TagDetector::new(FAMILY);
        // The hints are ignored: none, or wrong ones, give the same answer.
        let wrong = [Expected { id: 5, pixel: [1.0, 1.0] }];
        let started = detector.start(&image, &wrong).unwrap();
        assert_eq!(started, detector.detect(&image).unwrap());
        assert_eq!(started, TagDetector::new(FAMILY).detect(&image).unwrap());
        let ids: Vec<u32> = started.iter().map(|d| d.id).collect();
        assert_eq!(ids, [0, 1, 2, 3, 12, 13, 14, 15]);
        assert!(started.iter().all(|d| d.found));
        let tags = detector.tags(&image).unwrap();
        for (k, d) in started.iter().enumerate() {
            assert_eq!(d.pixel, tags[k / 4].corners[k % 4]);
        }
        for (tag, placement) in tags.iter().zip([b, a]) {
            let truth = corners(FAMILY, &placement);
            for (found, want) in tag.corners.iter().zip(truth) {
                assert!((found[0] - want[0]).hypot(found[1] - want[1]) < 0.35, "{found:?} vs {want:?}");
            }
        }
    }

    #[test]
    fn a_tag_half_out_of_view_drops_its_four_corners() {
        let a = Placement { id: 3, centre: [60.0, 60.0], cell: 6.0, quarter_turns: 0 };
        let b = Placement { id: 8, centre: [215.0, 60.0], cell: 6.0, quarter_turns: 0 };
        let image = draw(FAMILY, 220, 130, &[a, b]);
        let found = TagDetector::new(FAMILY).detect(&image).unwrap();
        assert_eq!(found.iter().map(|d| d.id).collect::<Vec<_>>(), [12, 13, 14, 15]);
        let blank = draw(FAMILY, 220, 130, &[]);
        assert!(TagDetector::new(FAMILY).detect(&blank).unwrap().is_empty());
        // Images of another size reuse nothing by mistake.
        let mut detector = TagDetector::new(FAMILY);
        assert_eq!(detector.detect(&blank).unwrap().len(), 0);
        assert_eq!(detector.detect(&draw(FAMILY, 140, 120, &[a])).unwrap().len(), 4);
    }

    #[test]
    fn corner_identities() {
        assert_eq!(TagDetector::corner_id(0, 0), Some(0));
        assert_eq!(TagDetector::corner_id(586, 3), Some(2347));
        assert_eq!(TagDetector::corner_id(1, 4), None);
        assert_eq!(TagDetector::corner_id(u32::MAX, 0), None);
    }
}
