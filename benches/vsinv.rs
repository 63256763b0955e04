//! Criterion benchmarks of one control step.
//!
//! - `control_step/invariant/n`: [`InvariantController::step`], i.e. the five-dof law of
//!   eqs. (14), (17) and the rz law of eq. (24), for n = 6, 12, 50, 200 points.
//! - `control_step/ibvs/n`: [`IbvsController::step`] with [`Interaction::Current`], the
//!   classic pixel-space law, on the same inputs.
//! - `pose_integration/exp_twist`: [`vsinv::se3::exp_twist`], the SE(3) exponential that
//!   integrates the twist in a closed-loop simulation.
//!
//! The scene is synthetic and deterministic: a non-planar object (a grid about 0.6 m in
//! front of the reference camera with +-60 mm relief), a reference image taken with a
//! 1200 px lens and the current image taken with a 600 px lens from a displaced pose. The
//! controllers are built once and stepped repeatedly on the same pixels, so the numbers are
//! the steady-state cost of a step (the one-time structure check of the first step is paid
//! during warm-up).
//!
//! Run with `cargo bench --bench vsinv` (add `-- --quick` for a faster, rougher run).

#![allow(clippy::expect_used, clippy::unwrap_used)]

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion, Vector3};
use vsinv::{IbvsController, Interaction, Intrinsics, InvariantController, InvariantControllerConfig, choose_basis};

/// Point counts benchmarked.
const SIZES: [usize; 4] = [6, 12, 50, 200];

/// The inputs of one control step for `n` points.
struct Scene {
    reference: Vec<[f64; 2]>,
    pixels: Vec<[f64; 2]>,
    depths: Vec<f64>,
    basis: [usize; 3],
    k_hat: Intrinsics,
}

/// Grid shape (columns, rows) and extent (width, height in metres) for `n` points.
fn grid(n: usize) -> (usize, usize, f64, f64) {
    match n {
        6 => (3, 2, 0.30, 0.20),
        12 => (4, 3, 0.30, 0.24),
        50 => (10, 5, 0.36, 0.24),
        200 => (20, 10, 0.40, 0.30),
        _ => panic!("no grid for n = {n}"),
    }
}

/// `n` points on a grid centred 0.6 m in front of F*, with a deterministic relief in
/// [-60, 60] mm so that the structure is far from planar.
fn object(n: usize) -> Vec<[f64; 3]> {
    let (cols, rows, width, height) = grid(n);
    let mut points = Vec::with_capacity(n);
    for r in 0..rows {
        for c in 0..cols {
            let i = points.len() as f64;
            let x = width * (c as f64 / (cols - 1) as f64 - 0.5);
            let y = height * (r as f64 / (rows - 1) as f64 - 0.5);
            points.push([x, y, 0.6 + 0.06 * (1.7 * i + 0.4).sin()]);
        }
    }
    points
}

/// Camera coordinates of `object` (given in F*) for a camera at `pose` (camera in F*).
fn to_camera(object: &[[f64; 3]], pose: &Isometry3<f64>) -> Vec<[f64; 3]> {
    let inv = pose.inverse();
    object
        .iter()
        .map(|p| {
            let c = inv * Point3::new(p[0], p[1], p[2]);
            [c.x, c.y, c.z]
        })
        .collect()
}

fn scene(n: usize) -> Scene {
    let object = object(n);
    let k_star = Intrinsics::pinhole(1200.0, 1200.0, 384.0, 288.0).expect("reference lens");
    let k = Intrinsics::pinhole(600.0, 600.0, 384.0, 288.0).expect("current lens");
    let (reference, _) = vsinv::project_points(&object, &k_star).expect("reference view");
    // Displaced camera: 0.3 rad about a tilted axis, translated by (0.05, -0.03, -0.08) m.
    let axis = Unit::new_normalize(Vector3::new(0.3, -0.5, 1.0));
    let pose =
        Isometry3::from_parts(Translation3::new(0.05, -0.03, -0.08), UnitQuaternion::from_axis_angle(&axis, 0.3));
    let (pixels, depths) = vsinv::project_points(&to_camera(&object, &pose), &k).expect("current view");
    let basis = choose_basis(&reference).expect("basis");
    Scene { reference, pixels, depths, basis, k_hat: k }
}

fn control_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("control_step");
    for n in SIZES {
        let s = scene(n);

        let mut invariant =
            InvariantController::new(&s.reference, s.k_hat, s.basis, InvariantControllerConfig::default())
                .expect("invariant controller");
        // Fail here rather than benchmark an error path.
        invariant.step(&s.pixels, &s.depths).expect("invariant step");
        group.bench_with_input(BenchmarkId::new("invariant", n), &s, |b, s| {
            b.iter(|| invariant.step(black_box(&s.pixels), black_box(&s.depths)))
        });

        let mut ibvs =
            IbvsController::new(&s.reference, s.k_hat, 1.0, Interaction::Current, None).expect("IBVS controller");
        ibvs.step(&s.pixels, &s.depths).expect("IBVS step");
        group.bench_with_input(BenchmarkId::new("ibvs", n), &s, |b, s| {
            b.iter(|| ibvs.step(black_box(&s.pixels), black_box(&s.depths)))
        });
    }
    group.finish();
}

fn pose_integration(c: &mut Criterion) {
    let twist = [0.012, -0.034, 0.021, 0.05, -0.02, 0.11];
    let dt = 0.04;
    let scaled = twist.map(|x| x * dt);
    let mut group = c.benchmark_group("pose_integration");
    group.bench_function("exp_twist", |b| b.iter(|| vsinv::se3::exp_twist(black_box(&scaled))));
    group.finish();
}

fn config() -> Criterion {
    Criterion::default().warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(2)).sample_size(50)
}

criterion_group! {
    name = benches;
    config = config();
    targets = control_step, pose_integration
}
criterion_main!(benches);
