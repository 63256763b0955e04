//! Worker pools that survive `fork` (features `batch` and `vision`).
//!
//! POSIX `fork` copies only the calling thread (POSIX.1-2017, `fork()`: "a process shall be
//! created with a single thread"). A rayon pool started before a fork is therefore a pool
//! without workers in the child: its queues are copied, its threads are not, and the first job
//! given to it waits forever. This is what a `ProcessPoolExecutor` with the `fork` start
//! method did to a process that had run a batch before.
//!
//! vsinv runs all its parallel work (batches, dot detection, AprilTag decoding, and through
//! them any rayon work of the libraries they call) on its own pools, never on rayon's global
//! one, and keeps them in one registry where each pool is tagged with the id of the process
//! that started it. A process that finds pools of another process id (its parent's, copied by
//! `fork`) abandons them and starts its own. The abandoned pools are leaked, not dropped:
//! dropping one would signal worker threads that do not exist here (a few hundred bytes a
//! fork). The registry's lock may itself have been copied locked (another thread of the
//! parent held it at the instant of the fork, and that thread does not exist in the child):
//! the lock is only ever held for a lookup or an insertion, so a lock still taken after
//! [`LOCK_PATIENCE`] is taken for dead: that call and every later one of the process run on
//! a pool of their own, without waiting again. No path waits forever, and no `unsafe`
//! (`pthread_atfork`) is needed.

use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, TryLockError};
use std::time::{Duration, Instant};

use crate::error::{Error, Result};

/// The most worker threads a pool may have (each is an OS thread with its own stack).
pub const MAX_THREADS: usize = 1024;

/// How long a call waits for the registry's lock before it takes it for one copied locked by a
/// fork. A live holder keeps it for a lookup or an insertion: microseconds.
pub const LOCK_PATIENCE: Duration = Duration::from_millis(500);

/// A pool, the process that started it and its thread count (None: one per core).
struct Entry {
    process: u32,
    threads: Option<usize>,
    pool: Arc<rayon::ThreadPool>,
}

static POOLS: Mutex<Vec<Entry>> = Mutex::new(Vec::new());

/// The worker pool for `threads` (None: one thread per core) of this process, started on
/// first use. Pools are kept and reused: starting threads on every call costs their start-up
/// and, with glibc, fresh malloc arenas that keep the process's memory growing over the first
/// thousands of batches.
pub fn pool(threads: Option<usize>) -> Result<Arc<rayon::ThreadPool>> {
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
    /// The process whose registry lock was found dead (0: none).
    static DEAD_IN: AtomicU32 = AtomicU32::new(0);
    let process = std::process::id();
    if DEAD_IN.load(Ordering::Relaxed) == process {
        return start(threads).map(Arc::new);
    }
    let found = pool_of(process, threads, &POOLS, LOCK_PATIENCE);
    if let Ok((_, false)) = found {
        DEAD_IN.store(process, Ordering::Relaxed);
    }
    found.map(|(p, _)| p)
}

/// [`pool`] for the process `process` in the registry `registry`, and whether the registry
/// was usable (false: its lock stayed taken, the pool is this call's own).
fn pool_of(
    process: u32,
    threads: Option<usize>,
    registry: &Mutex<Vec<Entry>>,
    patience: Duration,
) -> Result<(Arc<rayon::ThreadPool>, bool)> {
    let Some(mut pools) = lock(registry, patience) else {
        return Ok((Arc::new(start(threads)?), false));
    };
    if let Some(found) = find(&mut pools, process, threads) {
        return Ok((found, true));
    }
    drop(pools); // threads are started outside the lock: a fork never waits for them
    let built = Arc::new(start(threads)?);
    let Some(mut pools) = lock(registry, patience) else {
        return Ok((built, false));
    };
    if let Some(found) = find(&mut pools, process, threads) {
        return Ok((found, true)); // another thread was first; ours is dropped (this process's threads)
    }
    pools.push(Entry { process, threads, pool: Arc::clone(&built) });
    Ok((built, true))
}

/// The registry's lock, or None when it stays taken for `patience` (copied locked by a fork).
fn lock(registry: &Mutex<Vec<Entry>>, patience: Duration) -> Option<MutexGuard<'_, Vec<Entry>>> {
    let since = Instant::now();
    loop {
        match registry.try_lock() {
            Ok(guard) => return Some(guard),
            Err(TryLockError::Poisoned(e)) => return Some(e.into_inner()),
            Err(TryLockError::WouldBlock) if since.elapsed() < patience => std::thread::yield_now(),
            Err(TryLockError::WouldBlock) => return None,
        }
    }
}

/// This process's pool for `threads`, after abandoning the pools of other processes.
fn find(pools: &mut Vec<Entry>, process: u32, threads: Option<usize>) -> Option<Arc<rayon::ThreadPool>> {
    if pools.iter().any(|e| e.process != process) {
        let (ours, theirs): (Vec<Entry>, Vec<Entry>) = pools.drain(..).partition(|e| e.process == process);
        std::mem::forget(theirs); // their threads are not in this process: never drop them
        *pools = ours;
    }
    pools.iter().find(|e| e.threads == threads).map(|e| Arc::clone(&e.pool))
}

fn start(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        builder = builder.num_threads(n);
    }
    builder
        .build()
        .map_err(|e| Error::InvalidParameter { name: "threads", reason: format!("cannot start the thread pool: {e}") })
}

/// Runs `op` on vsinv's pool of one thread per core, so that the rayon work inside it (its
/// own and its libraries') never lands on rayon's global pool. On a thread that already is a
/// rayon worker (a run of a batch) `op` runs there: nested work stays on the batch's pool.
pub fn install<R: Send>(op: impl FnOnce() -> R + Send) -> Result<R> {
    if rayon::current_thread_index().is_some() {
        return Ok(op());
    }
    Ok(pool(None)?.install(op))
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    #[test]
    fn pools_are_reused_per_thread_count_and_checked() {
        let a = pool(Some(2)).unwrap();
        assert!(Arc::ptr_eq(&a, &pool(Some(2)).unwrap()));
        assert_eq!(a.current_num_threads(), 2);
        assert!(pool(Some(0)).is_err());
        assert!(pool(Some(MAX_THREADS + 1)).is_err());
        assert_eq!(install(rayon::current_num_threads).unwrap(), pool(None).unwrap().current_num_threads());
        // Inside a pool's worker, nested work stays on that pool.
        assert_eq!(a.install(|| install(rayon::current_num_threads)).unwrap(), 2);
    }

    /// What a forked child sees: the parent's pools under another process id. They are
    /// abandoned (not dropped) and a new pool is started.
    #[test]
    fn a_child_abandons_its_parents_pools() {
        let registry = Mutex::new(Vec::new());
        let (parent, usable) = pool_of(1, Some(2), &registry, LOCK_PATIENCE).unwrap();
        assert!(usable);
        assert!(Arc::ptr_eq(&parent, &pool_of(1, Some(2), &registry, LOCK_PATIENCE).unwrap().0));
        let (child, _) = pool_of(2, Some(2), &registry, LOCK_PATIENCE).unwrap();
        assert!(!Arc::ptr_eq(&parent, &child));
        assert_eq!(Arc::strong_count(&parent), 2, "the abandoned entry is leaked, not dropped");
        let entries: Vec<(u32, Option<usize>)> =
            registry.lock().unwrap().iter().map(|e| (e.process, e.threads)).collect();
        assert_eq!(entries, [(2, Some(2))]);
        assert_eq!(child.install(rayon::current_num_threads), 2);
    }

    /// A registry lock that stays taken (copied locked by a fork) gives a pool of the call's own.
    #[test]
    fn a_lock_that_stays_taken_does_not_block() {
        let registry = Mutex::new(Vec::new());
        let held = registry.lock().unwrap();
        let started = Instant::now();
        let (own, usable) = pool_of(7, Some(1), &registry, Duration::from_millis(20)).unwrap();
        assert!(!usable && started.elapsed() < Duration::from_secs(5));
        assert_eq!(own.install(|| 1 + 1), 2);
        drop(held);
        assert!(registry.lock().unwrap().is_empty());
    }
}
