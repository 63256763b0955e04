//! The package's logger, `logging.getLogger("vsinv")` (quiet by default: the package adds a
//! `NullHandler`), for the bindings' start and end messages.

use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;

/// `logging.INFO`.
pub const INFO: u32 = 20;
/// `logging.DEBUG`.
pub const DEBUG: u32 = 10;

/// Logs the message `message()` at `level` on the `vsinv` logger; the message is only built
/// when the logger is enabled for that level.
pub fn log(py: Python<'_>, level: u32, message: impl FnOnce() -> String) -> PyResult<()> {
    static LOGGER: PyOnceLock<Py<PyAny>> = PyOnceLock::new();
    let logger = LOGGER
        .get_or_try_init(py, || py.import("logging")?.call_method1("getLogger", ("vsinv",)).map(Bound::unbind))?;
    let logger = logger.bind(py);
    if logger.call_method1("isEnabledFor", (level,))?.is_truthy()? {
        logger.call_method1("log", (level, "%s", message()))?;
    }
    Ok(())
}
