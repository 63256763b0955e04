//! AprilTag detection ([`detect_tags`]): the tags of one family found in an image, each with
//! its id and its four corners, by the AprilTag 3 detector (Wang & Olson, "AprilTag 2:
//! Efficient and robust fiducial detection", IROS 2016; Krogius, Haggenmiller & Olson,
//! "Flexible layouts for fiducial tags", IROS 2019): its threshold, regions and gradient
//! clusters here (`level.rs`, `components.rs`, `clusters.rs`), its quad fit and decoding from
//! `kornia-apriltag` (a pure-Rust port), on every level of a pyramid (`pyramid.rs`).
//!
//! # Corners: order and pixel convention
//!
//! The corners are reported as OpenCV's `cv::aruco::ArucoDetector` reports them for the same
//! family (`DICT_APRILTAG_36h11`, ...), so the two can be swapped:
//!
//! - **Pixel convention:** pixel `(u, v)` covers `[u - 0.5, u + 0.5] x [v - 0.5, v + 0.5]`
//!   (its centre is at integer coordinates), as OpenCV and [`detect_dots`](super::detect_dots).
//!   The AprilTag library (and so `kornia-apriltag`, ViSP and its published ground truth)
//!   puts pixel centres at `u + 0.5`; its corners are moved by `-0.5` here.
//! - **Order:** OpenCV's: top-left, top-right, bottom-right, bottom-left of the marker as
//!   OpenCV's `generateImageMarker` draws it, which is clockwise in an image with `v`
//!   pointing down. OpenCV draws the AprilTag families rotated by half a turn with respect to
//!   the AprilTag library's own images (the `apriltag-imgs` PNG files, the family's
//!   `bit_x`/`bit_y` layout with `y` down): in that layout, corner 0 is the bottom-right
//!   corner of the black square, then bottom-left, top-left and top-right
//!   ([`TAG_CORNERS_IN_LAYOUT`]). The AprilTag library reports bottom-left, bottom-right,
//!   top-right, top-left of its layout (ViSP's ground-truth files too).
//!
//! # Corners: accuracy
//!
//! The detector's corners are measured again on the black square's outer edges
//! (`src/vision/tags/edges.rs`): subpixel, unbiased on anti-aliased or blurred edges, and a tag whose edges
//! do not support its corners is not reported (never reported with a wrong corner).

mod budget;
mod clusters;
mod components;
mod edge_search;
mod edges;
mod face;
mod follow;
mod level;
mod profile;
mod pyramid;
mod smoothed;
mod threshold;

pub use self::budget::{MAX_MEASURED_CANDIDATES, MAX_SEARCHED_REGIONS, TagReport};
pub use self::face::TagFace;

use kornia_apriltag::family::TagFamilyKind;
use kornia_image::Image;

pub use follow::TagFollower;

use crate::error::Error;
use crate::vision::error::{Result, VisionError};
use crate::vision::image::{GreyBuffer, Pixels, check_image};

/// The tag families [`detect_tags`] reads, declared once (`FAMILIES`): AprilTag 3's nine
/// (the classic four are also OpenCV aruco's `DICT_APRILTAG_*`, whose corner order is checked
/// against it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub enum TagFamily {
    /// tag36h11: 587 ids, 6 x 6 data bits, minimum Hamming distance 11 (the recommended family).
    #[default]
    Tag36h11,
    /// tag36h10: 2320 ids, 6 x 6 data bits, minimum Hamming distance 10.
    Tag36h10,
    /// tag25h9: 35 ids, 5 x 5 data bits, minimum Hamming distance 9.
    Tag25h9,
    /// tag16h5: 30 ids, 4 x 4 data bits, minimum Hamming distance 5 (false positives likely).
    Tag16h5,
    /// tagStandard41h12 (AprilTag 3's recommended family): 2115 ids, 41 bits, minimum Hamming
    /// distance 12; its square is white inside a black ring, with data bits inside and outside.
    TagStandard41h12,
    /// tagStandard52h13: 48714 ids (those up to 65534 are read), 52 bits, distance 13.
    TagStandard52h13,
    /// tagCircle21h7: 38 ids, 21 bits, distance 7 (a round tag around a white square).
    TagCircle21h7,
    /// tagCircle49h12: 65535 ids (those up to 65534 are read), 49 bits, distance 12.
    TagCircle49h12,
    /// tagCustom48h12: 42211 ids, 48 bits, distance 12 (a square hole for a custom pattern).
    TagCustom48h12,
}

/// The one declaration of the families: each with its name (AprilTag's, as Python spells it).
/// Everything else is read from kornia-apriltag's family of that name (its layout and codes):
/// by the decoder, the renderer ([`TagFace`]), the scenario key `object.tag_family` and
/// Python's `TAG_FAMILIES`. Adding a family is a variant and a row here.
const FAMILIES: [(TagFamily, &str); 9] = [
    (TagFamily::Tag36h11, "tag36h11"),
    (TagFamily::Tag36h10, "tag36h10"),
    (TagFamily::Tag25h9, "tag25h9"),
    (TagFamily::Tag16h5, "tag16h5"),
    (TagFamily::TagStandard41h12, "tagStandard41h12"),
    (TagFamily::TagStandard52h13, "tagStandard52h13"),
    (TagFamily::TagCircle21h7, "tagCircle21h7"),
    (TagFamily::TagCircle49h12, "tagCircle49h12"),
    (TagFamily::TagCustom48h12, "tagCustom48h12"),
];

impl TagFamily {
    /// The names, as Python spells them (AprilTag's names), in the order of [`TagFamily::ALL`].
    pub const NAMES: [&'static str; FAMILIES.len()] = {
        let mut names = [""; FAMILIES.len()];
        let mut i = 0;
        while i < FAMILIES.len() {
            names[i] = FAMILIES[i].1;
            i += 1;
        }
        names
    };
    /// Every family.
    pub const ALL: [Self; FAMILIES.len()] = {
        let mut all = [Self::Tag36h11; FAMILIES.len()];
        let mut i = 0;
        while i < FAMILIES.len() {
            all[i] = FAMILIES[i].0;
            i += 1;
        }
        all
    };

    /// The family of a name (`"tag36h11"`, ...), `None` for another name.
    pub fn from_name(name: &str) -> Option<Self> {
        FAMILIES.iter().find(|(_, n)| *n == name).map(|(f, _)| *f)
    }

    /// The name of a family.
    pub fn name(self) -> &'static str {
        FAMILIES.iter().find(|(f, _)| *f == self).map_or("", |(_, n)| n)
    }

    /// Whether the family's square is white inside a black ring (AprilTag 3's families), not
    /// black inside the white quiet zone (the layout's `reversed_border`).
    pub fn reversed_border(self) -> bool {
        face::layout(self).is_ok_and(|l| l.reversed_border)
    }

    /// Cells across the square whose corners are reported (the layout's `width_at_border`).
    pub fn border_cells(self) -> u32 {
        face::layout(self).map_or(1, |l| u32::try_from(l.width_at_border).unwrap_or(1))
    }

    /// The most bit errors a decoded tag may have: two (the AprilTag library's default), one
    /// for tag16h5, whose codes are only five bits apart (with two, random squares of the
    /// coarse levels decode as tags).
    pub fn max_bit_errors(self) -> u8 {
        match self {
            Self::Tag16h5 => 1,
            _ => 2,
        }
    }

    /// kornia-apriltag's family of the same name (`tagStandard41h12` is its
    /// `tagstandard41_h12`).
    fn kind(self) -> TagFamilyKind {
        let name = self.name().to_lowercase();
        let kornia = match name.rfind('h') {
            Some(h) => format!("{}_{}", &name[..h], &name[h..]),
            None => name,
        };
        kornia.parse().unwrap_or(TagFamilyKind::Tag36H11)
    }
}

/// Where the corners of [`Tag::corners`] are in the family's own layout (the AprilTag
/// library's `bit_x`/`bit_y` frame: `x` right, `y` down, unit one data cell, `(0, 0)` the
/// top-left corner of the black square, whose side is `width_at_border` cells: 8 for
/// tag36h11, 7 for tag25h9, 6 for tag16h5), as fractions of that side: corner `k` is at
/// `TAG_CORNERS_IN_LAYOUT[k] * width_at_border`.
pub const TAG_CORNERS_IN_LAYOUT: [[f64; 2]; 4] = [[1.0, 1.0], [0.0, 1.0], [0.0, 0.0], [1.0, 0.0]];

/// A tag found in an image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tag {
    /// Its id in the family.
    pub id: u32,
    /// The corners `(u, v)` of its black square, pixels, in OpenCV's order and convention
    /// (see the [module docs](self)).
    pub corners: [[f64; 2]; 4],
}

/// Finds the tags of `family` in an 8-bit grey image, sorted by id (an id seen twice is
/// reported once, the detection with the best decoding margin). An empty image is an
/// error; an image without tags gives an empty list.
pub fn detect_tags<C: Pixels>(image: &GreyBuffer<C>, family: TagFamily) -> Result<Vec<Tag>> {
    TagDecoder::new(family).detect(image)
}

/// [`detect_tags`], saying whether the search stopped early on a cluttered frame (the work
/// per frame is bounded: [`MAX_SEARCHED_REGIONS`], [`MAX_MEASURED_CANDIDATES`]).
pub fn detect_tags_report<C: Pixels>(image: &GreyBuffer<C>, family: TagFamily) -> Result<TagReport> {
    TagDecoder::new(family).detect_report(image)
}

/// A tag detector kept from image to image: its buffers are reused while the image size
/// stays the same ([`detect_tags`] makes a new one each call).
///
/// Quads are searched at several scales: in the image shrunk by the decimation (by the
/// AprilTag detector's own decimation), then in the image halved again and again (each
/// pixel the mean of those it covers, see `pyramid.rs`) down to [`MIN_LEVEL_SIDE`] pixels,
/// so a tag is found whatever its size in the image, and its corners are always measured on
/// the full image's edges.
pub struct TagDecoder {
    family: TagFamily,
    /// `None`: chosen per image ([`automatic_decimation`]).
    decimation: Option<u32>,
    /// One search per level, for the size it reads and its own decimation.
    levels: Vec<level::LevelSearch>,
    /// The image and its halves, as the levels read them.
    pyramid: pyramid::Pyramid,
    /// The regions and clusters of the level searched.
    scratch: level::Scratch,
}

/// AprilTag's own default decimation, for callers that fix one ([`TagDecoder::new`] chooses it
/// per image: [`automatic_decimation`]).
pub const DEFAULT_DECIMATION: u32 = 2;
/// [`automatic_decimation`] keeps the finest search's shorter side at least this long.
pub const AUTOMATIC_MIN_SIDE: u32 = 480;
/// Where the adaptive threshold splits black from white between a tile's darkest and
/// brightest pixels: the AprilTag library's midpoint (kornia's default, a third, breaks the
/// black border of blurred tags into white).
const THRESHOLD_SPLIT: f32 = 0.5;
/// The contrast (grey levels between the darkest and brightest pixel around a 4 x 4 tile)
/// below which a tile of the threshold is left out of the quad search (`level.rs`).
///
/// Why 15 and not the AprilTag library's 5: on a real photograph the background's faint
/// texture (paper grain, a wall, shadows) passes 5 everywhere and becomes thousands of small
/// clusters that the quad fit reads one by one: on ViSP's `AprilTag.pgm` (640 x 480, 12
/// tags) the search at decimation 1 took 33 ms at 5 and 4.7 ms at 15, with the same 12 tags.
/// A tag's own contrast is its black border against its white quiet zone, far above 15 even
/// blurred or in dim light (tests: a tag of contrast 24 is found); OpenCV's aruco leaves out
/// the same faint texture (a pixel is black only 7 grey levels below its neighbourhood's mean).
const MIN_WHITE_BLACK_DIFFERENCE: u8 = 15;

/// The decimation [`TagDecoder::new`] chooses for a `width x height` image: the largest that
/// keeps the finest search's shorter side at least [`AUTOMATIC_MIN_SIDE`] pixels (1 up to
/// 959 pixels, 2 at 1920 x 1080, 4 at 3840 x 2160), so the smallest tag it finds is about the
/// same share of the image at any resolution (larger tags are found on the coarser levels).
/// A larger one is taken when the search would read more than [`MAX_SEARCH_PIXELS`] (a long
/// strip of an image, or one of more than 2^24 pixels).
pub fn automatic_decimation(width: u32, height: u32) -> u32 {
    let preferred = (width.min(height) / AUTOMATIC_MIN_SIDE).clamp(1, MAX_DECIMATION);
    (preferred..=MAX_DECIMATION)
        .find(|&d| searched_pixels(width, height, d) <= MAX_SEARCH_PIXELS)
        .unwrap_or(MAX_DECIMATION)
}

/// The most pixels the finest quad search reads (the image shrunk by the decimation), which
/// bounds the detector's memory: `kornia-apriltag` takes up to about 70 bytes a searched pixel
/// (its connected components and edge clusters, on noise; 50 on stripes or a checkerboard).
/// 2^22 (2048 x 2048; 1920 x 1080 is searched at decimation 1), plus 2^14 for the rounding up
/// of the largest image [`check_dimensions`](crate::vision::image::check_dimensions) accepts
/// ([`MAX_IMAGE_PIXELS`](crate::vision::image::MAX_IMAGE_PIXELS)) decimated by
/// [`MAX_DECIMATION`], so that every image has a decimation that fits.
pub const MAX_SEARCH_PIXELS: u64 = (1 << 22) + (1 << 14);

/// The pixels of the image `width x height` shrunk by `decimation` (rounded up, as the
/// detector does).
pub fn searched_pixels(width: u32, height: u32, decimation: u32) -> u64 {
    let side = |s: u32| decimated_side(s as usize, decimation as usize) as u64;
    side(width) * side(height)
}

/// A side of `side` pixels decimated by `decimation` (one pixel of each `d x d` block, the
/// last block partial: rounded up, as the detector decimates).
fn decimated_side(side: usize, decimation: usize) -> usize {
    side.div_ceil(decimation.max(1))
}

/// Refuses a decimation that leaves more than [`MAX_SEARCH_PIXELS`] to search, naming the
/// smallest that fits.
fn check_search(width: u32, height: u32, decimation: u32) -> Result<()> {
    let searched = searched_pixels(width, height, decimation);
    if searched <= MAX_SEARCH_PIXELS {
        return Ok(());
    }
    let fits = (decimation..=MAX_DECIMATION)
        .find(|&d| searched_pixels(width, height, d) <= MAX_SEARCH_PIXELS)
        .unwrap_or(MAX_DECIMATION);
    Err(Error::InvalidParameter {
        name: "decimation",
        reason: format!(
            "{decimation} leaves {searched} pixels of this {height} x {width} image to search, at most \
             {MAX_SEARCH_PIXELS} are searched (the detector's memory): use decimation >= {fits}"
        ),
    }
    .into())
}
/// The largest decimation accepted.
pub const MAX_DECIMATION: u32 = 8;
/// The coarsest level searched has no side shorter than this (pixels): a tag filling most
/// of the image is some 30 to 60 pixels wide there, a size the quad fit reads.
pub const MIN_LEVEL_SIDE: u32 = 40;

impl std::fmt::Debug for TagDecoder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TagDecoder")
            .field("family", &self.family)
            .field("decimation", &self.decimation)
            .finish_non_exhaustive()
    }
}

fn decoder_error(reason: impl std::fmt::Display) -> VisionError {
    VisionError::InvalidImage { what: "image".to_string(), reason: format!("tag detection failed: {reason}") }
}

/// The smallest side the detector reads: its adaptive threshold works on 4 x 4 tiles of the
/// image decimated by 2. A smaller image cannot hold a readable tag and gives none.
const MIN_SIDE: u32 = 8;

/// A decoded tag: its bit errors and decoding margin, its id and its corners as the detector puts them, in
/// OpenCV's order and convention (before they are measured on the edges).
type Candidate = ((u8, f32), u32, [[f64; 2]; 4]);

impl TagDecoder {
    /// A detector of `family`'s tags, which chooses the decimation per image
    /// ([`automatic_decimation`]).
    pub fn new(family: TagFamily) -> Self {
        Self { family, decimation: None, levels: Vec::new(), pyramid: Default::default(), scratch: Default::default() }
    }

    /// A detector whose finest quad search is in the image shrunk by `decimation` (`1..=8`;
    /// coarser levels follow, and the corners are always measured at full resolution). A
    /// larger decimation is faster; a smaller one finds smaller tags.
    pub fn with_decimation(family: TagFamily, decimation: u32) -> Result<Self> {
        if !(1..=MAX_DECIMATION).contains(&decimation) {
            return Err(Error::InvalidParameter {
                name: "decimation",
                reason: format!("must be in 1..={MAX_DECIMATION}, got {decimation}"),
            }
            .into());
        }
        Ok(Self {
            family,
            decimation: Some(decimation),
            levels: Vec::new(),
            pyramid: Default::default(),
            scratch: Default::default(),
        })
    }

    /// The decimation of the finest quad search, `None` when chosen per image.
    pub fn decimation(&self) -> Option<u32> {
        self.decimation
    }

    /// The family it finds.
    pub fn family(&self) -> TagFamily {
        self.family
    }

    /// The tags in `image`, as [`detect_tags`].
    pub fn detect<C: Pixels>(&mut self, image: &GreyBuffer<C>) -> Result<Vec<Tag>> {
        Ok(self.detect_report(image)?.tags)
    }

    /// The tags in `image` and whether the search stopped early, as [`detect_tags_report`].
    pub fn detect_report<C: Pixels>(&mut self, image: &GreyBuffer<C>) -> Result<TagReport> {
        check_image("image", image)?;
        if image.width() < MIN_SIDE || image.height() < MIN_SIDE {
            return Ok(TagReport::default());
        }
        let decimation = self.decimation.unwrap_or_else(|| automatic_decimation(image.width(), image.height()));
        check_search(image.width(), image.height(), decimation)?;
        let mut budget = budget::Budget::new();
        // The levels are kept in the decoder (their buffers reused), out of it while searched.
        let mut pyramid = std::mem::take(&mut self.pyramid);
        // One hand-off to vsinv's pool a frame: kornia's threshold, quad fit and decoding of
        // every level run with rayon there, where their own `install`s stay on the worker. Each
        // hand-off wakes a pool thread, which on a loaded machine waits to be scheduled: one a
        // level costs more than the search of a small image's coarse levels.
        let search = || self.search_levels(&mut pyramid, &mut budget, image, decimation);
        let candidates = crate::parallel::install(search)?;
        self.pyramid = pyramid;
        let mut candidates = candidates?;
        let border =
            edges::Border { cells: f64::from(self.family.border_cells()), reversed: self.family.reversed_border() };
        let max_errors = self.family.max_bit_errors();
        candidates.retain(|&((errors, _), _, _)| errors <= max_errors);
        // Per id, the measured candidate with the fewest bit errors, then the best margin.
        let (tags, stopped) = budget::measure_best_first(candidates, |corners| {
            edges::refine_corners(image, corners, border)
                .or_else(|| smoothed::refine_corners(image, corners, border))
                .or_else(|| edges::refine_blurred_corners(image, corners, border))
        });
        Ok(TagReport { tags, stopped_early: budget.stopped_early || stopped })
    }

    /// The candidates of every level: the image at `decimation`, then halved again and again
    /// (the halves finer than the decimation are not searched) down to [`MIN_LEVEL_SIDE`].
    fn search_levels<C: Pixels>(
        &mut self,
        pyramid: &mut pyramid::Pyramid,
        budget: &mut budget::Budget,
        image: &GreyBuffer<C>,
        decimation: u32,
    ) -> Result<Vec<Candidate>> {
        let full = pyramid.set(image).ok_or_else(|| decoder_error("short buffer"))?;
        let mut candidates = self.search_within(budget, 0, full, decimation, 1.0)?;
        let (mut k, mut level) = (0, 0);
        loop {
            k += 1;
            let Some(next) = pyramid.halve(k) else { break };
            if next.width().min(next.height()) < MIN_LEVEL_SIDE as usize {
                break;
            }
            let scale = 1u32 << k;
            if scale > decimation {
                level += 1;
                candidates.extend(self.search_within(budget, level, next, 1, f64::from(scale))?);
            }
        }
        Ok(candidates)
    }

    /// The tags decoded in `source` (a level `scale` times smaller than the full image, searched
    /// at `decimation`), with their corners in the full image: none when its regions do not fit
    /// in what is left of the frame's budget ([`budget::Budget::admit`]).
    fn search_within(
        &mut self,
        budget: &mut budget::Budget,
        level: usize,
        source: &Image<u8, 1>,
        decimation: u32,
        scale: f64,
    ) -> Result<Vec<Candidate>> {
        let Self { family, levels, scratch, .. } = self;
        let (size, decimation) = (source.size(), decimation as usize);
        if levels.get(level).is_none_or(|l| !l.fits(size, decimation)) {
            levels.truncate(level);
            levels.push(level::LevelSearch::new(*family, size, decimation)?);
        }
        let search = levels.get_mut(level).ok_or_else(|| decoder_error("no level"))?;
        if !budget.admit(search.regions(source, scratch)?) {
            return Ok(Vec::new());
        }
        Ok(search
            .decode(source, scratch)
            .iter()
            .map(|d| {
                // The decoded homography maps the tag frame (x right, y down in the AprilTag
                // layout, the black square at -1..1) to the level, with pixel centres at +0.5
                // (so a level point p is at scale * p in the full image); OpenCV's order is the
                // layout's bottom-right, bottom-left, top-left, top-right.
                let corner = |(x, y): (f32, f32)| {
                    let p = d.quad.homography_project(x, y);
                    [f64::from(p.x) * scale - 0.5, f64::from(p.y) * scale - 0.5]
                };
                let corners = [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)].map(corner);
                ((d.hamming, d.decision_margin), u32::from(d.id), corners)
            })
            .collect())
    }
}

/// Tags drawn in closed form for the tests: a fronto-parallel tag, turned by quarter turns,
/// each pixel the exact area average of the cells it overlaps (a perfect box-filter camera).
#[cfg(test)]
#[allow(clippy::unwrap_used)]
pub(crate) mod synthetic {
    use kornia_apriltag::family::TagFamily as Layout;

    use super::{TAG_CORNERS_IN_LAYOUT, TagFamily};
    use crate::vision::image::GreyImage;

    /// A small deterministic generator (xorshift64*), so that the tests need no crate.
    pub struct Rng(pub u64);

    impl Rng {
        pub fn next(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
        }

        pub fn below(&mut self, n: usize) -> usize {
            (self.next() % n as u64) as usize
        }

        pub fn unit(&mut self) -> f64 {
            (self.next() >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// Where a tag is drawn: the centre of its black square `(u, v)` in pixels (OpenCV's
    /// convention), the side of one cell in pixels, and quarter turns (counter-clockwise on the
    /// screen, `v` down) of the layout.
    #[derive(Debug, Clone, Copy)]
    pub struct Placement {
        pub id: usize,
        pub centre: [f64; 2],
        pub cell: f64,
        pub quarter_turns: u32,
    }

    fn layout(family: TagFamily) -> Layout {
        Layout::try_from(&family.kind()).unwrap()
    }

    /// Layout point (cells, from the black square's top-left) to pixel.
    fn to_pixel(p: &Placement, half: f64, x: f64, y: f64) -> [f64; 2] {
        let (dx, dy) = ((x - half) * p.cell, (y - half) * p.cell);
        let (dx, dy) = (0..p.quarter_turns % 4).fold((dx, dy), |(a, b), _| (b, -a));
        [p.centre[0] + dx, p.centre[1] + dy]
    }

    /// The true corners of a drawn tag, in [`Tag::corners`](super::Tag)'s order.
    pub fn corners(family: TagFamily, p: &Placement) -> [[f64; 2]; 4] {
        let w = layout(family).width_at_border as f64;
        TAG_CORNERS_IN_LAYOUT.map(|[x, y]| to_pixel(p, w / 2.0, x * w, y * w))
    }

    /// Draws tags (black 30, white 220) on a white `width x height` image: each tag's face
    /// ([`TagFace`](super::TagFace)), its grid's cells that are not white drawn black (a round
    /// face's grid whole, its corners black too).
    pub fn draw(family: TagFamily, width: u32, height: u32, tags: &[Placement]) -> GreyImage {
        let mut darkness = vec![0.0f64; (width * height) as usize];
        for p in tags {
            let face = super::TagFace::new(family, p.id as u32).unwrap();
            let half = face.total as f64 / 2.0;
            for (y, row) in face.white.iter().enumerate() {
                for (x, &white) in row.iter().enumerate() {
                    if !white {
                        let a = to_pixel(p, half, x as f64, y as f64);
                        let b = to_pixel(p, half, (x + 1) as f64, (y + 1) as f64);
                        paint(&mut darkness, width, [a[0].min(b[0]), a[1].min(b[1])], [a[0].max(b[0]), a[1].max(b[1])]);
                    }
                }
            }
        }
        let grey = darkness.iter().map(|d| (220.0 - 190.0 * d.min(1.0)).round() as u8).collect();
        GreyImage::from_raw(width, height, grey).unwrap()
    }

    /// Adds the area of the rectangle `lo..hi` (pixels) to each pixel it overlaps.
    fn paint(darkness: &mut [f64], width: u32, lo: [f64; 2], hi: [f64; 2]) {
        let height = darkness.len() as u32 / width;
        let overlap = |c: f64, a: f64, b: f64| ((c + 0.5).min(b) - (c - 0.5).max(a)).max(0.0);
        let first = |a: f64| (a + 0.5).floor().max(0.0) as u32;
        for v in first(lo[1])..(first(hi[1]) + 1).min(height) {
            for u in first(lo[0])..(first(hi[0]) + 1).min(width) {
                let area = overlap(f64::from(u), lo[0], hi[0]) * overlap(f64::from(v), lo[1], hi[1]);
                darkness[(v * width + u) as usize] += area;
            }
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::synthetic::{Placement, corners, draw};
    use super::*;
    use crate::vision::image::GreyImage;

    /// On these closed-form images the corners of the AprilTag 3 detector alone (kornia-apriltag)
    /// are off by 0.25-0.33 px (median 0.28), up to 0.45 px once blurred; measured again on
    /// the edges they are off by at most 0.003 px sharp, 0.1 px with a blur up to a quarter
    /// of a cell, 0.37 px when the blur reaches the data cells (sigma 1.5 px, 4 px cells).
    const SHARP_TOLERANCE: f64 = 0.01;
    const BLURRED_TOLERANCE: f64 = 0.12;
    const VERY_BLURRED_TOLERANCE: f64 = 0.5;

    fn worst_error(found: &[[f64; 2]; 4], truth: &[[f64; 2]; 4]) -> f64 {
        found.iter().zip(truth).map(|(f, t)| (f[0] - t[0]).hypot(f[1] - t[1])).fold(0.0, f64::max)
    }

    #[test]
    fn finds_drawn_tags_at_their_closed_form_corners_in_every_orientation() {
        for quarter_turns in 0..4 {
            for (cell, centre) in [(6.0, [80.0, 60.0]), (7.3, [81.37, 58.81]), (11.0, [90.5, 70.25])] {
                let p = Placement { id: 17, centre, cell, quarter_turns };
                let image = draw(TagFamily::Tag36h11, 180, 140, &[p]);
                let tags = detect_tags(&image, TagFamily::Tag36h11).unwrap();
                let truth = corners(TagFamily::Tag36h11, &p);
                assert_eq!(tags.len(), 1, "{p:?}");
                assert_eq!(tags[0].id, 17);
                let error = worst_error(&tags[0].corners, &truth);
                assert!(error < SHARP_TOLERANCE, "{p:?}: {:?} vs {truth:?}", tags[0].corners);
            }
        }
    }

    #[test]
    fn blurred_tags_keep_their_corners() {
        for sigma in [0.6f32, 1.0, 1.5] {
            for quarter_turns in 0..4 {
                for (cell, centre) in [(4.0, [70.2, 60.7]), (7.3, [81.37, 58.81])] {
                    let p = Placement { id: 101, centre, cell, quarter_turns };
                    let image = imageproc::filter::gaussian_blur_f32(&draw(TagFamily::Tag36h11, 180, 140, &[p]), sigma);
                    let tags = detect_tags(&image, TagFamily::Tag36h11).unwrap();
                    assert_eq!(tags.iter().map(|t| t.id).collect::<Vec<_>>(), [101], "{p:?} sigma {sigma}");
                    let error = worst_error(&tags[0].corners, &corners(TagFamily::Tag36h11, &p));
                    let tolerance =
                        if f64::from(sigma) <= cell / 4.0 { BLURRED_TOLERANCE } else { VERY_BLURRED_TOLERANCE };
                    assert!(error < tolerance, "{p:?} sigma {sigma}: {error}");
                }
            }
        }
    }

    #[test]
    fn several_tags_sorted_by_id_in_every_family() {
        for family in TagFamily::ALL {
            let tags = [(9, [60.0, 50.0], 0), (2, [160.0, 55.0], 3), (5, [110.0, 130.0], 2)];
            let placed = tags.map(|(id, centre, quarter_turns)| Placement { id, centre, cell: 7.0, quarter_turns });
            let found = detect_tags(&draw(family, 220, 180, &placed), family).unwrap();
            assert_eq!(found.iter().map(|t| t.id).collect::<Vec<_>>(), [2, 5, 9], "{family:?}");
            for tag in &found {
                let p = placed.iter().find(|p| p.id as u32 == tag.id).unwrap();
                assert!(worst_error(&tag.corners, &corners(family, p)) < SHARP_TOLERANCE, "{family:?} {tag:?}");
            }
            assert_eq!(TagFamily::from_name(family.name()), Some(family));
        }
        assert_eq!(TagFamily::NAMES.map(|n| TagFamily::from_name(n).unwrap().name()), TagFamily::NAMES);
        assert_eq!(TagFamily::from_name("tag36h12"), None);
    }

    #[test]
    fn every_decimation_finds_the_same_corners() {
        let placed = [(4, [60.0, 55.0], 0), (8, [170.0, 60.0], 1)].map(|(id, centre, quarter_turns)| Placement {
            id,
            centre,
            cell: 9.0,
            quarter_turns,
        });
        let image = draw(TagFamily::Tag36h11, 240, 120, &placed);
        for decimation in 1..=4 {
            let mut decoder = TagDecoder::with_decimation(TagFamily::Tag36h11, decimation).unwrap();
            assert_eq!(decoder.decimation(), Some(decimation));
            let tags = decoder.detect(&image).unwrap();
            assert_eq!(tags.iter().map(|t| t.id).collect::<Vec<_>>(), [4, 8], "decimation {decimation}");
            for (tag, p) in tags.iter().zip(&placed) {
                assert!(worst_error(&tag.corners, &corners(TagFamily::Tag36h11, p)) < SHARP_TOLERANCE, "{decimation}");
            }
        }
        assert_eq!(TagDecoder::new(TagFamily::Tag16h5).decimation(), None);
        assert_eq!(
            [(320, 240), (640, 480), (1920, 1080), (3840, 2160), (1, 100_000)].map(|(w, h)| automatic_decimation(w, h)),
            [1, 1, 2, 4, 1]
        );
        for bad in [0, MAX_DECIMATION + 1, u32::MAX] {
            let err = TagDecoder::with_decimation(TagFamily::Tag36h11, bad).unwrap_err();
            assert!(err.to_string().contains("decimation"), "{err}");
        }
    }

    /// Large tags far from the image's origin: the quad fit of the finest level alone loses
    /// them (its single-precision sums); a coarser level finds them, at every decimation.
    #[test]
    fn tags_of_every_size_are_found_anywhere_at_every_decimation() {
        for decimation in [1, 2] {
            let mut decoder = TagDecoder::with_decimation(TagFamily::Tag36h11, decimation).unwrap();
            for (cell, centre) in
                [(5.0, [1050.3, 770.6]), (16.0, [900.2, 600.7]), (30.0, [700.4, 450.1]), (52.0, [620.5, 430.5])]
            {
                let p = Placement { id: 33, centre, cell, quarter_turns: 1 };
                let image = draw(TagFamily::Tag36h11, 1200, 880, &[p]);
                let tags = decoder.detect(&image).unwrap();
                assert_eq!(tags.iter().map(|t| t.id).collect::<Vec<_>>(), [33], "cell {cell}, decimation {decimation}");
                let error = worst_error(&tags[0].corners, &corners(TagFamily::Tag36h11, &p));
                assert!(error < SHARP_TOLERANCE, "cell {cell}, decimation {decimation}: {error}");
            }
        }
    }

    #[test]
    fn border_cells_are_the_layouts() {
        for family in TagFamily::NAMES.map(|n| TagFamily::from_name(n).unwrap()) {
            let layout = kornia_apriltag::family::TagFamily::try_from(&family.kind()).unwrap();
            assert_eq!(family.border_cells() as usize, layout.width_at_border, "{family:?}");
        }
    }

    #[test]
    fn empty_images_are_refused_and_small_or_blank_ones_have_no_tags() {
        let err = detect_tags(&GreyImage::new(0, 0), TagFamily::Tag36h11).unwrap_err();
        assert!(matches!(err, VisionError::InvalidImage { .. }), "{err}");
        assert!(err.to_string().contains("image"), "{err}");
        assert!(detect_tags(&GreyImage::new(5, 0), TagFamily::Tag36h11).is_err());
        for (w, h) in [(1, 1), (2, 3), (7, 100), (100, 7), (8, 8), (9, 13), (1000, 1), (1, 1000), (640, 480)] {
            for level in [0u8, 128, 255] {
                let image = GreyImage::from_pixel(w, h, ::image::Luma([level]));
                assert!(detect_tags(&image, TagFamily::Tag36h11).unwrap().is_empty(), "{w} x {h}");
            }
        }
        // Borrowed bytes read as an owned image.
        let p = Placement { id: 1, centre: [40.0, 40.0], cell: 6.0, quarter_turns: 0 };
        let owned = draw(TagFamily::Tag36h11, 80, 80, &[p]);
        let view = crate::vision::image::view("image", 80, 80, owned.as_raw()).unwrap();
        assert_eq!(detect_tags(&view, TagFamily::Tag36h11).unwrap(), detect_tags(&owned, TagFamily::Tag36h11).unwrap());
    }

    #[test]
    fn every_accepted_image_has_a_decimation_within_the_search_bound() {
        use crate::vision::image::{MAX_IMAGE_PIXELS, MAX_IMAGE_SIDE};
        // The extremes check_dimensions accepts: the longest strips and the squares just
        // under 2^28 pixels whose sides are not multiples of 8 (rounded up when decimated).
        let side = MAX_IMAGE_SIDE;
        let strip = (MAX_IMAGE_PIXELS / u64::from(side)) as u32;
        for (w, h) in [(side, strip), (strip, side), (side, 1), (16_385, 16_383), (16_383, 16_385), (16_000, 16_000)] {
            assert!(u64::from(w) * u64::from(h) <= MAX_IMAGE_PIXELS);
            let d = automatic_decimation(w, h);
            // Independent count: the decimated sides as (side + d - 1) / d, in floating point.
            let n = (f64::from(w) / f64::from(d)).ceil() * (f64::from(h) / f64::from(d)).ceil();
            assert!(n <= MAX_SEARCH_PIXELS as f64, "{w} x {h}: decimation {d} leaves {n}");
            assert!(check_search(w, h, d).is_ok());
        }
        // The automatic choice is unchanged where it fits (issue 27's figures).
        assert_eq!([automatic_decimation(640, 480), automatic_decimation(1920, 1080)], [1, 2]);
        assert_eq!(automatic_decimation(3840, 2160), 4);
        // A long strip is decimated more than its short side asks for.
        assert_eq!(automatic_decimation(65_536, 600), 4);
    }

    #[test]
    fn a_decimation_leaving_too_many_pixels_is_refused_before_allocating() {
        // 16000 x 16000 at decimation 1 would take ~15 GB in the detector: refused with the
        // decimation that fits. The image is a zero-filled buffer the detector never reads.
        let image = GreyImage::new(16_000, 16_000);
        let err = TagDecoder::with_decimation(TagFamily::Tag36h11, 1).unwrap().detect(&image).unwrap_err();
        let text = err.to_string();
        assert!(matches!(err, VisionError::Core(Error::InvalidParameter { name: "decimation", .. })), "{text}");
        assert!(text.contains("use decimation >= 8") && text.contains(&MAX_SEARCH_PIXELS.to_string()), "{text}");
        assert!(check_search(2048, 2048, 1).is_ok() && check_search(2049, 2100, 1).is_err());
    }
}
