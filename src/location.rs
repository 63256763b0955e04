//! Where in an input an error is: a [`Location`], a path of keys and indices from the input's
//! root (`control.gain`, `object.points[2][1]`, `[3].camera.fku`, `pixels[4][1]`).
//!
//! It is the core's own vocabulary (keys and indices, nothing about scenarios, images or
//! files): every layer names a position with it, errors carry it as data
//! ([`crate::Error::location`]) and render it one way (its `Display`), and the Python bindings
//! expose it as the tuple `err.location` (`("control", "gain")`, `("pixels", 4, 1)`), as
//! pydantic-core's `loc`.

use std::fmt;

/// One step of a [`Location`]: a key of a table (a dictionary, a TOML table, a named argument)
/// or an index of a sequence (an array's row or column, a batch's item).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Step {
    /// A key of a table or the name of an argument.
    Key(String),
    /// An index in a sequence (0-based).
    Index(usize),
}

/// A path of keys and indices from the root of an input; empty for the whole input.
#[derive(Debug, Clone, Default, PartialEq, Eq, Hash)]
pub struct Location(Vec<Step>);

impl Location {
    /// The whole input (no step).
    pub fn root() -> Self {
        Self(Vec::new())
    }

    /// The location of one key (an argument's name) at the root.
    pub fn key(key: impl Into<String>) -> Self {
        Self(vec![Step::Key(key.into())])
    }

    /// This location followed by the key `key`.
    pub fn then_key(mut self, key: impl Into<String>) -> Self {
        self.0.push(Step::Key(key.into()));
        self
    }

    /// This location followed by the index `index`.
    pub fn then_index(mut self, index: usize) -> Self {
        self.0.push(Step::Index(index));
        self
    }

    /// This location under the index `index` (an item of a batch: `[3].control.gain`).
    pub fn under_index(mut self, index: usize) -> Self {
        self.0.insert(0, Step::Index(index));
        self
    }

    /// The steps, from the root.
    pub fn steps(&self) -> &[Step] {
        &self.0
    }

    /// True for the whole input.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// Reads the text [`Location`]'s `Display` writes (and serde_path_to_error's paths):
    /// keys joined by dots, indices in brackets; `""` and `"."` are the root. A bracket that
    /// does not hold a number stays part of the key.
    pub fn parse(text: &str) -> Self {
        let mut steps = Vec::new();
        if text == "." {
            return Self(steps);
        }
        for part in text.split('.').filter(|p| !p.is_empty()) {
            let (key, mut rest) = match part.find('[') {
                Some(at) => part.split_at(at),
                None => (part, ""),
            };
            let mut indices = Vec::new();
            while let Some(inner) = rest.strip_prefix('[').and_then(|r| r.split_once(']')) {
                match inner.0.parse::<usize>() {
                    Ok(i) => indices.push(Step::Index(i)),
                    Err(_) => break,
                }
                rest = inner.1;
            }
            if !rest.is_empty() {
                // Not a path of ours: the whole part is one key.
                steps.push(Step::Key(part.to_string()));
                continue;
            }
            if !key.is_empty() {
                steps.push(Step::Key(key.to_string()));
            }
            steps.extend(indices);
        }
        Self(steps)
    }
}

impl From<&str> for Location {
    fn from(text: &str) -> Self {
        Self::parse(text)
    }
}

impl From<String> for Location {
    fn from(text: String) -> Self {
        Self::parse(&text)
    }
}

/// Keys joined by dots, indices in brackets: `control.gain`, `object.points[2][1]`,
/// `[3].camera.fku`; nothing for the root.
impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, step) in self.0.iter().enumerate() {
            match step {
                Step::Key(k) if i == 0 => write!(f, "{k}")?,
                Step::Key(k) => write!(f, ".{k}")?,
                Step::Index(n) => write!(f, "[{n}]")?,
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::{Location, Step};

    #[test]
    fn text_and_steps_agree() {
        let cases: [(&str, Vec<Step>); 6] = [
            ("", vec![]),
            ("control.gain", vec![Step::Key("control".into()), Step::Key("gain".into())]),
            (
                "object.points[2][1]",
                vec![Step::Key("object".into()), Step::Key("points".into()), Step::Index(2), Step::Index(1)],
            ),
            ("[3].camera.fku", vec![Step::Index(3), Step::Key("camera".into()), Step::Key("fku".into())]),
            ("[3]", vec![Step::Index(3)]),
            ("tags[0].id", vec![Step::Key("tags".into()), Step::Index(0), Step::Key("id".into())]),
        ];
        for (text, steps) in cases {
            let loc = Location::parse(text);
            assert_eq!(loc.steps(), steps.as_slice(), "{text}");
            assert_eq!(loc.to_string(), text);
        }
        assert!(Location::parse(".").is_empty());
        // Built step by step, it renders as parsed.
        let built = Location::key("points").then_index(3).then_key("u").under_index(1);
        assert_eq!(built.to_string(), "[1].points[3].u");
        assert_eq!(Location::parse(&built.to_string()), built);
        // A bracket without a number is part of the key.
        assert_eq!(Location::parse("a[x]").steps(), &[Step::Key("a[x]".into())]);
    }
}
