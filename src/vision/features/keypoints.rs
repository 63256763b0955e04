//! The keypoints of an image and their SIFT descriptors (kornia-rs's port of OpenCV's SIFT).

use kornia_imgproc::features::{FirstOctave, SiftConfig, SiftWorkspace, sift_detect_and_compute};

use crate::vision::error::{Result, VisionError};
use crate::vision::image::GreyView;

/// The length of one descriptor.
pub const DESCRIPTOR_LEN: usize = kornia_imgproc::features::DESCR_LEN;

/// The most keypoints kept of one image (the strongest; OpenCV's `nfeatures`).
pub const MAX_KEYPOINTS: usize = 4000;

/// Keypoints of one image: pixel, strength, and a descriptor each.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Keypoints {
    /// Pixel of each keypoint (OpenCV's convention: the centre of pixel `(0, 0)` at `(0, 0)`).
    pub pixels: Vec<[f64; 2]>,
    /// The detector's response of each (its contrast).
    pub responses: Vec<f32>,
    /// `pixels.len() * DESCRIPTOR_LEN` values, row-major.
    pub descriptors: Vec<f32>,
}

impl Keypoints {
    /// How many.
    pub fn len(&self) -> usize {
        self.pixels.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.pixels.is_empty()
    }

    /// The descriptor of keypoint `i`.
    pub fn descriptor(&self, i: usize) -> &[f32] {
        self.descriptors.get(i * DESCRIPTOR_LEN..(i + 1) * DESCRIPTOR_LEN).unwrap_or(&[])
    }

    /// The keypoints `indices`, in that order.
    pub fn subset(&self, indices: &[usize]) -> Keypoints {
        let mut out = Keypoints::default();
        for &i in indices.iter().filter(|&&i| i < self.len()) {
            out.pixels.push(self.pixels[i]);
            out.responses.push(self.responses[i]);
            out.descriptors.extend_from_slice(self.descriptor(i));
        }
        out
    }
}

/// The SIFT keypoints of `image` (`what` names it in errors), the image doubled first as
/// OpenCV does, at most [`MAX_KEYPOINTS`] (the strongest).
pub fn sift(what: &str, image: &GreyView<'_>) -> Result<Keypoints> {
    let (w, h) = (image.width() as usize, image.height() as usize);
    let pixels: Vec<f32> = image.as_raw().iter().take(w * h).map(|&v| f32::from(v)).collect();
    let config = SiftConfig { n_features: MAX_KEYPOINTS, ..SiftConfig::default() };
    let run = || {
        let mut workspace = SiftWorkspace::new();
        sift_detect_and_compute(&mut workspace, &pixels, w, h, &config, FirstOctave::Double, usize::MAX, false)
    };
    // kornia runs with rayon: on vsinv's pool (see `parallel`).
    let features = crate::parallel::install(run)?
        .map_err(|e| VisionError::InvalidImage { what: what.into(), reason: format!("no SIFT keypoints: {e}") })?;
    Ok(Keypoints {
        pixels: features.keypoints.iter().map(|k| [f64::from(k.x), f64::from(k.y)]).collect(),
        responses: features.keypoints.iter().map(|k| k.response).collect(),
        descriptors: features.descriptors,
    })
}
