//! AprilTags as a [`Detector`]: each corner of each decoded tag is a point, with identity
//! `4 * tag_id + corner` (corner 0..3 in the order of [`Tag::corners`](crate::vision::Tag)).
//! The detector needs no help: the expected pixels are ignored. After the first image each
//! tag is searched near its last corners, the whole image when one is lost (see
//! [`TagDetector`]). A tag that is not decoded (out of view, too small, occluded) is not reported: its
//! four corners are missing from the list, never reported at a wrong place.

use rayon::prelude::*;

use crate::error::Error;
use crate::vision::detector::tag_regions::{Region, merged};
use crate::vision::detector::{Detection, Detector, Expected};
use crate::vision::error::{Result, VisionError};
use crate::vision::image::{GreyBuffer, GreyView, Pixels, view};
use crate::vision::tags::{Tag, TagDecoder, TagFamily, TagFollower, automatic_decimation};

/// A whole-frame search every this many frames by default, so that tags coming into view (or
/// out from behind an occluder) are picked up while the others are tracked (half a second at
/// 30 frames a second).
pub const DEFAULT_REFRESH: u32 = 15;
/// Crops larger than this share of the frame are not worth cutting: the whole frame is read.
const MAX_CROP_SHARE: f64 = 0.5;
/// A tag read in a crop counts only with its corners this far inside the crop's cut sides.
const CROP_GUARD: f64 = 2.0;
/// Decoders kept for crop sizes seen lately.
const KEPT_CROP_DECODERS: usize = 32;

/// How a tag of the last frame of [`TagDetector::track`] was read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TagRead {
    /// Followed from its last corners: its edges measured again where they were and its bits
    /// read there ([`TagFollower`]), no quad search.
    Edges,
    /// Found by the quad search in a crop around its last corners.
    Crop,
    /// Found by the quad search in the whole frame.
    Whole,
}

impl TagRead {
    /// Its name: `"edges"`, `"crop"` or `"whole"`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Edges => "edges",
            Self::Crop => "crop",
            Self::Whole => "whole",
        }
    }
}

/// A tag of the last frame: where it was, how far it moved since the frame before (its
/// largest corner move, pixels) and its corners' moves.
#[derive(Debug, Clone, Copy)]
struct Last {
    tag: Tag,
    motion: f64,
    step: [[f64; 2]; 4],
}

/// Tags of one family, found in each image: after a frame, each tag is first followed from
/// its last corners with no quad search ([`TagFollower`]: its edges measured again near
/// them, its bits read there, accepted only as the same identity), then, when that fails,
/// searched in a
/// crop around its last corners (a margin proportional to its size plus its last
/// motion), and the whole frame is read when one of them is not found there, when the image
/// size changes, and every [`DEFAULT_REFRESH`] frames (to pick up tags coming into view).
/// The crops sit on the decoder's grid (4 x decimation pixels: its threshold tiles), so a tag
/// read in a crop is the one the whole frame gives, its corners within about 0.01 px: the
/// decoder's quad fit runs in f32 in the crop's coordinates, and the edge refinement after it
/// stops when its corners move by less than 0.05 px, keeping a trace of its start (1e-6 px on
/// fronto-parallel tags; 5e-9 px when the refinement is iterated to a fixed point).
#[derive(Debug)]
pub struct TagDetector {
    decoder: TagDecoder,
    /// The decimation asked for (None: the decoder's default), for the crops' decoders.
    decimation: Option<u32>,
    crops: Vec<((u32, u32), TagDecoder)>,
    /// Built at the first tracked frame.
    follower: Option<TagFollower>,
    /// Whether tags are followed from their last corners before any crop is searched.
    follow: bool,
    buffer: Vec<u8>,
    /// The tags of the last frame, how each was read, and that frame's size.
    last: Vec<Last>,
    reads: Vec<TagRead>,
    size: (u32, u32),
    refresh: u32,
    since_whole: u32,
    whole: bool,
    /// Whether a search of the last frame stopped early (a cluttered frame, see
    /// [`TagReport`](crate::vision::tags::TagReport)).
    stopped_early: bool,
}

impl TagDetector {
    /// A detector of `family`'s tags.
    pub fn new(family: TagFamily) -> Self {
        Self::build(TagDecoder::new(family), None)
    }

    /// A detector reading tags with `decoder` (e.g. [`TagDecoder::with_decimation`]).
    pub fn with_decoder(decoder: TagDecoder) -> Self {
        let decimation = decoder.decimation();
        Self::build(decoder, decimation)
    }

    fn build(decoder: TagDecoder, decimation: Option<u32>) -> Self {
        Self {
            decoder,
            decimation,
            crops: Vec::new(),
            follower: None,
            follow: true,
            buffer: Vec::new(),
            last: Vec::new(),
            reads: Vec::new(),
            size: (0, 0),
            refresh: DEFAULT_REFRESH,
            since_whole: 0,
            whole: true,
            stopped_early: false,
        }
    }

    /// The same, reading the whole frame every `frames` frames (1: every frame, no tracking;
    /// 0: only when a tag is lost or the size changes).
    pub fn with_refresh(mut self, frames: u32) -> Self {
        self.refresh = frames;
        self
    }

    /// The same, following each tag from its last corners first (`true`, the default) or
    /// searching each tracked tag's crop straight away (`false`: the quad search every frame).
    pub fn with_following(mut self, follow: bool) -> Self {
        self.follow = follow;
        self
    }

    /// The family it finds.
    pub fn family(&self) -> TagFamily {
        self.decoder.family()
    }

    /// The identity of corner `corner` (0..3) of tag `tag_id`: `4 * tag_id + corner`;
    /// `None` when it does not fit a `u32` or `corner > 3`.
    pub fn corner_id(tag_id: u32, corner: u32) -> Option<u32> {
        if corner > 3 {
            return None;
        }
        tag_id.checked_mul(4)?.checked_add(corner)
    }

    /// The tags in an image, as [`detect_tags`](crate::vision::detect_tags) (buffers reused;
    /// the whole image is read, the tracking is left as it was).
    pub fn tags<C: Pixels>(&mut self, image: &GreyBuffer<C>) -> Result<Vec<Tag>> {
        self.decoder.detect(image)
    }

    /// The tags in the next frame of a sequence, sorted by id: tracked near the last frame's
    /// when it can, read in the whole frame otherwise (see the type's documentation).
    pub fn track<C: Pixels>(&mut self, image: &GreyBuffer<C>) -> Result<Vec<Tag>> {
        let size = image.dimensions();
        self.stopped_early = false;
        let due = self.refresh != 0 && self.since_whole + 1 >= self.refresh;
        let tracked = if size == self.size && !due && !self.last.is_empty() { self.tracked(image)? } else { None };
        let (tags, reads) = match tracked {
            Some(found) => {
                self.since_whole += 1;
                found
            }
            None => {
                self.since_whole = 0;
                let report = self.decoder.detect_report(image)?;
                self.stopped_early = report.stopped_early;
                let tags = report.tags;
                let reads = vec![TagRead::Whole; tags.len()];
                (tags, reads)
            }
        };
        self.whole = self.since_whole == 0;
        self.remember(&tags, size);
        self.reads = reads;
        Ok(tags)
    }

    /// How each tag of the last frame of [`TagDetector::track`] was read, in the order of the
    /// tags it returned.
    pub fn reads(&self) -> &[TagRead] {
        &self.reads
    }

    /// The last frame's tags in this one: each followed from its last corners, those that
    /// cannot be searched in crops ([`TagDetector::in_crops`]); `None` when one is lost.
    fn tracked<C: Pixels>(&mut self, image: &GreyBuffer<C>) -> Result<Option<(Vec<Tag>, Vec<TagRead>)>> {
        if self.follow && self.follower.is_none() {
            self.follower = Some(TagFollower::new(self.decoder.family())?);
        }
        // Each tag's edges are read on its own (a tracked 1920 x 1080 frame of five tags spends
        // most of its time there): one tag a worker, on vsinv's pool (see `parallel`).
        let follower = self.follower.as_ref();
        let followed: Vec<Option<Tag>> = crate::parallel::install(|| {
            self.last.par_iter().map(|last| follower.and_then(|f| followed(f, image, last))).collect()
        })?;
        let mut found = Vec::with_capacity(self.last.len());
        let mut rest = Vec::new();
        for (last, tag) in self.last.iter().zip(followed) {
            match tag {
                Some(tag) => found.push((tag, TagRead::Edges)),
                None => rest.push(*last),
            }
        }
        if !rest.is_empty() {
            let Some(in_crops) = self.in_crops(image, &rest)? else { return Ok(None) };
            let new: Vec<Tag> = in_crops.into_iter().filter(|t| found.iter().all(|(f, _)| f.id != t.id)).collect();
            found.extend(new.into_iter().map(|t| (t, TagRead::Crop)));
        }
        found.sort_by_key(|(t, _)| t.id);
        Ok(Some(found.into_iter().unzip()))
    }

    /// Whether a quad search of the last frame of [`TagDetector::track`] stopped early (the
    /// frame too cluttered: see [`TagReport`](crate::vision::tags::TagReport)).
    pub fn stopped_early(&self) -> bool {
        self.stopped_early
    }

    /// Whether the last frame of [`TagDetector::track`] was read whole (not tracked in crops).
    pub fn read_whole(&self) -> bool {
        self.whole
    }

    /// Forgets the last frame: the next one is read whole.
    pub fn reset(&mut self) {
        self.last.clear();
        self.reads.clear();
        self.size = (0, 0);
    }

    /// The tags of `lasts`, each read in a crop around it (with any other tag read whole in
    /// those crops); `None` when one is not found there, two share an id, or the crops would
    /// cover too much of the frame.
    fn in_crops<C: Pixels>(&mut self, image: &GreyBuffer<C>, lasts: &[Last]) -> Result<Option<Vec<Tag>>> {
        let (width, height) = image.dimensions();
        // The crops are read at the decimation the whole frame is read at.
        let decimation = self.decimation.unwrap_or_else(|| automatic_decimation(width, height));
        let align = 4 * decimation;
        let regions: Option<Vec<Region>> =
            lasts.iter().map(|l| Region::around(&l.tag, l.motion, width, height, align)).collect();
        let Some(regions) = regions.map(merged) else { return Ok(None) };
        let area: u64 = regions.iter().map(Region::area).sum();
        if area as f64 > MAX_CROP_SHARE * f64::from(width) * f64::from(height) {
            return Ok(None);
        }
        let mut tags = Vec::new();
        for region in &regions {
            let found = self.read_crop(image, region, decimation)?;
            tags.extend(
                found.into_iter().filter(|t| t.corners.iter().all(|&c| region.holds(c, CROP_GUARD, width, height))),
            );
        }
        tags.sort_by_key(|t| t.id);
        let twice = tags.windows(2).any(|w| w[0].id == w[1].id);
        let lost = lasts.iter().any(|last| tags.binary_search_by_key(&last.tag.id, |t| t.id).is_err());
        Ok((!twice && !lost).then_some(tags))
    }

    /// The tags decoded in a copy of `region`, their corners in the whole image's pixels.
    fn read_crop<C: Pixels>(&mut self, image: &GreyBuffer<C>, region: &Region, decimation: u32) -> Result<Vec<Tag>> {
        let (w, h) = (region.x1 - region.x0, region.y1 - region.y0);
        self.buffer.clear();
        let raw: &[u8] = image.as_raw();
        let stride = image.width() as usize;
        for y in region.y0..region.y1 {
            let start = y as usize * stride + region.x0 as usize;
            let row = raw.get(start..start + w as usize).ok_or_else(|| crop_error("the image buffer is short"))?;
            self.buffer.extend_from_slice(row);
        }
        let crop = view("crop", w, h, &self.buffer)?;
        let decoder = crop_decoder(&mut self.crops, (w, h), self.decoder.family(), decimation)?;
        let report = decoder.detect_report(&crop)?;
        self.stopped_early |= report.stopped_early;
        let mut tags = report.tags;
        let offset = [f64::from(region.x0), f64::from(region.y0)];
        for tag in &mut tags {
            for c in &mut tag.corners {
                *c = [c[0] + offset[0], c[1] + offset[1]];
            }
        }
        Ok(tags)
    }

    /// Keeps `tags` with how far each moved since the last frame (0 for a new one).
    fn remember(&mut self, tags: &[Tag], size: (u32, u32)) {
        let last = |tag: &Tag| {
            let before = self.last.iter().find(|l| l.tag.id == tag.id);
            let step: [[f64; 2]; 4] = std::array::from_fn(|k| {
                before.map_or([0.0; 2], |l| [0, 1].map(|i| tag.corners[k][i] - l.tag.corners[k][i]))
            });
            let motion = step.iter().map(|s| s[0].hypot(s[1])).fold(0.0, f64::max);
            Last { tag: *tag, motion, step }
        };
        self.last = tags.iter().map(last).collect();
        self.size = size;
    }

    /// The corners of `tags` as detections, sorted by identity, all found.
    fn detections(tags: &[Tag]) -> Result<Vec<Detection>> {
        let mut out = Vec::with_capacity(4 * tags.len());
        for tag in tags {
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

/// The tag of `last` followed in `image` from its last corners, or from where its last step
/// would take them (see [`TagFollower::follow`]).
fn followed<C: Pixels>(follower: &TagFollower, image: &GreyBuffer<C>, last: &Last) -> Option<Tag> {
    let id = last.tag.id;
    follower.follow(image, id, &last.tag.corners).or_else(|| {
        let ahead: [[f64; 2]; 4] = std::array::from_fn(|k| [0, 1].map(|i| last.tag.corners[k][i] + last.step[k][i]));
        (last.motion > 0.0).then(|| follower.follow(image, id, &ahead)).flatten()
    })
}

/// The decoder kept for crops of `size` (a new one, the oldest dropped, when none is).
fn crop_decoder(
    crops: &mut Vec<((u32, u32), TagDecoder)>,
    size: (u32, u32),
    family: TagFamily,
    decimation: u32,
) -> Result<&mut TagDecoder> {
    let k = match crops.iter().position(|(s, d)| *s == size && d.decimation() == Some(decimation)) {
        Some(k) => k,
        None => {
            if crops.len() >= KEPT_CROP_DECODERS {
                crops.remove(0);
            }
            crops.push((size, TagDecoder::with_decimation(family, decimation)?));
            crops.len() - 1
        }
    };
    crops.get_mut(k).map(|(_, d)| d).ok_or_else(|| crop_error("no decoder"))
}

fn crop_error(reason: &str) -> VisionError {
    VisionError::InvalidImage { what: "image".to_string(), reason: format!("tag tracking failed: {reason}") }
}

impl Detector for TagDetector {
    /// The corners in the first image, read whole; `expected` is not needed and ignored.
    fn start(&mut self, image: &GreyView<'_>, _expected: &[Expected]) -> Result<Vec<Detection>> {
        self.reset();
        let tags = self.track(image)?;
        Self::detections(&tags)
    }

    /// The corners of the tags in `image` ([`TagDetector::track`]), sorted by identity, all found.
    fn detect(&mut self, image: &GreyView<'_>) -> Result<Vec<Detection>> {
        let tags = self.track(image)?;
        Self::detections(&tags)
    }

    fn stopped_early(&self) -> bool {
        TagDetector::stopped_early(self)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::vision::image::view_of;
    use crate::vision::tags::synthetic::{Placement, corners, draw};

    const FAMILY: TagFamily = TagFamily::Tag36h11;

    #[test]
    fn reports_four_corners_a_tag_under_their_identities() {
        let a = Placement { id: 3, centre: [60.0, 60.0], cell: 6.0, quarter_turns: 1 };
        let b = Placement { id: 0, centre: [150.0, 70.0], cell: 7.0, quarter_turns: 0 };
        let drawn = draw(FAMILY, 220, 130, &[a, b]);
        let image = view_of(&drawn).unwrap();
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
        let found = TagDetector::new(FAMILY).detect(&view_of(&image).unwrap()).unwrap();
        assert_eq!(found.iter().map(|d| d.id).collect::<Vec<_>>(), [12, 13, 14, 15]);
        let blank = draw(FAMILY, 220, 130, &[]);
        let blank = view_of(&blank).unwrap();
        assert!(TagDetector::new(FAMILY).detect(&blank).unwrap().is_empty());
        // Images of another size reuse nothing by mistake.
        let mut detector = TagDetector::new(FAMILY);
        assert_eq!(detector.detect(&blank).unwrap().len(), 0);
        let smaller = draw(FAMILY, 140, 120, &[a]);
        assert_eq!(detector.detect(&view_of(&smaller).unwrap()).unwrap().len(), 4);
    }

    #[test]
    fn corner_identities() {
        assert_eq!(TagDetector::corner_id(0, 0), Some(0));
        assert_eq!(TagDetector::corner_id(586, 3), Some(2347));
        assert_eq!(TagDetector::corner_id(1, 4), None);
        assert_eq!(TagDetector::corner_id(u32::MAX, 0), None);
    }

    /// Tracked frames give what the whole frame gives: same ids, corners within 1e-6 px.
    fn assert_same(tracked: &[Tag], whole: &[Tag], what: &str) {
        let ids = |t: &[Tag]| t.iter().map(|t| t.id).collect::<Vec<_>>();
        assert_eq!(ids(tracked), ids(whole), "{what}");
        for (a, b) in tracked.iter().zip(whole) {
            for (p, q) in a.corners.iter().zip(&b.corners) {
                assert!((p[0] - q[0]).abs() < 1e-6 && (p[1] - q[1]).abs() < 1e-6, "{what}: {p:?} vs {q:?}");
            }
        }
    }

    fn place(id: usize, u: f64, v: f64, cell: f64) -> Placement {
        Placement { id, centre: [u, v], cell, quarter_turns: 0 }
    }

    /// Three tags drifting by fractions of a pixel: every frame after the first is tracked in
    /// crops, and equals the whole-frame detection, at decimations 1 to 3.
    #[test]
    fn tracked_frames_equal_the_whole_frame() {
        for decimation in [1, 2, 3] {
            let decoder = || TagDecoder::with_decimation(FAMILY, decimation).unwrap();
            let mut tracker = TagDetector::with_decoder(decoder());
            let mut whole = decoder();
            for k in 0..12 {
                let t = f64::from(k);
                let tags = [
                    place(3, 70.0 + 0.37 * t, 80.0 - 0.21 * t, 5.0),
                    place(9, 330.0 - 0.45 * t, 90.0 + 0.3 * t, 7.0),
                    place(17, 190.0 + 0.13 * t, 270.0 + 0.52 * t, 6.0),
                ];
                let image = draw(FAMILY, 480, 360, &tags);
                let got = tracker.track(&image).unwrap();
                assert_eq!(tracker.read_whole(), k == 0, "decimation {decimation}, frame {k}");
                let read = if k == 0 { TagRead::Whole } else { TagRead::Edges };
                assert_eq!(tracker.reads(), [read; 3], "decimation {decimation}, frame {k}");
                assert_same(&got, &whole.detect(&image).unwrap(), &format!("decimation {decimation}, frame {k}"));
                assert_eq!(got.len(), 3);
            }
        }
    }

    /// A tag leaving the view makes that frame read whole (it is lost), and the others are
    /// tracked again after; a tag coming into view is picked up by the periodic whole read;
    /// a sudden jump out of the crop falls back to the whole frame.
    #[test]
    fn leaving_entering_and_jumping_tags() {
        let mut tracker = TagDetector::new(FAMILY).with_refresh(4);
        let mut whole = TagDecoder::new(FAMILY);
        let a = place(3, 60.0, 70.0, 6.0);
        let b = place(9, 200.0, 80.0, 6.0);
        let c = place(17, 120.0, 190.0, 6.0);
        let far = place(9, 260.0, 200.0, 6.0);
        // (tags in the frame, read whole, ids found)
        let script: [(&[Placement], bool, &[u32]); 12] = [
            (&[a, b], true, &[3, 9]),
            (&[a, b], false, &[3, 9]),
            (&[a], true, &[3]),     // 9 left: lost in its crop, whole frame
            (&[a, c], false, &[3]), // 17 came in far from 3: not seen until the refresh
            (&[a, c], false, &[3]),
            (&[a, c], false, &[3]),
            (&[a, c], true, &[3, 17]), // the 4th frame since the whole read
            (&[a, c, far], false, &[3, 17]),
            (&[a, c, b], false, &[3, 17]),
            (&[a, c, b], false, &[3, 17]),
            (&[a, c, far], true, &[3, 9, 17]),
            (&[a, c, b], true, &[3, 9, 17]), // 9 jumped out of its crop: whole frame
        ];
        for (k, (tags, read_whole, ids)) in script.iter().enumerate() {
            let image = draw(FAMILY, 320, 260, tags);
            let got = tracker.track(&image).unwrap();
            assert_eq!(tracker.read_whole(), *read_whole, "frame {k}");
            assert_eq!(got.iter().map(|t| t.id).collect::<Vec<_>>(), *ids, "frame {k}");
            let all = whole.detect(&image).unwrap();
            // Never an identity the whole frame does not have, nor other corners.
            let same: Vec<Tag> = all.iter().filter(|t| ids.contains(&t.id)).copied().collect();
            assert_same(&got, &same, &format!("frame {k}"));
            if *read_whole {
                assert_same(&got, &all, &format!("frame {k}"));
            }
        }
    }

    /// A tag replaced by another id at the same place is refused by the follower (its edges
    /// are there, its bits are not), lost in its crop, and the whole frame reads the new one;
    /// the same tag turned by a quarter is found by the crop search, with its corners in its
    /// new order. With the following off, each tracked tag is read in its crop.
    #[test]
    fn a_tag_replaced_or_turned_in_place_is_never_followed() {
        let other = place(9, 200.0, 80.0, 6.0);
        let turned = Placement { quarter_turns: 1, ..place(5, 70.6, 70.0, 6.0) };
        // (tags, reads in the order of the ids found, ids)
        let script: [(&[Placement], &[TagRead], &[u32]); 5] = [
            (&[place(3, 70.0, 70.0, 6.0), other], &[TagRead::Whole; 2], &[3, 9]),
            (&[place(3, 70.6, 70.0, 6.0), other], &[TagRead::Edges; 2], &[3, 9]),
            (&[place(5, 70.6, 70.0, 6.0), other], &[TagRead::Whole; 2], &[5, 9]),
            (&[turned, other], &[TagRead::Crop, TagRead::Edges], &[5, 9]),
            (&[turned, other], &[TagRead::Edges; 2], &[5, 9]),
        ];
        let mut tracker = TagDetector::new(FAMILY).with_refresh(0);
        let mut searched = TagDetector::new(FAMILY).with_refresh(0).with_following(false);
        let mut whole = TagDecoder::new(FAMILY);
        for (k, (tags, reads, ids)) in script.iter().enumerate() {
            let image = draw(FAMILY, 320, 200, tags);
            let got = tracker.track(&image).unwrap();
            assert_eq!(got.iter().map(|t| t.id).collect::<Vec<_>>(), *ids, "frame {k}");
            assert_eq!(tracker.reads(), *reads, "frame {k}");
            assert_same(&got, &whole.detect(&image).unwrap(), &format!("frame {k}"));
            assert_same(&searched.track(&image).unwrap(), &got, &format!("frame {k}, not followed"));
            assert!(searched.reads().iter().all(|r| *r != TagRead::Edges), "frame {k}");
        }
    }

    /// A tag that jumps within the margin is still tracked; a tag near another one is read
    /// with it in one merged crop; a change of image size reads the whole frame.
    #[test]
    fn small_jumps_neighbours_and_new_sizes() {
        let mut tracker = TagDetector::new(FAMILY);
        let mut whole = TagDecoder::new(FAMILY);
        let frames: [(u32, [Placement; 2], bool); 4] = [
            (320, [place(3, 100.0, 100.0, 6.0), place(4, 175.0, 100.0, 6.0)], true),
            (320, [place(3, 108.0, 104.0, 6.0), place(4, 183.0, 104.0, 6.0)], false),
            (320, [place(3, 110.0, 100.0, 6.0), place(4, 185.0, 100.0, 6.0)], false),
            (300, [place(3, 110.0, 100.0, 6.0), place(4, 185.0, 100.0, 6.0)], true),
        ];
        for (k, (width, tags, read_whole)) in frames.iter().enumerate() {
            let image = draw(FAMILY, *width, 240, tags);
            let got = tracker.track(&image).unwrap();
            assert_eq!(tracker.read_whole(), *read_whole, "frame {k}");
            assert_same(&got, &whole.detect(&image).unwrap(), &format!("frame {k}"));
            assert_eq!(got.len(), 2, "frame {k}");
        }
    }
}
