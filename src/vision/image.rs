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

/// Writes a PNG file.
pub fn save_png(image: &GreyImage, path: &Path) -> Result<()> {
    image
        .save_with_format(path, ::image::ImageFormat::Png)
        .map_err(|e| image_error(&path.display().to_string(), e.to_string()))
}

/// Reads a PNG (or any format the `image` crate was built with) as 8-bit grey; colour
/// images are converted to luma.
pub fn load_png(path: &Path) -> Result<GreyImage> {
    let img = ::image::open(path).map_err(|e| image_error(&path.display().to_string(), e.to_string()))?;
    let grey = img.into_luma8();
    check_image(&path.display().to_string(), &grey)?;
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
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
