//! Scenario files (TOML, or the same structure as JSON or a Python dictionary): parsing with
//! errors that name the key at fault, the conversion to a
//! [`SimulationConfig`], and the built-in scenarios reproducing
//! the paper's experiments. The keys are described once, in the README's "Scenario files"
//! block (a test parses it and checks that it covers the schema).

mod builtin;
mod convert;
pub use convert::{MAX_LATENCY_FRAMES, MAX_OBJECT_POINTS, MIN_TAG_SIDE_PIXELS, check_point_count};
mod files;
mod law_keys;
pub mod schema;

pub use builtin::{BUILTIN, builtin};
pub use files::FileAccess;
pub(crate) use files::FileScope;
pub use law_keys::{COMMON_CONTROL_KEYS, LAW_KEYS, law_keys};
pub use schema::*;

use crate::sim::config::SimulationConfig;
use crate::sim::error::{Result, SimError};

/// The largest scenario file, bytes.
pub use crate::input_file::MAX_SCENARIO_BYTES;

/// How a scenario passes depths to the invariant law, added to the core's remedies when a
/// run stops on a degenerate structure ([`crate::Error::message_with_remedy`]).
pub const DEPTHS_REMEDY: &str = "; scenario control.depths = \"reference\" or \"estimated\"";

/// A TOML syntax error: the parser's message and the line, without the quoted source.
fn toml_message(text: &str, e: &toml::de::Error) -> String {
    let message = shorten_quotes(e.message().trim());
    match e.span() {
        Some(span) => {
            let line = text.as_bytes()[..span.start.min(text.len())].iter().filter(|&&b| b == b'\n').count() + 1;
            format!("TOML syntax error at line {line}: {message}")
        }
        None => format!("TOML syntax error: {message}"),
    }
}

/// A message with every quoted value (`"..."`, as serde quotes strings) cut to a short
/// excerpt ([`excerpt`](crate::input_file::excerpt)).
fn shorten_quotes(message: &str) -> String {
    let mut out = String::new();
    let mut rest = message;
    while let Some(start) = rest.find('"') {
        out.push_str(&rest[..start]);
        let after = &rest[start + 1..];
        // serde's quotes are Debug-escaped: the closing quote is the first one not escaped.
        let mut end = None;
        let mut escaped = false;
        for (i, c) in after.char_indices() {
            match c {
                '\\' if !escaped => escaped = true,
                '"' if !escaped => {
                    end = Some(i);
                    break;
                }
                _ => escaped = false,
            }
        }
        let Some(end) = end else {
            out.push_str(&crate::input_file::excerpt(after));
            return out;
        };
        out.push_str(&crate::input_file::excerpt(&after[..end]));
        rest = &after[end + 1..];
    }
    out.push_str(rest);
    out
}

pub(crate) fn scenario_error(key: &str, reason: impl Into<String>) -> SimError {
    // serde_path_to_error names the document root "." ([`Location::parse`] reads it as the root).
    SimError::Scenario { key: crate::Location::parse(key), reason: reason.into() }
}

/// Scenario text (TOML, or JSON: a batch's items) is held to the file limit,
/// [`MAX_SCENARIO_BYTES`], before it is parsed.
fn check_text_size(text: &str) -> Result<()> {
    if text.len() as u64 > MAX_SCENARIO_BYTES {
        let reason = format!("{} bytes of text, more than the limit of {MAX_SCENARIO_BYTES} bytes", text.len());
        return Err(scenario_error("", reason));
    }
    Ok(())
}

impl Scenario {
    /// Parses TOML text; errors name the key (and line) at fault.
    pub fn from_toml(text: &str) -> Result<Self> {
        let scenario = Self::parse_toml(text)?;
        scenario.validate()?;
        Ok(scenario)
    }

    /// Reads a TOML file (a regular file of at most [`MAX_SCENARIO_BYTES`]); the files it
    /// names (`calibration`, `robot.urdf`) must be inside its folder ([`FileAccess`]).
    pub fn from_toml_file(path: impl AsRef<std::path::Path>) -> Result<Self> {
        Self::from_toml_file_with(path, FileAccess::ScenarioFolder)
    }

    /// Reads a TOML file, its files resolved by the rule `access`.
    pub fn from_toml_file_with(path: impl AsRef<std::path::Path>, access: FileAccess) -> Result<Self> {
        let path = path.as_ref();
        let text = crate::input_file::read_text(path, MAX_SCENARIO_BYTES)
            .map_err(|reason| scenario_error("", format!("{}: {reason}", path.display())))?;
        let mut scenario = Self::parse_toml(&text)?;
        scenario.directory = path.parent().map(std::path::Path::to_path_buf);
        scenario.file_access = access;
        scenario.validate()?;
        Ok(scenario)
    }

    /// Parses TOML text, its files resolved by the rule `access` (relative to the working
    /// directory).
    pub fn from_toml_with(text: &str, access: FileAccess) -> Result<Self> {
        let mut scenario = Self::parse_toml(text)?;
        scenario.file_access = access;
        scenario.validate()?;
        Ok(scenario)
    }

    fn parse_toml(text: &str) -> Result<Self> {
        check_text_size(text)?;
        // The parser's message only, with the line: its Display quotes the source line, which
        // may be anything (a binary file, a secret).
        let de = toml::Deserializer::parse(text).map_err(|e| scenario_error("", toml_message(text, &e)))?;
        let scenario: Scenario = serde_path_to_error::deserialize(de).map_err(|e| {
            let key = e.path().to_string();
            scenario_error(&key, shorten_quotes(e.into_inner().message().trim()))
        })?;
        Ok(scenario)
    }

    /// Parses JSON text (the form a batch's scenarios take while they wait to run).
    pub fn from_json(text: &str) -> Result<Self> {
        Self::from_json_with(text, FileAccess::ScenarioFolder)
    }

    /// Parses JSON text, its files resolved by the rule `access` (relative to the working
    /// directory).
    pub fn from_json_with(text: &str, access: FileAccess) -> Result<Self> {
        let mut scenario = Self::parse_json(text)?;
        scenario.file_access = access;
        scenario.validate()?;
        Ok(scenario)
    }

    /// The simulation described by JSON text, parsed and validated once (batch runs).
    pub fn config_from_json(text: &str) -> Result<SimulationConfig> {
        Self::config_from_json_with(text, FileAccess::ScenarioFolder)
    }

    /// [`Scenario::config_from_json`] with the file rule `access`.
    pub fn config_from_json_with(text: &str, access: FileAccess) -> Result<SimulationConfig> {
        let mut scenario = Self::parse_json(text)?;
        scenario.file_access = access;
        scenario.to_config()
    }

    fn parse_json(text: &str) -> Result<Self> {
        check_text_size(text)?;
        let mut de = serde_json::Deserializer::from_str(text);
        serde_path_to_error::deserialize(&mut de).map_err(|e| {
            let key = e.path().to_string();
            let message = e.into_inner().to_string();
            // serde_json appends the position in the JSON text, meaningless for a dictionary
            // (a batch's dictionaries are written as JSON text while they wait).
            let message = message.split(" at line ").next().unwrap_or_default();
            scenario_error(&key, shorten_quotes(message))
        })
    }

    /// From a structured value (a Python dictionary walked by the bindings), its files
    /// resolved by the rule `access` (relative to the working directory).
    pub fn from_value_with(value: serde_json::Value, access: FileAccess) -> Result<Self> {
        let scenario = Self::deserialize_value(value, access)?;
        scenario.validate()?;
        Ok(scenario)
    }

    /// The simulation described by a structured value, parsed and validated once (sweep
    /// runs), its files resolved by the rule `access`.
    pub fn config_from_value_with(value: serde_json::Value, access: FileAccess) -> Result<SimulationConfig> {
        Self::deserialize_value(value, access)?.to_config()
    }

    /// The scenario of a structured value as the schema reads it (an error names the key), not
    /// yet validated.
    fn deserialize_value(value: serde_json::Value, access: FileAccess) -> Result<Self> {
        let mut scenario: Scenario = serde_path_to_error::deserialize(value).map_err(|e| {
            let key = e.path().to_string();
            scenario_error(&key, shorten_quotes(&e.into_inner().to_string()))
        })?;
        scenario.file_access = access;
        Ok(scenario)
    }

    /// The scenario as a structured value (entries in the order of the file's sections).
    pub fn to_value(&self) -> Result<serde_json::Value> {
        serde_json::to_value(self).map_err(|e| scenario_error("", e.to_string()))
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

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    /// Regression (issue 16): TOML errors quoted the source line and serde quoted string
    /// values in full; now the line number and a short excerpt only.
    #[test]
    fn errors_quote_no_more_than_an_excerpt() {
        let marker = "SECRET-MARKER";
        let garbage = format!("name = \"x\"\nAKIA-0123456789-{marker} = = \n");
        let e = Scenario::from_toml(&garbage).unwrap_err().to_string();
        assert!(e.contains("line 2") && !e.contains(marker), "{e}");
        let value = format!("name = \"x\"\n[control]\ngain = \"AKIA-0123456789-{marker}\"\n");
        let e = Scenario::from_toml(&value).unwrap_err().to_string();
        assert!(e.contains("control.gain") && e.contains("AKIA") && !e.contains(marker), "{e}");
        assert_eq!(shorten_quotes(r#"a "b\"c" d"#), r#"a "b\\\"c" d"#);
    }

    /// `[world] engine = "mujoco"` parses and validates as any scenario, and the Rust
    /// simulator refuses to run it naming `world.engine`; a latency is the MuJoCo loop's only.
    #[test]
    fn the_mujoco_engine_is_refused_by_the_rust_runner() {
        let text = include_str!("../../../scenarios/lens-12-6.toml");
        let s = Scenario::from_toml(&format!("{text}\n[world]\nengine = \"mujoco\"\nlatency_frames = 2\n")).unwrap();
        assert_eq!((s.world.engine, s.world.latency_frames), (Engine::Mujoco, 2));
        let e = s.to_config().unwrap_err();
        assert!(matches!(&e, SimError::Scenario { key, .. } if key.to_string() == "world.engine"), "{e}");
        assert!(e.to_string().contains("mujoco extra"), "{e}");
        let e = Scenario::from_toml(&format!("{text}\n[world]\nlatency_frames = 1\n")).unwrap_err();
        assert!(e.to_string().contains("world.latency_frames: a latency"), "{e}");
        // What the MuJoCo loop does not simulate is refused by its key, not ignored.
        for (table, key) in [
            ("[noise]\npixel_sigma = 0.5", "noise.pixel_sigma"),
            ("[path]\nsamples = 100", "path"),
            ("[robot]\nkind = \"cartesian\"", "robot.kind"),
        ] {
            let e = Scenario::from_toml(&format!("{text}\n[world]\nengine = \"mujoco\"\n{table}\n")).unwrap_err();
            assert!(e.to_string().contains(&format!("{key}: ")) && e.to_string().contains("not simulated"), "{e}");
        }
        // A built-in arm runs in MuJoCo: its arm is the kinematic simulator's (start joints,
        // limits), and none for a free camera.
        let arm_text = include_str!("../../../scenarios/arm-ur5-12-6.toml");
        let s = Scenario::from_toml(&format!("{arm_text}\n[world]\nengine = \"mujoco\"\n")).unwrap();
        let arm = s.arm().unwrap().unwrap();
        let kinematic = Scenario::from_toml(arm_text).unwrap().to_config().unwrap();
        let crate::sim::robot::Robot::Arm(k) = &kinematic.robot else { panic!("an arm") };
        assert_eq!(&arm, k.as_ref());
        assert!(Scenario::from_toml(text).unwrap().arm().unwrap().is_none());
        // Eye-to-hand: the arm carries F*, which the start puts at the inverse of [start] in
        // the fixed camera's frame; refused by the kinematic engine and with an arm in [robot].
        let e2h = builtin("mujoco-eye-to-hand-12-6").unwrap();
        let arm = e2h.arm().unwrap().unwrap();
        let start = e2h.start.as_ref().map(|s| convert::pose_of(s.position, s.rotation_deg)).unwrap();
        let (dt, dr) = crate::core::se3::pose_error(&arm.camera_pose(&arm.start).unwrap(), &start.inverse());
        assert!(dt < 1e-9 && dr < 1e-9, "{dt} {dr}");
        let e2h_text = include_str!("../../../scenarios/mujoco-eye-to-hand-12-6.toml");
        let e = Scenario::from_toml(&e2h_text.replace("engine = \"mujoco\"", "engine = \"kinematic\"")).unwrap_err();
        assert!(e.to_string().contains("world.eye_to_hand: "), "{e}");
        let e = Scenario::from_toml(&format!("{e2h_text}\n[robot]\nkind = \"cartesian\"\n")).unwrap_err();
        assert!(e.to_string().contains("world.eye_to_hand: "), "{e}");
        let e = Scenario::from_toml(&e2h_text.replace("urdf = \"ur5e\"", "urdf = \"ur7\"")).unwrap_err();
        assert!(e.to_string().contains("world.eye_to_hand.urdf: ") && e.to_string().contains("nor a file"), "{e}");
        let bad =
            e2h_text.replace("target_mount = {", "camera_to_base = { position = [0.0, nan, 0.0] }\ntarget_mount = {");
        let e = Scenario::from_toml(&bad).unwrap_err();
        assert!(e.to_string().contains("world.eye_to_hand.camera_to_base.position[1]: "), "{e}");
        let plain = Scenario::from_toml(text).unwrap();
        assert!(plain.world.is_default() && !plain.to_toml().unwrap().contains("[world]"));
    }
}
