//! Sensor noise: additive Gaussian noise drawn from a fixed table of 65,536 N(0, 1) values,
//! indexed by 16 hashed bits per pixel (splitmix64 of the frame's seed and the pixel's index),
//! so a frame's noise is reproducible and costs one look-up per pixel.

use std::sync::OnceLock;

use crate::vision::image::GreyImage;

/// 65,536 draws of N(0, 1) (Box-Muller on a fixed splitmix64 stream), indexed by 16
/// random bits per pixel: an empirical Gaussian that costs one table look-up.
pub(super) fn gaussian_table() -> &'static [f32] {
    static TABLE: OnceLock<Vec<f32>> = OnceLock::new();
    TABLE.get_or_init(|| {
        let mut state = 0x5EED_u64;
        let mut uniform = || ((splitmix64(&mut state) >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
        let mut table = Vec::with_capacity(1 << 16);
        while table.len() < 1 << 16 {
            let (u1, u2) = (uniform(), uniform());
            let r = (-2.0 * u1.ln()).sqrt();
            let a = 2.0 * std::f64::consts::PI * u2;
            table.push((r * a.cos()) as f32);
            table.push((r * a.sin()) as f32);
        }
        table
    })
}

pub(super) fn splitmix64(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The seed of frame `frame` for a configuration's `seed`.
pub(super) fn frame_seed(seed: u64, frame: u64) -> u64 {
    splitmix64(&mut (seed ^ frame.wrapping_mul(0xA24B_AED4_963E_E407)))
}

/// The 16-bit noise index of pixel `index` in the frame of seed `seed` (four pixels per hash).
#[inline]
pub(super) fn noise_index(seed: u64, index: usize) -> usize {
    let mut state = seed ^ ((index / 4) as u64).wrapping_mul(0xD1B5_4A32_D192_ED03);
    ((splitmix64(&mut state) >> (16 * (index % 4))) & 0xFFFF) as usize
}

/// `background + sigma n` quantised for every entry `n` of the Gaussian table.
pub(super) fn noisy_background(background: u8, sigma: f64) -> Vec<u8> {
    let bg = f64::from(background);
    gaussian_table().iter().map(|&n| (bg + sigma * f64::from(n)).round().clamp(0.0, 255.0) as u8).collect()
}

/// The noise of one frame.
#[derive(Debug, Clone, Copy)]
pub(super) struct Noise<'a> {
    /// `background + noise` quantised, indexed by 16 random bits ([`noisy_background`]).
    pub(super) noisy_background: &'a [u8],
    /// The background's grey level.
    pub(super) background: u8,
    /// Standard deviation, grey levels (0: none).
    pub(super) sigma: f64,
    /// The frame's seed ([`frame_seed`]).
    pub(super) seed: u64,
}

impl Noise<'_> {
    /// The noise added to pixel `index` of the frame, grey levels.
    #[inline]
    pub(super) fn at(&self, index: usize) -> f64 {
        if self.sigma > 0.0 { self.sigma * f64::from(gaussian_table()[noise_index(self.seed, index)]) } else { 0.0 }
    }

    /// The background with its noise.
    pub(super) fn background_frame(&self, width: u32, height: u32) -> GreyImage {
        let n = width as usize * height as usize;
        let data = if self.sigma > 0.0 {
            // noise_index(seed, i) for every pixel, one hash per four pixels.
            let (table, seed) = (self.noisy_background, self.seed);
            let block_bits =
                |block: usize| splitmix64(&mut (seed ^ (block as u64).wrapping_mul(0xD1B5_4A32_D192_ED03)));
            let mut data = vec![0u8; n];
            let mut blocks = data.chunks_exact_mut(4);
            for (block, pixels) in blocks.by_ref().enumerate() {
                let bits = block_bits(block);
                for (k, p) in pixels.iter_mut().enumerate() {
                    *p = table[((bits >> (16 * k)) & 0xFFFF) as usize];
                }
            }
            let bits = block_bits(n / 4);
            for (k, p) in blocks.into_remainder().iter_mut().enumerate() {
                *p = table[((bits >> (16 * k)) & 0xFFFF) as usize];
            }
            data
        } else {
            vec![self.background; n]
        };
        GreyImage::from_raw(width, height, data).unwrap_or_else(|| GreyImage::new(width, height))
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    #[test]
    fn background_frame_is_the_noise_index_of_every_pixel() {
        let table = noisy_background(30, 3.0);
        let noise = Noise { noisy_background: &table, background: 30, sigma: 3.0, seed: 0x1234_5678_9ABC };
        // 13 x 7 = 91 pixels: the last block of four is partial.
        let img = noise.background_frame(13, 7);
        for (i, &p) in img.as_raw().iter().enumerate() {
            assert_eq!(p, table[noise_index(0x1234_5678_9ABC, i)], "pixel {i}");
        }
        let flat = Noise { sigma: 0.0, ..noise }.background_frame(5, 3);
        assert!(flat.as_raw().iter().all(|&p| p == 30));
        assert_eq!(Noise { sigma: 0.0, ..noise }.at(4), 0.0);
    }
}
