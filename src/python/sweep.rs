//! Bindings of sweeps ([`crate::sim::sweep`]): the runs of one scenario with keys overridden
//! per run, applied and run in Rust (the base read once, each run's scenario parsed once).
//! `vsinv.sweep` plans the runs and passes their values here, a chunk at a time.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use serde_json::Value;

use super::batch_watch::run_watched;
use super::errors::invalid_argument;
use super::sim::{BatchTable, access, scenario_value};
use super::values;
use crate::sim::sweep::{DERIVED_KEYS, Run, Sweep};

/// The most values one column may hold (one per run of a chunk).
const MAX_VALUES: usize = 1 << 31;

/// The runs of `values` (one list per key, one value per run) and `seeds` (one per run, or
/// None); `InvalidInput` naming `values` or `seeds` when their lengths differ or a value cannot
/// be read.
fn runs(keys: usize, values: &Bound<'_, PyAny>, seeds: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<Run>> {
    let columns = match values::to_value(values, MAX_VALUES)? {
        Ok(Value::Array(c)) if c.len() == keys && c.iter().all(Value::is_array) => c,
        Ok(_) => return Err(invalid_argument("values", format!("values: expected {keys} lists, one per key"))),
        Err(e) => return Err(invalid_argument("values", format!("values: {}: {}", e.path, e.reason))),
    };
    let columns: Vec<Vec<Value>> =
        columns.into_iter().map(|c| if let Value::Array(v) = c { v } else { Vec::new() }).collect();
    let n = match (columns.first(), seeds) {
        (Some(c), _) => c.len(),
        (None, Some(s)) => s.len()?,
        (None, None) => 0,
    };
    if let Some(k) = columns.iter().position(|c| c.len() != n) {
        let msg = format!("values: list {k} has {} values, expected {n} (one per run)", columns[k].len());
        return Err(invalid_argument("values", msg));
    }
    let seeds = match seeds {
        None => vec![None; n],
        Some(s) => seed_list(s, n)?,
    };
    let mut out: Vec<Run> = seeds.into_iter().map(|seed| Run { values: Vec::with_capacity(keys), seed }).collect();
    for column in columns {
        for (run, v) in out.iter_mut().zip(column) {
            run.values.push(v);
        }
    }
    Ok(out)
}

/// `seeds` as `n` integers in [0, 2^64).
fn seed_list(seeds: &Bound<'_, PyAny>, n: usize) -> PyResult<Vec<Option<u64>>> {
    let bad = |why: String| invalid_argument("seeds", format!("seeds: {why}"));
    let Ok(Value::Array(items)) = values::to_value(seeds, MAX_VALUES)? else {
        return Err(bad("expected a list of integers".into()));
    };
    if items.len() != n {
        return Err(bad(format!("{} seeds for {n} runs", items.len())));
    }
    items
        .iter()
        .enumerate()
        .map(|(i, s)| {
            s.as_u64().map(Some).ok_or_else(|| bad(format!("expected a non-negative integer at index {i}, got {s}")))
        })
        .collect()
}

/// The sweep of `base` over `keys` and its runs of `values` and `seeds`: the parameters both
/// bindings take, read in one place (`InvalidInput` naming the argument or key at fault).
fn planned(
    base: &Bound<'_, PyAny>,
    keys: &[String],
    values: &Bound<'_, PyAny>,
    seeds: Option<&Bound<'_, PyAny>>,
    allow_outside_files: bool,
) -> PyResult<(Sweep, Vec<Run>)> {
    let sweep = Sweep::new(scenario_value(base)?, keys, access(allow_outside_files))?;
    Ok((sweep, runs(keys.len(), values, seeds)?))
}

/// The scenarios of a sweep's runs as dictionaries: the scenario dictionary `base` with, for
/// run i, `values[k][i]` set for each key `keys[k]` (dotted scenario keys as given, then the
/// derived keys in the order of `SWEEP_DERIVED_KEYS`) and `noise.seed = seeds[i]` unless
/// `seeds` is None. `InvalidInput` names the key at fault ("vary key 'control.gian': ...").
#[pyfunction]
#[pyo3(signature = (base, keys, values, seeds = None))]
pub fn sweep_scenarios<'py>(
    py: Python<'py>,
    base: &Bound<'py, PyAny>,
    keys: Vec<String>,
    values: &Bound<'py, PyAny>,
    seeds: Option<&Bound<'py, PyAny>>,
) -> PyResult<Vec<Bound<'py, PyAny>>> {
    let (sweep, runs) = planned(base, &keys, values, seeds, false)?;
    runs.iter().map(|run| values::to_python(py, &sweep.scenario(run)?)).collect()
}

/// Runs a sweep's runs (the scenarios `sweep_scenarios` gives for the same arguments) with the
/// GIL released and returns `run_batch`'s table, one row per run. Each run's scenario is
/// parsed once, on the worker that runs it; a run whose scenario is invalid raises, its index
/// in the key (`[17].estimate.fku`), and the runs not started are skipped. `threads`,
/// `allow_outside_files` and `progress` as for `run_batch`.
#[pyfunction]
#[pyo3(signature = (base, keys, values, seeds = None, threads = None, allow_outside_files = false, progress = None))]
#[allow(clippy::too_many_arguments)]
pub fn run_sweep_runs<'py>(
    base: &Bound<'py, PyAny>,
    keys: Vec<String>,
    values: &Bound<'py, PyAny>,
    seeds: Option<&Bound<'py, PyAny>>,
    #[pyo3(from_py_with = super::args::threads)] threads: Option<usize>,
    allow_outside_files: bool,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    super::sim::check_progress(progress.as_ref())?;
    let (sweep, runs) = planned(base, &keys, values, seeds, allow_outside_files)?;
    let py = base.py();
    let results = run_watched(py, runs.len(), threads, progress.as_ref(), |watch| sweep.run(&runs, threads, watch))?;
    let mut table = BatchTable::with_capacity(results.len());
    results.iter().for_each(|r| table.push(r));
    table.into_dict(py)
}

/// Adds the sweep runner and `SWEEP_DERIVED_KEYS`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("SWEEP_DERIVED_KEYS", PyTuple::new(m.py(), DERIVED_KEYS)?)?;
    m.add_function(wrap_pyfunction!(sweep_scenarios, m)?)?;
    m.add_function(wrap_pyfunction!(run_sweep_runs, m)?)?;
    Ok(())
}
