//! Many simulations at once, in parallel (rayon), without per-iteration recording so that
//! memory stays flat however many runs there are.

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::simulator::{SimulationConfig, Summary, simulate};

/// Runs every configuration (recording off) on `threads` worker threads (None: one per
/// core) and returns one result per configuration, in order. A run that cannot start
/// (invalid configuration) gives its error in place; the others are unaffected.
pub fn run_batch(configs: &[SimulationConfig], threads: Option<usize>) -> Result<Vec<Result<Summary>>> {
    let run = |c: &SimulationConfig| {
        let mut c = c.clone();
        c.record = false;
        simulate(&c, &mut |_, _| true).map(|o| o.summary)
    };
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        if n == 0 {
            return Err(Error::InvalidParameter { name: "threads", reason: "must be >= 1".into() });
        }
        builder = builder.num_threads(n);
    }
    let pool = builder.build().map_err(|e| Error::InvalidParameter {
        name: "threads",
        reason: format!("cannot start the thread pool: {e}"),
    })?;
    Ok(pool.install(|| configs.par_iter().map(run).collect()))
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::scenario::builtin;

    #[test]
    fn batch_equals_sequential_runs() {
        let mut configs = Vec::new();
        for seed in 0..6 {
            let mut s = builtin("noise-12-6").unwrap();
            s.noise.seed = seed;
            configs.push(s.to_config().unwrap());
        }
        configs.push(builtin("planar").unwrap().to_config().unwrap());
        let batch = run_batch(&configs, Some(2)).unwrap();
        for (c, r) in configs.iter().zip(&batch) {
            let alone = simulate(c, &mut |_, _| true).unwrap().summary;
            assert_eq!(r.as_ref().unwrap(), &alone);
        }
        assert!(run_batch(&configs, Some(0)).is_err());
    }
}
