//! The files a scenario names (`calibration`, `robot.urdf`): where they are looked for and
//! where they may be. Scenario files are shared, so by default the files they name must be
//! inside the scenario's folder (the folder of the TOML file; the working directory for a
//! scenario given as text or a dictionary): no absolute path, no `..` and no symbolic link
//! leading out of it. The caller lifts this with [`FileAccess::Anywhere`] (Python:
//! `allow_outside_files=True`; CLI: `--allow-outside-files`). Either way the file must be a
//! regular file below its size limit (module [`input_file`](crate::input_file)).

use std::path::{Path, PathBuf};

use super::scenario_error;
use crate::sim::error::Result;

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
            let reason = format!(
                "{} leads outside the scenario's folder (through .. or a symbolic link): {OPT_IN}",
                quoted(file)
            );
            return Err(scenario_error(key, reason));
        }
        Ok(real)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::sim::error::SimError;

    fn key_and_reason(r: Result<PathBuf>) -> (String, String) {
        match r.unwrap_err() {
            SimError::Scenario { key, reason } => (key.to_string(), reason),
            other => panic!("{other:?}"),
        }
    }

    /// Regression (issue 16): `calibration` and `robot.urdf` accepted absolute paths and
    /// `..` out of the scenario's folder (`calibration = "/etc/passwd"`).
    #[test]
    fn files_stay_in_the_folder_unless_allowed() {
        let root = std::env::temp_dir().join(format!("vsinv-scope-{}", std::process::id()));
        let folder = root.join("scenario");
        std::fs::create_dir_all(folder.join("sub")).unwrap();
        std::fs::write(folder.join("sub/cal.yaml"), "x").unwrap();
        std::fs::write(root.join("outside.yaml"), "x").unwrap();
        let confined = FileScope { directory: Some(&folder), access: FileAccess::ScenarioFolder };
        assert!(confined.resolve("camera.calibration", "sub/cal.yaml").unwrap().ends_with("sub/cal.yaml"));
        assert!(confined.resolve("camera.calibration", "sub/../sub/cal.yaml").is_ok());
        let outside = root.join("outside.yaml");
        let absolute = outside.to_str().unwrap();
        for file in [absolute, "../outside.yaml", "/etc/passwd", "sub/../../outside.yaml"] {
            let (key, reason) = key_and_reason(confined.resolve("camera.calibration", file));
            assert_eq!(key, "camera.calibration");
            assert!(reason.contains("allow_outside_files"), "{file}: {reason}");
        }
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(&outside, folder.join("link.yaml")).unwrap();
            let (_, reason) = key_and_reason(confined.resolve("robot.urdf", "link.yaml"));
            assert!(reason.contains("symbolic link"), "{reason}");
        }
        let anywhere = FileScope { directory: Some(&folder), access: FileAccess::Anywhere };
        assert_eq!(anywhere.resolve("camera.calibration", absolute).unwrap(), outside);
        assert!(anywhere.resolve("camera.calibration", "../outside.yaml").is_ok());
        std::fs::remove_dir_all(&root).unwrap();
    }
}
