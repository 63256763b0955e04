//! Many simulations at once, in parallel (rayon), without per-iteration recording so that
//! memory stays flat however many runs there are. The runs go on vsinv's own pools
//! ([`crate::parallel`]), which a forked child rebuilds.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Condvar, Mutex, PoisonError};
use std::time::Duration;

use rayon::prelude::*;

use crate::error::Error;
use crate::parallel::pool;
use crate::sim::error::{Result, SimError};
use crate::sim::scenario::{FileAccess, Scenario};
use crate::sim::{SimulationConfig, Summary, simulate};

/// The most worker threads a batch may ask for (each is an OS thread with its own stack).
pub use crate::parallel::MAX_THREADS;

/// Runs every configuration (recording off) on `threads` worker threads (None: one per
/// core) and returns one result per configuration, in order. A run that cannot start
/// (invalid configuration) gives its error in place; the others are unaffected.
pub fn run_batch(configs: &[SimulationConfig], threads: Option<usize>) -> Result<Vec<Result<Summary>>> {
    let watch = BatchWatch::default();
    Ok(pool(threads)?.install(|| configs.par_iter().map(|c| run_config(c.clone(), &watch)).collect()))
}

/// Like [`run_batch`] for scenarios given as JSON texts, parsed in parallel too. Every
/// scenario is validated before any runs: the first invalid one fails the whole batch with
/// its index in the key (`[17].control.gain`). Each text is parsed once when the batch holds
/// at most 4,096 of them (the configurations kept until they run), twice beyond (checked, then
/// parsed again to run: memory stays flat).
pub fn run_json_batch(texts: &[String], threads: Option<usize>) -> Result<Vec<Result<Summary>>> {
    run_json_batch_with(texts, threads, FileAccess::ScenarioFolder)
}

/// [`run_json_batch`] with the rule `access` for the files the scenarios name.
pub fn run_json_batch_with(
    texts: &[String],
    threads: Option<usize>,
    access: FileAccess,
) -> Result<Vec<Result<Summary>>> {
    run_json_batch_watched(texts, threads, access, &BatchWatch::default())
}

/// [`run_json_batch_with`] that counts the finished runs in `watch` (for a progress report
/// from another thread) and skips or stops the runs once `watch` is cancelled (those give an
/// error). `watch` is marked finished when the batch returns, whatever the result.
pub fn run_json_batch_watched(
    texts: &[String],
    threads: Option<usize>,
    access: FileAccess,
    watch: &BatchWatch,
) -> Result<Vec<Result<Summary>>> {
    let _returned = Returned(watch);
    json_batch_on_pool(texts, threads, access, watch)
}

/// Marks a batch returned however it ends (a panicking run included).
pub(crate) struct Returned<'a>(pub(crate) &'a BatchWatch);

impl Drop for Returned<'_> {
    fn drop(&mut self) {
        self.0.finish();
    }
}

/// The error of the scenario `i` of a batch, its key under the index (`[17].control.gain`).
pub(crate) fn at_index(err: SimError, i: usize) -> SimError {
    match err {
        SimError::Scenario { key, reason } => SimError::Scenario { key: key.under_index(i), reason },
        other => SimError::Scenario { key: crate::Location::root().then_index(i), reason: other.to_string() },
    }
}

/// Batches of at most this many scenarios keep each parsed configuration until its run (each
/// text parsed once); larger ones parse each text to check it before any runs and again when
/// it runs, so that memory stays flat: a configuration is about 15 KB (4096 of them, 60 MB; a
/// batch of 10^5 kept 1.5 GB before its first run).
const KEPT_CONFIGS: usize = 4096;

fn json_batch_on_pool(
    texts: &[String],
    threads: Option<usize>,
    access: FileAccess,
    watch: &BatchWatch,
) -> Result<Vec<Result<Summary>>> {
    pool(threads)?.install(|| {
        // Every scenario is checked before any runs; the first error names its index.
        if texts.len() <= KEPT_CONFIGS {
            let configs: Vec<Result<SimulationConfig>> =
                texts.par_iter().map(|t| Scenario::config_from_json_with(t, access)).collect();
            let configs: Vec<SimulationConfig> =
                configs.into_iter().enumerate().map(|(i, c)| c.map_err(|e| at_index(e, i))).collect::<Result<_>>()?;
            return Ok(configs.into_par_iter().map(|c| run_config(c, watch)).collect());
        }
        let first_error = texts
            .par_iter()
            .enumerate()
            .find_map_first(|(i, t)| Scenario::config_from_json_with(t, access).err().map(|e| (i, e)));
        if let Some((i, err)) = first_error {
            return Err(at_index(err, i));
        }
        Ok(texts.par_iter().map(|t| run_one(t, access, watch)).collect())
    })
}

fn run_one(text: &str, access: FileAccess, watch: &BatchWatch) -> Result<Summary> {
    if watch.is_cancelled() {
        return Err(cancelled().into());
    }
    match Scenario::config_from_json_with(text, access) {
        Ok(config) => run_config(config, watch),
        Err(e) => {
            watch.finished_one();
            Err(e)
        }
    }
}

pub(crate) fn run_config(mut config: SimulationConfig, watch: &BatchWatch) -> Result<Summary> {
    if watch.is_cancelled() {
        return Err(cancelled().into());
    }
    config.record = false;
    let result = simulate(&config, &mut |_, _| !watch.is_cancelled()).map(|o| o.summary);
    watch.finished_one();
    result
}

fn cancelled() -> Error {
    Error::InvalidParameter { name: "batch", reason: "cancelled before this run started".into() }
}

/// A running batch seen from another thread: how many runs have finished, whether the batch
/// has returned, and a switch that stops it early.
#[derive(Debug, Default)]
pub struct BatchWatch {
    /// Finished runs, and whether the batch has returned.
    state: Mutex<(usize, bool)>,
    changed: Condvar,
    cancelled: AtomicBool,
}

impl BatchWatch {
    fn update(&self, f: impl FnOnce(&mut (usize, bool))) {
        f(&mut self.state.lock().unwrap_or_else(PoisonError::into_inner));
        self.changed.notify_all();
    }

    fn finished_one(&self) {
        self.update(|s| s.0 += 1);
    }

    fn finish(&self) {
        self.update(|s| s.1 = true);
    }

    /// Waits at most `timeout` for more than `seen` runs to have finished or for the batch to
    /// return; gives (finished runs, batch returned).
    pub fn wait_past(&self, seen: usize, timeout: Duration) -> (usize, bool) {
        let state = self.state.lock().unwrap_or_else(PoisonError::into_inner);
        let (state, _) = self
            .changed
            .wait_timeout_while(state, timeout, |s| s.0 <= seen && !s.1)
            .unwrap_or_else(PoisonError::into_inner);
        *state
    }

    /// Stops the batch: runs not started are skipped, running ones stop at their next iteration.
    pub fn cancel(&self) {
        self.cancelled.store(true, Ordering::Relaxed);
    }

    /// Whether [`cancel`](Self::cancel) was called.
    pub fn is_cancelled(&self) -> bool {
        self.cancelled.load(Ordering::Relaxed)
    }
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
            Err(SimError::Scenario { key, .. }) => assert_eq!(key.to_string(), "[1].control.gain"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_watched_batch_counts_its_runs_and_can_be_cancelled() {
        let texts = vec![builtin("lens-12-6").unwrap().to_json().unwrap(); 5];
        let watch = BatchWatch::default();
        let results = std::thread::scope(|s| {
            let batch = s.spawn(|| run_json_batch_watched(&texts, Some(2), FileAccess::ScenarioFolder, &watch));
            let mut seen = 0;
            loop {
                let (done, returned) = watch.wait_past(seen, Duration::from_secs(60));
                assert!(done >= seen && done <= texts.len());
                seen = done;
                if returned {
                    break;
                }
            }
            batch.join().unwrap().unwrap()
        });
        assert_eq!(watch.wait_past(0, Duration::ZERO), (5, true));
        assert!(results.iter().all(Result::is_ok));
        let stopped = BatchWatch::default();
        stopped.cancel();
        let results = run_json_batch_watched(&texts, Some(2), FileAccess::ScenarioFolder, &stopped).unwrap();
        assert!(results.iter().all(Result::is_err));
    }
}
