//! Sensor noise: additive Gaussian noise N(0, sigma^2), added to the grey level and quantised
//! with it. The draws come from a pool of 2^20 independent draws (each an index into a fixed
//! table of 65,536 N(0, 1) values), read in runs of [`RUN`] pixels from an offset hashed
//! (splitmix64) from the frame's seed and the run's number. The pool is quantised once per
//! background level and sigma ([`quantised_pool`], cached), so a frame's background is a copy
//! of runs of it (memory speed, no per-pixel hash or table look-up), and the noise of any
//! pixel is found again from its index ([`Noise::span`]) for the primitives drawn over it.
//!
//! Statistics (tested against closed forms below): every pixel is `round(background + sigma
//! n)` clamped to [0, 255] with `n` drawn from the table; two pixels take the same draw
//! only when their runs' offsets overlap (probability about 2^-20 for two given pixels, and
//! within a frame of `N` pixels about `N / 2^20` of the pixels share their draw with another
//! one, at the same rate from frame to frame), so the frames have no measurable correlation
//! between neighbours, rows or frames.

use std::sync::{Arc, Mutex, OnceLock};

use crate::vision::image::GreyImage;
use crate::vision::image::Window;

/// Pixels read from one offset of the pool.
pub(super) const RUN: usize = 64;

/// Bits of a run's offset: the pool holds `2^POOL_BITS` draws (plus one run, so that a run
/// at the last offset stays inside).
const POOL_BITS: u32 = 20;

/// 65,536 draws of N(0, 1) (Box-Muller on a fixed splitmix64 stream): an empirical Gaussian.
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

/// The pool: `2^POOL_BITS + RUN` independent uniform indices into [`gaussian_table`] (16 bits
/// each, four from one splitmix64 draw of a fixed stream), built once per process.
fn pool_indices() -> &'static [u16] {
    static POOL: OnceLock<Vec<u16>> = OnceLock::new();
    POOL.get_or_init(|| {
        let mut state = 0x9001_u64;
        let len = (1 << POOL_BITS) + RUN;
        let mut pool = Vec::with_capacity(len + 3);
        while pool.len() < len {
            let bits = splitmix64(&mut state);
            pool.extend((0..4).map(|k| (bits >> (16 * k)) as u16));
        }
        pool.truncate(len);
        pool
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

/// Where run `run` of the frame of seed `seed` starts in the pool.
#[inline]
fn run_offset(seed: u64, run: usize) -> usize {
    let mut state = seed ^ (run as u64).wrapping_mul(0xD1B5_4A32_D192_ED03);
    (splitmix64(&mut state) >> (64 - POOL_BITS)) as usize
}

/// `x` rounded to the nearest grey level (halves away from zero) and clamped to [0, 255],
/// exactly `x.round().clamp(0.0, 255.0) as u8` without the call to libm's `round` (the
/// baseline x86-64 target has no rounding instruction); NaN gives 0.
#[inline]
pub(super) fn quantise(x: f64) -> u8 {
    let x = x.clamp(0.0, 255.0);
    let whole = x as u8; // truncation; NaN gives 0
    whole + u8::from(x - f64::from(whole) >= 0.5)
}

/// `background + sigma n` quantised for every draw `n` of the pool (empty when sigma is 0),
/// shared between renderers of the same background and sigma: a few are kept, and building
/// one (a few milliseconds) happens once per process and pair. The cache's lock is only
/// tried, never waited for (a fork may have copied it locked): when it is taken, the pool is
/// built for this caller alone.
pub(super) fn quantised_pool(background: u8, sigma: f64) -> Arc<[u8]> {
    type Cache = Vec<((u8, u64), Arc<[u8]>)>;
    static CACHE: Mutex<Cache> = Mutex::new(Vec::new());
    const KEPT: usize = 4;
    if sigma <= 0.0 {
        return Arc::from(Vec::new());
    }
    let key = (background, sigma.to_bits());
    if let Ok(cache) = CACHE.try_lock()
        && let Some((_, pool)) = cache.iter().find(|(k, _)| *k == key)
    {
        return Arc::clone(pool);
    }
    let bg = f64::from(background);
    let levels: Vec<u8> = gaussian_table().iter().map(|&n| quantise(bg + sigma * f64::from(n))).collect();
    let pool: Arc<[u8]> = pool_indices().iter().map(|&i| levels[usize::from(i)]).collect();
    if let Ok(mut cache) = CACHE.try_lock() {
        if cache.len() >= KEPT {
            cache.remove(0);
        }
        cache.push((key, Arc::clone(&pool)));
    }
    pool
}

/// The noise of one frame.
#[derive(Debug, Clone, Copy)]
pub(super) struct Noise<'a> {
    /// The quantised pool ([`quantised_pool`]) of the background level and sigma.
    pub(super) pool: &'a [u8],
    /// The background's grey level.
    pub(super) background: u8,
    /// Standard deviation, grey levels (0: none).
    pub(super) sigma: f64,
    /// The frame's seed ([`frame_seed`]).
    pub(super) seed: u64,
}

impl Noise<'_> {
    /// The noise added to pixel `index` (row-major) of the frame, grey levels: the draw the
    /// background took there (what `Noise::span` is tested against).
    #[cfg(test)]
    pub(super) fn at(&self, index: usize) -> f64 {
        if self.sigma > 0.0 {
            let draw = pool_indices()[run_offset(self.seed, index / RUN) + index % RUN];
            self.sigma * f64::from(gaussian_table()[usize::from(draw)])
        } else {
            0.0
        }
    }

    /// The noise added to the pixels `start..start + len` (row-major), in order: the run's
    /// offset hashed once a run.
    pub(super) fn span(&self, start: usize, len: usize) -> impl Iterator<Item = f64> + '_ {
        (start..start + len).map(self.reader())
    }

    /// Reads the first draw of each run of the pixels `start..start + len`, all at once: each
    /// run starts at a random place of a pool larger than the caches, so its first read
    /// misses; read together, the misses of a shape's rows overlap instead of coming one after
    /// another (most of the time of painting a small shape). Changes nothing.
    pub(super) fn warm(&self, rows: impl Iterator<Item = (usize, usize)>) {
        if self.sigma <= 0.0 {
            return;
        }
        let draws = pool_indices();
        let mut sum = 0u16;
        for (start, len) in rows.filter(|&(_, len)| len > 0) {
            for run in start / RUN..=(start + len - 1) / RUN {
                let first = run_offset(self.seed, run) + if run == start / RUN { start % RUN } else { 0 };
                sum = sum.wrapping_add(draws.get(first).copied().unwrap_or(0));
            }
        }
        std::hint::black_box(sum);
    }

    /// The noise of pixel `index` (row-major), for pixels read in increasing order (any may
    /// be skipped): the run's offset hashed when the run changes, so a pixel the caller does
    /// not need costs nothing.
    pub(super) fn reader(&self) -> impl FnMut(usize) -> f64 + '_ {
        let (draws, table) = (pool_indices(), gaussian_table());
        let mut cached = (usize::MAX, 0);
        move |index| {
            if self.sigma <= 0.0 {
                return 0.0;
            }
            if cached.0 != index / RUN {
                cached = (index / RUN, run_offset(self.seed, index / RUN));
            }
            self.sigma * f64::from(table[usize::from(draws[cached.1 + index % RUN])])
        }
    }

    /// [`Noise::background_frame_in`] inside `windows` only (clipped to the image): there each
    /// pixel is what the whole frame has; elsewhere `buffer` keeps what it held (zero where
    /// it was shorter). A frame of which a tracker reads a few windows costs those windows.
    pub(super) fn background_windows_in(
        &self,
        width: u32,
        height: u32,
        mut buffer: Vec<u8>,
        windows: &[Window],
    ) -> GreyImage {
        let (w, n) = (width as usize, width as usize * height as usize);
        buffer.resize(n, 0);
        let noisy = self.sigma > 0.0 && !self.pool.is_empty();
        for window in windows {
            let (u0, u1) = (window.u0 as usize, (window.u1 as usize).min(w.saturating_sub(1)));
            if u0 > u1 {
                continue;
            }
            for v in window.v0 as usize..=(window.v1 as usize).min((height as usize).saturating_sub(1)) {
                let (first, end) = (v * w + u0, v * w + u1 + 1);
                if !noisy {
                    buffer[first..end].fill(self.background);
                    continue;
                }
                // Every run the row's piece meets, whole (a fixed-size copy, as the whole frame
                // is written; the pixels of a run beyond the window get their own values).
                for run in first / RUN..=(end - 1) / RUN {
                    let (at, start) = (run * RUN, run_offset(self.seed, run));
                    let len = RUN.min(n - at);
                    match (
                        <&mut [u8; RUN]>::try_from(&mut buffer[at..at + len]),
                        <&[u8; RUN]>::try_from(&self.pool[start..start + len]),
                    ) {
                        (Ok(to), Ok(from)) => *to = *from,
                        _ => buffer[at..at + len].copy_from_slice(&self.pool[start..start + len]),
                    }
                }
            }
        }
        GreyImage::from_raw(width, height, buffer).unwrap_or_else(|| GreyImage::new(width, height))
    }

    /// The background with its noise: each run of [`RUN`] pixels copied from the quantised
    /// pool at the run's offset (what the tests read; the renderer writes into a buffer).
    #[cfg(test)]
    pub(super) fn background_frame(&self, width: u32, height: u32) -> GreyImage {
        self.background_frame_in(width, height, Vec::new())
    }

    /// The background with its noise written into `buffer` (its contents dropped, its memory
    /// kept: a run renders every frame into the previous frame's pixels, without a fresh
    /// allocation, page faults and zeroing per frame): each run of [`RUN`] pixels copied from
    /// the quantised pool at the run's offset.
    pub(super) fn background_frame_in(&self, width: u32, height: u32, mut buffer: Vec<u8>) -> GreyImage {
        let n = width as usize * height as usize;
        buffer.clear();
        buffer.reserve_exact(n);
        if self.sigma > 0.0 && !self.pool.is_empty() {
            for run in 0..n.div_ceil(RUN) {
                let start = run_offset(self.seed, run);
                let len = RUN.min(n - run * RUN);
                match <&[u8; RUN]>::try_from(&self.pool[start..start + len]) {
                    // A whole run: a fixed-size copy (no call to memcpy).
                    Ok(whole) => buffer.extend_from_slice(whole),
                    Err(_) => buffer.extend_from_slice(&self.pool[start..start + len]),
                }
            }
        } else {
            buffer.resize(n, self.background);
        }
        GreyImage::from_raw(width, height, buffer).unwrap_or_else(|| GreyImage::new(width, height))
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    fn noise(pool: &[u8], background: u8, sigma: f64, seed: u64) -> Noise<'_> {
        Noise { pool, background, sigma, seed }
    }

    #[test]
    fn quantise_is_round_then_clamp() {
        let mut state = 3u64;
        for _ in 0..200_000 {
            let x = (splitmix64(&mut state) >> 11) as f64 / (1u64 << 53) as f64 * 300.0 - 20.0;
            for v in [x, x.floor() + 0.5, x.floor() + 0.5 - 1e-12, x.floor()] {
                assert_eq!(quantise(v), v.round().clamp(0.0, 255.0) as u8, "{v}");
            }
        }
        for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -0.5, 0.5, 254.5, 255.49, 1e300] {
            assert_eq!(quantise(v), v.round().clamp(0.0, 255.0) as u8, "{v}");
        }
    }

    /// Inside the windows (any place and size, clipped to the image, at the frame's ends),
    /// the pixels of the whole frame; outside, what the buffer held or a background value.
    #[test]
    fn background_windows_are_the_whole_frames_pixels() {
        // Any pool will do (and this one takes no lock of the pools' cache).
        let pool: Vec<u8> = (0..(1usize << POOL_BITS) + RUN).map(|i| (i * 7 % 251) as u8).collect();
        let mut state = 11u64;
        let mut below = |n: u32| (splitmix64(&mut state) % u64::from(n)) as u32;
        for sigma in [3.0, 0.0] {
            for k in 0..200 {
                let (w, h) = (1 + below(90), 1 + below(40));
                let n = noise(&pool, 30, sigma, 77 + k);
                let whole = n.background_frame(w, h);
                let windows: Vec<Window> = (0..below(4))
                    .map(|_| {
                        let (u0, v0) = (below(w), below(h));
                        Window { u0, v0, u1: u0 + below(w + 5), v1: v0 + below(h + 5) }
                    })
                    .collect();
                let stale = vec![7u8; below(2 * w * h) as usize];
                let part = n.background_windows_in(w, h, stale, &windows);
                for (i, (&a, &b)) in part.as_raw().iter().zip(whole.as_raw()).enumerate() {
                    let (u, v) = (i as u32 % w, i as u32 / w);
                    if windows.iter().any(|r| (r.u0..=r.u1).contains(&u) && (r.v0..=r.v1).contains(&v)) {
                        assert_eq!(a, b, "pixel ({u}, {v}) of {w} x {h}, sigma {sigma}");
                    } else {
                        assert!(a == b || a == 7 || a == 0, "pixel ({u}, {v}): {a}");
                    }
                }
            }
        }
    }

    #[test]
    fn background_frame_is_the_noise_of_every_pixel() {
        let pool = quantised_pool(30, 3.0);
        let n = noise(&pool, 30, 3.0, 0x1234_5678_9ABC);
        // 29 x 7 = 203 pixels: three whole runs and a partial one.
        let img = n.background_frame(29, 7);
        for (i, &p) in img.as_raw().iter().enumerate() {
            assert_eq!(p, quantise(30.0 + n.at(i)), "pixel {i}");
        }
        // A span across run boundaries gives the draws pixel by pixel.
        let span: Vec<f64> = n.span(37, 150).collect();
        assert_eq!(span, (37..187).map(|i| n.at(i)).collect::<Vec<f64>>());
        assert!(Noise { sigma: 0.0, ..n }.span(0, 9).all(|x| x == 0.0));
        // Read with pixels skipped (within a run and across runs): each pixel's draw.
        let mut read = n.reader();
        for i in (3..400).step_by(7).chain([401, 402, 530]) {
            assert_eq!(read(i), n.at(i), "pixel {i}");
        }
        let flat = Noise { sigma: 0.0, ..n }.background_frame(5, 3);
        assert!(flat.as_raw().iter().all(|&p| p == 30));
        assert_eq!(Noise { sigma: 0.0, ..n }.at(4), 0.0);
        assert!(quantised_pool(30, 0.0).is_empty());
        // Cached: the same pool again.
        assert!(Arc::ptr_eq(&pool, &quantised_pool(30, 3.0)));
    }

    /// The standard normal CDF by Simpson's rule on its density (independent of the table).
    fn phi(x: f64) -> f64 {
        let (a, steps) = (-12.0f64, 20_000);
        if x <= a {
            return 0.0;
        }
        let h = (x - a) / f64::from(steps);
        let f = |t: f64| (-0.5 * t * t).exp() / (2.0 * std::f64::consts::PI).sqrt();
        let inner: f64 = (1..steps).map(|i| f(a + f64::from(i) * h) * if i % 2 == 1 { 4.0 } else { 2.0 }).sum();
        (f(a) + inner + f(x)) * h / 3.0
    }

    /// Mean and standard deviation of `round(bg + sigma Z)` clamped to [0, 255], Z ~ N(0, 1).
    fn quantised_gaussian(bg: f64, sigma: f64) -> (f64, f64) {
        let p = |k: f64| {
            let lo = if k <= 0.0 { 0.0 } else { phi((k - 0.5 - bg) / sigma) };
            let hi = if k >= 255.0 { 1.0 } else { phi((k + 0.5 - bg) / sigma) };
            hi - lo
        };
        let (mut m1, mut m2) = (0.0, 0.0);
        for k in 0..=255 {
            let (k, pk) = (f64::from(k), p(f64::from(k)));
            m1 += k * pk;
            m2 += k * k * pk;
        }
        (m1, (m2 - m1 * m1).sqrt())
    }

    /// Pearson correlation of two equally long sequences of grey levels.
    fn correlation(a: &[u8], b: &[u8]) -> f64 {
        let n = a.len() as f64;
        let (ma, mb) =
            (a.iter().map(|&x| f64::from(x)).sum::<f64>() / n, b.iter().map(|&x| f64::from(x)).sum::<f64>() / n);
        let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
        for (&x, &y) in a.iter().zip(b) {
            let (dx, dy) = (f64::from(x) - ma, f64::from(y) - mb);
            sab += dx * dy;
            saa += dx * dx;
            sbb += dy * dy;
        }
        sab / (saa * sbb).sqrt()
    }

    #[test]
    fn frames_have_the_mean_and_std_of_the_quantised_gaussian() {
        let (w, h) = (832u32, 624u32);
        // Sigma 30 on 30: about a sixth of the draws clamped to 0.
        for (bg, sigma) in [(30u8, 0.5), (30, 2.0), (30, 4.0), (128, 10.0), (30, 30.0), (250, 7.0)] {
            let pool = quantised_pool(bg, sigma);
            let frames: Vec<Vec<u8>> =
                (0..3).map(|f| noise(&pool, bg, sigma, frame_seed(11, f)).background_frame(w, h).into_raw()).collect();
            let all: Vec<f64> = frames.iter().flatten().map(|&p| f64::from(p)).collect();
            let n = all.len() as f64;
            let mean = all.iter().sum::<f64>() / n;
            let std = (all.iter().map(|p| (p - mean).powi(2)).sum::<f64>() / n).sqrt();
            let (m, s) = quantised_gaussian(f64::from(bg), sigma);
            // 5 standard errors: of the frames' pixels, and of the 65,536-value table and the
            // 2^20-draw pool they are drawn from (fixed samples: their own errors count).
            let se = (1.0 / n + 1.0 / 65_536.0 + 1.0 / 1_048_576.0).sqrt();
            assert!((mean - m).abs() < 5.0 * s * se, "bg {bg} sigma {sigma}: mean {mean} vs {m}");
            assert!((std / s - 1.0).abs() < 5.0 * se / 2f64.sqrt(), "bg {bg} sigma {sigma}: std {std} vs {s}");
            // No correlation between neighbours (horizontal, vertical) nor between frames.
            let (a, b) = (&frames[0], &frames[1]);
            let bound = 5.0 / f64::from(w * h).sqrt();
            let wide = w as usize;
            for (what, r) in [
                ("horizontal", correlation(&a[..a.len() - 1], &a[1..])),
                ("vertical", correlation(&a[..a.len() - wide], &a[wide..])),
                ("run apart", correlation(&a[..a.len() - RUN], &a[RUN..])),
                ("frame to frame", correlation(a, b)),
            ] {
                assert!(r.abs() < bound, "bg {bg} sigma {sigma}: {what} correlation {r}");
            }
        }
    }

    #[test]
    fn frames_are_reproducible_and_differ() {
        let pool = quantised_pool(30, 4.0);
        let frame = |f| noise(&pool, 30, 4.0, frame_seed(5, f)).background_frame(64, 48);
        assert_eq!(frame(2), frame(2));
        assert_ne!(frame(2), frame(3));
        // Into a reused buffer (larger, smaller, of another frame): the same pixels.
        let n = noise(&pool, 30, 4.0, frame_seed(5, 2));
        for buffer in [vec![7u8; 64 * 48 + 1000], vec![9u8; 10], frame(3).into_raw(), Vec::new()] {
            assert_eq!(n.background_frame_in(64, 48, buffer), frame(2));
        }
        let flat = Noise { sigma: 0.0, ..n };
        assert_eq!(flat.background_frame_in(64, 48, frame(3).into_raw()), flat.background_frame(64, 48));
    }
}
