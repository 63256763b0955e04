//! Fuzzing the image decoders and the detectors (issue 28): [`check`] feeds bytes to every
//! image decoder (`decode_image`, what `load_image` calls once a file is read: PNG, PGM/PPM,
//! JPEG, GIF) and, read as raw pixels, to the tag detector (at the automatic decimation and at
//! 1 and 2) and the dot detector. A decoded image must be within the size limits, a detection
//! finite and every error the crate's own, naming its argument; a panic or an abort is a failure.
//!
//! CI replays the fixed corpus of `tests/fixtures/fuzz/` (made by its `make_corpus.py`) and
//! checks what each file holds, then a fixed sequence of mutations of it (byte edits, most of
//! them in the headers, truncations, runs of one byte inserted). `make fuzz` runs the
//! mutations on new random draws for `VSINV_FUZZ_SECONDS` seconds (stable Rust: proptest's
//! runner, no nightly fuzzing engine).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestRunner};
use vsinv::vision::image::{GreyBuffer, MAX_IMAGE_PIXELS, MAX_IMAGE_SIDE, Pixels, decode_image, view};
use vsinv::vision::tags::{TagDecoder, TagFamily};
use vsinv::vision::{DetectConfig, detect_dots};

/// Decoded images up to this many pixels are also searched (larger ones, which a mutated
/// header can declare, are only decoded: the search would just take longer).
const SEARCHED_PIXELS: u64 = 1 << 16;

/// The fuzz target: `data` as an image file, then as a raw image (its first byte the width
/// less one, then the pixels row by row).
pub fn check(data: &[u8]) {
    match decode_image("fuzzed", data) {
        Ok(image) => {
            let (w, h) = image.dimensions();
            assert!(w <= MAX_IMAGE_SIDE && h <= MAX_IMAGE_SIDE && u64::from(w) * u64::from(h) <= MAX_IMAGE_PIXELS);
            if u64::from(w) * u64::from(h) <= SEARCHED_PIXELS {
                detectors(&image);
            }
        }
        Err(e) => assert!(e.to_string().starts_with("fuzzed: "), "{e}"),
    }
    if let Some((&first, pixels)) = data.split_first() {
        let width = usize::from(first) + 1;
        let height = pixels.len() / width;
        if height > 0 {
            let image = view("raw", width as u32, height as u32, &pixels[..width * height]).unwrap();
            detectors(&image);
        }
    }
}

/// The tag and dot detectors on one image: finite results or the crate's errors.
fn detectors<C: Pixels>(image: &GreyBuffer<C>) {
    for decimation in [None, Some(1), Some(2)] {
        let mut decoder = match decimation {
            Some(d) => TagDecoder::with_decimation(TagFamily::Tag36h11, d).unwrap(),
            None => TagDecoder::new(TagFamily::Tag36h11),
        };
        for tag in decoder.detect(image).unwrap() {
            assert!(tag.corners.as_flattened().iter().all(|c| c.is_finite()), "{tag:?}");
        }
    }
    match detect_dots(image, &DetectConfig::default()) {
        Ok(dots) => assert!(dots.iter().all(|d| d.centroid.iter().all(|c| c.is_finite()) && d.area > 0.0)),
        Err(e) => assert!(e.to_string().starts_with("image: "), "{e}"),
    }
}

fn corpus() -> Vec<(PathBuf, Vec<u8>)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/fuzz");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e != "py"))
        .collect();
    files.sort();
    files.into_iter().map(|p| (p.clone(), std::fs::read(p).unwrap())).collect()
}

#[test]
fn the_corpus_decodes_to_what_it_holds() {
    let corpus = corpus();
    assert!(corpus.len() >= 20, "{} files", corpus.len());
    for (path, data) in &corpus {
        check(data);
        let name = path.file_name().unwrap().to_str().unwrap();
        let decoded = decode_image("fuzzed", data);
        match name {
            "grey16.png" | "truncated.png" | "truncated.jpg" | "tag.raw" | "dots.raw" => {
                assert!(decoded.is_err(), "{name}")
            }
            "ascii.pgm" => assert_eq!(decoded.unwrap().into_raw(), (0..240).step_by(20).collect::<Vec<u8>>()),
            "rgb.ppm" => assert_eq!(decoded.unwrap().dimensions(), (20, 20)),
            "progressive.jpg" => assert_eq!(decoded.unwrap().dimensions(), (24, 24)),
            "dots.png" => assert_eq!(detect_dots(&decoded.unwrap(), &DetectConfig::default()).unwrap().len(), 4),
            _ => {
                // The 40 x 40 tag image in every other variant: tag36h11 id 3.
                let image = decoded.unwrap_or_else(|e| panic!("{name}: {e}"));
                let tags = TagDecoder::new(TagFamily::Tag36h11).detect(&image).unwrap();
                assert_eq!(tags.iter().map(|t| t.id).collect::<Vec<_>>(), [3], "{name}");
            }
        }
    }
    // The raw images, as the target reads them.
    let raw = |name: &str| corpus.iter().find(|(p, _)| p.ends_with(name)).unwrap().1.clone();
    let tag = raw("tag.raw");
    let image = view("raw", u32::from(tag[0]) + 1, 40, &tag[1..]).unwrap();
    assert_eq!(TagDecoder::new(TagFamily::Tag36h11).detect(&image).unwrap()[0].id, 3);
    let dots = raw("dots.raw");
    let image = view("raw", u32::from(dots[0]) + 1, 32, &dots[1..]).unwrap();
    assert_eq!(detect_dots(&image, &DetectConfig::default()).unwrap().len(), 4);
}

/// A corpus file changed: bytes set (half of them in the first 64 bytes, the headers), then
/// cut short, then a run of one byte inserted; a PNG file's chunk checksums then made right
/// again when `fix_crc` (else the decoder refuses nearly every mutation at the first checksum).
#[derive(Debug, Clone)]
struct Mutation {
    file: usize,
    edits: Vec<(usize, u8)>,
    cut: Option<usize>,
    run: Option<(usize, u8, usize)>,
    fix_crc: bool,
}

impl Mutation {
    fn apply(&self, corpus: &[(PathBuf, Vec<u8>)]) -> Vec<u8> {
        let mut data = corpus[self.file % corpus.len()].1.clone();
        for &(at, byte) in &self.edits {
            if !data.is_empty() {
                let i = at % data.len();
                data[i] = byte;
            }
        }
        if let Some(cut) = self.cut {
            data.truncate(cut % (data.len() + 1));
        }
        if let Some((at, byte, n)) = self.run {
            let i = at % (data.len() + 1);
            data.splice(i..i, std::iter::repeat_n(byte, n));
        }
        if self.fix_crc {
            fix_png_crcs(&mut data);
        }
        data
    }
}

/// Sets the CRC-32 of every whole chunk of a PNG file to its type and data's.
fn fix_png_crcs(data: &mut [u8]) {
    if !data.starts_with(b"\x89PNG\r\n\x1a\n") {
        return;
    }
    let mut at = 8;
    while at + 12 <= data.len() {
        let len = u32::from_be_bytes(data[at..at + 4].try_into().unwrap()) as usize;
        let Some(end) = (at + 8).checked_add(len).filter(|&e| e + 4 <= data.len()) else { return };
        let crc = crc32(&data[at + 4..end]);
        data[end..end + 4].copy_from_slice(&crc.to_be_bytes());
        at = end + 4;
    }
}

fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
        }
    }
    !crc
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let position = prop_oneof![0..64usize, any::<usize>()];
    let byte = prop_oneof![Just(0u8), Just(0xFF), Just(0x7F), Just(0x80), any::<u8>()];
    (
        any::<usize>(),
        prop::collection::vec((position.clone(), byte.clone()), 0..8),
        prop::option::weighted(0.2, any::<usize>()),
        prop::option::weighted(0.2, (position, byte, 1..256usize)),
        prop::bool::weighted(0.7),
    )
        .prop_map(|(file, edits, cut, run, fix_crc)| Mutation { file, edits, cut, run, fix_crc })
}

fn run_mutations(corpus: &[(PathBuf, Vec<u8>)], cases: u32, rng_seed: RngSeed) -> u32 {
    let config = Config { cases, failure_persistence: None, rng_seed, ..Config::default() };
    if let Err(e) = TestRunner::new(config).run(&mutation(), |m| {
        check(&m.apply(corpus));
        Ok(())
    }) {
        panic!("{e}");
    }
    cases
}

#[test]
fn mutations_of_the_corpus() {
    let corpus = corpus();
    let seconds = std::env::var("VSINV_FUZZ_SECONDS").ok().and_then(|s| s.parse::<u64>().ok());
    let random = std::env::var_os("VSINV_PROPTEST_RANDOM").is_some();
    let Some(seconds) = seconds else {
        // CI: a fixed sequence (a red run means a bug, not a draw).
        run_mutations(&corpus, 256, if random { RngSeed::Random } else { RngSeed::Fixed(0x5eed) });
        return;
    };
    let deadline = Instant::now() + Duration::from_secs(seconds);
    let mut cases = 0;
    while Instant::now() < deadline {
        cases += run_mutations(&corpus, 64, RngSeed::Random);
    }
    eprintln!("fuzz_images: {cases} mutated files in {seconds} s, no failure");
}
