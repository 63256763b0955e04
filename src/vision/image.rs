//! 8-bit grey images: the `image` crate's `GrayImage` (row-major, `(height, width)`), its
//! checks and image files (PNG, PGM/PPM, JPEG).

mod png_file;

use std::path::Path;

use crate::vision::error::{Result, VisionError};

/// An 8-bit grey image, row-major: pixel `(u, v)` is `data[v * width + u]`.
pub type GreyImage = ::image::GrayImage;

/// An 8-bit grey image over any row-major buffer: an owned [`GreyImage`], or borrowed bytes
/// (`GreyBuffer<&[u8]>`, e.g. a NumPy array read in place).
pub type GreyBuffer<C> = ::image::ImageBuffer<::image::Luma<u8>, C>;

/// Borrowed row-major bytes read as an image, in place: what a [`Detector`](crate::vision::Detector)
/// reads (a NumPy array, a camera's frame buffer, or an owned image through [`view_of`]).
pub type GreyView<'a> = GreyBuffer<&'a [u8]>;

/// Any grey buffer seen as a [`GreyView`] (no copy).
pub fn view_of<C: Pixels>(image: &GreyBuffer<C>) -> Result<GreyView<'_>> {
    let data: &[u8] = image.as_raw();
    let len = image.width() as usize * image.height() as usize;
    let data = data.get(..len).ok_or_else(|| image_error("image", "short buffer"))?;
    view("image", image.width(), image.height(), data)
}

/// What the detection and tracking functions read: any grey buffer of bytes (shared between
/// threads: read in parallel).
pub trait Pixels: std::ops::Deref<Target = [u8]> + Sync {}
impl<C: std::ops::Deref<Target = [u8]> + Sync> Pixels for C {}

/// A rectangle of pixels, inclusive bounds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Window {
    /// First column.
    pub u0: u32,
    /// First row.
    pub v0: u32,
    /// Last column.
    pub u1: u32,
    /// Last row.
    pub v1: u32,
}

impl Window {
    /// The whole image.
    pub fn full<C: Pixels>(image: &GreyBuffer<C>) -> Self {
        Self { u0: 0, v0: 0, u1: image.width() - 1, v1: image.height() - 1 }
    }

    /// The square of half-side `radius` around `(u, v)`, clipped to the image; None when it
    /// falls outside.
    pub fn around<C: Pixels>(image: &GreyBuffer<C>, center: [f64; 2], radius: f64) -> Option<Self> {
        let (w, h) = (f64::from(image.width()), f64::from(image.height()));
        let (u0, u1) = ((center[0] - radius).round().max(0.0), (center[0] + radius).round().min(w - 1.0));
        let (v0, v1) = ((center[1] - radius).round().max(0.0), (center[1] + radius).round().min(h - 1.0));
        (u0 <= u1 && v0 <= v1).then_some(Self { u0: u0 as u32, v0: v0 as u32, u1: u1 as u32, v1: v1 as u32 })
    }

    /// Columns.
    pub fn width(&self) -> u32 {
        self.u1 - self.u0 + 1
    }

    /// Rows.
    pub fn height(&self) -> u32 {
        self.v1 - self.v0 + 1
    }
}

/// Borrows row-major bytes as an image; `what` names the argument in errors.
pub fn view<'a>(what: &str, width: u32, height: u32, data: &'a [u8]) -> Result<GreyBuffer<&'a [u8]>> {
    check_size(what, width, height, data.len())?;
    GreyBuffer::from_raw(width, height, data).ok_or_else(|| image_error(what, "inconsistent size"))
}

fn check_size(what: &str, width: u32, height: u32, len: usize) -> Result<()> {
    check_dimensions(what, u64::from(width), u64::from(height))?;
    let expected = width as usize * height as usize;
    if len != expected {
        return Err(image_error(what, format!("{len} values for a {height} x {width} image ({expected} expected)")));
    }
    Ok(())
}

/// The largest side of an image, pixels: a file's declared size, an array's shape, a
/// detector's input.
pub const MAX_IMAGE_SIDE: u32 = 65_536;
/// The most pixels (width x height, 2^28: 256 MiB of grey levels) an image may have: every
/// entry point that takes an image (a file, an array, a buffer given to a detector, the
/// renderer's output) refuses a larger one before allocating anything for it.
pub const MAX_IMAGE_PIXELS: u64 = 1 << 28;

/// Checks an image's size against [`MAX_IMAGE_SIDE`] and [`MAX_IMAGE_PIXELS`] (and that it is
/// not empty) before anything is allocated for it; `what` names the argument in errors.
pub fn check_dimensions(what: &str, width: u64, height: u64) -> Result<()> {
    if width == 0 || height == 0 {
        return Err(image_error(what, format!("empty image ({height} x {width})")));
    }
    let side = u64::from(MAX_IMAGE_SIDE);
    if width > side || height > side || width.saturating_mul(height) > MAX_IMAGE_PIXELS {
        return Err(image_error(
            what,
            format!(
                "{height} x {width} pixels: too large (at most {MAX_IMAGE_PIXELS} pixels, 2^28, and {side} on a side)"
            ),
        ));
    }
    Ok(())
}

fn image_error(what: &str, reason: impl Into<String>) -> VisionError {
    VisionError::InvalidImage { what: what.to_string(), reason: reason.into() }
}

/// A grey image from row-major data; `what` names the argument in errors.
pub fn from_raw(what: &str, width: u32, height: u32, data: Vec<u8>) -> Result<GreyImage> {
    check_size(what, width, height, data.len())?;
    GreyImage::from_raw(width, height, data).ok_or_else(|| image_error(what, "inconsistent size"))
}

/// Checks that an image is neither empty nor larger than [`check_dimensions`] allows.
pub fn check_image<C: Pixels>(what: &str, image: &GreyBuffer<C>) -> Result<()> {
    check_dimensions(what, u64::from(image.width()), u64::from(image.height()))
}

/// The most memory decoding an image file may take, bytes.
pub const MAX_IMAGE_ALLOC: u64 = 512 << 20;

/// Writes a PNG file: the image is checked first (not empty), then encoded to a temporary
/// file in the same folder which is renamed over `path`, so a failure leaves no partial file
/// and a symbolic link planted at `path` is replaced, not followed.
pub fn save_png(image: &GreyImage, path: &Path) -> Result<()> {
    let what = path.display().to_string();
    check_image(&what, image)?;
    let folder = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    // Read-write for everyone the umask allows, like a file created directly (the
    // temporary file's default is owner-only).
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let mut temp = builder.tempfile_in(folder).map_err(|e| image_error(&what, e.to_string()))?;
    image
        .write_to(&mut std::io::BufWriter::new(temp.as_file_mut()), ::image::ImageFormat::Png)
        .map_err(|e| image_error(&what, e.to_string()))?;
    temp.persist(path).map_err(|e| image_error(&what, e.error.to_string()))?;
    Ok(())
}

/// Reads an image file as 8-bit grey: PNG, PGM/PPM (binary P5/P6 and ASCII P2/P3, and PAM),
/// JPEG, or GIF's first frame, recognised by its first bytes (not its name). Colour images are
/// converted to grey with the Rec. 601 luma weights `0.299 R + 0.587 G + 0.114 B`, rounded
/// (as OpenCV and ViSP do); an alpha channel is ignored. A truncated JPEG is refused. Images of more than 8 bits a sample
/// (16-bit PGM or PNG) are refused: scaling them down would hide a choice (which bits matter)
/// that belongs to the caller. The file must be a regular file of at most
/// [`MAX_IMAGE_BYTES`](crate::input_file::MAX_IMAGE_BYTES); decoding is bounded by
/// [`check_dimensions`] (the declared size, before decoding) and [`MAX_IMAGE_ALLOC`] (a small
/// file declaring a huge image is refused); a PNG file's colour profile and text chunks are
/// skipped unread (compressed, they could inflate to any size: `png_file.rs`).
/// Errors name the file and never quote its contents.
pub fn load_image(path: &Path) -> Result<GreyImage> {
    let what = path.display().to_string();
    let bytes = crate::input_file::read_bytes(path, crate::input_file::MAX_IMAGE_BYTES)
        .map_err(|reason| image_error(&what, reason))?;
    decode_image(&what, &bytes)
}

/// An image file's bytes decoded as [`load_image`] decodes them (what it calls once the file is
/// read; the fuzz target's entry point); `what` names the file in errors.
pub fn decode_image(what: &str, bytes: &[u8]) -> Result<GreyImage> {
    let format = ::image::guess_format(bytes)
        .map_err(|_| image_error(what, "not a PNG, PGM/PPM, JPEG or GIF image (unknown signature)"))?;
    if format == ::image::ImageFormat::Jpeg && !jpeg_is_whole(bytes) {
        return Err(image_error(what, "not a valid JPEG image (truncated: no end of image after the last scan)"));
    }
    let img = if format == ::image::ImageFormat::Png {
        png_file::decode(what, bytes)?
    } else {
        let name = format!("{format:?}").to_uppercase();
        let invalid = |e| image_error(what, format!("not a valid {name} image ({})", decode_reason(&e)));
        let reader = || {
            let mut reader = ::image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
            let mut limits = ::image::Limits::default();
            limits.max_image_width = Some(MAX_IMAGE_SIDE);
            limits.max_image_height = Some(MAX_IMAGE_SIDE);
            limits.max_alloc = Some(MAX_IMAGE_ALLOC);
            reader.limits(limits);
            reader
        };
        let (width, height) = reader().into_dimensions().map_err(invalid)?;
        check_dimensions(what, u64::from(width), u64::from(height))?;
        reader().decode().map_err(invalid)?
    };
    let grey = to_grey(what, img)?;
    check_image(what, &grey)?;
    Ok(grey)
}

/// Reads an image file as 8-bit grey: the same as [`load_image`] (kept for its name).
pub fn load_png(path: &Path) -> Result<GreyImage> {
    load_image(path)
}

/// What went wrong while decoding, in the decoder's words for limits and unsupported
/// features, and as a category otherwise (a malformed file's details may quote its bytes).
fn decode_reason(e: &::image::ImageError) -> String {
    match e {
        ::image::ImageError::Limits(l) => l.to_string(),
        ::image::ImageError::Unsupported(u) => u.to_string(),
        ::image::ImageError::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => "truncated".into(),
        ::image::ImageError::IoError(_) => "read error".into(),
        _ => "corrupt or truncated".into(),
    }
}

/// 8-bit grey from a decoded image: grey as is, colour by Rec. 601 luma, more than 8 bits
/// refused.
fn to_grey(what: &str, img: ::image::DynamicImage) -> Result<GreyImage> {
    use ::image::DynamicImage as D;
    match img {
        D::ImageLuma8(grey) => Ok(grey),
        D::ImageLumaA8(_) | D::ImageRgb8(_) | D::ImageRgba8(_) => {
            let rgb = img.into_rgb8();
            let (width, height) = rgb.dimensions();
            let data = rgb.pixels().map(|p| luma_601(p.0)).collect();
            from_raw(what, width, height, data)
        }
        other => Err(image_error(
            what,
            format!("{:?} samples: only 8-bit images are read (convert 16-bit images to 8 bits first)", other.color()),
        )),
    }
}

/// Rec. 601 luma of an 8-bit RGB pixel, in fixed point with rounding: weights 9798, 19235
/// and 3735 over 2^15, OpenCV's `COLOR_RGB2GRAY` to the bit.
fn luma_601([r, g, b]: [u8; 3]) -> u8 {
    let l = 9798 * u32::from(r) + 19235 * u32::from(g) + 3735 * u32::from(b);
    ((l + (1 << 14)) >> 15).min(255) as u8
}

/// Whether a JPEG file is whole: its last scan (marker `FF DA`) is followed by the end of
/// image (`FF D9`); neither can occur inside entropy-coded data. The decoder itself fills a
/// truncated image with grey without a word.
fn jpeg_is_whole(bytes: &[u8]) -> bool {
    let last_scan = bytes.windows(2).rposition(|w| w == [0xFF, 0xDA]);
    last_scan.is_some_and(|start| bytes[start..].windows(2).any(|w| w == [0xFF, 0xD9]))
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    #[test]
    fn raw_round_trip_and_errors() {
        let img = from_raw("image", 3, 2, vec![0, 1, 2, 3, 4, 5]).unwrap();
        assert_eq!(img.get_pixel(2, 1)[0], 5);
        assert!(from_raw("image", 3, 2, vec![0; 5]).is_err());
        assert!(from_raw("image", 0, 2, vec![]).is_err());
    }

    #[test]
    fn pgm_ppm_and_refusals() {
        let dir = std::env::temp_dir().join(format!("vsinv-pnm-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let pgm = dir.join("a.pgm");
        std::fs::write(&pgm, [b"P5\n3 2\n255\n".as_slice(), &[0, 1, 2, 3, 4, 250]].concat()).unwrap();
        assert_eq!(load_image(&pgm).unwrap(), from_raw("image", 3, 2, vec![0, 1, 2, 3, 4, 250]).unwrap());
        let ppm = dir.join("a.ppm");
        std::fs::write(&ppm, "P3\n2 1\n255\n255 0 0  10 200 30\n").unwrap();
        assert_eq!(load_image(&ppm).unwrap().into_raw(), vec![76, 124]);
        let deep = dir.join("deep.pgm");
        std::fs::write(&deep, [b"P5\n1 1\n65535\n".as_slice(), &[1, 2]].concat()).unwrap();
        assert!(load_image(&deep).unwrap_err().to_string().contains("16-bit"));
        let magic = dir.join("magic.pgm");
        std::fs::write(&magic, "Q5\n1 1\n255\nA").unwrap();
        assert!(load_image(&magic).unwrap_err().to_string().contains("magic.pgm"));
        assert!(!jpeg_is_whole(&[0xFF, 0xD8, 0xFF, 0xDA, 1, 2]) && jpeg_is_whole(&[0xFF, 0xDA, 1, 0xFF, 0xD9]));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn png_round_trip() {
        let dir = std::env::temp_dir().join(format!("vsinv-png-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.png");
        let img = from_raw("image", 4, 3, (0..12).map(|v| v * 20).collect()).unwrap();
        save_png(&img, &path).unwrap();
        assert_eq!(load_png(&path).unwrap(), img);
        let err = load_png(&dir.join("missing.png")).unwrap_err();
        assert!(err.to_string().contains("missing.png"));
        // Regression (issue 16): an empty image is refused before any file is created.
        let empty = dir.join("empty.png");
        assert!(save_png(&GreyImage::new(0, 0), &empty).is_err());
        assert!(!empty.exists());
        // Regression (issue 16): a symbolic link at the destination is replaced, not followed.
        #[cfg(unix)]
        {
            let target = dir.join("target.txt");
            std::fs::write(&target, "keep").unwrap();
            let link = dir.join("link.png");
            std::os::unix::fs::symlink(&target, &link).unwrap();
            save_png(&img, &link).unwrap();
            assert_eq!(std::fs::read_to_string(&target).unwrap(), "keep");
            assert_eq!(load_png(&link).unwrap(), img);
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
