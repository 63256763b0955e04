//! Gaussian pixel noise on the visible points.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use crate::error::Error;
use crate::sim::error::Result;

/// Gaussian pixel noise (seeded: runs are reproducible).
pub(super) struct PixelNoise {
    rng: ChaCha8Rng,
    normal: Option<Normal<f64>>,
}

impl PixelNoise {
    pub(super) fn new(sigma: f64, seed: u64) -> Result<Self> {
        let normal = if sigma > 0.0 {
            Some(
                Normal::new(0.0, sigma)
                    .map_err(|e| Error::InvalidParameter { name: "noise.pixel_sigma", reason: e.to_string() })?,
            )
        } else {
            None
        };
        Ok(Self { rng: ChaCha8Rng::seed_from_u64(seed), normal })
    }

    pub(super) fn add(&mut self, pixels: &mut [[f64; 2]], visible: &[bool]) {
        let Some(normal) = &self.normal else { return };
        for (p, _) in pixels.iter_mut().zip(visible).filter(|(_, v)| **v) {
            p[0] += normal.sample(&mut self.rng);
            p[1] += normal.sample(&mut self.rng);
        }
    }
}
