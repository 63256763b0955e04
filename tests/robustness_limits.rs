//! Scenario limits that hold together (issue 28, finding 3 and its Build point): a run of
//! `stop.max_iterations = 10_000_000` (the documented maximum) with recording on and a stop
//! rule never met aborted on memory after 29 s. The record now holds at most
//! `record_bytes`: past it, one iteration in 2, 4, ... is kept, with the first and the last.
//! Checked against the whole record of the same run (the kept rows are its rows).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use vsinv::sim::scenario::builtin;
use vsinv::sim::{MAX_RECORD_BYTES, Recording, SimulationConfig, simulate};

/// lens-12-6 with pixel noise and stop thresholds never met: runs to `max_iterations`.
fn endless(max_iterations: usize) -> SimulationConfig {
    let mut c = builtin("lens-12-6").unwrap().to_config().unwrap();
    c.stop.max_iterations = max_iterations;
    c.stop.pixel_error = 1e-9;
    c.stop.invariant_error = 1e-12;
    c.stop.tau21 = 1e-12;
    c.noise.pixel_sigma = 1.0;
    c
}

fn record(config: &SimulationConfig) -> (Recording, usize) {
    let out = simulate(config, &mut |_, _| true).unwrap();
    (out.recording.unwrap(), out.summary.iterations)
}

/// Row `i` of every column of `r`, flattened (NaN as a bit pattern, so rows compare exactly).
fn row(r: &Recording, i: usize) -> Vec<u64> {
    let n = r.len();
    let f = |c: &Vec<f64>| -> Vec<u64> {
        let w = c.len() / n;
        c[i * w..(i + 1) * w].iter().map(|v| v.to_bits()).collect()
    };
    let mut out = Vec::new();
    for c in [
        &r.time,
        &r.pose,
        &r.twist,
        &r.joints,
        &r.pixels,
        &r.invariant_error,
        &r.tracking_error,
        &r.eps,
        &r.eps_z,
        &r.image_error,
        &r.translation_error,
        &r.rotation_error,
    ] {
        out.extend(f(c));
    }
    let w = r.visible.len() / n;
    out.extend(r.visible[i * w..(i + 1) * w].iter().map(|&v| u64::from(v)));
    out
}

#[test]
fn a_run_that_fits_is_recorded_whole() {
    let c = endless(500);
    assert_eq!(c.record_bytes, MAX_RECORD_BYTES);
    let (r, iterations) = record(&c);
    assert_eq!((iterations, r.len()), (500, 501));
}

#[test]
fn a_long_run_keeps_a_thinned_record_within_the_budget() {
    let whole = endless(1000);
    let (full, iterations) = record(&whole);
    assert_eq!(full.len(), iterations + 1);
    for bytes in [20_000, 50_000, 123_457] {
        let mut c = whole.clone();
        c.record_bytes = bytes;
        let (r, _) = record(&c);
        let row_bytes = 8
            * (r.time.len()
                + r.pose.len()
                + r.twist.len()
                + r.joints.len()
                + r.pixels.len()
                + r.invariant_error.len()
                + r.tracking_error.len()
                + r.eps.len()
                + r.eps_z.len()
                + r.image_error.len()
                + r.translation_error.len()
                + r.rotation_error.len())
            + r.visible.len();
        assert!(row_bytes <= bytes, "{row_bytes} bytes recorded for a budget of {bytes}");
        assert!(r.len() >= 3 && r.len() < full.len());
        // The rows are the whole record's rows at iterations 0, s, 2s, ... and the last.
        let iters: Vec<usize> = r.time.iter().map(|t| (t / c.dt).round() as usize).collect();
        let stride = iters[1];
        assert!(stride.is_power_of_two() && stride >= 2, "{iters:?}");
        assert_eq!(*iters.last().unwrap(), iterations);
        for (k, &it) in iters[..iters.len() - 1].iter().enumerate() {
            assert_eq!(it, k * stride, "{iters:?}");
        }
        for (k, &it) in iters.iter().enumerate() {
            assert_eq!(row(&r, k), row(&full, it), "row {k} (iteration {it})");
        }
    }
}
