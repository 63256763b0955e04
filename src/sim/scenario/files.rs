//! The files a scenario names (`calibration`, `robot.urdf`): where they are looked for and
//! where they may be. Scenario files are shared, so by default the files they name must be
//! inside the scenario's folder (the folder of the TOML file; the working directory for a
//! scenario given as text or a dictionary): no absolute path, no `..` and no symbolic link
//! leading out of it. The caller lifts this with [`FileAccess::Anywhere`] (Python:
//! `allow_outside_files=True`; CLI: `--allow-outside-files`). Either way the file must be a
//! regular file below its size limit (module [`input_file`](crate::input_file)).

use std::path::{Path, PathBuf};

use super::scenario_error;
use crate::error::Result;

/// Which files a scenario may name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FileAccess {
    /// Inside the scenario's folder only (the default; module docs).
    #[default]
    ScenarioFolder,
    /// Anywhere the process may read (the caller's explicit choice).
    Anywhere,
}

/// Where a scenario's files are resolved: its folder (if it came from a file) and the rule.
#[derive(Debug, Clone, Copy)]
pub(crate) struct FileScope<'a> {
    pub(crate) directory: Option<&'a Path>,
    pub(crate) access: FileAccess,
}

/// A path as an error quotes it: escaped, at most 80 characters.
fn quoted(file: &str) -> String {
    let n = file.chars().count();
    let head: String = file.chars().take(80).collect();
    if n <= 80 { format!("\"{}\"", head.escape_debug()) } else { format!("\"{}...\"", head.escape_debug()) }
}

impl FileScope<'_> {
    /// The folder relative paths start at (the working directory when unknown).
    fn folder(&self) -> &Path {
        match self.directory {
            Some(dir) if !dir.as_os_str().is_empty() => dir,
            _ => Path::new("."),
        }
    }

    /// The path of `file`, named by the scenario key `key`, checked against the rule.
    pub(crate) fn resolve(&self, key: &str, file: &str) -> Result<PathBuf> {
        let path = Path::new(file);
        let joined = if path.is_relative() { self.folder().join(path) } else { path.to_path_buf() };
        if self.access == FileAccess::Anywhere {
            return Ok(joined);
        }
        const OPT_IN: &str = "files named in a scenario must be inside its folder unless the caller allows others \
                              (allow_outside_files=True, or --allow-outside-files on the command line)";
        if !path.is_relative() {
            return Err(scenario_error(key, format!("{} is an absolute path: {OPT_IN}", quoted(file))));
        }
        let folder = self.folder().canonicalize().map_err(|e| {
            scenario_error(key, format!("cannot resolve the scenario's folder {}: {e}", self.folder().display()))
        })?;
        let real = joined
            .canonicalize()
            .map_err(|e| scenario_error(key, format!("{} ({}): {e}", quoted(file), joined.display())))?;
        if !real.starts_with(&folder) {
            let reason = format!("{} leads outside the scenario's folder (through .. or a symbolic link): {OPT_IN}", quoted(file));
            return Err(scenario_error(key, reason));
        }
        Ok(real)
    }
}
