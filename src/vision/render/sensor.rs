//! The renderer's optics and sensor on an image made elsewhere (a MuJoCo render, a photograph):
//! [`Renderer::degrade`] blurs it with the renderer's Gaussian PSF and adds the sensor noise of a
//! frame, the same kernel and the same draws as the renderer's own frames, so that a `[vision]`
//! table means the same thing whoever drew the image.

use super::Renderer;
use super::noise::{Noise, frame_seed, quantise};
use super::raster::{Patch, blur};
use crate::vision::error::Result;
use crate::vision::image::{GreyBuffer, GreyImage, Pixels, from_raw, view_of};

impl Renderer {
    /// `image` as this renderer's camera gives it: blurred by the PSF (`blur_sigma`; near the
    /// border the kernel's weights inside the image renormalised, so a uniform image stays
    /// uniform), plus the sensor noise of frame `frame` (`noise_sigma`, the draws pixel by
    /// pixel that the renderer's frame `frame` takes, from `seed`), rounded and clamped to 8
    /// bits. The dots, grey levels and polarity of the configuration are not used.
    pub fn degrade<C: Pixels>(&self, image: &GreyBuffer<C>, frame: u64) -> Result<GreyImage> {
        let (width, height) = image.dimensions();
        let (w, h) = (width as usize, height as usize);
        let patch = Patch { u0: 0, v0: 0, w, h };
        let pixels = view_of(image)?;
        let mut values: Vec<f32> = pixels.as_raw().iter().map(|&g| f32::from(g)).collect();
        let mut weight = vec![1.0f32; w * h];
        blur(&mut values, &patch, &self.kernel);
        blur(&mut weight, &patch, &self.kernel);
        let noise = Noise {
            pool: &self.noise_pool,
            background: self.config.background,
            sigma: self.config.noise_sigma,
            seed: frame_seed(self.config.seed, frame),
        };
        let data = values
            .iter()
            .zip(&weight)
            .zip(noise.span(0, w * h))
            .map(|((&v, &k), n)| quantise(f64::from(v / k) + n))
            .collect();
        from_raw("image", width, height, data)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::vision::render::RenderConfig;

    fn renderer(blur_sigma: f64, noise_sigma: f64) -> Renderer {
        Renderer::new(RenderConfig { blur_sigma, noise_sigma, seed: 5, ..RenderConfig::default() }).unwrap()
    }

    #[test]
    fn without_blur_and_noise_the_image_is_unchanged() {
        let data: Vec<u8> = (0..37 * 23).map(|i| (i * 7 % 251) as u8).collect();
        let image = GreyImage::from_raw(37, 23, data).unwrap();
        assert_eq!(renderer(0.0, 0.0).degrade(&image, 3).unwrap(), image);
    }

    #[test]
    fn the_blur_is_the_gaussian_convolution_inside_and_keeps_a_uniform_image() {
        let flat = GreyImage::from_pixel(20, 15, ::image::Luma([90]));
        assert_eq!(renderer(1.5, 0.0).degrade(&flat, 0).unwrap(), flat);
        // One bright pixel: its image is the sampled Gaussian (a closed form), to a grey level.
        let mut spot = GreyImage::new(21, 21);
        spot.put_pixel(10, 10, ::image::Luma([255]));
        let sigma = 1.2;
        let out = renderer(sigma, 0.0).degrade(&spot, 0).unwrap();
        let g = |x: f64| (-(x * x) / (2.0 * sigma * sigma)).exp();
        let norm: f64 = (-4..=4).map(|x| g(f64::from(x))).sum();
        for (u, v) in [(10, 10), (11, 10), (12, 11), (10, 13)] {
            let expected = 255.0 * g(f64::from(u) - 10.0) * g(f64::from(v) - 10.0) / (norm * norm);
            let got = f64::from(out.get_pixel(u, v)[0]);
            assert!((got - expected).abs() <= 0.5 + 1e-6, "({u}, {v}): {got} vs {expected}");
        }
    }

    #[test]
    fn the_noise_is_the_renderers_draw_of_the_frame() {
        let r = renderer(0.0, 3.0);
        let flat = GreyImage::from_pixel(40, 30, ::image::Luma([r.config().background]));
        // The renderer's own frame of nothing is the background with the frame's noise.
        struct Nothing;
        impl crate::vision::render::Drawing for Nothing {
            fn point_count(&self) -> usize {
                0
            }
            fn draw_on(&self, _: &mut crate::vision::render::Canvas<'_>, _: Option<&[bool]>) -> Vec<bool> {
                Vec::new()
            }
        }
        let k = crate::core::camera::Intrinsics::new(500.0, 500.0, 20.0, 15.0, std::f64::consts::FRAC_PI_2).unwrap();
        let distortion = crate::core::distortion::Distortion::none();
        let pose = nalgebra::Isometry3::identity();
        let view =
            crate::vision::render::CameraView { pose: &pose, intrinsics: &k, distortion: &distortion, size: (40, 30) };
        for frame in [0, 7] {
            let own = r.render(&Nothing, None, &view, frame).unwrap().image;
            assert_eq!(r.degrade(&flat, frame).unwrap(), own, "frame {frame}");
        }
        assert_ne!(r.degrade(&flat, 1).unwrap(), r.degrade(&flat, 2).unwrap());
    }
}
