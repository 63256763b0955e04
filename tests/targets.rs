//! The targets are declared once (`vision::targets::TARGETS`) and the scenario and simulation
//! layers read the table: for each entry, a built-in scenario shows it, the scenario schema has
//! each key the entry names, and the image loop's builder draws it and its detector finds every
//! point at its true projection. Nothing here lists the targets: a new entry is tested as it is
//! added (and needs a scenario that shows it, unless it is not `simulated`: no scene shows a
//! target of real images only, and the builder refuses to make one).

use vsinv::sim::scenario::{BUILTIN, Scenario};
use vsinv::sim::{Shot, SimulationConfig, render_view};
use vsinv::vision::detector::Expected;
use vsinv::vision::image::view_of;
use vsinv::vision::targets::{SceneObject, TARGETS, TargetSpec, scene_vision};

fn object(config: &SimulationConfig) -> SceneObject<'_> {
    let scene = &config.scene;
    SceneObject { points: scene.points(), normals: scene.normals(), tags: scene.tags() }
}

/// The first built-in scenario (name, TOML text, config) whose object the target shows.
fn builtin_showing(spec: &TargetSpec) -> (&'static str, &'static str, SimulationConfig) {
    let shown = kinematic_builtins().find_map(|(name, text)| {
        let config = Scenario::from_toml(text).unwrap().to_config().unwrap();
        (config.vision.is_some() && (spec.shows)(&object(&config))).then_some((name, text, config))
    });
    shown.unwrap_or_else(|| panic!("no built-in scenario with [vision] shows target {:?}", spec.name))
}

#[test]
fn exactly_one_target_shows_each_builtin() {
    for (name, text) in kinematic_builtins() {
        let config = Scenario::from_toml(text).unwrap().to_config().unwrap();
        let showing: Vec<&str> = TARGETS.iter().filter(|t| (t.shows)(&object(&config))).map(|t| t.name).collect();
        assert_eq!(showing.len(), 1, "{name}: shown by {showing:?}");
    }
}

/// The built-ins this crate's simulator runs (the `mujoco-*` ones run from Python: each is a
/// kinematic built-in with `[world] engine = "mujoco"`, `tests/builtin_results.rs`).
fn kinematic_builtins() -> impl Iterator<Item = (&'static str, &'static str)> {
    BUILTIN
        .iter()
        .copied()
        .filter(|(_, text)| Scenario::from_toml(text).unwrap().world.engine == vsinv::sim::scenario::Engine::Kinematic)
}

/// The error of the scenario `text` with `key` (`table.key`) set to a value of no kind a key
/// takes (a table of a table holding a string).
fn error_with(text: &str, key: &str) -> String {
    let mut doc: toml::Table = toml::from_str(text).unwrap();
    let (table, field) = key.split_once('.').unwrap();
    let entry = doc.entry(table).or_insert_with(|| toml::Value::Table(toml::Table::new()));
    let wrong: toml::Table = toml::from_str("x = { y = \"z\" }").unwrap();
    entry.as_table_mut().unwrap().insert(field.to_string(), toml::Value::Table(wrong));
    Scenario::from_toml(&toml::to_string(&doc).unwrap()).unwrap_err().to_string()
}

#[test]
fn the_schema_has_every_key_each_target_reads() {
    for spec in TARGETS.iter().filter(|t| t.simulated) {
        let (name, text, _) = builtin_showing(spec);
        assert!(!spec.scenario_keys.is_empty(), "{}: no scenario key", spec.name);
        for key in spec.scenario_keys {
            let (_, field) = key.split_once('.').unwrap();
            let err = error_with(text, key);
            let unknown = err.contains(&format!("unknown field `{field}`"));
            assert!(!unknown, "{} ({name}): {key} is not a key of the schema: {err}", spec.name);
        }
        let (table, _) = spec.scenario_keys[0].split_once('.').unwrap();
        let err = error_with(text, &format!("{table}.no_such_key"));
        assert!(err.contains("unknown field `no_such_key`"), "the check cannot fail: {err}");
    }
}

#[test]
fn the_image_loop_builds_each_target_and_its_detector_finds_it() {
    for spec in TARGETS.iter().filter(|t| t.simulated) {
        let (name, _, config) = builtin_showing(spec);
        let vision = config.vision.unwrap_or_default();
        let mut built = scene_vision(&object(&config), &vision).unwrap();
        assert_eq!(built.target.points().len(), config.scene.points().len(), "{name}");
        // The simulator's view (rendered through the same table) and the true projections.
        let view = render_view(&config, Shot::Reference, None).unwrap();
        assert!(view.visible.iter().all(|&v| v), "{name}: every point in the reference view");
        let expected: Vec<Expected> =
            built.target.points().iter().zip(&view.pixels).map(|(p, &pixel)| Expected { id: p.id, pixel }).collect();
        let found = built.detector.start(&view_of(&view.image).unwrap(), &expected).unwrap();
        for e in &expected {
            let d = found.iter().find(|d| d.id == e.id && d.found);
            let d = d.unwrap_or_else(|| panic!("{} ({name}): point {} not found", spec.name, e.id));
            let error = (d.pixel[0] - e.pixel[0]).hypot(d.pixel[1] - e.pixel[1]);
            assert!(error < 0.5, "{} ({name}): point {} found {error} px from its projection", spec.name, e.id);
        }
    }
}

#[test]
fn a_target_of_real_images_only_is_shown_by_no_scene_and_refused_by_its_builder() {
    for spec in TARGETS.iter().filter(|t| !t.simulated) {
        assert!(spec.scenario_keys.is_empty(), "{}", spec.name);
        for (name, text) in kinematic_builtins() {
            let config = Scenario::from_toml(text).unwrap().to_config().unwrap();
            assert!(!(spec.shows)(&object(&config)), "{name} shows {}", spec.name);
            let vision = config.vision.unwrap_or_default();
            assert!((spec.scene)(&object(&config), &vision).is_err(), "{name}: {}", spec.name);
        }
    }
}
