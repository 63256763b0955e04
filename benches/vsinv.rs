//! Criterion benchmarks of one control step.
//!
//! - `control_step/invariant/n`: [`InvariantController::step`], i.e. the five-dof law of
//!   eqs. (14), (17) and the rz law of eq. (24), for n = 6, 12, 50, 200 points.
//! - `control_step/ibvs/n`: [`IbvsController::step`] with [`Interaction::Current`], the
//!   classic pixel-space law, on the same inputs.
//! - `pose_integration/exp_twist`: [`vsinv::core::se3::exp_twist`], the SE(3) exponential that
//!   integrates the twist in a closed-loop simulation.
//! - `simulation/step`: the cost of *one* closed-loop iteration of the built-in scenario
//!   `lens-12-6` (12 points, free-flying camera): observe (projection and image-bounds
//!   visibility), measure, stop rule, control step, SE(3) integration. Measured by
//!   difference, so that the one-time set-up of a run (reference image, basis, controller,
//!   Prop. 1/2 check) cancels out: each sample times runs with `stop.max_iterations` = 201
//!   and = 1 (both end as `max_iterations`; the scenario converges only at 213) and reports
//!   `(T(201) - T(1)) / 200` per iteration (`iter_custom`).
//! - `simulation/lens-12-6`: a full sec. 5.2 run, [`vsinv::sim::simulate`] of the
//!   built-in `lens-12-6` with `record = false` (213 iterations, set-up included). Its
//!   throughput is set to 213 elements, so criterion also prints iterations per second
//!   (full run divided by its iteration count: the amortised per-iteration cost).
//! - `simulation/lens-12-6-recorded`: the same run with `record = true` (the per-iteration
//!   arrays the Python API hands to NumPy).
//! - `batch/lens-12-6x256/threads`: [`vsinv::sim::batch::run_batch`] of 256 copies of the
//!   `lens-12-6` configuration on 1 and 2 worker threads (the pool of each thread count is
//!   started once and reused by later calls); throughput in runs per second.
//! - `vision/render`: [`vsinv::vision::Renderer::render`] of one 832 x 624 image of the 12
//!   dots of the built-in scenario `vision-12-6` (3 mm discs, blur 0.8 px, noise 4 grey
//!   levels) seen by its 6 mm servo camera from the start pose: the image the simulator
//!   renders at every iteration (renderer built once, as in a run).
//! - `vision/detect_full_frame`: [`vsinv::vision::detect_dots`] on that image (automatic
//!   threshold, connected components and weighted centroids over the whole frame).
//! - `vision/track`: [`vsinv::vision::DotTracker::track`] of the 12 dots in that image (a
//!   40 x 40 px window per dot), in steady state: the tracker is started from the true
//!   projections and has tracked the image once.
//! - `vision/iteration`: one closed-loop iteration of `vision-12-6` through images (render,
//!   track, measure, stop rule, control step, integration), by difference as
//!   `simulation/step`: runs with `stop.max_iterations` = 51 and = 1 (both end as
//!   `max_iterations`; the scenario converges only at 572), `(T(51) - T(1)) / 50` per
//!   iteration. The 1-iteration run also pays the reference image and the tracker's start,
//!   which cancel out.
//! - `vision/render_ratio` (printed, not a criterion measurement): the render of a
//!   `vision-12-6` frame against what the loop does with it, tracking its 12 dots and one
//!   step of the invariant law on 12 points, timed in alternating rounds of one run (each
//!   the fastest of 7 rounds), with the ratio render / (track + law); the target is below 20.
//! - `choose_basis/{uniform,disk}/n`: [`vsinv::choose_basis`] (basis `"auto"`, the widest
//!   triangle) of n = 10^3 .. 10^6 pixels uniform in a 640 x 480 image or in a disc
//!   (about 3.4 n^(1/3) hull vertices); `choose_basis/circle/n`: n points on a circle, all
//!   hull vertices (the `O(h^2)` case), n = 10^3 and 10^4 (the limit).
//!
//! The scene is synthetic and deterministic: a non-planar object (a grid about 0.6 m in
//! front of the reference camera with +-60 mm relief), a reference image taken with a
//! 1200 px lens and the current image taken with a 600 px lens from a displaced pose. The
//! controllers are built once and stepped repeatedly on the same pixels, so the numbers are
//! the steady-state cost of a step (the one-time structure check of the first step is paid
//! during warm-up).
//!
//! Run with `cargo bench --bench vsinv` (add `-- --quick` for a faster, rougher run; add a
//! filter such as `-- simulation` to run one group). The slow groups use fewer samples and a
//! short measurement time so that the whole target takes about two minutes (`vision` alone
//! about half a minute).

#![allow(clippy::expect_used, clippy::unwrap_used)]

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, SamplingMode, Throughput, criterion_group, criterion_main};
use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion, Vector3};
use vsinv::sim::scene::Observation;
use vsinv::sim::{SimulationConfig, Status, simulate};
use vsinv::vision::{CameraView, DetectConfig, Disc, DotTracker, Dots, Renderer, TrackerConfig, detect_dots};
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
    group.bench_function("exp_twist", |b| b.iter(|| vsinv::core::se3::exp_twist(black_box(&scaled))));
    group.finish();
}

/// The built-in sec. 5.2 scenario as a simulation configuration.
fn lens_12_6(record: bool, max_iterations: Option<usize>) -> SimulationConfig {
    let mut c = vsinv::sim::scenario::builtin("lens-12-6").expect("built-in scenario").to_config().expect("config");
    c.record = record;
    if let Some(m) = max_iterations {
        c.stop.max_iterations = m;
    }
    c
}

/// One run; panics unless it ends with `status` after `iterations` iterations, so that a
/// change of behaviour cannot go unnoticed as a change of speed.
fn run_checked(config: &SimulationConfig, status: Status, iterations: usize) {
    let s = simulate(config, &mut |_, _| true).expect("simulation").summary;
    assert_eq!((s.status, s.iterations), (status, iterations), "lens-12-6 changed: {}", s.message);
}

/// Iterations of the full `lens-12-6` run (docs/results/built-in-scenarios.md).
const LENS_12_6_ITERATIONS: usize = 213;

/// One iteration's time: a `long`-iteration run minus a 1-iteration run (the set-up cancels
/// out), divided by `long - 1`; `iters` of each.
fn per_iteration(iters: u64, long: &SimulationConfig, short: &SimulationConfig, iterations: usize) -> Duration {
    let (mut t_long, mut t_short) = (Duration::ZERO, Duration::ZERO);
    for _ in 0..iters {
        let start = Instant::now();
        black_box(simulate(black_box(long), &mut |_, _| true).expect("run"));
        t_long += start.elapsed();
        let start = Instant::now();
        black_box(simulate(black_box(short), &mut |_, _| true).expect("run"));
        t_short += start.elapsed();
    }
    t_long.saturating_sub(t_short) / (iterations as u32 - 1)
}

fn simulation(c: &mut Criterion) {
    let mut group = c.benchmark_group("simulation");
    group.warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(4)).sample_size(30);

    // Per iteration, by difference of a 201- and a 1-iteration run (set-up cancels out).
    const LONG: usize = 201;
    let (long, short) = (lens_12_6(false, Some(LONG)), lens_12_6(false, Some(1)));
    run_checked(&long, Status::MaxIterations, LONG);
    run_checked(&short, Status::MaxIterations, 1);
    group.bench_function("step", |b| b.iter_custom(|iters| per_iteration(iters, &long, &short, LONG)));

    // Full sec. 5.2 runs, with and without recording.
    group.throughput(Throughput::Elements(LENS_12_6_ITERATIONS as u64));
    for (name, record) in [("lens-12-6", false), ("lens-12-6-recorded", true)] {
        let config = lens_12_6(record, None);
        run_checked(&config, Status::Converged, LENS_12_6_ITERATIONS);
        group.bench_function(name, |b| b.iter(|| simulate(black_box(&config), &mut |_, _| true).expect("run")));
    }
    group.finish();
}

fn batch(c: &mut Criterion) {
    const RUNS: usize = 256;
    let configs = vec![lens_12_6(false, None); RUNS];
    let mut group = c.benchmark_group("batch");
    group.warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(5)).sample_size(10);
    // ~0.1 s per call: every sample runs the same number of calls.
    group.sampling_mode(SamplingMode::Flat);
    group.throughput(Throughput::Elements(RUNS as u64));
    for threads in [1, 2] {
        let out = vsinv::sim::batch::run_batch(&configs, Some(threads)).expect("batch");
        assert!(out.iter().all(|r| r.as_ref().is_ok_and(|s| s.iterations == LENS_12_6_ITERATIONS)));
        group.bench_with_input(BenchmarkId::new("lens-12-6x256", threads), &threads, |b, &t| {
            b.iter(|| vsinv::sim::batch::run_batch(black_box(&configs), Some(t)).expect("batch"))
        });
    }
    group.finish();
}

/// The built-in `vision-12-6` scenario as a simulation configuration.
fn vision_12_6(max_iterations: usize) -> SimulationConfig {
    let mut c = vsinv::sim::scenario::builtin("vision-12-6").expect("built-in scenario").to_config().expect("config");
    c.record = false;
    c.stop.max_iterations = max_iterations;
    c
}

fn vision(c: &mut Criterion) {
    // The scene, cameras and start pose of the scenario (the stop rule does not matter here).
    let config = vision_12_6(1);
    let settings = config.vision.expect("vision-12-6 has a [vision] table");
    let renderer = Renderer::new(settings).expect("renderer");
    let scene = &config.scene;
    let discs: Result<Vec<Disc>, vsinv::vision::VisionError> = match scene.normals() {
        Some(normals) => {
            scene.points().iter().zip(normals).map(|(&p, &n)| Disc::new(p, n, settings.dot_radius)).collect()
        }
        None => scene.points().iter().map(|&p| Disc::facing_reference(p, settings.dot_radius)).collect(),
    };
    let discs = discs.expect("discs");
    let k = config.camera.at(0.0).expect("servo camera");
    let bounds = config.camera.image.expect("image size");
    let size = (bounds.width as u32, bounds.height as u32);
    assert_eq!(size, (832, 624));
    let mut obs = Observation::default();
    scene.observe(&config.start, &k, config.camera.image, &mut obs);
    assert!(obs.visible.iter().all(|&v| v), "vision-12-6 changed: a dot is not visible at the start");
    // Frame 1: the simulator's first image.
    let dots = Dots::new(discs);
    let none = vsinv::Distortion::none();
    let view = CameraView { pose: &config.start, intrinsics: &k, distortion: &none, size };
    let render = || renderer.render(&dots, Some(&obs.visible), &view, 1).expect("render");
    let rendered = render();
    assert!(rendered.drawn.iter().all(|&d| d));
    let image = rendered.image;

    let dots = detect_dots(&image, &DetectConfig::default()).expect("detection");
    assert_eq!(dots.len(), 12, "vision-12-6 changed: {} dots detected", dots.len());
    let mut tracker = DotTracker::new(&image, &obs.pixels, TrackerConfig::default()).expect("tracker");
    let first = tracker.track(&image).expect("track");
    assert!(first.found.iter().all(|&f| f), "a dot was lost");

    let mut group = c.benchmark_group("vision");
    group.warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(3)).sample_size(30);
    group.bench_function("render", |b| b.iter(render));
    // About 10 ms a call: fewer samples.
    group.sample_size(10);
    group.bench_function("detect_full_frame", |b| {
        b.iter(|| detect_dots(black_box(&image), &DetectConfig::default()).expect("detection"))
    });
    group.sample_size(30);
    group.bench_function("track", |b| b.iter(|| tracker.track(black_box(&image)).expect("track")));

    // Per iteration, by difference of a 51- and a 1-iteration run (set-up cancels out).
    const LONG: usize = 51;
    let (long, short) = (vision_12_6(LONG), vision_12_6(1));
    for (c, n) in [(&long, LONG), (&short, 1)] {
        let s = simulate(c, &mut |_, _| true).expect("simulation").summary;
        assert_eq!((s.status, s.iterations), (Status::MaxIterations, n), "vision-12-6 changed: {}", s.message);
    }
    group.sample_size(10).measurement_time(Duration::from_secs(8));
    group.bench_function("iteration", |b| b.iter_custom(|iters| per_iteration(iters, &long, &short, LONG)));
    group.finish();
    render_ratio(&renderer, &dots_view(&config), &image, &obs.pixels);
}

/// The 12 dots of `config`'s scene as drawn (discs of the scenario's radius).
fn dots_view(config: &SimulationConfig) -> Dots {
    let radius = config.vision.expect("[vision]").dot_radius;
    let scene = &config.scene;
    let discs: Result<Vec<Disc>, vsinv::vision::VisionError> = match scene.normals() {
        Some(normals) => scene.points().iter().zip(normals).map(|(&p, &n)| Disc::new(p, n, radius)).collect(),
        None => scene.points().iter().map(|&p| Disc::facing_reference(p, radius)).collect(),
    };
    Dots::new(discs.expect("discs"))
}

/// Whether the command line's filter (criterion's positional argument) selects `name`.
fn selected(name: &str) -> bool {
    let filters: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with('-')).collect();
    filters.is_empty() || filters.iter().any(|f| name.contains(f.as_str()))
}

/// Seconds per call of each closure: `rounds` rounds alternate between them (so that they
/// share the machine's load), a round times enough calls to take at least 20 ms, and each
/// closure's figure is its fastest round.
fn interleaved(fns: &mut [&mut dyn FnMut()], rounds: usize) -> Vec<f64> {
    let calls: Vec<u32> = fns
        .iter_mut()
        .map(|f| {
            let mut n = 1u32;
            loop {
                let start = Instant::now();
                (0..n).for_each(|_| f());
                if start.elapsed() >= Duration::from_millis(20) {
                    return n;
                }
                n *= 2;
            }
        })
        .collect();
    let mut best = vec![f64::INFINITY; fns.len()];
    for _ in 0..rounds {
        for ((f, &n), b) in fns.iter_mut().zip(&calls).zip(&mut best) {
            let start = Instant::now();
            (0..n).for_each(|_| f());
            *b = b.min(start.elapsed().as_secs_f64() / f64::from(n));
        }
    }
    best
}

/// `vision/render_ratio`: the render of one `vision-12-6` frame against what the loop does
/// with it (track its 12 dots, one step of the invariant law on 12 points), timed
/// alternately in one run; the target is a render under 20 times tracking plus the law.
fn render_ratio(renderer: &Renderer, dots: &Dots, image: &vsinv::vision::GreyImage, truth: &[[f64; 2]]) {
    if !selected("vision/render_ratio") {
        return;
    }
    let config = vision_12_6(1);
    let k = config.camera.at(0.0).expect("servo camera");
    let none = vsinv::Distortion::none();
    let view = CameraView { pose: &config.start, intrinsics: &k, distortion: &none, size: (832, 624) };
    // Agreement first: the frame timed is the frame the loop tracks, every dot found.
    let mut frame = 1u64;
    let rendered = renderer.render(dots, None, &view, frame).expect("render");
    assert_eq!(&rendered.image, image, "the frame rendered here is not the bench's frame 1");
    let mut tracker = DotTracker::new(image, truth, TrackerConfig::default()).expect("tracker");
    let tracked = tracker.track(image).expect("track");
    assert!(tracked.found.iter().all(|&f| f), "a dot was lost");
    let s = scene(12);
    let mut law = InvariantController::new(&s.reference, s.k_hat, s.basis, InvariantControllerConfig::default())
        .expect("invariant controller");
    law.step(&s.pixels, &s.depths).expect("invariant step");

    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    let mut render = || {
        frame += 1;
        black_box(renderer.render(dots, None, &view, frame).expect("render"));
    };
    let mut track = || {
        black_box(tracker.track(black_box(image)).expect("track"));
    };
    let mut step = || {
        black_box(law.step(black_box(&s.pixels), black_box(&s.depths)).expect("step"));
    };
    let t = interleaved(&mut [&mut render, &mut track, &mut step], 7);
    let (render_us, track_us, law_us) = (t[0] * 1e6, t[1] * 1e6, t[2] * 1e6);
    println!("vision/render_ratio (832 x 624, 12 dots; fastest of 7 alternating rounds; load {})", load.trim());
    println!("  render {render_us:.1} us, track {track_us:.2} us, invariant law {law_us:.2} us");
    println!("  render / (track + law) = {:.1} (target: below 20)", render_us / (track_us + law_us));
}

fn config() -> Criterion {
    Criterion::default().warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(2)).sample_size(50)
}

/// `n` pixels of a deterministic pseudo-random set: uniform in 640 x 480 px, uniform in a
/// disc, or evenly on a circle.
fn pixel_set(shape: &str, n: usize) -> Vec<[f64; 2]> {
    let mut state = 0x2545_F491_4F6C_DD1D_u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let tau = std::f64::consts::TAU;
    (0..n)
        .map(|i| match shape {
            "uniform" => [640.0 * next(), 480.0 * next()],
            "disk" => {
                let (r, t) = (200.0 * next().sqrt(), tau * next());
                [320.0 + r * t.cos(), 240.0 + r * t.sin()]
            }
            _ => {
                let t = tau * i as f64 / n as f64;
                [320.0 + 200.0 * t.cos(), 240.0 + 200.0 * t.sin()]
            }
        })
        .collect()
}

fn basis_choice(c: &mut Criterion) {
    let mut group = c.benchmark_group("choose_basis");
    group.sample_size(10).measurement_time(Duration::from_secs(3)).sampling_mode(SamplingMode::Flat);
    let cases = [
        ("uniform", &[16, 32, 33, 64, 128, 200, 201, 256, 1_000, 10_000, 100_000, 1_000_000][..]),
        ("disk", &[1_000, 10_000, 100_000, 1_000_000][..]),
        ("circle", &[1_000, 10_000][..]),
    ];
    for (shape, sizes) in cases {
        for &n in sizes {
            let px = pixel_set(shape, n);
            choose_basis(&px).expect("basis");
            group.throughput(Throughput::Elements(n as u64));
            group.bench_with_input(BenchmarkId::new(shape, n), &px, |b, px| b.iter(|| choose_basis(black_box(px))));
        }
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = config();
    targets = control_step, pose_integration, simulation, batch, vision, basis_choice
}
criterion_main!(benches);
