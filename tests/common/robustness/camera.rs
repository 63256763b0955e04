//! The camera: intrinsics, projection and lens distortion.
//!
//! The properties of tests/robustness_camera.rs (and the census of tests/robustness_census.rs).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common::{Lcg, random_intrinsics};
use crate::robustness::*;
use nalgebra::{Matrix3, Vector3};
use proptest::prelude::*;
use vsinv::{Distortion, DistortionModel, Intrinsics, distort_points, project_points, undistort_points};

/// `(fku, fkv, u0, v0, theta)`: a plausible camera with at most one entry replaced by a
/// special value (often), or five arbitrary values (sometimes).
fn intrinsic_parameters() -> impl Strategy<Value = [f64; 5]> {
    let plausible = (10.0..5000.0f64, 10.0..5000.0f64, -1e3..1e3f64, -1e3..1e3f64, 0.2..2.9f64)
        .prop_map(|(fku, fkv, u0, v0, theta)| [fku, fkv, u0, v0, theta]);
    let one_off = (plausible, 0usize..10, num()).prop_map(|(mut p, i, v)| {
        if i < 5 {
            p[i] = v;
        }
        p
    });
    prop_oneof![3 => one_off, 1 => prop::array::uniform5(num())]
}

pub fn prop_intrinsics(cases: u32) {
    run(cases, (intrinsic_parameters(), prop::array::uniform2(num()), prop::array::uniform9(num())), |(p, px, m)| {
        let [fku, fkv, u0, v0, theta] = p;
        let r = Intrinsics::new(fku, fkv, u0, v0, theta);
        check("Intrinsics::new", &r, |k| {
            let km = k.matrix();
            let (s, c) = theta.sin_cos();
            finite(km.iter())
                && km[(0, 0)] == fku
                && km[(0, 2)] == u0
                && km[(1, 2)] == v0
                && (km[(1, 1)] - fkv / s).abs() <= 1e-12 * km[(1, 1)].abs()
                && (km[(0, 1)] + fku * c / s).abs() <= 1e-12 * (fku * c / s).abs().max(fku * 1e-15)
        })?;
        if let Ok(k) = r {
            let n = k.normalise(px);
            check("Intrinsics::normalise", &n, |n| finite(n))?;
            let moderate = [fku, fkv].iter().all(|f| (1e-3..1e9).contains(f)) && (0.01..3.13).contains(&theta);
            if moderate && finite(&px) && px.iter().all(|v| v.abs() < 1e6) {
                prop_assert!(n.is_ok(), "normalise({px:?}) = {n:?} for {k:?}");
                let n = n.unwrap();
                let back = k.matrix() * Vector3::new(n[0], n[1], 1.0);
                let scale = 1.0 + px[0].abs().max(px[1].abs()) + u0.abs().max(v0.abs());
                prop_assert!(max_abs_diff(&[back.x, back.y], &px) <= 1e-9 * scale, "K K^-1 p = {back:?} vs {px:?}");
            }
            let back = Intrinsics::from_matrix(&k.matrix());
            check("Intrinsics::from_matrix", &back, |b| {
                let rel = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1e-300);
                rel(b.fku(), fku) && rel(b.fkv(), fkv) && rel(b.theta(), theta) && b.u0() == u0 && b.v0() == v0
            })?;
        }
        let any = Matrix3::from_row_slice(&m);
        check("Intrinsics::from_matrix", &Intrinsics::from_matrix(&any), |k| finite(k.matrix().iter()))?;
        let r = Intrinsics::pinhole(fku, fkv, u0, v0);
        check("Intrinsics::pinhole", &r, |k| finite(k.matrix().iter()) && finite(k.f_matrix().iter()))
    });
}

pub fn prop_project_points(cases: u32) {
    run(cases, (prop::collection::vec(point3(), 0..8), fault(), 0u64..1000), |(mut points, f, seed)| {
        f.apply(&mut points);
        // The first non-finite coordinate (generated or injected) is the one named.
        let first = points.as_flattened().iter().position(|v| !v.is_finite());
        let hit = first.map(|i| (i / 3, i % 3, f64::NAN));
        let k = random_intrinsics(&mut Lcg(seed));
        let r = project_points(&points, &k);
        let km = k.matrix();
        check_located("project_points", &r, nan_at("points", hit), |(px, z)| {
            finite(px.as_flattened())
                && finite(z)
                && points.iter().zip(px).all(|(p, q)| {
                    let m = km * Vector3::new(p[0] / p[2], p[1] / p[2], 1.0);
                    max_abs_diff(&[m.x, m.y], q) <= 1e-9 * (1.0 + m.x.abs().max(m.y.abs()))
                })
        })
    });
}

// ---------------------------------------------------------------------------------------------
// Lens distortion.

/// Coefficients: small realistic ones, or anything, of any length.
fn coefficients() -> impl Strategy<Value = Vec<f64>> {
    let small = prop::sample::select(vec![4usize, 5, 8]).prop_flat_map(|n| prop::collection::vec(-0.05..0.05f64, n));
    prop_oneof![3 => small, 1 => prop::collection::vec(num(), 0..10)]
}

fn pixels_in_image() -> impl Strategy<Value = Vec<[f64; 2]>> {
    prop::collection::vec((0.0..832.0f64, 0.0..624.0f64).prop_map(|(u, v)| [u, v]), 0..8)
}

pub fn prop_distortion(cases: u32) {
    let tol = prop_oneof![3 => Just(1e-10), 1 => num()];
    let inputs = (coefficients(), any::<bool>(), pixels_in_image(), fault(), tol, 0usize..60, 0u64..1000);
    run(cases, inputs, |(c, rational, mut px, f, tol, max_iter, seed)| {
        let model = if rational { DistortionModel::RationalPolynomial } else { DistortionModel::PlumbBob };
        check("Distortion::with_model", &Distortion::with_model(model, &c), |d| d.coefficients().len() == model.len())?;
        let d = Distortion::from_coefficients(&c);
        check("Distortion::from_coefficients", &d, |d| d.coefficients()[..c.len().min(5)] == c[..c.len().min(5)])?;
        let Ok(d) = d else { return Ok(()) };
        let hit = f.apply(&mut px);
        let k = random_intrinsics(&mut Lcg(seed));
        let dist = distort_points(&px, &k, &d);
        check_located("distort_points", &dist, nan_at("pixels", hit), |p| finite(p.as_flattened()))?;
        let und = undistort_points(&px, &k, &d, tol, max_iter);
        let needles = nan_at("pixels", hit).or_else(|| match () {
            _ if !(tol.is_finite() && tol >= 0.0) => Some(vec!["tol".to_string()]),
            _ if max_iter == 0 => Some(vec!["max_iter".to_string()]),
            _ => None,
        });
        check_located("undistort_points", &und, needles, |p| finite(p.as_flattened()))?;
        // Round trip where the lens cannot fold (small coefficients, |m| <= 1): back to the
        // ideal pixels within 1e-6 px.
        let no_fold = c.iter().all(|v| v.abs() <= 0.05)
            && px.iter().all(|&p| k.normalise(p).is_ok_and(|m| m[0].hypot(m[1]) <= 1.0));
        if let (true, Ok(dist)) = (no_fold, &dist) {
            let back = undistort_points(dist, &k, &d, 1e-10, 50);
            check("undistort_points", &back, |b| max_abs_diff(b.as_flattened(), px.as_flattened()) < 1e-6)?;
        }
        Ok(())
    });
}
