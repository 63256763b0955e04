//! PNG files, read with the `png` crate's own decoder rather than through the `image` crate,
//! for two of its options the `image` crate does not pass on: the colour profile (iCCP) and
//! the text chunks (tEXt, zTXt, iTXt) are skipped unread. They are ancillary (an 8-bit grey
//! image does not need them) and the profile and the compressed text are deflated streams: a
//! few hundred kilobytes of file inflate to hundreds of megabytes (a colour-profile bomb) that
//! the pixel limits do not cover. No other chunk the decoder reads is compressed.

use std::io::Cursor;

use ::image::{DynamicImage, ImageBuffer};
use png::{BitDepth, ColorType, DecodingError, Transformations};

use super::{MAX_IMAGE_ALLOC, check_dimensions, image_error};
use crate::vision::error::Result;

/// The first frame of a PNG file as 8-bit samples (palettes and grey levels below 8 bits
/// expanded); 16-bit samples are refused. The declared size is checked against
/// [`check_dimensions`] before any pixel is allocated, and the decoder's allocations are held
/// to [`MAX_IMAGE_ALLOC`].
pub(super) fn decode(what: &str, bytes: &[u8]) -> Result<DynamicImage> {
    let invalid = |e: DecodingError| image_error(what, format!("not a valid PNG image ({})", reason(&e)));
    let bytes_limit = usize::try_from(MAX_IMAGE_ALLOC).unwrap_or(usize::MAX);
    let mut decoder = png::Decoder::new_with_limits(Cursor::new(bytes), png::Limits { bytes: bytes_limit });
    decoder.set_ignore_iccp_chunk(true);
    decoder.set_ignore_text_chunk(true);
    let (width, height) = decoder.read_header_info().map(|info| info.size()).map_err(invalid)?;
    check_dimensions(what, u64::from(width), u64::from(height))?;
    decoder.set_transformations(Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(invalid)?;
    let (color, depth) = reader.output_color_type();
    if depth != BitDepth::Eight {
        let reason = format!(
            "{color:?} {}-bit samples: only 8-bit images are read (convert 16-bit images to 8 bits first)",
            depth as u8
        );
        return Err(image_error(what, reason));
    }
    let size = reader.output_buffer_size().ok_or_else(|| image_error(what, "not a valid PNG image (too large)"))?;
    let mut buf = vec![0; size];
    let frame = reader.next_frame(&mut buf).map_err(invalid)?;
    buf.truncate(frame.buffer_size());
    let image = match color {
        ColorType::Grayscale => ImageBuffer::from_raw(width, height, buf).map(DynamicImage::ImageLuma8),
        ColorType::GrayscaleAlpha => ImageBuffer::from_raw(width, height, buf).map(DynamicImage::ImageLumaA8),
        ColorType::Rgb => ImageBuffer::from_raw(width, height, buf).map(DynamicImage::ImageRgb8),
        ColorType::Rgba => ImageBuffer::from_raw(width, height, buf).map(DynamicImage::ImageRgba8),
        ColorType::Indexed => None,
    };
    image.ok_or_else(|| image_error(what, "not a valid PNG image (corrupt or truncated)"))
}

/// What went wrong, in the decoder's words for limits, as a category otherwise (a malformed
/// file's details may quote its bytes).
fn reason(e: &DecodingError) -> String {
    match e {
        DecodingError::LimitsExceeded => format!("decoding would take more than {MAX_IMAGE_ALLOC} bytes"),
        DecodingError::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => "truncated".into(),
        DecodingError::IoError(_) => "read error".into(),
        _ => "corrupt or truncated".into(),
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// A PNG chunk: length, type, data, CRC-32 (computed bit by bit, independent of the decoder).
    fn chunk(kind: &[u8; 4], data: &[u8]) -> Vec<u8> {
        let mut crc = !0u32;
        for &b in kind.iter().chain(data) {
            crc ^= u32::from(b);
            for _ in 0..8 {
                crc = if crc & 1 == 1 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
            }
        }
        [&(data.len() as u32).to_be_bytes()[..], kind, data, &(!crc).to_be_bytes()].concat()
    }

    /// A zlib stream of `data` in stored (uncompressed) blocks.
    fn stored_zlib(data: &[u8]) -> Vec<u8> {
        let mut out = vec![0x78, 0x01];
        let blocks: Vec<&[u8]> = data.chunks(65_535).collect();
        for (i, block) in blocks.iter().enumerate() {
            out.push(u8::from(i + 1 == blocks.len()));
            let n = block.len() as u16;
            out.extend(n.to_le_bytes());
            out.extend((!n).to_le_bytes());
            out.extend_from_slice(block);
        }
        let (mut a, mut b) = (1u32, 0u32);
        for &x in data {
            a = (a + u32::from(x)) % 65_521;
            b = (b + a) % 65_521;
        }
        out.extend(((b << 16) | a).to_be_bytes());
        out
    }

    /// A 2 x 2 grey PNG with `extra` chunks before its pixels.
    fn png_with(extra: &[Vec<u8>]) -> Vec<u8> {
        let ihdr = [&2u32.to_be_bytes()[..], &2u32.to_be_bytes(), &[8, 0, 0, 0, 0]].concat();
        let pixels = stored_zlib(&[0, 10, 20, 0, 30, 40]);
        let mut file = b"\x89PNG\r\n\x1a\n".to_vec();
        file.extend(chunk(b"IHDR", &ihdr));
        extra.iter().for_each(|c| file.extend(c));
        file.extend(chunk(b"IDAT", &pixels));
        file.extend(chunk(b"IEND", &[]));
        file
    }

    #[test]
    fn ancillary_compressed_chunks_are_skipped_and_pixels_read() {
        let plain = decode("a.png", &png_with(&[])).unwrap().into_luma8().into_raw();
        assert_eq!(plain, vec![10, 20, 30, 40]);
        // A profile and text whose compressed streams are corrupt: skipped unread, so the
        // pixels come out the same (read, a corrupt stream would be an error).
        let iccp = chunk(b"iCCP", &[b"icc\0\0".as_slice(), &[0x78, 0x9c, 0xff, 0xff, 0xff]].concat());
        let ztxt = chunk(b"zTXt", &[b"Comment\0\0".as_slice(), &[0x78, 0x9c, 0xff, 0xff]].concat());
        let itxt = chunk(b"iTXt", &[b"Comment\0\x01\0\0\0".as_slice(), &[0x78, 0x9c, 0xff, 0xff]].concat());
        let hostile = decode("a.png", &png_with(&[iccp, ztxt, itxt])).unwrap().into_luma8().into_raw();
        assert_eq!(hostile, plain);
    }

    #[test]
    fn declared_size_is_checked_before_decoding() {
        let mut file = png_with(&[]);
        // IHDR's width (bytes 16..20 of the file) set to 2^20, its CRC made right again.
        let ihdr = [&(1u32 << 20).to_be_bytes()[..], &2u32.to_be_bytes(), &[8, 0, 0, 0, 0]].concat();
        file.splice(8..33, chunk(b"IHDR", &ihdr));
        let err = decode("big.png", &file).unwrap_err().to_string();
        assert!(err.contains("too large") && err.contains("big.png"), "{err}");
    }
}
