//! The dot tracker's settings, declared once: [`TRACKER_SETTINGS`] (name, kind, default,
//! bound, meaning) is what `ImageServo`'s `tracker` dictionary, the ROS parameters `tracker.*`
//! and the command options `--search-radius`... read (Python sees it as
//! `vsinv.vision.TRACKER_SETTINGS`), and [`TrackerConfig::set`] applies one by name.
//!
//! A new setting is a field of [`TrackerConfig`], an entry here and an arm of
//! [`TrackerConfig::set`] (a test checks every entry is set by name to its default).

use super::TrackerConfig;
use crate::error::Error;
use crate::vision::error::Result;
use crate::vision::polarity::Polarity;

/// The kind of value a setting takes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SettingKind {
    /// A finite number of pixels (or a ratio) at least `min` (more than `min` when `strict`).
    Number {
        /// The bound.
        min: f64,
        /// True when the bound itself is refused.
        strict: bool,
    },
    /// A whole number of pixels, >= 0.
    Count,
    /// One of these names.
    Choice(&'static [&'static str]),
}

impl SettingKind {
    /// The kind's name, as Python's table gives it: `number`, `count`, `choice`.
    pub fn name(self) -> &'static str {
        match self {
            SettingKind::Number { .. } => "number",
            SettingKind::Count => "count",
            SettingKind::Choice(_) => "choice",
        }
    }
}

/// A setting's value.
#[derive(Debug, Clone, PartialEq)]
pub enum SettingValue {
    /// Of a [`SettingKind::Number`].
    Number(f64),
    /// Of a [`SettingKind::Count`].
    Count(usize),
    /// Of a [`SettingKind::Choice`].
    Choice(String),
}

/// One setting of the dot tracker.
#[derive(Debug, Clone, Copy)]
pub struct TrackerSetting {
    /// The name: the key of `ImageServo`'s `tracker`, the ROS parameter `tracker.NAME`,
    /// `--NAME` (dashes) on the command line.
    pub name: &'static str,
    /// The kind of value.
    pub kind: SettingKind,
    /// The default, as text (`TrackerConfig::default()`'s, which a test checks).
    pub default: &'static str,
    /// The unit (`px`, or empty).
    pub unit: &'static str,
    /// What it does.
    pub doc: &'static str,
}

/// The tracker's settings, in the order errors and help texts list them.
pub const TRACKER_SETTINGS: [TrackerSetting; 5] = [
    TrackerSetting {
        name: "search_radius",
        kind: SettingKind::Number { min: 2.0, strict: false },
        default: "20",
        unit: "px",
        doc: "the search window's half-side around each dot's prediction",
    },
    TrackerSetting {
        name: "max_search_radius",
        kind: SettingKind::Number { min: 2.0, strict: false },
        default: "80",
        unit: "px",
        doc: "the largest window while a dot is lost (or search_radius when larger)",
    },
    TrackerSetting {
        name: "min_area",
        kind: SettingKind::Count,
        default: "4",
        unit: "px",
        doc: "the smallest dot, pixels above its threshold",
    },
    TrackerSetting {
        name: "max_area_ratio",
        kind: SettingKind::Number { min: 1.0, strict: true },
        default: "1.5",
        unit: "",
        doc: "the largest change of a dot's area from image to image",
    },
    TrackerSetting {
        name: "polarity",
        kind: SettingKind::Choice(&Polarity::NAMES),
        default: "light",
        unit: "",
        doc: "light dots, dark dots, or decided by the image the dots are clicked in",
    },
];

/// The setting named `name`.
pub fn tracker_setting(name: &str) -> Option<&'static TrackerSetting> {
    TRACKER_SETTINGS.iter().find(|s| s.name == name)
}

/// The settings' names, comma-separated, for error messages.
pub fn tracker_setting_names() -> String {
    TRACKER_SETTINGS.map(|s| s.name).join(", ")
}

impl TrackerConfig {
    /// Sets the setting `name` (of [`TRACKER_SETTINGS`]) to `value`: an unknown name, or a
    /// value of another kind, is `InvalidParameter` naming `tracker.NAME`. The bounds are
    /// checked together when the tracker starts (they depend on each other).
    pub fn set(&mut self, name: &str, value: SettingValue) -> Result<()> {
        let wrong = |reason: String| Error::InvalidParameter { name: "tracker", reason: format!("{name}: {reason}") };
        let Some(setting) = tracker_setting(name) else {
            return Err(wrong(format!("unknown key; known: {}", tracker_setting_names())).into());
        };
        match (setting.name, value) {
            ("search_radius", SettingValue::Number(x)) => self.search_radius = x,
            ("max_search_radius", SettingValue::Number(x)) => self.max_search_radius = x,
            ("max_area_ratio", SettingValue::Number(x)) => self.max_area_ratio = x,
            ("min_area", SettingValue::Count(n)) => self.min_area = n,
            ("polarity", SettingValue::Choice(p)) => {
                self.polarity = Polarity::from_name(&p).ok_or_else(|| {
                    wrong(format!(
                        "expected one of {}, got {p:?}",
                        Polarity::NAMES.map(|n| format!("{n:?}")).join(", ")
                    ))
                })?;
            }
            (_, other) => return Err(wrong(format!("expected a {}, got {other:?}", setting.kind.name())).into()),
        }
        Ok(())
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    /// The value of a default as its kind reads it.
    fn default_value(s: &TrackerSetting) -> SettingValue {
        match s.kind {
            SettingKind::Number { .. } => SettingValue::Number(s.default.parse().unwrap()),
            SettingKind::Count => SettingValue::Count(s.default.parse().unwrap()),
            SettingKind::Choice(_) => SettingValue::Choice(s.default.to_string()),
        }
    }

    /// Every entry is set by name, and the table's defaults are `TrackerConfig::default()`:
    /// setting each default on a config of other values gives the default config back.
    #[test]
    fn every_setting_is_set_by_name_to_the_default() {
        let mut config = TrackerConfig {
            search_radius: 3.0,
            max_search_radius: 5.0,
            min_area: 99,
            max_area_ratio: 7.0,
            polarity: Polarity::Auto,
        };
        for s in &TRACKER_SETTINGS {
            config.set(s.name, default_value(s)).unwrap();
        }
        assert_eq!(config, TrackerConfig::default());
    }

    #[test]
    fn unknown_names_and_wrong_kinds_are_named() {
        let mut config = TrackerConfig::default();
        let e = config.set("radius", SettingValue::Number(3.0)).unwrap_err().to_string();
        assert_eq!(
            e,
            "invalid parameter `tracker`: radius: unknown key; known: search_radius, max_search_radius, min_area, \
             max_area_ratio, polarity"
        );
        let e = config.set("min_area", SettingValue::Number(3.0)).unwrap_err().to_string();
        assert!(e.contains("min_area: expected a count"), "{e}");
        let e = config.set("polarity", SettingValue::Choice("grey".into())).unwrap_err().to_string();
        assert!(e.contains(r#"polarity: expected one of "light", "dark", "auto", got "grey""#), "{e}");
        assert_eq!(config, TrackerConfig::default());
    }
}
