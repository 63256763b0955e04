//! What the camera sees: a [`Drawing`] (every target is one) rendered by a [`Renderer`]
//! through one entry point, [`Renderer::render`]. The target draws itself on a [`Canvas`] with the renderer's
//! primitives (today white discs, whose perspective image is an exact ellipse); the canvas
//! starts as the frame's noisy background and each primitive is anti-aliased, blurred (the
//! optical PSF), noised, clipped and quantised to 8 bits.
//!
//! | concern | file |
//! |---|---|
//! | the canvas and its primitives ([`Disc`], [`Polygon`]) | `render/canvas.rs` |
//! | the image of a disc: its conic and bounding box | `render/conic.rs` |
//! | the image of convex polygons: exact areas by clipping | `render/polygon.rs` |
//! | the lens between the ideal pinhole image and the rendered one | `render/lens.rs` |
//! | coverage, supersampling, blur, quantisation | `render/raster.rs` |
//! | the sensor noise | `render/noise.rs` |
//! | textured planar faces ([`TexturedFace`]): homography, area sampling, culling, depth | `render/texture.rs` |
//! | the PSF and noise on an image drawn elsewhere ([`Renderer::degrade`]) | `render/sensor.rs` |

mod canvas;
mod conic;
mod lens;
mod noise;
mod polygon;
mod raster;
mod sensor;
mod texture;

use nalgebra::Isometry3;

pub use self::canvas::{Canvas, Disc, Polygon};
use self::noise::{Noise, frame_seed, quantised_pool};
use self::raster::{Paint, gaussian_kernel};
pub use self::texture::{MAX_FACES, TexturedFace, TexturedFaces};
use crate::core::camera::Intrinsics;
use crate::core::distortion::Distortion;
use crate::error::{Error, Short};
use crate::vision::error::Result;
use crate::vision::image::{GreyImage, Window};
use crate::vision::polarity::Polarity;

/// The largest image the renderer draws (width x height, 2^28: 256 MiB of grey levels); larger
/// sizes are refused with `InvalidParameter("image size")` before any allocation.
pub const MAX_RENDER_PIXELS: u64 = crate::vision::image::MAX_IMAGE_PIXELS;

/// How the images are made (the `[vision]` table of a scenario).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields, default))]
pub struct RenderConfig {
    /// Radius of the white discs drawn at the feature points, metres
    /// ([`Dots`](crate::vision::Dots) of a scene).
    pub dot_radius: f64,
    /// Gaussian blur (optical PSF), standard deviation in pixels (0: none).
    pub blur_sigma: f64,
    /// Additive Gaussian sensor noise, standard deviation in grey levels (0: none).
    pub noise_sigma: f64,
    /// Grey level of the background.
    pub background: u8,
    /// Grey level of a disc.
    pub foreground: u8,
    /// Seed of the noise; each frame number gives another draw.
    pub seed: u64,
    /// The dots the images show and the tracker looks for: `light` (discs of `foreground` on
    /// `background`, the default), `dark` (the negative image: every grey level `g` drawn as
    /// `255 - g`, dark discs on a light background) or `auto` (drawn light, the tracker
    /// decides from the reference image).
    pub polarity: Polarity,
}

impl Default for RenderConfig {
    fn default() -> Self {
        Self {
            dot_radius: 0.004,
            blur_sigma: 0.8,
            noise_sigma: 2.0,
            background: 30,
            foreground: 220,
            seed: 0,
            polarity: Polarity::Light,
        }
    }
}

impl RenderConfig {
    /// Checks the values.
    pub fn validate(&self) -> Result<()> {
        let bad = |name, reason: String| Err(Error::InvalidParameter { name, reason }.into());
        if !(self.dot_radius.is_finite() && self.dot_radius > 0.0) {
            return bad("dot_radius", format!("must be > 0 metres, got {}", Short(self.dot_radius)));
        }
        if !(self.blur_sigma.is_finite() && (0.0..=20.0).contains(&self.blur_sigma)) {
            return bad("blur_sigma", format!("must be in [0, 20] pixels, got {}", Short(self.blur_sigma)));
        }
        if !(self.noise_sigma.is_finite() && (0.0..=100.0).contains(&self.noise_sigma)) {
            return bad("noise_sigma", format!("must be in [0, 100] grey levels, got {}", Short(self.noise_sigma)));
        }
        if self.foreground <= self.background {
            return bad("foreground", format!("must be brighter than background ({})", self.background));
        }
        Ok(())
    }
}

/// A rendered image and, per point of the target, whether it was drawn (false: hidden by the
/// caller's mask, behind the camera, straddling the camera plane, seen edge-on or outside).
#[derive(Debug, Clone, PartialEq)]
pub struct Rendered {
    /// The 8-bit image.
    pub image: GreyImage,
    /// Per point of the target: drawn or not.
    pub drawn: Vec<bool>,
}

/// Where a camera looks from and through what.
#[derive(Debug, Clone, Copy)]
pub struct CameraView<'a> {
    /// The camera frame in F*.
    pub pose: &'a Isometry3<f64>,
    /// Its intrinsics.
    pub intrinsics: &'a Intrinsics,
    /// Its lens distortion.
    pub distortion: &'a Distortion,
    /// `(width, height)`, pixels.
    pub size: (u32, u32),
}

/// Renders images with one configuration (it keeps the noise pool and the blur kernel: build
/// it once and render every frame with it).
#[derive(Debug, Clone)]
pub struct Renderer {
    config: RenderConfig,
    /// `background + noise` quantised for every draw of the noise pool (shared).
    noise_pool: std::sync::Arc<[u8]>,
    /// The blur kernel (normalised), `2 radius + 1` taps.
    kernel: Vec<f32>,
}

impl Renderer {
    /// A renderer for a configuration.
    pub fn new(config: RenderConfig) -> Result<Self> {
        config.validate()?;
        let noise_pool = quantised_pool(config.background, config.noise_sigma);
        Ok(Self { config, noise_pool, kernel: gaussian_kernel(config.blur_sigma) })
    }

    /// The configuration.
    pub fn config(&self) -> &RenderConfig {
        &self.config
    }

    /// The image the camera of `view` sees of a target, `view.size` pixels: pixel `p` shows
    /// what the ideal pinhole image shows at `K d^-1(K^-1 p)` (a primitive reaching beyond the
    /// lens model's fold is not drawn); `visible` (one flag per point of the target) hides
    /// occluded points; `frame` selects the noise draw.
    pub fn render<T: Drawing + ?Sized>(
        &self,
        target: &T,
        visible: Option<&[bool]>,
        view: &CameraView<'_>,
        frame: u64,
    ) -> Result<Rendered> {
        self.render_in(target, visible, view, frame, Vec::new())
    }

    /// [`Renderer::render`] into the memory of `buffer` (an earlier frame's pixels, e.g.
    /// `rendered.image.into_raw()`; its contents do not matter): the same image, without a
    /// fresh allocation per frame.
    pub fn render_in<T: Drawing + ?Sized>(
        &self,
        target: &T,
        visible: Option<&[bool]>,
        view: &CameraView<'_>,
        frame: u64,
        buffer: Vec<u8>,
    ) -> Result<Rendered> {
        self.render_with(target, visible, view, frame, buffer, None)
    }

    /// [`Renderer::render_in`] right only inside `windows` (clipped to the image): there
    /// each pixel is the whole frame's, bit for bit; elsewhere the image holds anything (the
    /// shapes drawn over what `buffer` held). For a detector that reads only windows
    /// ([`Detector::reads`](crate::vision::detector::Detector::reads)): the background of the
    /// rest of the frame, most of a frame's time, is not written.
    pub fn render_windows_in<T: Drawing + ?Sized>(
        &self,
        target: &T,
        visible: Option<&[bool]>,
        view: &CameraView<'_>,
        frame: u64,
        buffer: Vec<u8>,
        windows: &[Window],
    ) -> Result<Rendered> {
        self.render_with(target, visible, view, frame, buffer, Some(windows))
    }

    fn render_with<T: Drawing + ?Sized>(
        &self,
        target: &T,
        visible: Option<&[bool]>,
        view: &CameraView<'_>,
        frame: u64,
        buffer: Vec<u8>,
        windows: Option<&[Window]>,
    ) -> Result<Rendered> {
        let (width, height) = view.size;
        if width == 0 || height == 0 || u64::from(width) * u64::from(height) > MAX_RENDER_PIXELS {
            let reason = format!("{width} x {height}: at least 1 x 1 and at most {MAX_RENDER_PIXELS} pixels (2^28)");
            return Err(Error::InvalidParameter { name: "image size", reason }.into());
        }
        let n = target.point_count();
        check_flags("visible", visible.map_or(n, <[bool]>::len), n)?;
        let noise = Noise {
            pool: &self.noise_pool,
            background: self.config.background,
            sigma: self.config.noise_sigma,
            seed: frame_seed(self.config.seed, frame),
        };
        let paint = Paint {
            kernel: &self.kernel,
            background: self.config.background,
            foreground: self.config.foreground,
            noise,
        };
        let background = match windows {
            Some(windows) => noise.background_windows_in(width, height, buffer, windows),
            None => noise.background_frame_in(width, height, buffer),
        };
        let mut canvas = Canvas::new(background, *view, paint);
        let drawn = target.draw_on(&mut canvas, visible);
        check_flags("drawn", drawn.len(), n)?;
        let mut image = canvas.into_image();
        if self.config.polarity == Polarity::Dark {
            image.iter_mut().for_each(|g| *g = 255 - *g);
        }
        Ok(Rendered { image, drawn })
    }
}

/// What [`Renderer::render`] draws: points drawn with the canvas's primitives. The renderer
/// needs nothing more of a target, so it does not depend on the targets: every
/// `vision::target::Target` is a drawing (a blanket implementation there).
pub trait Drawing {
    /// The number of points (one visibility flag each).
    fn point_count(&self) -> usize;

    /// Draws the points on `canvas`, hiding those `visible` flags off; returns, per point,
    /// whether it was drawn.
    fn draw_on(&self, canvas: &mut Canvas<'_>, visible: Option<&[bool]>) -> Vec<bool>;
}

/// `got` flags where the target has `expected` points.
fn check_flags(what: &'static str, got: usize, expected: usize) -> Result<()> {
    if got == expected {
        return Ok(());
    }
    Err(Error::Shape { what, expected: format!("{expected} flags (one per point)"), got: format!("{got} flags") }
        .into())
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::vision::target::dots::Dots;

    /// A pinhole camera at F*.
    fn pinhole(k: &Intrinsics, size: (u32, u32)) -> CameraView<'_> {
        static NONE: std::sync::OnceLock<Distortion> = std::sync::OnceLock::new();
        static IDENTITY: std::sync::OnceLock<Isometry3<f64>> = std::sync::OnceLock::new();
        let distortion = NONE.get_or_init(Distortion::none);
        CameraView { pose: IDENTITY.get_or_init(Isometry3::identity), intrinsics: k, distortion, size }
    }

    /// Area and centroid of a polygon (shoelace).
    fn polygon_area_centroid(p: &[[f64; 2]]) -> (f64, [f64; 2]) {
        let (mut a, mut cx, mut cy) = (0.0, 0.0, 0.0);
        for i in 0..p.len() {
            let (q, r) = (p[i], p[(i + 1) % p.len()]);
            let cross = q[0] * r[1] - r[0] * q[1];
            a += cross;
            cx += (q[0] + r[0]) * cross;
            cy += (q[1] + r[1]) * cross;
        }
        (a / 2.0, [cx / (3.0 * a), cy / (3.0 * a)])
    }

    #[test]
    fn through_a_lens_a_disc_covers_its_distorted_rim() {
        let config =
            RenderConfig { blur_sigma: 0.0, noise_sigma: 0.0, background: 20, foreground: 220, ..Default::default() };
        let renderer = Renderer::new(config).unwrap();
        let k = Intrinsics::pinhole(600.0, 600.0, 416.0, 312.0).unwrap();
        let d = Distortion::from_coefficients(&[-0.30, 0.10, 0.0005, -0.0008, -0.02]).unwrap();
        // Near a corner, where barrel distortion squeezes the disc by about 20 %.
        let disc = Disc::new([0.28, 0.2, 0.5], [0.0, 0.0, -1.0], 0.01).unwrap();
        let view = CameraView { pose: &Isometry3::identity(), intrinsics: &k, distortion: &d, size: (832, 624) };
        let out = renderer.render(&Dots::new(vec![disc]), None, &view, 0).unwrap();
        assert_eq!(out.drawn, vec![true]);
        let (mut sum, mut su, mut sv) = (0.0, 0.0, 0.0);
        for (u, v, p) in out.image.enumerate_pixels() {
            let w = (f64::from(p[0]) - 20.0) / 200.0;
            sum += w;
            su += w * f64::from(u);
            sv += w * f64::from(v);
        }
        // The rim, projected and distorted by the core's distort_points.
        let rim: Vec<[f64; 2]> = (0..720)
            .map(|i| {
                let t = f64::from(i) * std::f64::consts::TAU / 720.0;
                let (x, y) = (0.28 + 0.01 * t.cos(), 0.2 + 0.01 * t.sin());
                [416.0 + 600.0 * x / 0.5, 312.0 + 600.0 * y / 0.5]
            })
            .collect();
        let (area, centroid) = polygon_area_centroid(&crate::core::distortion::distort_points(&rim, &k, &d).unwrap());
        let pinhole_area = std::f64::consts::PI * 12.0 * 12.0;
        assert!(area < 0.85 * pinhole_area, "{area} vs {pinhole_area}");
        assert!((sum / area - 1.0).abs() < 0.005, "{sum} vs {area}");
        assert!((su / sum - centroid[0]).abs() < 0.02 && (sv / sum - centroid[1]).abs() < 0.02);
    }

    #[test]
    fn fronto_parallel_disc_has_the_area_of_its_circle() {
        let config =
            RenderConfig { blur_sigma: 0.0, noise_sigma: 0.0, background: 20, foreground: 220, ..Default::default() };
        let renderer = Renderer::new(config).unwrap();
        let k = Intrinsics::pinhole(1000.0, 1000.0, 160.0, 120.0).unwrap();
        // radius 0.006 m at 0.5 m: 12 px.
        let disc = Disc::new([0.0123, -0.0071, 0.5], [0.0, 0.0, -1.0], 0.006).unwrap();
        let out = renderer.render(&Dots::new(vec![disc]), None, &pinhole(&k, (320, 240)), 0).unwrap();
        assert_eq!(out.drawn, vec![true]);
        let (mut sum, mut su, mut sv) = (0.0, 0.0, 0.0);
        for (u, v, p) in out.image.enumerate_pixels() {
            let w = f64::from(p[0]) - 20.0;
            sum += w;
            su += w * f64::from(u);
            sv += w * f64::from(v);
        }
        let expected = 200.0 * std::f64::consts::PI * 12.0 * 12.0;
        assert!((sum / expected - 1.0).abs() < 0.005, "{sum} vs {expected}");
        // Fronto-parallel: the centroid is the projected centre (160 + 24.6, 120 - 14.2).
        assert!((su / sum - (160.0 + 24.6)).abs() < 0.01 && (sv / sum - (120.0 - 14.2)).abs() < 0.01);
    }

    #[test]
    fn blur_keeps_the_total_and_the_centroid() {
        let sharp = RenderConfig { blur_sigma: 0.0, noise_sigma: 0.0, ..Default::default() };
        let soft = RenderConfig { blur_sigma: 1.5, ..sharp };
        let k = Intrinsics::pinhole(1000.0, 1000.0, 100.0, 100.0).unwrap();
        let disc = Disc::new([0.0031, 0.0017, 0.5], [0.0, 0.0, -1.0], 0.003).unwrap();
        let moments = |c: RenderConfig| {
            let img =
                Renderer::new(c).unwrap().render(&Dots::new(vec![disc]), None, &pinhole(&k, (200, 200)), 0).unwrap();
            let (mut s, mut su) = (0.0, 0.0);
            for (u, _, p) in img.image.enumerate_pixels() {
                let w = f64::from(p[0]) - f64::from(c.background);
                s += w;
                su += w * f64::from(u);
            }
            (s, su / s)
        };
        let (s0, u0) = moments(sharp);
        let (s1, u1) = moments(soft);
        assert!((s1 / s0 - 1.0).abs() < 0.01 && (u1 - u0).abs() < 0.02, "{s0} {s1} {u0} {u1}");
    }

    #[test]
    fn noise_is_reproducible_and_has_its_sigma() {
        let config = RenderConfig { noise_sigma: 3.0, seed: 7, ..Default::default() };
        let r = Renderer::new(config).unwrap();
        let k = Intrinsics::pinhole(500.0, 500.0, 80.0, 60.0).unwrap();
        let render = |frame| r.render(&Dots::new(vec![]), None, &pinhole(&k, (160, 120)), frame).unwrap().image;
        assert_eq!(render(3), render(3));
        assert_ne!(render(3), render(4));
        // Into an earlier frame's memory: the same frame.
        let dots = Dots::new(vec![Disc::facing_reference([0.01, 0.0, 0.5], 0.004).unwrap()]);
        let fresh = r.render(&dots, None, &pinhole(&k, (160, 120)), 5).unwrap();
        let reused = r.render_in(&dots, None, &pinhole(&k, (160, 120)), 5, render(4).into_raw()).unwrap();
        assert_eq!(fresh, reused);
        assert_eq!(fresh.drawn, vec![true]);
        let img = render(1);
        let n = f64::from(img.width() * img.height());
        let mean = img.pixels().map(|p| f64::from(p[0])).sum::<f64>() / n;
        let var = img.pixels().map(|p| (f64::from(p[0]) - mean).powi(2)).sum::<f64>() / n;
        assert!((mean - 30.0).abs() < 0.1 && (var.sqrt() - 3.0).abs() < 0.15, "{mean} {}", var.sqrt());
    }

    #[test]
    fn hidden_behind_and_edge_on_discs_are_not_drawn() {
        let r = Renderer::new(RenderConfig::default()).unwrap();
        let k = Intrinsics::pinhole(500.0, 500.0, 80.0, 60.0).unwrap();
        let discs = vec![
            Disc::facing_reference([0.0, 0.0, 0.5], 0.005).unwrap(),
            Disc::facing_reference([0.0, 0.0, -0.5], 0.005).unwrap(),
            Disc::new([0.0, 0.0, 0.5], [1.0, 0.0, 0.0], 0.005).unwrap(),
            Disc::facing_reference([0.02, 0.0, 0.5], 0.005).unwrap(),
            Disc::facing_reference([5.0, 0.0, 0.5], 0.005).unwrap(),
        ];
        let visible = [true, true, true, false, true];
        let dots = Dots::new(discs);
        let out = r.render(&dots, Some(&visible), &pinhole(&k, (160, 120)), 0).unwrap();
        assert_eq!(out.drawn, vec![true, false, false, false, false]);
        assert!(r.render(&dots, Some(&[true]), &pinhole(&k, (160, 120)), 0).is_err());
        assert!(r.render(&dots, None, &pinhole(&k, (0, 120)), 0).is_err());
        assert!(Renderer::new(RenderConfig { foreground: 10, ..Default::default() }).is_err());
        assert!(Renderer::new(RenderConfig { blur_sigma: f64::NAN, ..Default::default() }).is_err());
        assert!(Disc::new([0.0, 0.0, 1.0], [0.0; 3], 0.01).is_err());
        assert!(Disc::facing_reference([0.0, f64::NAN, 1.0], 0.01).is_err());
    }
}
