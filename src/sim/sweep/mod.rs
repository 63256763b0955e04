//! Sweeps: many runs of one scenario with some keys overridden per run (feature `batch`).
//! The base scenario is read once into a value tree; each run's overrides ([`keys`]: dotted
//! keys, then the [`derived`] keys, then the noise seed) are applied to a copy of it, which is
//! parsed once into the run's configuration and run on vsinv's pools like a batch
//! ([`crate::sim::batch`]). `vsinv.sweep` plans the runs (grids, draws, seeds) and names them.

pub mod derived;
pub mod keys;

use rayon::prelude::*;
use serde_json::{Map, Value};

pub use derived::DERIVED_KEYS;
pub use derived::Derived;
pub use keys::{Segment, SweepKey};

use crate::parallel::pool;
use crate::sim::batch::{BatchWatch, run_config};
use crate::sim::config::SimulationConfig;
use crate::sim::error::{Result, SimError};
use crate::sim::outcome::Summary;
use crate::sim::scenario::{FileAccess, Scenario};

/// One scenario and the keys its runs vary.
#[derive(Debug, Clone)]
pub struct Sweep {
    base: Map<String, Value>,
    keys: Vec<SweepKey>,
    /// The keys in the order they are applied (dotted keys as given, then derived keys).
    order: Vec<usize>,
    access: FileAccess,
}

/// The varied values of one run, one per key, and its noise seed (None: the base's).
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// One value per key of the sweep, in the keys' order.
    pub values: Vec<Value>,
    /// `noise.seed` of the run.
    pub seed: Option<u64>,
}

impl Sweep {
    /// A sweep of `base` (a scenario's value tree, a table) over `keys`, its files resolved by
    /// the rule `access`.
    pub fn new(base: Value, keys: &[String], access: FileAccess) -> Result<Self> {
        let Value::Object(base) = base else {
            return Err(SimError::Scenario { key: crate::Location::root(), reason: "expected a table".into() });
        };
        let keys = keys.iter().map(|k| SweepKey::parse(k)).collect::<Result<Vec<_>>>()?;
        let derived_at = |k: &SweepKey| match k {
            SweepKey::Dotted { .. } => 0,
            SweepKey::Derived(d) => 1 + d.order(),
        };
        let mut order: Vec<usize> = (0..keys.len()).collect();
        order.sort_by_key(|&i| derived_at(&keys[i])); // stable: dotted keys keep their order
        Ok(Self { base, keys, order, access })
    }

    /// The keys, as read.
    pub fn keys(&self) -> &[SweepKey] {
        &self.keys
    }

    /// The scenario of `run` as a value tree: the base with the run's values applied.
    pub fn scenario(&self, run: &Run) -> Result<Value> {
        if run.values.len() != self.keys.len() {
            let reason = format!("{} values for {} keys", run.values.len(), self.keys.len());
            return Err(SimError::Scenario { key: crate::Location::root(), reason });
        }
        let mut d = self.base.clone();
        for key in &self.keys {
            keys::check_start_varies(&d, key)?;
        }
        for &i in &self.order {
            match &self.keys[i] {
                SweepKey::Dotted { key, path } => keys::set_dotted(&mut d, key, path, run.values[i].clone())?,
                SweepKey::Derived(k) => k.apply(&mut d, &run.values[i])?,
            }
        }
        if let Some(seed) = run.seed {
            let noise = d.entry("noise").or_insert(Value::Null);
            if !noise.is_object() {
                *noise = Value::Object(Map::new());
            }
            if let Value::Object(n) = noise {
                n.insert("seed".into(), Value::from(seed));
            }
        }
        Ok(Value::Object(d))
    }

    /// The configuration of `run` (its scenario parsed once, and validated).
    pub fn config(&self, run: &Run) -> Result<SimulationConfig> {
        Scenario::config_from_value_with(self.scenario(run)?, self.access)
    }

    /// Runs every run on `threads` worker threads (None: one per core), counting the finished
    /// runs in `watch` (marked finished on return) and stopping once it is cancelled. A run
    /// whose scenario is invalid fails the sweep with its index in the key (`[17].estimate`),
    /// the lowest such index; a run that fails on the way gives its error in place.
    pub fn run(&self, runs: &[Run], threads: Option<usize>, watch: &BatchWatch) -> Result<Vec<Result<Summary>>> {
        let _returned = crate::sim::batch::Returned(watch);
        let results: Vec<Result<Result<Summary>>> = pool(threads)?.install(|| {
            runs.par_iter()
                .map(|run| match self.config(run) {
                    Ok(config) => Ok(run_config(config, watch)),
                    Err(e) => {
                        watch.cancel();
                        Err(e)
                    }
                })
                .collect()
        });
        let mut out = Vec::with_capacity(results.len());
        for (i, r) in results.into_iter().enumerate() {
            out.push(r.map_err(|e| crate::sim::batch::at_index(e, i))?);
        }
        Ok(out)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::sim::scenario::builtin;
    use serde_json::json;

    /// A sweep's run equals the batch run of the same scenario written out (one parse here,
    /// JSON text there); an invalid run names its index and the sweep stops.
    #[test]
    fn sweep_runs_equal_batch_runs_of_their_scenarios() {
        let base = builtin("lens-12-6").unwrap().to_value().unwrap();
        let keys = ["focal_error".to_string(), "roll_deg".to_string(), "control.gain".to_string()];
        let sweep = Sweep::new(base, &keys, FileAccess::ScenarioFolder).unwrap();
        let runs: Vec<Run> = [(0.2, 10.0, 0.8, 3), (-0.3, -20.0, 1.0, 4)]
            .iter()
            .map(|&(e, r, g, s)| Run { values: vec![json!(e), json!(r), json!(g)], seed: Some(s) })
            .collect();
        let texts: Vec<String> = runs.iter().map(|r| sweep.scenario(r).unwrap().to_string()).collect();
        let batch = crate::sim::batch::run_json_batch(&texts, Some(2)).unwrap();
        let swept = sweep.run(&runs, Some(2), &BatchWatch::default()).unwrap();
        for (a, b) in swept.iter().zip(&batch) {
            assert_eq!(a.as_ref().unwrap(), b.as_ref().unwrap());
        }
        let v = sweep.scenario(&runs[0]).unwrap();
        assert_eq!((v["noise"]["seed"].clone(), v["control"]["gain"].clone()), (json!(3), json!(0.8)));
        let mut bad = runs.clone();
        bad[1].values[0] = json!(-1.5);
        let e = sweep.run(&bad, Some(2), &BatchWatch::default()).unwrap_err().to_string();
        assert!(e.contains("[1].estimate.fku"), "{e}");
    }
}
