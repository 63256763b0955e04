//! Scenario files (TOML, or the same structure as JSON or a Python dictionary): parsing with
//! errors that name the key at fault, the conversion to a
//! [`SimulationConfig`], and the built-in scenarios reproducing
//! the paper's experiments. The keys are described once, in the README's "Scenario files"
//! block (a test parses it and checks that it covers the schema).

mod builtin;
mod convert;
pub mod schema;

pub use builtin::{BUILTIN, builtin};
pub use schema::*;

use crate::error::{Error, Result};
use crate::sim::config::SimulationConfig;

pub(crate) fn scenario_error(key: &str, reason: impl Into<String>) -> Error {
    // serde_path_to_error names the document root ".".
    let key = if key == "." { "" } else { key };
    Error::Scenario { key: key.to_string(), reason: reason.into() }
}

impl Scenario {
    /// Parses TOML text; errors name the key (and line) at fault.
    pub fn from_toml(text: &str) -> Result<Self> {
        let scenario = Self::parse_toml(text)?;
        scenario.validate()?;
        Ok(scenario)
    }

    /// Reads a TOML file; relative `robot.urdf` paths start at the file's directory.
    pub fn from_toml_file(path: impl AsRef<std::path::Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| scenario_error("", format!("{}: {e}", path.display())))?;
        let mut scenario = Self::parse_toml(&text)?;
        scenario.directory = path.parent().map(std::path::Path::to_path_buf);
        scenario.validate()?;
        Ok(scenario)
    }

    fn parse_toml(text: &str) -> Result<Self> {
        let de = toml::Deserializer::parse(text).map_err(|e| scenario_error("", e.to_string().trim().to_string()))?;
        let scenario: Scenario = serde_path_to_error::deserialize(de).map_err(|e| {
            let key = e.path().to_string();
            scenario_error(&key, e.into_inner().message().trim().to_string())
        })?;
        Ok(scenario)
    }

    /// Parses JSON text (the form Python dictionaries take on their way in).
    pub fn from_json(text: &str) -> Result<Self> {
        let scenario = Self::parse_json(text)?;
        scenario.validate()?;
        Ok(scenario)
    }

    /// The simulation described by JSON text, parsed and validated once (batch runs).
    pub fn config_from_json(text: &str) -> Result<SimulationConfig> {
        Self::parse_json(text)?.to_config()
    }

    fn parse_json(text: &str) -> Result<Self> {
        let mut de = serde_json::Deserializer::from_str(text);
        serde_path_to_error::deserialize(&mut de).map_err(|e| {
            let key = e.path().to_string();
            let message = e.into_inner().to_string();
            // serde_json appends the position in the JSON text, meaningless for a dictionary.
            let message = message.split(" at line ").next().unwrap_or_default().to_string();
            scenario_error(&key, message)
        })
    }

    /// The scenario as JSON text.
    pub fn to_json(&self) -> Result<String> {
        serde_json::to_string(self).map_err(|e| scenario_error("", e.to_string()))
    }

    /// The scenario as TOML text.
    pub fn to_toml(&self) -> Result<String> {
        toml::to_string(self).map_err(|e| scenario_error("", e.to_string()))
    }
}
