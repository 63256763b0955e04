//! Compressed camera frames: the PNG or JPEG bytes of a ROS `sensor_msgs/CompressedImage`
//! (image_transport's `compressed` transport) decoded to 8-bit grey, as an image file's bytes
//! are ([`decode_image`]: the declared size checked against the pixel limit before anything
//! is decoded, the decoder's memory bounded, a truncated JPEG refused, colour by Rec. 601
//! luma), but only PNG or JPEG, and only the one the message says when it says one.

use crate::input_file::MAX_IMAGE_BYTES;
use crate::vision::error::{Result, VisionError};
use crate::vision::image::{GreyImage, decode_image};

/// The compression of a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compression {
    /// PNG (lossless).
    Png,
    /// JPEG (baseline or progressive).
    Jpeg,
}

impl Compression {
    /// The compression whose signature `bytes` start with, if PNG or JPEG.
    pub fn of(bytes: &[u8]) -> Option<Self> {
        match ::image::guess_format(bytes).ok()? {
            ::image::ImageFormat::Png => Some(Self::Png),
            ::image::ImageFormat::Jpeg => Some(Self::Jpeg),
            _ => None,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Self::Png => "png",
            Self::Jpeg => "jpeg",
        }
    }
}

/// The grey image of a compressed frame's `bytes`; with `expected`, bytes of the other
/// compression are refused. `what` names the frame in errors: empty data, more than
/// [`MAX_IMAGE_BYTES`], neither PNG nor JPEG, the other compression, a declared size over the
/// pixel limit, a corrupt or truncated image, more than 8 bits a sample.
pub fn decode_compressed(what: &str, bytes: &[u8], expected: Option<Compression>) -> Result<GreyImage> {
    if bytes.is_empty() {
        return Err(invalid(what, "no data".into()));
    }
    if bytes.len() as u64 > MAX_IMAGE_BYTES {
        return Err(invalid(what, format!("{} bytes of data: more than {MAX_IMAGE_BYTES}", bytes.len())));
    }
    let Some(found) = Compression::of(bytes) else {
        return Err(invalid(what, "neither PNG nor JPEG data (unknown signature)".into()));
    };
    if let Some(expected) = expected.filter(|&e| e != found) {
        return Err(invalid(what, format!("the format says {} but the data is {}", expected.name(), found.name())));
    }
    decode_image(what, bytes)
}

fn invalid(what: &str, reason: String) -> VisionError {
    VisionError::InvalidImage { what: what.to_string(), reason }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    fn png(width: u32, height: u32, data: &[u8]) -> Vec<u8> {
        let img = GreyImage::from_raw(width, height, data.to_vec()).unwrap();
        let mut out = std::io::Cursor::new(Vec::new());
        img.write_to(&mut out, ::image::ImageFormat::Png).unwrap();
        out.into_inner()
    }

    #[test]
    fn png_round_trips_and_formats_are_checked() {
        let pixels: Vec<u8> = (0..35u8).map(|i| i * 7).collect();
        let bytes = png(7, 5, &pixels);
        assert_eq!(Compression::of(&bytes), Some(Compression::Png));
        assert_eq!(decode_compressed("frame", &bytes, None).unwrap().into_raw(), pixels);
        assert_eq!(decode_compressed("frame", &bytes, Some(Compression::Png)).unwrap().into_raw(), pixels);
        let wrong = decode_compressed("frame", &bytes, Some(Compression::Jpeg)).unwrap_err().to_string();
        assert!(wrong.contains("says jpeg but the data is png"), "{wrong}");
        let pgm = [b"P5\n1 1\n255\n".as_slice(), &[7]].concat();
        assert!(decode_compressed("frame", &pgm, None).unwrap_err().to_string().contains("neither PNG nor JPEG"));
        assert!(decode_compressed("frame", &[], None).unwrap_err().to_string().contains("no data"));
        let cut = decode_compressed("frame", &bytes[..bytes.len() / 2], None).unwrap_err().to_string();
        assert!(cut.starts_with("frame: "), "{cut}");
    }

    /// CRC-32 (ISO 3309, PNG's), bit by bit.
    fn crc32(data: &[u8]) -> u32 {
        let mut crc = !0u32;
        for &b in data {
            crc ^= u32::from(b);
            for _ in 0..8 {
                crc = if crc & 1 == 1 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
            }
        }
        !crc
    }

    #[test]
    fn a_header_over_the_pixel_limit_is_refused_before_decoding() {
        // A PNG whose IHDR declares 40000 x 40000 (1.6e9 pixels, over 2^28) and holds no data.
        let mut bytes = png(1, 1, &[0]);
        bytes[16..20].copy_from_slice(&40_000u32.to_be_bytes());
        bytes[20..24].copy_from_slice(&40_000u32.to_be_bytes());
        let crc = crc32(&bytes[12..29]); // the chunk's type and data
        bytes[29..33].copy_from_slice(&crc.to_be_bytes());
        let err = decode_compressed("frame", &bytes, None).unwrap_err().to_string();
        assert!(err.contains("too large"), "{err}");
    }
}
