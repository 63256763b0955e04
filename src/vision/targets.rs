//! The targets, declared once. [`TARGETS`] gives each kind of target its name, its detector,
//! the keyword arguments a real-image pipeline takes for it, the scenario keys it reads, and
//! the two builders every layer goes through:
//!
//! | layer | what it takes from the table |
//! |---|---|
//! | simulated images (`sim::image_loop::scene_vision`, the views, Python's `render`) | which entry a scene shows ([`TargetSpec::shows`]), its [`TargetSpec::scene`] builder |
//! | the real-image pipeline (`ImageServo`; Python's `ImageServo(reference, target, ...)`) | the name, the arguments (others refused by name), its [`TargetSpec::image`] builder |
//! | Python (`vsinv._core.TARGETS`) | everything but the builders |
//! | `vsinv replay --target`, `vsinv invariance --target`, the ROS 2 parameter `target` | the names |
//! | scenario files (`[object]`, `[vision]`) | the keys each target reads ([`TargetSpec::scenario_keys`], checked against the schema by a test) |
//!
//! Detectors are not chosen on their own: each target names the detector that finds it
//! ([`TargetSpec::detector`]), and its builders make it.
//!
//! **Adding a target** touches these files:
//! 1. `src/vision/target/<name>.rs` (declared in `target.rs`): a type implementing
//!    [`Target`] (its points with identities, `draw` with the [`Canvas`](crate::vision::Canvas)
//!    primitives) and, for real images, one implementing [`ImageTargetKind`] (its detector and
//!    the hints it starts with in the reference image and the first frame);
//! 2. `src/vision/targets.rs`: one entry in [`TARGETS`] with its two builders;
//! 3. `python/vsinv/_core.pyi`: the name in `ImageServo`'s `target` and its keyword
//!    arguments;
//! 4. what the scene holds of it, if a scenario describes it with new keys:
//!    `src/sim/scenario/schema.rs` (the keys), `src/sim/scenario/convert.rs` (into the scene,
//!    `src/sim/scene.rs`) and the scenario-files page's block (`docs/reference/scenario-files.md`,
//!    which names every key); and a built-in scenario that shows it (`scenarios/<name>.toml`,
//!    `src/sim/scenario/builtin.rs`, its recorded result in `tests/fixtures/builtin_results.txt`), which
//!    `tests/targets.rs` renders and detects.
//!
//! **Adding a detector** (for a target no detector finds) is one more file,
//! `src/vision/detector/<name>.rs` (declared in `detector.rs`), implementing
//! [`Detector`] and reporting the target's point identities, named in the target's entry.
//!
//! `tests/targets.rs` and `tests/test_targets.py` go through the table in every layer (the
//! schema has each key, the image loop builds each target, `ImageServo`, `vsinv replay`, the
//! ROS parameters and the stub take each name): they fail until the files agree.

use crate::error::Error;
use crate::vision::detector::Detector;
use crate::vision::detector::dot_tracking::DotTracking;
use crate::vision::detector::features::{DEFAULT_MAX_POINTS, DEFAULT_MIN_TRACKED, FeatureSettings};
use crate::vision::detector::tags::TagDetector;
use crate::vision::error::Result;
use crate::vision::features::matching::MIN_MATCHES;
use crate::vision::image_servo::{ImageTarget, ImageTargetKind};
use crate::vision::render::{Disc, RenderConfig};
use crate::vision::tags::{MAX_DECIMATION, TagFamily};
use crate::vision::target::Target;
use crate::vision::target::dots::Dots;
use crate::vision::target::features::{FeatureTarget, MAX_FEATURE_POINTS};
use crate::vision::target::tags::TagRig;
use crate::vision::tracker::TrackerConfig;

/// The values a target's argument takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArgKind {
    /// Approximate pixels, `(n, 2)`.
    Points,
    /// One of these names.
    Choice(&'static [&'static str]),
    /// Identities: non-negative integers, at least one.
    Ids,
    /// An integer from `min` to `max`.
    Count {
        /// The smallest value.
        min: u32,
        /// The largest value.
        max: u32,
    },
    /// The dot tracker's settings by name ([`TrackerConfig`]).
    Tracker,
}

impl ArgKind {
    /// The kind's name, as Python sees it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Points => "points",
            Self::Choice(_) => "choice",
            Self::Ids => "ids",
            Self::Count { .. } => "count",
            Self::Tracker => "tracker",
        }
    }
}

/// One keyword argument of a target (Python's `ImageServo`, the ROS parameter and the
/// command option of the same name).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TargetArg {
    /// The name.
    pub name: &'static str,
    /// The values it takes.
    pub kind: ArgKind,
    /// Its value when not given (None: unset).
    pub default: Option<ArgDefault>,
    /// Whether it must be given.
    pub required: bool,
    /// One line of documentation.
    pub doc: &'static str,
}

/// An argument's value when it is not given, typed as its [`ArgKind`] (Python, the ROS
/// parameters and the command's help read it as it is).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArgDefault {
    /// One of an [`ArgKind::Choice`]'s names.
    Name(&'static str),
    /// An [`ArgKind::Count`]'s value.
    Count(usize),
}

/// A given argument's value, as its [`ArgKind`] says.
#[derive(Debug, Clone, PartialEq)]
pub enum ArgValue {
    /// [`ArgKind::Points`].
    Points(Vec<[f64; 2]>),
    /// [`ArgKind::Choice`].
    Name(String),
    /// [`ArgKind::Ids`].
    Ids(Vec<u32>),
    /// [`ArgKind::Count`].
    Count(i64),
    /// [`ArgKind::Tracker`].
    Tracker(TrackerConfig),
}

/// The arguments given for a target, by name (the others unset).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TargetArgs(pub Vec<(&'static str, ArgValue)>);

impl TargetArgs {
    /// The value given for `name`.
    pub fn get(&self, name: &str) -> Option<&ArgValue> {
        self.0.iter().find(|(n, _)| *n == name).map(|(_, v)| v)
    }

    fn points(&self, name: &'static str) -> Result<Option<Vec<[f64; 2]>>> {
        match self.get(name) {
            None => Ok(None),
            Some(ArgValue::Points(p)) => Ok(Some(p.clone())),
            Some(_) => Err(expected(name, "approximate pixels (n, 2)").into()),
        }
    }
}

fn expected(name: &'static str, what: &str) -> Error {
    Error::InvalidParameter { name, reason: format!("expected {what}") }
}

/// What a scene's object holds, for the scene builders: the points (F*, metres), the normals
/// of their dots, and a tag rig.
#[derive(Debug, Clone, Copy)]
pub struct SceneObject<'a> {
    /// The feature points in F*, metres.
    pub points: &'a [[f64; 3]],
    /// Per point, the normal of its dot (None: facing the reference camera).
    pub normals: Option<&'a [[f64; 3]]>,
    /// The rig of AprilTags, if the object is one.
    pub tags: Option<&'a TagRig>,
}

/// What a simulated camera looks at and what finds it in its images.
pub struct SceneVision {
    /// What is drawn.
    pub target: Box<dyn Target>,
    /// What finds it, not started.
    pub detector: Box<dyn Detector>,
}

/// The detector a target is found by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DetectorSpec {
    /// Its name.
    pub name: &'static str,
    /// Its module, under `src/vision/detector/`.
    pub module: &'static str,
    /// One line of documentation.
    pub doc: &'static str,
}

/// One kind of target.
#[derive(Debug, Clone, Copy)]
pub struct TargetSpec {
    /// The name: `ImageServo`'s `target`, `--target`, the ROS parameter `target`.
    pub name: &'static str,
    /// One line of documentation.
    pub doc: &'static str,
    /// The detector that finds it.
    pub detector: DetectorSpec,
    /// The real-image pipeline's arguments for it; another target's are refused by name.
    pub args: &'static [TargetArg],
    /// The scenario keys (dotted, `table.key`) it reads.
    pub scenario_keys: &'static [&'static str],
    /// Whether vsinv's renderer draws it (a built-in scenario shows it); false for a target
    /// of real images only (the keypoints of a textured object).
    pub simulated: bool,
    /// Whether a scene's object shows this target (exactly one entry does).
    pub shows: fn(&SceneObject<'_>) -> bool,
    /// The target of a scene and a fresh detector for it, with the `[vision]` settings.
    pub scene: fn(&SceneObject<'_>, &RenderConfig) -> Result<SceneVision>,
    /// The real-image pipeline's target from its arguments, each checked (errors name it).
    pub image: fn(&TargetArgs) -> Result<Box<dyn ImageTargetKind>>,
}

/// The dots' arguments.
const DOT_ARGS: &[TargetArg] = &[
    TargetArg {
        name: "reference_points",
        kind: ArgKind::Points,
        default: None,
        required: true,
        doc: "approximate pixels (n, 2) of the dots in the reference image",
    },
    TargetArg {
        name: "first_points",
        kind: ArgKind::Points,
        default: None,
        required: false,
        doc: "approximate pixels (n, 2) in the first frame (unset: near those found in the reference image)",
    },
    TargetArg {
        name: "tracker",
        kind: ArgKind::Tracker,
        default: None,
        required: false,
        doc: "the tracker's settings: search_radius, max_search_radius, min_area, max_area_ratio, polarity",
    },
];

/// The tags' arguments.
const TAG_ARGS: &[TargetArg] = &[
    TargetArg {
        name: "family",
        kind: ArgKind::Choice(&TagFamily::NAMES),
        default: Some(ArgDefault::Name(TagFamily::NAMES[0])), // the default family is the first
        required: false,
        doc: "the AprilTag family",
    },
    TargetArg {
        name: "tag_ids",
        kind: ArgKind::Ids,
        default: None,
        required: false,
        doc: "the tags to servo on (unset: every tag decoded in the reference image)",
    },
    TargetArg {
        name: "decimation",
        kind: ArgKind::Count { min: 1, max: MAX_DECIMATION },
        default: None,
        required: false,
        doc: "the quad search's decimation (unset: the detector's default)",
    },
];

/// The keypoint target's arguments.
const FEATURE_ARGS: &[TargetArg] = &[
    TargetArg {
        name: "max_points",
        kind: ArgKind::Count { min: MIN_MATCHES as u32, max: MAX_FEATURE_POINTS },
        default: Some(ArgDefault::Count(DEFAULT_MAX_POINTS)),
        required: false,
        doc: "how many keypoints of the reference image the target holds (a spread over the image)",
    },
    TargetArg {
        name: "min_tracked",
        kind: ArgKind::Count { min: MIN_MATCHES as u32, max: MAX_FEATURE_POINTS },
        default: Some(ArgDefault::Count(DEFAULT_MIN_TRACKED)),
        required: false,
        doc: "fewer points tracked than this (or than half of the last match's) and the frame is matched afresh",
    },
    TargetArg {
        name: "point_ids",
        kind: ArgKind::Ids,
        default: None,
        required: false,
        doc: "the keypoints to servo on, by identity (unset: every point of the reference image's spread)",
    },
];

/// White discs, one per point, tracked from approximate pixels.
pub const DOTS: TargetSpec = TargetSpec {
    name: "dots",
    doc: "white discs, one per point, tracked from approximate pixels (clicks); dot i has identity i",
    detector: DetectorSpec {
        name: "dot_tracking",
        module: "dot_tracking",
        doc: "the dot tracker: each dot near its last position, never swapping two",
    },
    args: DOT_ARGS,
    scenario_keys: &["object.points", "object.normals", "vision.dot_radius", "vision.polarity"],
    simulated: true,
    shows: |object| object.tags.is_none(),
    scene: dots_scene,
    image: dots_image,
};

/// A rig of AprilTags, their corners found by identity.
pub const TAGS: TargetSpec = TargetSpec {
    name: "tags",
    doc: "AprilTags of one family, decoded in every image: corner c of tag t has identity 4 t + c",
    detector: DetectorSpec {
        name: "tags",
        module: "tags",
        doc: "AprilTag corners by identity, searched near their last corners first",
    },
    args: TAG_ARGS,
    scenario_keys: &["object.tags", "object.tag_family", "object.rig"],
    simulated: true,
    shows: |object| object.tags.is_some(),
    scene: tags_scene,
    image: tags_image,
};

/// Natural keypoints of a textured object: no markers, no clicks.
pub const FEATURES: TargetSpec = TargetSpec {
    name: "features",
    doc: "natural keypoints (SIFT) of a textured object, matched across cameras by descriptors and the \
          fundamental matrix, then tracked (Lucas-Kanade, forward-backward); keypoint i has identity i",
    detector: DetectorSpec {
        name: "features",
        module: "features",
        doc: "keypoints matched once by descriptors, tracked frame to frame, checked, matched afresh when too few",
    },
    args: FEATURE_ARGS,
    scenario_keys: &[],
    // vsinv's renderer draws no textures: no simulated scene shows it.
    simulated: false,
    shows: |_| false,
    scene: features_scene,
    image: features_image,
};

/// Every target, in the order Python lists them.
pub const TARGETS: [TargetSpec; 3] = [DOTS, TAGS, FEATURES];

/// The target named `name`.
pub fn target(name: &str) -> Option<&'static TargetSpec> {
    TARGETS.iter().find(|t| t.name == name)
}

/// The targets' names.
pub fn target_names() -> Vec<&'static str> {
    TARGETS.iter().map(|t| t.name).collect()
}

/// The target a scene's object shows, and a fresh detector for it.
pub fn scene_vision(object: &SceneObject<'_>, config: &RenderConfig) -> Result<SceneVision> {
    let spec = TARGETS
        .iter()
        .find(|t| (t.shows)(object))
        .ok_or_else(|| Error::InvalidParameter { name: "object", reason: "no target shows this object".into() })?;
    (spec.scene)(object, config)
}

/// The dots of a scene: discs of `radius` at its points, with its normals (default: facing
/// the reference camera).
pub fn scene_discs(object: &SceneObject<'_>, radius: f64) -> Result<Vec<Disc>> {
    let points = object.points.iter();
    match object.normals {
        Some(normals) => points.zip(normals).map(|(&p, &n)| Disc::new(p, n, radius)).collect(),
        None => points.map(|&p| Disc::facing_reference(p, radius)).collect(),
    }
}

fn dots_scene(object: &SceneObject<'_>, config: &RenderConfig) -> Result<SceneVision> {
    let tracker = TrackerConfig { polarity: config.polarity, ..TrackerConfig::default() };
    Ok(SceneVision {
        target: Box::new(Dots::new(scene_discs(object, config.dot_radius)?)),
        detector: Box::new(DotTracking::new(tracker)),
    })
}

fn tags_scene(object: &SceneObject<'_>, _config: &RenderConfig) -> Result<SceneVision> {
    let tags = object
        .tags
        .cloned()
        .ok_or(Error::InvalidParameter { name: "object.tags", reason: "the scene has no tag rig".into() })?;
    let detector = Box::new(TagDetector::new(tags.family()));
    Ok(SceneVision { target: Box::new(tags), detector })
}

fn dots_image(args: &TargetArgs) -> Result<Box<dyn ImageTargetKind>> {
    let reference_points = args.points("reference_points")?.ok_or_else(|| Error::InvalidParameter {
        name: "reference_points",
        reason: "target \"dots\" needs the dots' approximate pixels (n, 2) in the reference image".into(),
    })?;
    let first_points = args.points("first_points")?;
    let tracker = match args.get("tracker") {
        None => TrackerConfig::default(),
        Some(ArgValue::Tracker(t)) => *t,
        Some(_) => return Err(expected("tracker", "the tracker's settings").into()),
    };
    Ok(Box::new(ImageTarget::Dots { reference_points, first_points, tracker }))
}

fn features_scene(_object: &SceneObject<'_>, _config: &RenderConfig) -> Result<SceneVision> {
    let reason = "vsinv's renderer draws no textures: the keypoint target is for real (or MuJoCo) images".into();
    Err(Error::InvalidParameter { name: "object", reason }.into())
}

fn count_arg(args: &TargetArgs, name: &'static str, default: usize) -> Result<usize> {
    match args.get(name) {
        None => Ok(default),
        Some(&ArgValue::Count(n)) => usize::try_from(n)
            .map_err(|_| Error::InvalidParameter { name, reason: format!("must be positive, got {n}") }.into()),
        Some(_) => Err(expected(name, "an integer").into()),
    }
}

fn features_image(args: &TargetArgs) -> Result<Box<dyn ImageTargetKind>> {
    let defaults = FeatureSettings::default();
    let settings = FeatureSettings {
        max_points: count_arg(args, "max_points", defaults.max_points)?,
        min_tracked: count_arg(args, "min_tracked", defaults.min_tracked)?,
        ..defaults
    };
    let ids = match args.get("point_ids") {
        None => None,
        Some(ArgValue::Ids(ids)) => Some(ids.clone()),
        Some(_) => return Err(expected("point_ids", "a sequence of point identities (non-negative integers)").into()),
    };
    let target = FeatureTarget { settings, ids };
    target.validate()?;
    Ok(Box::new(target))
}

fn tags_image(args: &TargetArgs) -> Result<Box<dyn ImageTargetKind>> {
    let family = match args.get("family") {
        None => TagFamily::default(),
        Some(ArgValue::Name(name)) => TagFamily::from_name(name).ok_or_else(|| {
            let names = TagFamily::NAMES.map(|n| format!("{n:?}")).join(", ");
            Error::InvalidParameter { name: "family", reason: format!("expected one of {names}, got {name:?}") }
        })?,
        Some(_) => return Err(expected("family", "a family's name").into()),
    };
    let ids = match args.get("tag_ids") {
        None => None,
        Some(ArgValue::Ids(ids)) if ids.is_empty() => {
            let reason = "empty (None: every tag in the reference image)".into();
            return Err(Error::InvalidParameter { name: "tag_ids", reason }.into());
        }
        Some(ArgValue::Ids(ids)) => Some(ids.clone()),
        Some(_) => return Err(expected("tag_ids", "a sequence of tag ids (non-negative integers)").into()),
    };
    let decimation = match args.get("decimation") {
        None => None,
        Some(&ArgValue::Count(d)) => {
            Some(u32::try_from(d).ok().filter(|d| (1..=MAX_DECIMATION).contains(d)).ok_or_else(|| {
                let reason = format!("must be in 1..={MAX_DECIMATION}, got {d}");
                Error::InvalidParameter { name: "decimation", reason }
            })?)
        }
        Some(_) => return Err(expected("decimation", "an integer").into()),
    };
    Ok(Box::new(ImageTarget::Tags { family, ids, decimation }))
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    #[test]
    fn names_and_arguments_are_unique() {
        let names = target_names();
        for (i, n) in names.iter().enumerate() {
            assert!(!names[..i].contains(n), "{n} twice");
            assert_eq!(target(n).map(|t| t.name), Some(*n));
        }
        let args: Vec<&str> = TARGETS.iter().flat_map(|t| t.args.iter().map(|a| a.name)).collect();
        for (i, a) in args.iter().enumerate() {
            assert!(!args[..i].contains(a), "argument {a} in two targets");
        }
    }

    /// Every default is a value of its argument's kind, and the one the builder uses when the
    /// argument is not given.
    #[test]
    fn each_default_is_of_its_kind_and_is_the_builders() {
        for a in TARGETS.iter().flat_map(|t| t.args) {
            match (a.kind, a.default) {
                (_, None) => {}
                (ArgKind::Choice(names), Some(ArgDefault::Name(n))) => assert!(names.contains(&n), "{}", a.name),
                (ArgKind::Count { min, max }, Some(ArgDefault::Count(n))) => {
                    assert!((min as usize..=max as usize).contains(&n), "{}", a.name);
                }
                (kind, default) => panic!("{}: default {default:?} for a {}", a.name, kind.name()),
            }
        }
        assert_eq!(TagFamily::default(), TagFamily::ALL[0]);
        let settings = FeatureSettings::default();
        assert_eq!((settings.max_points, settings.min_tracked), (DEFAULT_MAX_POINTS, DEFAULT_MIN_TRACKED));
    }

    #[test]
    fn exactly_one_target_shows_each_object() {
        let rig = TagRig::new(TagFamily::Tag36h11, Vec::new()).unwrap();
        let points = [[0.0, 0.0, 0.5]];
        let plain = SceneObject { points: &points, normals: None, tags: None };
        let count = |o: &SceneObject<'_>| TARGETS.iter().filter(|t| (t.shows)(o)).count();
        assert_eq!(count(&plain), 1);
        assert_eq!(count(&SceneObject { points: &points, normals: None, tags: Some(&rig) }), 1);
    }

    #[test]
    fn the_image_builders_check_their_arguments_by_name() {
        let err = (DOTS.image)(&TargetArgs::default()).unwrap_err();
        assert!(err.to_string().contains("reference_points"), "{err}");
        let bad = TargetArgs(vec![("decimation", ArgValue::Count(0))]);
        assert!((TAGS.image)(&bad).unwrap_err().to_string().contains("must be in 1..=8"));
        let bad = TargetArgs(vec![("family", ArgValue::Name("tag99".into()))]);
        assert!((TAGS.image)(&bad).unwrap_err().to_string().contains("expected one of"));
        let ok = TargetArgs(vec![("tag_ids", ArgValue::Ids(vec![1, 2])), ("decimation", ArgValue::Count(2))]);
        let expected = ImageTarget::Tags { family: TagFamily::Tag36h11, ids: Some(vec![1, 2]), decimation: Some(2) };
        assert_eq!(format!("{:?}", (TAGS.image)(&ok).unwrap()), format!("{expected:?}"));
    }
}
