//! Depths and planning.
//!
//! The properties of tests/robustness_planning.rs (and the census of tests/robustness_census.rs).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common::object_points;
use crate::robustness::*;
use nalgebra::Vector3;
use proptest::prelude::*;
use vsinv::core::depth::{ResectionDepths, depths_from_translation, resect};
use vsinv::core::planning::{InvariantPath, estimate_plane_parallax};

pub fn prop_depths(cases: u32) {
    let inputs = (0u64..1000, any::<bool>(), fault(), prop::collection::vec(any::<bool>(), 10..14), num());
    run(cases, inputs, |(seed, on_first, f, visible, mean_depth)| {
        let (mut a, mut b, z) = translation_pair(seed);
        let clean = matches!(f, Fault::None);
        let hit = f.apply(if on_first { &mut a } else { &mut b });
        let what = if on_first { "first image" } else { "second image" };
        let r = depths_from_translation(&a, &b);
        check_located("depths_from_translation", &r, nan_at(what, hit), |d| {
            let mean = z.iter().sum::<f64>() / z.len() as f64;
            let exact = !clean || d.depths.iter().zip(&z).all(|(e, t)| (e - t / mean).abs() < 1e-6);
            finite(&d.depths) && d.depths.iter().all(|&v| v > 0.0) && finite(d.epipole.iter()) && exact
        })?;
        let cloud: Vec<Vector3<f64>> = object_points().iter().map(|p| Vector3::from(*p)).collect();
        check("resect", &resect(&cloud, &b), |p| finite(p.iter()))?;
        let first_depths = r.map(|d| d.depths).unwrap_or(z);
        let est = ResectionDepths::new(&a, &first_depths, &b, mean_depth);
        check("ResectionDepths::new", &est, |_| true)?;
        let Ok(mut est) = est else { return Ok(()) };
        let sc = scene(seed);
        let (mut px, mut out) = (sc.pixels.clone(), vec![0.0; visible.len()]);
        let hit = f.apply(&mut px);
        let used = hit.filter(|h| visible.len() == 12 && px.len() == 12 && visible[h.0]);
        let r = est.estimate(&px, &visible, &mut out);
        check_located("ResectionDepths::estimate", &r, nan_at("pixels", used), |_| finite(&out))
    });
}

pub fn prop_planning(cases: u32) {
    let inputs = (0u64..1000, any::<bool>(), fault(), 4usize..10, num(), prop::collection::vec(num(), 1..4));
    run(cases, inputs, |(seed, on_q, f, m, duration, times)| {
        let (q, q_star) = invariants(seed);
        let (mut q, mut q_star): (Vec<[f64; 3]>, Vec<[f64; 3]>) =
            (q.iter().take(m).map(|v| (*v).into()).collect(), q_star.iter().take(m).map(|v| (*v).into()).collect());
        let hit = f.apply(if on_q { &mut q } else { &mut q_star });
        let what = if on_q { "q" } else { "q_star" };
        let (q, q_star): (Vec<Vector3<f64>>, Vec<Vector3<f64>>) =
            (q.into_iter().map(Vector3::from).collect(), q_star.into_iter().map(Vector3::from).collect());
        let r = estimate_plane_parallax(&q, &q_star);
        check_located("estimate_plane_parallax", &r, nan_at(what, hit), |p| {
            let mu = p.mu_e.iter().all(|v| finite(v.iter()));
            finite(p.gamma.iter()) && finite(p.epipole.iter()) && finite(&p.gamma_k) && p.residual.is_finite() && mu
        })?;
        let Ok(est) = r else { return Ok(()) };
        let path = InvariantPath::new(&q_star, &est, duration);
        check("InvariantPath::new", &path, |p| p.duration() == duration)?;
        let Ok(path) = path else { return Ok(()) };
        let (mut points, mut rates) = (vec![[0.0; 3]; q_star.len()], vec![[0.0; 3]; q_star.len()]);
        for t in times {
            let r = path.sample(t, &mut points, &mut rates);
            check("InvariantPath::sample", &r, |_| true)?;
            prop_assert_eq!(r.is_err(), t.is_nan(), "sample({}) = {:?}", t, r);
            if !t.is_nan() {
                prop_assert!(finite(points.as_flattened()) && finite(rates.as_flattened()), "sample({t})");
                let sums = points.iter().all(|p| (p.iter().sum::<f64>() - 1.0).abs() < 1e-6);
                prop_assert!(sums, "path points off the invariant plane at t = {t}: {points:?}");
            }
        }
        Ok(())
    });
}
