//! The built-in scenarios reproducing the paper's experiments (files in `scenarios/`).

use super::{Scenario, scenario_error};
use crate::sim::error::Result;

/// The built-in scenarios: (name, TOML text). The `mujoco-` ones have `[world] engine = "mujoco"`:
/// Python's `vsinv.mujoco.run` runs them; this crate's simulator refuses them.
pub const BUILTIN: &[(&str, &str)] = &[
    ("zoom-stationary", include_str!("../../../scenarios/zoom-stationary.toml")),
    ("lens-12-12", include_str!("../../../scenarios/lens-12-12.toml")),
    ("lens-12-6", include_str!("../../../scenarios/lens-12-6.toml")),
    ("lens-12-6-barrel", include_str!("../../../scenarios/lens-12-6-barrel.toml")),
    ("lens-12-fisheye", include_str!("../../../scenarios/lens-12-fisheye.toml")),
    ("lens-25-12", include_str!("../../../scenarios/lens-25-12.toml")),
    ("lens-6-12", include_str!("../../../scenarios/lens-6-12.toml")),
    ("ibvs-12-12", include_str!("../../../scenarios/ibvs-12-12.toml")),
    ("ibvs-12-6", include_str!("../../../scenarios/ibvs-12-6.toml")),
    ("ibvs-25-12", include_str!("../../../scenarios/ibvs-25-12.toml")),
    ("ibvs-6-12", include_str!("../../../scenarios/ibvs-6-12.toml")),
    ("zoom-servo", include_str!("../../../scenarios/zoom-servo.toml")),
    ("path-500", include_str!("../../../scenarios/path-500.toml")),
    ("path-3000", include_str!("../../../scenarios/path-3000.toml")),
    ("path-500-feedforward", include_str!("../../../scenarios/path-500-feedforward.toml")),
    ("noise-12-6", include_str!("../../../scenarios/noise-12-6.toml")),
    ("cartesian-12-6", include_str!("../../../scenarios/cartesian-12-6.toml")),
    ("arm-ur5-12-6", include_str!("../../../scenarios/arm-ur5-12-6.toml")),
    ("arm-panda-12-6", include_str!("../../../scenarios/arm-panda-12-6.toml")),
    ("occlusion", include_str!("../../../scenarios/occlusion.toml")),
    ("planar", include_str!("../../../scenarios/planar.toml")),
    ("vision-12-12", include_str!("../../../scenarios/vision-12-12.toml")),
    ("vision-12-6", include_str!("../../../scenarios/vision-12-6.toml")),
    ("vision-25-12", include_str!("../../../scenarios/vision-25-12.toml")),
    ("vision-zoom", include_str!("../../../scenarios/vision-zoom.toml")),
    ("tags-12-12", include_str!("../../../scenarios/tags-12-12.toml")),
    ("tags-12-6", include_str!("../../../scenarios/tags-12-6.toml")),
    ("mujoco-lens-12-6", include_str!("../../../scenarios/mujoco-lens-12-6.toml")),
    ("mujoco-lens-12-6-tags", include_str!("../../../scenarios/mujoco-lens-12-6-tags.toml")),
    ("mujoco-zoom", include_str!("../../../scenarios/mujoco-zoom.toml")),
    ("mujoco-ibvs-12-6", include_str!("../../../scenarios/mujoco-ibvs-12-6.toml")),
    ("mujoco-arm-ur5e-12-6", include_str!("../../../scenarios/mujoco-arm-ur5e-12-6.toml")),
    ("mujoco-arm-ur5e-12-6-tags", include_str!("../../../scenarios/mujoco-arm-ur5e-12-6-tags.toml")),
    ("mujoco-arm-panda-zoom", include_str!("../../../scenarios/mujoco-arm-panda-zoom.toml")),
    ("mujoco-arm-ur5e-ibvs-12-6", include_str!("../../../scenarios/mujoco-arm-ur5e-ibvs-12-6.toml")),
    ("mujoco-eye-to-hand-12-6", include_str!("../../../scenarios/mujoco-eye-to-hand-12-6.toml")),
    ("mujoco-arm-ur5e-zoom-stationary", include_str!("../../../scenarios/mujoco-arm-ur5e-zoom-stationary.toml")),
];

/// A built-in scenario by name (parsed once, then cloned).
pub fn builtin(name: &str) -> Result<Scenario> {
    static PARSED: std::sync::OnceLock<Vec<Result<Scenario>>> = std::sync::OnceLock::new();
    let parsed = PARSED.get_or_init(|| BUILTIN.iter().map(|(_, text)| Scenario::from_toml(text)).collect());
    match BUILTIN.iter().position(|(n, _)| *n == name) {
        Some(i) => parsed[i].clone(),
        None => {
            let names: Vec<&str> = BUILTIN.iter().map(|(n, _)| *n).collect();
            Err(scenario_error("", format!("no built-in scenario {name:?}; known: {}", names.join(", "))))
        }
    }
}
