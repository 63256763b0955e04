//! Objects shared between Python threads. A class whose methods release the GIL while they
//! change the object (a frame's detection and servo step) cannot lend `&mut self` to PyO3:
//! a second thread calling it meanwhile would get PyO3's `RuntimeError: Already borrowed`.
//! Such classes are `frozen` and keep their state in a [`Shared`]: calls from several
//! threads take turns, each waiting with the GIL released, so every class of `vsinv._core`
//! works from several threads (the others hold the GIL for the whole call).

use std::sync::{Mutex, MutexGuard, TryLockError};

use pyo3::prelude::*;

use super::errors::not_ready;

/// A value used by one call at a time; the others wait with the GIL released.
pub(crate) struct Shared<T> {
    value: Mutex<T>,
    class: &'static str,
}

fn broken(class: &str) -> PyErr {
    not_ready(&format!("{class}: an earlier call stopped inside it, so its state is unknown; create a new one"))
}

impl<T: Send> Shared<T> {
    pub(crate) fn new(value: T, class: &'static str) -> Self {
        Self { value: Mutex::new(value), class }
    }

    /// The value, for a call that holds the GIL: while another thread's call has it, waits
    /// for that call to end with the GIL released (that call may need the GIL to finish).
    pub(crate) fn lock(&self, py: Python<'_>) -> PyResult<MutexGuard<'_, T>> {
        loop {
            match self.value.try_lock() {
                Ok(guard) => return Ok(guard),
                Err(TryLockError::Poisoned(_)) => return Err(broken(self.class)),
                Err(TryLockError::WouldBlock) => py.detach(|| drop(self.value.lock())),
            }
        }
    }

    /// Runs `f` on the value with the GIL released (after the other threads' calls).
    pub(crate) fn detached<R: Send>(&self, py: Python<'_>, f: impl FnOnce(&mut T) -> R + Send) -> PyResult<R> {
        py.detach(|| self.value.lock().map(|mut guard| f(&mut guard)).map_err(|_| ())).map_err(|()| broken(self.class))
    }
}
