//! Many simulations at once, in parallel (rayon), without per-iteration recording so that
//! memory stays flat however many runs there are.

use std::sync::{Arc, Mutex};

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::sim::scenario::{FileAccess, Scenario};
use crate::sim::{SimulationConfig, Summary, simulate};

/// Runs every configuration (recording off) on `threads` worker threads (None: one per
/// core) and returns one result per configuration, in order. A run that cannot start
/// (invalid configuration) gives its error in place; the others are unaffected.
pub fn run_batch(configs: &[SimulationConfig], threads: Option<usize>) -> Result<Vec<Result<Summary>>> {
    Ok(pool(threads)?.install(|| configs.par_iter().map(run_one).collect()))
}

/// Like [`run_batch`] for scenarios given as JSON texts, parsed in parallel too. Every
/// scenario is validated before any runs: the first invalid one fails the whole batch with
/// its index in the key (`[17].control.gain`).
pub fn run_json_batch(texts: &[String], threads: Option<usize>) -> Result<Vec<Result<Summary>>> {
    run_json_batch_with(texts, threads, FileAccess::ScenarioFolder)
}

/// [`run_json_batch`] with the rule `access` for the files the scenarios name.
pub fn run_json_batch_with(
    texts: &[String],
    threads: Option<usize>,
    access: FileAccess,
) -> Result<Vec<Result<Summary>>> {
    pool(threads)?.install(|| {
        let configs: Vec<Result<SimulationConfig>> =
            texts.par_iter().map(|t| Scenario::config_from_json_with(t, access)).collect();
        if let Some((i, err)) = configs.iter().enumerate().find_map(|(i, c)| c.as_ref().err().map(|e| (i, e))) {
            return Err(match err {
                Error::Scenario { key, reason } => Error::Scenario {
                    key: if key.is_empty() { format!("[{i}]") } else { format!("[{i}].{key}") },
                    reason: reason.clone(),
                },
                other => Error::Scenario { key: format!("[{i}]"), reason: other.to_string() },
            });
        }
        Ok(configs.into_par_iter().flatten().collect::<Vec<_>>().par_iter().map(run_one).collect())
    })
}

fn run_one(c: &SimulationConfig) -> Result<Summary> {
    let mut c = c.clone();
    c.record = false;
    simulate(&c, &mut |_, _| true).map(|o| o.summary)
}

/// The most worker threads a batch may ask for (each is an OS thread with its own stack).
pub const MAX_THREADS: usize = 1024;

/// The worker pool for `threads` (None: one thread per core). Pools are kept and reused, one
/// per thread count: starting threads on every call costs their start-up and, with glibc,
/// fresh malloc arenas that keep the process's memory growing over the first thousands of
/// batches.
fn pool(threads: Option<usize>) -> Result<Arc<rayon::ThreadPool>> {
    static POOLS: Mutex<Vec<(Option<usize>, Arc<rayon::ThreadPool>)>> = Mutex::new(Vec::new());
    if threads == Some(0) {
        return Err(Error::InvalidParameter { name: "threads", reason: "must be >= 1".into() });
    }
    if let Some(n) = threads
        && n > MAX_THREADS
    {
        return Err(Error::InvalidParameter {
            name: "threads",
            reason: format!("must be at most {MAX_THREADS}, got {n}"),
        });
    }
    let mut pools = POOLS.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    if let Some((_, p)) = pools.iter().find(|(n, _)| *n == threads) {
        return Ok(Arc::clone(p));
    }
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        builder = builder.num_threads(n);
    }
    let built = builder.build().map_err(|e| Error::InvalidParameter {
        name: "threads",
        reason: format!("cannot start the thread pool: {e}"),
    })?;
    let built = Arc::new(built);
    pools.push((threads, Arc::clone(&built)));
    Ok(built)
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::sim::scenario::builtin;

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

    #[test]
    fn json_batch_equals_config_batch_and_names_the_bad_index() {
        let s = builtin("lens-12-6").unwrap();
        let texts = vec![s.to_json().unwrap(); 3];
        let a = run_json_batch(&texts, Some(2)).unwrap();
        let b = run_batch(&[s.to_config().unwrap()], Some(1)).unwrap();
        assert!(a.iter().all(|r| r.as_ref().unwrap() == b[0].as_ref().unwrap()));
        let mut bad = texts.clone();
        bad[1] = bad[1].replace("\"gain\":1.0", "\"gain\":-1.0");
        match run_json_batch(&bad, None) {
            Err(Error::Scenario { key, .. }) => assert_eq!(key, "[1].control.gain"),
            other => panic!("{other:?}"),
        }
    }
}
