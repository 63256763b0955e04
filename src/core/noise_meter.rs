//! The pixel noise of an image stream, measured from the images themselves (not in the paper).
//!
//! The second difference of a point's pixel over three consecutive images,
//! `d = p(k) - 2 p(k+1) + p(k+2)`, cancels any motion that is linear in time (near the goal
//! the camera barely moves, so its acceleration term is far below the noise), and for noise
//! independent between images with standard deviation `sigma` per coordinate,
//! `E[d^2] = 6 sigma^2`. The meter averages `d^2` over the last images, every point seen in
//! all three and both coordinates.

use std::collections::VecDeque;

use crate::error::{Error, Result};

/// The largest number of images a meter keeps.
pub const MAX_NOISE_IMAGES: usize = 4096;

/// Measures the pixel noise of the last `capacity` images.
#[derive(Debug, Clone)]
pub struct PixelNoiseMeter {
    capacity: usize,
    /// One image a row, NaN for hidden points.
    images: VecDeque<Vec<[f64; 2]>>,
}

impl PixelNoiseMeter {
    /// A meter over the last `capacity` images (3 to [`MAX_NOISE_IMAGES`]).
    pub fn new(capacity: usize) -> Result<Self> {
        if !(3..=MAX_NOISE_IMAGES).contains(&capacity) {
            return Err(Error::InvalidParameter {
                name: "capacity",
                reason: format!("must be from 3 to {MAX_NOISE_IMAGES} images, got {capacity}"),
            });
        }
        Ok(Self { capacity, images: VecDeque::with_capacity(capacity) })
    }

    /// Adds an image's pixels (`visible`: the points found; `None`: all; a hidden point's pixel
    /// is ignored and may be NaN, a visible one must be finite). An image with another number
    /// of points than the previous ones starts the measurement again.
    pub fn push(&mut self, pixels: &[[f64; 2]], visible: Option<&[bool]>) -> Result<()> {
        if let Some(v) = visible
            && v.len() != pixels.len()
        {
            return Err(Error::Shape {
                what: "visible",
                expected: format!("{} flags (one per point)", pixels.len()),
                got: format!("{} flags", v.len()),
            });
        }
        if let Some(row) =
            (0..pixels.len()).find(|&i| visible.is_none_or(|v| v[i]) && !pixels[i].iter().all(|x| x.is_finite()))
        {
            let column = usize::from(pixels[row][0].is_finite());
            return Err(Error::NonFinitePoint { what: "pixels", row, column });
        }
        if self.images.front().is_some_and(|f| f.len() != pixels.len()) {
            self.images.clear();
        }
        let mut row =
            if self.images.len() == self.capacity { self.images.pop_front().unwrap_or_default() } else { Vec::new() };
        row.clear();
        row.extend(
            pixels.iter().enumerate().map(|(i, p)| if visible.is_none_or(|v| v[i]) { *p } else { [f64::NAN; 2] }),
        );
        self.images.push_back(row);
        Ok(())
    }

    /// The images kept.
    pub fn len(&self) -> usize {
        self.images.len()
    }

    /// Whether no image was pushed since the start (or the last [`clear`](Self::clear)).
    pub fn is_empty(&self) -> bool {
        self.images.is_empty()
    }

    /// Forgets the images.
    pub fn clear(&mut self) {
        self.images.clear();
    }

    /// The standard deviation of a pixel coordinate, pixels: `sqrt(mean(d^2) / 6)`; `None`
    /// until some point was seen in three consecutive images.
    pub fn sigma(&self) -> Option<f64> {
        let (mut sum, mut count) = (0.0, 0usize);
        for k in 2..self.images.len() {
            let (a, b, c) = (&self.images[k - 2], &self.images[k - 1], &self.images[k]);
            for i in 0..a.len() {
                for axis in 0..2 {
                    let d = a[i][axis] - 2.0 * b[i][axis] + c[i][axis];
                    if d.is_finite() {
                        sum += d * d;
                        count += 1;
                    }
                }
            }
        }
        (count > 0).then(|| (sum / (6.0 * count as f64)).sqrt()).filter(|s| s.is_finite())
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    /// Gaussian samples from a fixed linear congruential sequence (Box-Muller).
    fn gauss(state: &mut u64, sigma: f64) -> f64 {
        let mut uniform = || {
            *state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((*state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        let (a, b) = (uniform(), uniform());
        sigma * (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
    }

    #[test]
    fn measures_the_noise_of_still_and_moving_points() {
        for (velocity, sigma) in [(0.0, 0.7), (0.8, 0.7), (3.0, 0.05), (0.0, 2.0)] {
            let mut meter = PixelNoiseMeter::new(500).unwrap();
            let mut state = 3;
            for k in 0..500 {
                let t = k as f64;
                let pixels: Vec<[f64; 2]> = (0..10)
                    .map(|i| {
                        [
                            100.0 + 10.0 * i as f64 + velocity * t + gauss(&mut state, sigma),
                            50.0 - velocity * t + gauss(&mut state, sigma),
                        ]
                    })
                    .collect();
                meter.push(&pixels, None).unwrap();
            }
            let measured = meter.sigma().unwrap();
            // 10 points x 2 coordinates x 498 triples: the estimate's spread is a few percent.
            assert!((measured / sigma - 1.0).abs() < 0.05, "velocity {velocity}: {measured} for {sigma}");
        }
    }

    #[test]
    fn noise_free_points_measure_zero_and_hidden_points_are_skipped() {
        let mut meter = PixelNoiseMeter::new(3).unwrap();
        assert_eq!(meter.sigma(), None);
        for k in 0..5 {
            let t = k as f64;
            meter.push(&[[1.0 + 2.0 * t, 4.0], [f64::NAN, 0.0], [9.0, 9.0]], Some(&[true, false, k != 3])).unwrap();
        }
        let nan = meter.push(&[[1.0, 4.0], [0.0, f64::NAN], [9.0, 9.0]], None);
        assert!(matches!(nan, Err(Error::NonFinitePoint { what: "pixels", row: 1, column: 1 })));
        assert_eq!(meter.len(), 3);
        assert_eq!(meter.sigma(), Some(0.0));
        meter.push(&[[0.0, 0.0]], None).unwrap(); // another point count: starts again
        assert_eq!((meter.len(), meter.sigma()), (1, None));
        assert!(matches!(meter.push(&[[0.0, 0.0]], Some(&[true, false])), Err(Error::Shape { what: "visible", .. })));
        assert!(matches!(PixelNoiseMeter::new(2), Err(Error::InvalidParameter { name: "capacity", .. })));
        assert!(PixelNoiseMeter::new(MAX_NOISE_IMAGES + 1).is_err());
    }
}
