//! A batch run with the GIL released while the calling thread reports its progress and
//! answers Ctrl-C: the batch is a job of vsinv's rayon pool, the calling thread waits on the
//! batch's counter and takes the GIL only to call `progress(done, total)` and to check for
//! signals (every 0.1 s, and without a reporter only then).

use std::time::Duration;

use pyo3::prelude::*;

use crate::sim::Summary;
use crate::sim::batch::{BatchWatch, run_json_batch_watched};
use crate::sim::scenario::FileAccess;

/// How long the calling thread waits for a run to finish before it checks for signals.
const SIGNAL_CHECK: Duration = Duration::from_millis(100);

/// Runs the scenarios (JSON texts) and calls `reporter(done, total)` (if given) whenever runs
/// have finished, with `done` increasing up to `total`. An exception raised by the reporter or
/// by a signal handler (KeyboardInterrupt) cancels the batch and is raised.
pub fn run_reporting(
    py: Python<'_>,
    texts: &[String],
    threads: Option<usize>,
    access: FileAccess,
    reporter: Option<&Bound<'_, PyAny>>,
) -> PyResult<Vec<crate::sim::error::Result<Summary>>> {
    let batch = |watch: &BatchWatch| run_json_batch_watched(texts, threads, access, watch);
    run_watched(py, texts.len(), threads, reporter, batch)
}

/// Runs `batch` (`total` runs, which it counts in the watch it is given) as [`run_reporting`]
/// does: on vsinv's pool, with the reports and Ctrl-C answered from the calling thread.
pub fn run_watched<F>(
    py: Python<'_>,
    total: usize,
    threads: Option<usize>,
    reporter: Option<&Bound<'_, PyAny>>,
    batch: F,
) -> PyResult<Vec<crate::sim::error::Result<Summary>>>
where
    F: FnOnce(&BatchWatch) -> crate::sim::error::Result<Vec<crate::sim::error::Result<Summary>>> + Send,
{
    let pool = crate::parallel::pool(threads)?;
    let watch = BatchWatch::default();
    let reporter = reporter.map(|r| r.clone().unbind());
    // Without a reporter the calling thread only wakes to check for signals.
    let news = if reporter.is_some() { 0 } else { usize::MAX };
    let mut raised: Option<PyErr> = None;
    let mut results = None;
    py.detach(|| {
        // The batch is a job of the pool (no thread is started for it); the calling thread
        // stays outside the pool and watches.
        pool.in_place_scope(|scope| {
            scope.spawn(|_| results = Some(batch(&watch)));
            let mut reported = 0;
            loop {
                let (done, returned) = watch.wait_past(reported.max(news), SIGNAL_CHECK);
                let news_due = reporter.is_some() && done > reported;
                if raised.is_none() && (news_due || !returned) {
                    let report = (done > reported).then_some(done);
                    if let Err(e) = Python::attach(|py| tell(py, reporter.as_ref(), report, total)) {
                        watch.cancel();
                        raised = Some(e);
                    }
                }
                reported = done;
                if returned {
                    break;
                }
            }
        });
    });
    if let Some(e) = raised {
        return Err(e);
    }
    match results {
        Some(results) => Ok(results?),
        None => Err(pyo3::exceptions::PyRuntimeError::new_err("run_batch: the batch did not run")),
    }
}

/// Checks for signals, then reports `done` runs if there is news.
fn tell(py: Python<'_>, reporter: Option<&Py<PyAny>>, done: Option<usize>, total: usize) -> PyResult<()> {
    py.check_signals()?;
    if let (Some(r), Some(done)) = (reporter, done) {
        r.call1(py, (done, total))?;
    }
    Ok(())
}
