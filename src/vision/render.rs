//! What the camera sees: each feature point is a physical white disc (a radius in metres, a
//! normal) on a dark background. A disc's image under perspective is the conic
//! `C = H^-T diag(1, 1, -r^2) H^-1` with `H = K [E1 E2 C_c]` the homography from the disc's
//! plane (orthonormal axes E1, E2 and centre C_c in the camera frame) to the image, so the
//! ellipse is exact. Pixels get the area fraction the ellipse covers (exact inside and
//! outside, supersampled 8 x 8 near the boundary), then an optional Gaussian blur (the
//! optical PSF), additive Gaussian sensor noise, clipping and quantisation to 8 bits.

use std::sync::OnceLock;

use nalgebra::{Isometry3, Matrix2, Matrix3, Point3, Vector2, Vector3};

use crate::core::camera::Intrinsics;
use crate::core::distortion::{Distortion, distort_normalised, undistort_point};
use crate::error::{Error, Result, Short};
use crate::vision::image::GreyImage;

/// Supersampling per axis on boundary pixels.
const SUBSAMPLES: usize = 8;

/// The largest image the renderer draws (width x height, 2^28: 256 MiB of grey levels); larger
/// sizes are refused with `InvalidParameter("image size")` before any allocation.
pub const MAX_RENDER_PIXELS: u64 = 1 << 28;

/// A white disc in F* (the reference camera frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Disc {
    /// Centre, metres.
    pub center: Vector3<f64>,
    /// Unit normal of the disc's plane.
    pub normal: Vector3<f64>,
    /// Radius, metres.
    pub radius: f64,
}

impl Disc {
    /// A disc facing the reference camera: its normal points from the centre to the origin
    /// of F* (the default of scenario files).
    pub fn facing_reference(center: [f64; 3], radius: f64) -> Result<Self> {
        Self::new(center, [-center[0], -center[1], -center[2]], radius)
    }

    /// A disc with a given normal (normalised here).
    pub fn new(center: [f64; 3], normal: [f64; 3], radius: f64) -> Result<Self> {
        crate::error::check_finite("disc", &[center, normal].concat())?;
        if !(radius.is_finite() && radius > 0.0) {
            return Err(Error::InvalidParameter {
                name: "dot_radius",
                reason: format!("must be > 0, got {}", Short(radius)),
            });
        }
        let normal = Vector3::from(normal);
        let largest = normal.amax();
        if !(largest > 1e-12) {
            return Err(Error::InvalidParameter { name: "normal", reason: "must not be zero".into() });
        }
        // Scaled first: the norm of a normal of 1e300 overflows.
        let normal = normal / largest;
        Ok(Self { center: Vector3::from(center), normal: normal / normal.norm(), radius })
    }
}

/// How the images are made (the `[vision]` table of a scenario).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields, default))]
pub struct RenderConfig {
    /// Radius of the white discs drawn at the feature points, metres
    /// ([`Renderer::render_points`]).
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
}

impl Default for RenderConfig {
    fn default() -> Self {
        Self { dot_radius: 0.004, blur_sigma: 0.8, noise_sigma: 2.0, background: 30, foreground: 220, seed: 0 }
    }
}

impl RenderConfig {
    /// Checks the values.
    pub fn validate(&self) -> Result<()> {
        let bad = |name, reason: String| Err(Error::InvalidParameter { name, reason });
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

/// A rendered image and, per disc, whether it was drawn (false: hidden by the caller's mask,
/// behind the camera, straddling the camera plane or seen edge-on).
#[derive(Debug, Clone, PartialEq)]
pub struct Rendered {
    /// The 8-bit image.
    pub image: GreyImage,
    /// Per disc: drawn or not.
    pub drawn: Vec<bool>,
}

/// Renders images with one configuration (it keeps the noise tables).
#[derive(Debug, Clone)]
pub struct Renderer {
    config: RenderConfig,
    /// `background + noise` quantised, indexed by 16 random bits.
    noisy_background: Vec<u8>,
    /// The blur kernel (normalised), `2 radius + 1` taps.
    kernel: Vec<f32>,
}

/// 65,536 draws of N(0, 1) (Box-Muller on a fixed splitmix64 stream), indexed by 16
/// random bits per pixel: an empirical Gaussian that costs one table look-up.
fn gaussian_table() -> &'static [f32] {
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

fn splitmix64(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The 16-bit noise index of pixel `index` in frame `frame` (four pixels per hash).
#[inline]
fn noise_index(seed: u64, index: usize) -> usize {
    let mut state = seed ^ ((index / 4) as u64).wrapping_mul(0xD1B5_4A32_D192_ED03);
    ((splitmix64(&mut state) >> (16 * (index % 4))) & 0xFFFF) as usize
}

impl Renderer {
    /// A renderer for a configuration.
    pub fn new(config: RenderConfig) -> Result<Self> {
        config.validate()?;
        let table = gaussian_table();
        let bg = f64::from(config.background);
        let noisy_background =
            table.iter().map(|&n| (bg + config.noise_sigma * f64::from(n)).round().clamp(0.0, 255.0) as u8).collect();
        Ok(Self { config, noisy_background, kernel: gaussian_kernel(config.blur_sigma) })
    }

    /// The configuration.
    pub fn config(&self) -> &RenderConfig {
        &self.config
    }

    /// The image a camera with intrinsics `k` at `pose` (camera frame in F*) sees of the
    /// discs, `width x height` pixels; `visible` (one flag per disc) hides occluded discs;
    /// `frame` selects the noise draw.
    pub fn render(
        &self,
        discs: &[Disc],
        visible: Option<&[bool]>,
        pose: &Isometry3<f64>,
        k: &Intrinsics,
        size: (u32, u32),
        frame: u64,
    ) -> Result<Rendered> {
        let view = CameraView { pose, intrinsics: k, distortion: &Distortion::none(), size };
        self.render_through(discs, visible, &view, frame)
    }

    /// [`Renderer::render`] through a distorting lens: pixel `p` shows what the ideal pinhole
    /// image shows at `K d^-1(K^-1 p)`; a disc reaching beyond the model's fold is not drawn.
    pub fn render_through(
        &self,
        discs: &[Disc],
        visible: Option<&[bool]>,
        view: &CameraView<'_>,
        frame: u64,
    ) -> Result<Rendered> {
        let (pose, k, size) = (view.pose, view.intrinsics, view.size);
        let warp = Warp::new(k, view.distortion);
        let (width, height) = size;
        if width == 0 || height == 0 || u64::from(width) * u64::from(height) > MAX_RENDER_PIXELS {
            let reason = format!("{width} x {height}: at least 1 x 1 and at most {MAX_RENDER_PIXELS} pixels (2^28)");
            return Err(Error::InvalidParameter { name: "image size", reason });
        }
        if let Some(v) = visible
            && v.len() != discs.len()
        {
            return Err(Error::Shape {
                what: "visible",
                expected: format!("{} flags (one per disc)", discs.len()),
                got: format!("{} flags", v.len()),
            });
        }
        let seed = splitmix64(&mut (self.config.seed ^ frame.wrapping_mul(0xA24B_AED4_963E_E407)));
        let mut image = self.noise_frame(width, height, seed);
        let mut drawn = vec![false; discs.len()];
        for (i, disc) in discs.iter().enumerate() {
            if visible.is_some_and(|v| !v[i]) {
                continue;
            }
            if let Some(ellipse) = ImageEllipse::of(disc, pose, k, &warp) {
                drawn[i] = self.draw(&mut image, &ellipse, &warp, seed);
            }
        }
        Ok(Rendered { image, drawn })
    }

    /// [`Renderer::render`] of discs of radius `dot_radius` at `points` (F*), facing the
    /// reference camera.
    pub fn render_points(
        &self,
        points: &[[f64; 3]],
        visible: Option<&[bool]>,
        pose: &Isometry3<f64>,
        k: &Intrinsics,
        size: (u32, u32),
        frame: u64,
    ) -> Result<Rendered> {
        let discs: Vec<Disc> =
            points.iter().map(|&p| Disc::facing_reference(p, self.config.dot_radius)).collect::<Result<_>>()?;
        self.render(&discs, visible, pose, k, size, frame)
    }

    /// The background with its noise.
    fn noise_frame(&self, width: u32, height: u32, seed: u64) -> GreyImage {
        let n = width as usize * height as usize;
        let data = if self.config.noise_sigma > 0.0 {
            // noise_index(seed, i) for every pixel, one hash per four pixels.
            let table = &self.noisy_background;
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
            vec![self.config.background; n]
        };
        GreyImage::from_raw(width, height, data).unwrap_or_else(|| GreyImage::new(width, height))
    }

    /// Draws one ellipse (coverage, blur, noise, quantisation) over the noisy background;
    /// false when it falls entirely outside the image.
    fn draw(&self, image: &mut GreyImage, ellipse: &ImageEllipse, warp: &Warp, seed: u64) -> bool {
        let margin = (self.kernel.len() / 2) as i64 + 1;
        let (w, h) = (i64::from(image.width()), i64::from(image.height()));
        let [u0, v0, u1, v1] = ellipse.bbox;
        let (u0, v0) = ((u0.floor() as i64 - margin).max(0), (v0.floor() as i64 - margin).max(0));
        let (u1, v1) = ((u1.ceil() as i64 + margin).min(w - 1), (v1.ceil() as i64 + margin).min(h - 1));
        if u0 > u1 || v0 > v1 {
            return false;
        }
        let patch = Patch { u0, v0, w: (u1 - u0 + 1) as usize, h: (v1 - v0 + 1) as usize };
        let mut coverage = ellipse.coverage(&patch, warp);
        blur(&mut coverage, &patch, &self.kernel);
        let (bg, fg) = (f64::from(self.config.background), f64::from(self.config.foreground));
        let table = gaussian_table();
        let width = image.width() as usize;
        let data: &mut [u8] = image;
        for (j, row) in coverage.chunks_exact(patch.w).enumerate() {
            let start = (patch.v0 as usize + j) * width + patch.u0 as usize;
            for (i, &c) in row.iter().enumerate() {
                let index = start + i;
                let noise = if self.config.noise_sigma > 0.0 {
                    self.config.noise_sigma * f64::from(table[noise_index(seed, index)])
                } else {
                    0.0
                };
                let value = (bg + (fg - bg) * f64::from(c) + noise).round().clamp(0.0, 255.0) as u8;
                // max: two overlapping discs do not add up.
                data[index] = data[index].max(value);
            }
        }
        true
    }
}

/// A rectangle of pixels: the top-left pixel and the size.
struct Patch {
    u0: i64,
    v0: i64,
    w: usize,
    h: usize,
}

/// The image of a disc: its conic and bounding box.
struct ImageEllipse {
    /// `x^T C x <= 0` inside, for `x = (u, v, 1)`.
    conic: Matrix3<f64>,
    /// `[u_min, v_min, u_max, v_max]`.
    bbox: [f64; 4],
}

impl ImageEllipse {
    /// The ellipse of a disc seen from `pose`; None when the disc is not entirely in front of
    /// the camera or is seen (nearly) edge-on.
    fn of(disc: &Disc, pose: &Isometry3<f64>, k: &Intrinsics, warp: &Warp) -> Option<Self> {
        let rt = pose.rotation.inverse();
        let center = rt * (Point3::from(disc.center) - pose.translation.vector).coords;
        let normal = rt * disc.normal;
        let e1 = normal.cross(&if normal.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() }).normalize();
        let e2 = normal.cross(&e1);
        let r = disc.radius;
        // The disc's nearest point to the camera plane must be in front of it.
        if center.z - r * (e1.z * e1.z + e2.z * e2.z).sqrt() <= 1e-9 {
            return None;
        }
        // Edge-on: the camera centre (nearly) in the disc's plane.
        if normal.dot(&center).abs() <= 1e-9 * center.norm() {
            return None;
        }
        let h = k.matrix() * Matrix3::from_columns(&[e1, e2, center]);
        let h_inv = h.try_inverse()?;
        let d = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -r * r));
        let conic = h_inv.transpose() * d * h_inv;
        // Tangent lines u = c and v = c from the dual conic H diag(1, 1, -1/r^2) H^T.
        let dual = h * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0 / (r * r))) * h.transpose();
        let (u_min, u_max) = tangent_range(dual[(0, 0)], dual[(0, 2)], dual[(2, 2)])?;
        let (v_min, v_max) = tangent_range(dual[(1, 1)], dual[(1, 2)], dual[(2, 2)])?;
        let bbox = match warp {
            Warp::Pinhole => [u_min, v_min, u_max, v_max],
            Warp::Lens { .. } => warp.bbox_of_circle(&h, r)?,
        };
        Some(Self { conic, bbox })
    }

    #[inline]
    fn gradient(&self, u: f64, v: f64) -> Vector2<f64> {
        let c = &self.conic;
        Vector2::new(
            2.0 * (c[(0, 0)] * u + c[(0, 1)] * v + c[(0, 2)]),
            2.0 * (c[(0, 1)] * u + c[(1, 1)] * v + c[(1, 2)]),
        )
    }

    #[inline]
    fn value(&self, u: f64, v: f64) -> f64 {
        let c = &self.conic;
        c[(0, 0)] * u * u
            + 2.0 * c[(0, 1)] * u * v
            + c[(1, 1)] * v * v
            + 2.0 * (c[(0, 2)] * u + c[(1, 2)] * v)
            + c[(2, 2)]
    }

    /// The area fraction of each pixel of the patch inside the ellipse (pixel `(u, v)`
    /// covers `[u - 0.5, u + 0.5] x [v - 0.5, v + 0.5]`), row-major.
    fn coverage(&self, patch: &Patch, warp: &Warp) -> Vec<f32> {
        let mut out = vec![0.0f32; patch.w * patch.h];
        for j in 0..patch.h {
            let v = (patch.v0 + j as i64) as f64;
            for i in 0..patch.w {
                let u = (patch.u0 + i as i64) as f64;
                out[j * patch.w + i] = warp.local(u, v).map_or(0.0, |local| self.pixel_coverage(&local));
            }
        }
        out
    }

    /// Exact inside and outside (first-order distance to the boundary beyond 1.5 pixels),
    /// supersampled near the boundary.
    fn pixel_coverage(&self, local: &Local) -> f32 {
        let [u, v] = local.ideal;
        let gradient = local.jacobian.transpose() * self.gradient(u, v);
        let distance = self.value(u, v) / gradient.norm().max(1e-300);
        if distance < -1.5 {
            1.0
        } else if distance > 1.5 {
            0.0
        } else {
            self.supersampled(local)
        }
    }

    fn supersampled(&self, local: &Local) -> f32 {
        let step = 1.0 / SUBSAMPLES as f64;
        let (j, [u, v]) = (&local.jacobian, local.ideal);
        let mut inside = 0usize;
        for a in 0..SUBSAMPLES {
            let dv = (a as f64 + 0.5) * step - 0.5;
            for b in 0..SUBSAMPLES {
                let du = (b as f64 + 0.5) * step - 0.5;
                let (uu, vv) = (u + j[(0, 0)] * du + j[(0, 1)] * dv, v + j[(1, 0)] * du + j[(1, 1)] * dv);
                inside += usize::from(self.value(uu, vv) <= 0.0);
            }
        }
        inside as f32 / (SUBSAMPLES * SUBSAMPLES) as f32
    }
}

/// A pixel of the rendered image in the ideal pinhole image: where its centre falls and the
/// local Jacobian `d ideal / d pixel` (the identity without distortion).
struct Local {
    ideal: [f64; 2],
    jacobian: Matrix2<f64>,
}

/// From the rendered (distorted) image to the ideal pinhole image the conics live in.
enum Warp {
    Pinhole,
    Lens { k: Intrinsics, distortion: Distortion },
}

impl Warp {
    fn new(k: &Intrinsics, distortion: &Distortion) -> Self {
        if distortion.is_identity() { Warp::Pinhole } else { Warp::Lens { k: *k, distortion: *distortion } }
    }

    /// The ideal position of pixel `(u, v)` and the local Jacobian `K J_d(m)^-1 K^-1`
    /// (2 x 2 parts); None for a pixel beyond the image of the fold.
    #[inline]
    fn local(&self, u: f64, v: f64) -> Option<Local> {
        let Warp::Lens { k, distortion } = self else {
            return Some(Local { ideal: [u, v], jacobian: Matrix2::identity() });
        };
        let ideal = undistort_point([u, v], k, distortion).ok()?;
        let m = k.normalise(ideal).ok()?;
        let k2 = k.matrix().fixed_view::<2, 2>(0, 0).into_owned();
        let jacobian = k2 * distortion.jacobian(m).ok()?.try_inverse()? * k2.try_inverse()?;
        Some(Local { ideal, jacobian })
    }

    /// The bounding box of a disc's distorted image, from 72 points of its rim (`h` maps the
    /// disc's plane to ideal pixels, `r` its radius) and one pixel of margin; None if part
    /// of the rim lies beyond the fold.
    fn bbox_of_circle(&self, h: &Matrix3<f64>, r: f64) -> Option<[f64; 4]> {
        let Warp::Lens { k, distortion } = self else { return None };
        let mut bbox = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
        for i in 0..72 {
            let t = f64::from(i) * std::f64::consts::TAU / 72.0;
            let x = h * Vector3::new(r * t.cos(), r * t.sin(), 1.0);
            let p = distort_normalised(k.normalise([x.x / x.z, x.y / x.z]).ok()?, k, distortion)?;
            bbox = [bbox[0].min(p[0]), bbox[1].min(p[1]), bbox[2].max(p[0]), bbox[3].max(p[1])];
        }
        Some([bbox[0] - 1.0, bbox[1] - 1.0, bbox[2] + 1.0, bbox[3] + 1.0])
    }
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

/// The roots of `a - 2 b x + c x^2 = 0` (a tangent line `x = const` of a dual conic), sorted.
fn tangent_range(a: f64, b: f64, c: f64) -> Option<(f64, f64)> {
    let disc = b * b - a * c;
    if !(disc >= 0.0) || c == 0.0 {
        return None;
    }
    let (x1, x2) = ((b - disc.sqrt()) / c, (b + disc.sqrt()) / c);
    let (lo, hi) = (x1.min(x2), x1.max(x2));
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
}

/// A normalised Gaussian kernel of standard deviation `sigma` (3 sigma each side); `[1]`
/// when sigma is 0.
fn gaussian_kernel(sigma: f64) -> Vec<f32> {
    if sigma <= 0.0 {
        return vec![1.0];
    }
    let radius = (3.0 * sigma).ceil() as i64;
    let taps: Vec<f64> = (-radius..=radius).map(|x| (-(x * x) as f64 / (2.0 * sigma * sigma)).exp()).collect();
    let sum: f64 = taps.iter().sum();
    taps.iter().map(|t| (t / sum) as f32).collect()
}

/// Separable convolution of a row-major patch with a symmetric kernel (zero outside).
fn blur(values: &mut [f32], patch: &Patch, kernel: &[f32]) {
    if kernel.len() == 1 {
        return;
    }
    let r = kernel.len() / 2;
    let (w, h) = (patch.w, patch.h);
    let mut tmp = vec![0.0f32; values.len()];
    let convolve = |get: &dyn Fn(usize) -> f32, n: usize, x: usize| -> f32 {
        let lo = x.saturating_sub(r);
        let hi = (x + r).min(n - 1);
        (lo..=hi).map(|y| kernel[y + r - x] * get(y)).sum()
    };
    for j in 0..h {
        let row = &values[j * w..(j + 1) * w];
        for i in 0..w {
            tmp[j * w + i] = convolve(&|y| row[y], w, i);
        }
    }
    for i in 0..w {
        for j in 0..h {
            values[j * w + i] = convolve(&|y| tmp[y * w + i], h, j);
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    fn camera() -> Intrinsics {
        Intrinsics::new(800.0, 760.0, 320.0, 240.0, 85f64.to_radians()).unwrap()
    }

    fn pose() -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(0.05, -0.03, -0.1),
            UnitQuaternion::from_scaled_axis(Vector3::new(0.1, -0.2, 0.3)),
        )
    }

    #[test]
    fn conic_passes_through_the_projected_circle() {
        let disc = Disc::new([0.05, 0.02, 0.6], [0.2, -0.1, -1.0], 0.01).unwrap();
        let ell = ImageEllipse::of(&disc, &pose(), &camera(), &Warp::Pinhole).unwrap();
        let e1 = disc.normal.cross(&Vector3::x()).normalize();
        let e2 = disc.normal.cross(&e1);
        let inv = pose().inverse();
        let scale = ell.conic.norm();
        for t in 0..64 {
            let a = t as f64 / 64.0 * std::f64::consts::TAU;
            let p = disc.center + disc.radius * (a.cos() * e1 + a.sin() * e2);
            let (px, _) = camera().project(&(inv * Point3::from(p))).unwrap();
            // Normalised by |C| |x|^2, the conic vanishes on the boundary.
            let x2 = px[0] * px[0] + px[1] * px[1] + 1.0;
            assert!(ell.value(px[0], px[1]).abs() / (scale * x2) < 1e-12, "t = {t}");
            assert!(px[0] >= ell.bbox[0] - 1e-9 && px[0] <= ell.bbox[2] + 1e-9);
            assert!(px[1] >= ell.bbox[1] - 1e-9 && px[1] <= ell.bbox[3] + 1e-9);
        }
        // The centre's projection is inside.
        let (c, _) = camera().project(&(inv * Point3::from(disc.center))).unwrap();
        assert!(ell.value(c[0], c[1]) < 0.0);
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
        let out = renderer.render_through(&[disc], None, &view, 0).unwrap();
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
        let out = renderer.render(&[disc], None, &Isometry3::identity(), &k, (320, 240), 0).unwrap();
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
                Renderer::new(c).unwrap().render(&[disc], None, &Isometry3::identity(), &k, (200, 200), 0).unwrap();
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
        let render = |frame| r.render(&[], None, &Isometry3::identity(), &k, (160, 120), frame).unwrap().image;
        assert_eq!(render(3), render(3));
        assert_ne!(render(3), render(4));
        let img = render(1);
        let n = f64::from(img.width() * img.height());
        let mean = img.pixels().map(|p| f64::from(p[0])).sum::<f64>() / n;
        let var = img.pixels().map(|p| (f64::from(p[0]) - mean).powi(2)).sum::<f64>() / n;
        assert!((mean - 30.0).abs() < 0.1 && (var.sqrt() - 3.0).abs() < 0.15, "{mean} {}", var.sqrt());
    }

    #[test]
    fn noise_frame_is_the_noise_index_of_every_pixel() {
        let r = Renderer::new(RenderConfig { noise_sigma: 3.0, seed: 7, ..Default::default() }).unwrap();
        // 13 x 7 = 91 pixels: the last block of four is partial.
        let img = r.noise_frame(13, 7, 0x1234_5678_9ABC);
        for (i, &p) in img.as_raw().iter().enumerate() {
            assert_eq!(p, r.noisy_background[noise_index(0x1234_5678_9ABC, i)], "pixel {i}");
        }
    }

    #[test]
    fn hidden_behind_and_edge_on_discs_are_not_drawn() {
        let r = Renderer::new(RenderConfig::default()).unwrap();
        let k = Intrinsics::pinhole(500.0, 500.0, 80.0, 60.0).unwrap();
        let discs = [
            Disc::facing_reference([0.0, 0.0, 0.5], 0.005).unwrap(),
            Disc::facing_reference([0.0, 0.0, -0.5], 0.005).unwrap(),
            Disc::new([0.0, 0.0, 0.5], [1.0, 0.0, 0.0], 0.005).unwrap(),
            Disc::facing_reference([0.02, 0.0, 0.5], 0.005).unwrap(),
            Disc::facing_reference([5.0, 0.0, 0.5], 0.005).unwrap(),
        ];
        let visible = [true, true, true, false, true];
        let out = r.render(&discs, Some(&visible), &Isometry3::identity(), &k, (160, 120), 0).unwrap();
        assert_eq!(out.drawn, vec![true, false, false, false, false]);
        assert!(r.render(&discs, Some(&[true]), &Isometry3::identity(), &k, (160, 120), 0).is_err());
        assert!(r.render(&discs, None, &Isometry3::identity(), &k, (0, 120), 0).is_err());
        assert!(Renderer::new(RenderConfig { foreground: 10, ..Default::default() }).is_err());
        assert!(Renderer::new(RenderConfig { blur_sigma: f64::NAN, ..Default::default() }).is_err());
        assert!(Disc::new([0.0, 0.0, 1.0], [0.0; 3], 0.01).is_err());
        assert!(Disc::facing_reference([0.0, f64::NAN, 1.0], 0.01).is_err());
    }
}
