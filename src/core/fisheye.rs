//! OpenCV's fisheye model (Kannala-Brandt, `cv2.fisheye`; ROS's `equidistant`), not in the
//! paper. A ray at the angle `theta` from the optical axis is imaged at the distance
//!
//! ```text
//! theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8)
//! ```
//!
//! from the principal point in normalised coordinates, in the ray's own direction: a ray
//! `(X, Y, Z)` has `theta = atan2(sqrt(X^2 + Y^2), Z)` and the distorted normalised point
//! `m_d = theta_d (X, Y) / sqrt(X^2 + Y^2)`. For a point in front of the camera, with
//! `m = (X/Z, Y/Z)` and `r = |m|`, this is `theta = atan(r)` and `m_d = (theta_d / r) m`,
//! OpenCV's `cv2.fisheye.distortPoints` (whose `alpha` is this crate's `K[0,1] / K[0,0]`).
//!
//! **Range.** `theta` runs from 0 to 180 degrees, but the model is one-to-one only while
//! `theta_d` increases: its *fold* is the first angle where `d theta_d / d theta =
//! 1 + 3 k1 theta^2 + 5 k2 theta^4 + 7 k3 theta^6 + 9 k4 theta^8` reaches 0. The model's
//! range is `0 <= theta < max_angle`, `max_angle` the fold or 180 degrees, whichever comes
//! first; a ray at or beyond it has no image (the lens does not image it where the model
//! says), and a distorted radius at or beyond `theta_d(max_angle)` has no pre-image. Rays
//! beyond 90 degrees (behind the image plane) are imaged where the range reaches them, but
//! they have no normalised point `(X/Z, Y/Z)` nor pinhole pixel: only the ray functions
//! ([`crate::core::distortion::distort_rays`], [`crate::core::distortion::undistort_rays`])
//! express them.

use std::f64::consts::PI;

/// Samples of `d theta_d / d theta` on `(0, pi]` looking for the fold.
const FOLD_SAMPLES: u32 = 4096;

/// `theta_d(theta)` (module docs), `k = (k1, k2, k3, k4)`.
#[inline]
pub(crate) fn theta_d(k: &[f64; 4], theta: f64) -> f64 {
    let t2 = theta * theta;
    theta * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))))
}

/// `d theta_d / d theta`.
#[inline]
pub(crate) fn theta_d_slope(k: &[f64; 4], theta: f64) -> f64 {
    let t2 = theta * theta;
    1.0 + t2 * (3.0 * k[0] + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])))
}

/// The model's range `max_angle` (module docs): the first angle in `(0, pi]` where
/// `d theta_d / d theta <= 0`, found on a grid of [`FOLD_SAMPLES`] angles and refined by
/// bisection (the slope is positive at every grid angle below it), or `pi` without a fold.
pub(crate) fn max_angle(k: &[f64; 4]) -> f64 {
    let step = PI / f64::from(FOLD_SAMPLES);
    let Some(i) = (1..=FOLD_SAMPLES).find(|&i| !(theta_d_slope(k, f64::from(i) * step) > 0.0)) else {
        return PI;
    };
    let (mut lo, mut hi) = (f64::from(i - 1) * step, f64::from(i) * step);
    while hi - lo > 4.0 * f64::EPSILON * hi {
        let mid = 0.5 * (lo + hi);
        if theta_d_slope(k, mid) > 0.0 { lo = mid } else { hi = mid }
    }
    hi
}

/// The angle `theta` in `[0, max_angle)` with `theta_d(theta) = rd`: Newton's method on
/// `theta` from `theta = rd`, kept inside a bracket that shrinks at every iteration (a step
/// that leaves it is replaced by bisection), at most `max_iter` iterations. It stops after
/// the step that is below `1e-13 theta` (quadratic convergence puts the answer at rounding
/// error), or where the residual `theta_d(theta) - rd` is at rounding error (`4 eps rd`:
/// near the fold, where the slope is small, that is as close as `theta` can be told). The
/// reason of the failure otherwise: `rd` at or beyond `theta_d(max_angle)`, the image of the
/// fold (no pre-image), or no convergence within `max_iter`.
pub(crate) fn solve_theta(k: &[f64; 4], max_angle: f64, rd: f64, max_iter: usize) -> Result<f64, String> {
    if rd == 0.0 {
        return Ok(0.0);
    }
    let edge = theta_d(k, max_angle);
    if !(rd < edge) {
        let limit = if max_angle < PI { "the model's fold" } else { "180 degrees (the ray straight back)" };
        return Err(format!(
            "distorted radius {rd:.6e} is at or beyond {edge:.6e}, the image of {limit} at theta = {:.4} deg: \
             the equidistant model has no ray there",
            max_angle.to_degrees()
        ));
    }
    let (mut lo, mut hi) = (0.0, max_angle);
    let mut theta = if rd < hi { rd } else { 0.5 * hi };
    for _ in 0..max_iter {
        let f = theta_d(k, theta) - rd;
        if f.abs() <= 4.0 * f64::EPSILON * rd {
            return Ok(theta);
        }
        if f < 0.0 {
            lo = theta
        } else {
            hi = theta
        }
        let newton = theta - f / theta_d_slope(k, theta);
        let next = if newton > lo && newton < hi { newton } else { 0.5 * (lo + hi) };
        let converged = (next - theta).abs() <= 1e-13 * theta;
        theta = next;
        if converged {
            return Ok(theta);
        }
    }
    Err(format!("Newton's method on theta did not converge in {max_iter} iterations (theta_d = {rd:.6e})"))
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    #[test]
    fn slope_is_the_derivative() {
        let k = [-0.05, 0.01, -0.002, 0.0003];
        for t in [0.0, 0.3, 1.2, 2.0, 3.0] {
            let h = 1e-6;
            let fd = (theta_d(&k, t + h) - theta_d(&k, t - h)) / (2.0 * h);
            assert!((fd - theta_d_slope(&k, t)).abs() < 1e-8, "{t}: {fd}");
        }
    }

    #[test]
    fn max_angle_is_the_first_zero_of_the_slope() {
        // k1 = -0.1 alone: slope 1 - 0.3 theta^2, zero at theta = sqrt(1 / 0.3).
        let a = max_angle(&[-0.1, 0.0, 0.0, 0.0]);
        assert!((a - (1.0f64 / 0.3).sqrt()).abs() < 1e-14, "{a}");
        assert_eq!(max_angle(&[0.0; 4]), PI);
        assert_eq!(max_angle(&[0.01, 0.0, 0.0, 0.0]), PI);
    }

    #[test]
    fn solve_inverts_and_refuses_beyond_the_fold() {
        let k = [-0.1, 0.0, 0.0, 0.0];
        let a = max_angle(&k);
        for t in [1e-9, 0.01, 0.7, 1.5, 0.999 * a] {
            let got = solve_theta(&k, a, theta_d(&k, t), 50).unwrap();
            assert!((got - t).abs() <= 1e-13 * t.max(1.0) + 1e-15, "{t}: {got}");
        }
        let e = solve_theta(&k, a, theta_d(&k, a) * 1.0001, 50).unwrap_err();
        assert!(e.contains("fold"), "{e}");
        let e = solve_theta(&[0.0; 4], PI, 3.2, 50).unwrap_err();
        assert!(e.contains("180"), "{e}");
        let e = solve_theta(&k, a, 1.0, 1).unwrap_err();
        assert!(e.contains("converge"), "{e}");
    }
}
