//! 8-bit grey images: the `image` crate's `GrayImage` (row-major, `(height, width)`), its
//! checks and PNG files.

use std::path::Path;

use crate::error::{Error, Result};

/// An 8-bit grey image, row-major: pixel `(u, v)` is `data[v * width + u]`.
pub type GreyImage = ::image::GrayImage;

/// An 8-bit grey image over any row-major buffer: an owned [`GreyImage`], or borrowed bytes
/// (`GreyBuffer<&[u8]>`, e.g. a NumPy array read in place).
pub type GreyBuffer<C> = ::image::ImageBuffer<::image::Luma<u8>, C>;

/// What the detection and tracking functions read: any grey buffer of bytes.
pub trait Pixels: std::ops::Deref<Target = [u8]> {}
impl<C: std::ops::Deref<Target = [u8]>> Pixels for C {}

/// Borrows row-major bytes as an image; `what` names the argument in errors.
pub fn view<'a>(what: &str, width: u32, height: u32, data: &'a [u8]) -> Result<GreyBuffer<&'a [u8]>> {
    check_size(what, width, height, data.len())?;
    GreyBuffer::from_raw(width, height, data).ok_or_else(|| image_error(what, "inconsistent size"))
}

fn check_size(what: &str, width: u32, height: u32, len: usize) -> Result<()> {
    if width == 0 || height == 0 {
        return Err(image_error(what, format!("empty image ({height} x {width})")));
    }
    let expected = width as usize * height as usize;
    if len != expected {
        return Err(image_error(what, format!("{len} values for a {height} x {width} image ({expected} expected)")));
    }
    Ok(())
}

fn image_error(what: &str, reason: impl Into<String>) -> Error {
    Error::InvalidImage { what: what.to_string(), reason: reason.into() }
}

/// A grey image from row-major data; `what` names the argument in errors.
pub fn from_raw(what: &str, width: u32, height: u32, data: Vec<u8>) -> Result<GreyImage> {
    check_size(what, width, height, data.len())?;
    GreyImage::from_raw(width, height, data).ok_or_else(|| image_error(what, "inconsistent size"))
}

/// Checks that an image is not empty.
pub fn check_image<C: Pixels>(what: &str, image: &GreyBuffer<C>) -> Result<()> {
    if image.width() == 0 || image.height() == 0 {
        return Err(image_error(what, format!("empty image ({} x {})", image.height(), image.width())));
    }
    Ok(())
}

/// The largest side of an image read from a file, pixels.
pub const MAX_IMAGE_SIDE: u32 = 65_536;
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

/// Reads a PNG (or any format the `image` crate was built with) as 8-bit grey; colour
/// images are converted to luma. The file must be a regular file of at most
/// [`MAX_IMAGE_BYTES`](crate::input_file::MAX_IMAGE_BYTES); decoding is bounded by
/// [`MAX_IMAGE_SIDE`] and [`MAX_IMAGE_ALLOC`] (a small file declaring a huge image is refused).
pub fn load_png(path: &Path) -> Result<GreyImage> {
    let what = path.display().to_string();
    let bytes = crate::input_file::read_bytes(path, crate::input_file::MAX_IMAGE_BYTES)
        .map_err(|reason| image_error(&what, reason))?;
    let mut reader = ::image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| image_error(&what, e.to_string()))?;
    let mut limits = ::image::Limits::default();
    limits.max_image_width = Some(MAX_IMAGE_SIDE);
    limits.max_image_height = Some(MAX_IMAGE_SIDE);
    limits.max_alloc = Some(MAX_IMAGE_ALLOC);
    reader.limits(limits);
    let img = reader.decode().map_err(|e| image_error(&what, e.to_string()))?;
    let grey = img.into_luma8();
    check_image(&what, &grey)?;
    Ok(grey)
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
