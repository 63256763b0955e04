//! The keys a sweep varies, read once per sweep: dotted scenario keys (`"control.gain"`,
//! `"start.position.2"`) set on the base scenario's value tree, and the derived keys
//! ([`DERIVED_KEYS`], [`super::derived`]). Whether a dotted key exists is the schema's to say:
//! the run's scenario is parsed after the keys are set, which names an unknown key.

use serde_json::{Map, Value};

use crate::sim::error::Result;
use crate::sim::sweep::derived::{DERIVED_KEYS, Derived, key_error};

/// One step of a dotted key: a table's entry or a list's index.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Segment {
    /// A table's entry.
    Name(String),
    /// A list's index (a segment of digits).
    Index(usize),
}

/// A varied key, read once: a dotted path or a derived key.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SweepKey {
    /// A dotted scenario key: its text and its path (the first segment a table's name).
    Dotted {
        /// The key as given.
        key: String,
        /// Its segments.
        path: Vec<Segment>,
    },
    /// A derived key.
    Derived(Derived),
}

impl SweepKey {
    /// Reads `key`: a derived key, or dotted segments (digits index a list; no empty segment;
    /// the first names a table).
    pub fn parse(key: &str) -> Result<Self> {
        if key.is_empty() {
            return Err(key_error(key, "expected a non-empty string"));
        }
        if let Some(d) = Derived::named(key) {
            return Ok(Self::Derived(d));
        }
        let parts: Vec<&str> = key.split('.').collect();
        if parts.iter().any(|p| p.is_empty()) {
            return Err(key_error(key, "empty segment"));
        }
        let digits = |p: &str| p.bytes().all(|b| b.is_ascii_digit());
        if digits(parts[0]) {
            let names = DERIVED_KEYS.join(", ");
            return Err(key_error(key, format!("expected a derived key ({names}) or a dotted scenario key")));
        }
        let path = parts
            .iter()
            .map(|p| match digits(p) {
                true => Segment::Index(p.parse().unwrap_or(usize::MAX)),
                false => Segment::Name((*p).to_string()),
            })
            .collect();
        Ok(Self::Dotted { key: key.to_string(), path })
    }

    /// The key as given.
    pub fn name(&self) -> &str {
        match self {
            Self::Dotted { key, .. } => key,
            Self::Derived(d) => d.name(),
        }
    }

    /// Whether the key moves the start pose (`start.*`, `roll_deg`).
    fn moves_start(&self) -> bool {
        match self {
            Self::Dotted { path, .. } => path[0] == Segment::Name("start".into()),
            Self::Derived(d) => *d == Derived::Roll,
        }
    }
}

/// A key moving the start pose needs a scenario whose start is a pose: an arm placed by
/// `robot.joints` has none (its start follows from the joints).
pub(crate) fn check_start_varies(d: &Map<String, Value>, key: &SweepKey) -> Result<()> {
    if !key.moves_start() {
        return Ok(());
    }
    let robot = d.get("robot").and_then(Value::as_object);
    let urdf_by_joints = robot.is_some_and(|r| {
        r.get("kind").and_then(Value::as_str) == Some("urdf") && r.get("joints").is_some_and(|j| !j.is_null())
    });
    if d.get("start").is_none_or(Value::is_null) && urdf_by_joints {
        return Err(key_error(
            key.name(),
            "this arm is placed by robot.joints, so its start pose is not a key to vary; place it by the camera \
             pose instead ([start] position and rotation_deg, robot.ik_seed to pick the joints' branch; the \
             joints then follow by inverse kinematics)",
        ));
    }
    Ok(())
}

/// The type of a value as the error messages name it (as Python would).
fn type_name(v: &Value) -> &'static str {
    match v {
        Value::Null => "NoneType",
        Value::Bool(_) => "bool",
        Value::Number(n) if n.is_f64() => "float",
        Value::Number(_) => "int",
        Value::String(_) => "str",
        Value::Array(_) => "list",
        Value::Object(_) => "dict",
    }
}

fn joined(path: &[Segment]) -> String {
    let text: Vec<String> = path
        .iter()
        .map(|s| match s {
            Segment::Name(n) => n.clone(),
            Segment::Index(i) => i.to_string(),
        })
        .collect();
    text.join(".")
}

/// The child of `node` at `seg` (None: a table without that entry); errors name `key` and
/// the path `upto`.
fn child<'a>(node: &'a mut Value, seg: &Segment, key: &str, upto: &[Segment]) -> Result<Option<&'a mut Value>> {
    let at = joined(upto);
    match (node, seg) {
        (Value::Array(list), Segment::Index(i)) => {
            let n = list.len();
            list.get_mut(*i).map(Some).ok_or_else(|| key_error(key, format!("{at}: index out of range (length {n})")))
        }
        (Value::Array(_), Segment::Name(_)) => Err(key_error(key, format!("{at}: expected a list index"))),
        (Value::Object(map), seg) => Ok(map.get_mut(&name_of(seg))),
        _ => Err(key_error(key, format!("{at}: not a table or a list"))),
    }
}

fn name_of(seg: &Segment) -> String {
    match seg {
        Segment::Name(n) => n.clone(),
        Segment::Index(i) => i.to_string(),
    }
}

/// Sets `d[path] = value`: a missing `camera` / `estimate` section is filled with its default
/// first ([`super::derived::ensure_section`]), other missing tables are created empty.
pub(crate) fn set_dotted(d: &mut Map<String, Value>, key: &str, path: &[Segment], value: Value) -> Result<()> {
    let Segment::Name(first) = &path[0] else { return Err(key_error(key, "expected a dotted scenario key")) };
    if path.len() > 1 {
        super::derived::ensure_section(d, first, key)?;
    }
    let mut node = d.entry(first.clone()).or_insert(Value::Null);
    if path.len() == 1 {
        *node = value;
        return Ok(());
    }
    for depth in 1..path.len() - 1 {
        let (seg, upto) = (&path[depth], &path[..=depth]);
        let next: &mut Value = match node {
            Value::Array(list) => {
                let n = list.len();
                match seg {
                    Segment::Index(i) => list
                        .get_mut(*i)
                        .ok_or_else(|| key_error(key, format!("{}: index out of range (length {n})", joined(upto))))?,
                    Segment::Name(_) => return Err(key_error(key, format!("{}: expected a list index", joined(upto)))),
                }
            }
            Value::Object(map) => {
                let slot = map.entry(name_of(seg)).or_insert(Value::Null);
                if slot.is_null() {
                    *slot = Value::Object(Map::new());
                }
                slot
            }
            _ => return Err(key_error(key, format!("{}: not a table or a list", joined(upto)))),
        };
        if !(next.is_object() || next.is_array()) {
            let kind = type_name(next);
            return Err(key_error(key, format!("{} is a {kind}, not a table or a list", joined(upto))));
        }
        node = next;
    }
    let last = &path[path.len() - 1];
    match (node, last) {
        (Value::Array(list), Segment::Index(i)) if *i < list.len() => list[*i] = value,
        (node @ Value::Array(_), last) => {
            child(node, last, key, path)?;
        }
        (Value::Object(_), Segment::Index(_)) => {
            return Err(key_error(key, format!("{} is not a list", joined(&path[..path.len() - 1]))));
        }
        (Value::Object(map), Segment::Name(n)) => {
            map.insert(n.clone(), value);
        }
        (other, _) => {
            let kind = type_name(other);
            return Err(key_error(
                key,
                format!("{} is a {kind}, not a table or a list", joined(&path[..path.len() - 1])),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn keys_are_read_once_with_their_errors() {
        assert_eq!(SweepKey::parse("roll_deg").unwrap(), SweepKey::Derived(Derived::Roll));
        let SweepKey::Dotted { path, .. } = SweepKey::parse("start.position.2").unwrap() else { panic!() };
        assert_eq!(path, [Segment::Name("start".into()), Segment::Name("position".into()), Segment::Index(2)]);
        for (bad, why) in [("", "non-empty"), ("control..gain", "empty segment"), ("0.gain", "derived key")] {
            let e = SweepKey::parse(bad).unwrap_err().to_string();
            assert!(e.contains(&format!("vary key '{bad}'")) && e.contains(why), "{e}");
        }
    }

    #[test]
    fn dotted_keys_set_tables_and_lists_and_name_what_is_wrong() {
        let base = json!({"start": {"position": [0.0, 0.1, 0.2]}, "noise": {"pixel_sigma": 0.5}});
        let set = |key: &str, v: Value| {
            let mut d = base.as_object().unwrap().clone();
            let SweepKey::Dotted { path, .. } = SweepKey::parse(key).unwrap() else { panic!() };
            set_dotted(&mut d, key, &path, v).map(|()| Value::Object(d))
        };
        assert_eq!(set("start.position.2", json!(0.7)).unwrap()["start"]["position"], json!([0.0, 0.1, 0.7]));
        assert_eq!(set("path.samples", json!(40)).unwrap()["path"], json!({"samples": 40}));
        assert_eq!(set("name", json!("x")).unwrap()["name"], json!("x"));
        for (key, why) in [
            ("start.position.7", "start.position.7: index out of range (length 3)"),
            ("start.position.x", "start.position.x: expected a list index"),
            ("noise.pixel_sigma.x", "noise.pixel_sigma is a float, not a table or a list"),
            ("noise.3", "noise is not a list"),
        ] {
            let e = set(key, json!(1.0)).unwrap_err().to_string();
            assert!(e.contains(&format!("vary key '{key}': {why}")), "{e}");
        }
    }
}
