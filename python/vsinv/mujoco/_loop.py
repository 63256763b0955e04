"""`run`: a scenario's closed loop through MuJoCo's images (`ImageServo` on each render, its
twist moving the free camera), with a summary in `RunResult.summary`'s schema where it applies."""

from __future__ import annotations

import time as _time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .. import geometry
from .._core import LAW_OPTIONS, ImageServo, Intrinsics, InvalidInput
from ..sim import load_scenario, summary_fields
from ._world import World

# [stop] keys the image session reads (the others are the kinematic simulator's own).
_STOP_KEYS = ("max_iterations", "pixel_error", "invariant_error", "tau21", "window",
              "max_translation_uncertainty", "max_rotation_uncertainty_deg", "reference_pixel_sigma")


@dataclass
class MujocoRun:
    """A run through MuJoCo's images: `summary` (the keys of `RunResult.summary` this loop can
    fill; the others are None), and per iteration `time` (s), `pose` (N, 4, 4: camera in F*),
    `twist` (N, 6), `K` (N, 4: fku, fkv, u0, v0 of the frame, which a `[camera] zoom` changes), `invariant_error` (N,), `found` (N, n) and the last image."""

    summary: dict[str, Any]
    time: np.ndarray
    pose: np.ndarray
    twist: np.ndarray
    K: np.ndarray
    invariant_error: np.ndarray
    found: np.ndarray
    last_image: np.ndarray = field(repr=False)
    seconds_per_iteration: dict[str, float] = field(default_factory=dict)


def pose_error(pose: np.ndarray) -> tuple[float, float]:
    """Translation (m) and rotation (rad) of the camera pose `pose` in F* from F*."""
    angle = np.arccos(np.clip((np.trace(pose[:3, :3]) - 1.0) / 2.0, -1.0, 1.0))
    return float(np.linalg.norm(pose[:3, 3])), float(angle)


def session_options(d: dict[str, Any], law: str | None) -> dict[str, Any]:
    """The `ImageServo` keyword arguments of a scenario's `[control]` and `[stop]` (LAW_OPTIONS
    names each option's scenario key and unit)."""
    control = d.get("control", {})
    chosen = law or control.get("law", "invariant")
    out: dict[str, Any] = {"law": chosen, "dt": float(control.get("dt", 0.04))}
    if "depths" in control and control["depths"] in ("reference", "per_step"):
        out["depths"] = control["depths"]
    for option in LAW_OPTIONS:
        key = option["scenario_key"]
        if key is None or control.get(key) is None or chosen not in option["laws"]:
            continue
        value = control[key]
        out[option["name"]] = float(np.radians(value)) if option["scenario_unit"] == "deg/s" else value
    stop = {k: v for k, v in d.get("stop", {}).items() if k in _STOP_KEYS and v is not None}
    out["stop"] = stop
    return out


def _reference_depths(world: World, servo_ids: np.ndarray, reference: np.ndarray, K_ref: Intrinsics) -> np.ndarray:
    """The true depths in F* of the session's points: dots in order; a tag corner 4 t + c the
    depth of the corner of tag t nearest to where it was detected in the reference image."""
    points, scenario = world.target_points, world.scenario
    if points is None or scenario is None:
        raise InvalidInput("world: expected a World.from_scenario")
    if world.target == "dots":
        return points[:, 2].copy()
    from .. import vision

    tags = vision.detect_tags(reference)
    corners = {int(i): c for i, c in zip(tags.ids, tags.corners)}
    truth = {int(t["id"]): k for k, t in enumerate(scenario["object"]["tags"])}
    depths = []
    for ident in servo_ids:
        tag, c = divmod(int(ident), 4)
        block = points[4 * truth[tag] : 4 * truth[tag] + 4]
        px, z = world.project(block, np.eye(4))
        depths.append(z[int(np.argmin(np.linalg.norm(px - corners[tag][c], axis=1)))])
    return np.array(depths)


def run(scenario: Any, *, law: str | None = None, start: Any = None, supersample: int = 1,
        max_iterations: int | None = None, world: World | None = None) -> MujocoRun:
    """Runs `scenario` (a `Scenario`, dict, built-in name or path) through MuJoCo's images: the
    reference image rendered at F* with `[reference_camera]`'s K, the servo camera with
    `[camera]`'s, `ImageServo` with `[estimate]` as K_hat and `[control]`/`[stop]` as its
    session, from `start` (4x4; default the scenario's `[start]`). `law` overrides
    `[control] law`; `world` reuses a `World.from_scenario` of the same scenario."""
    d = load_scenario(scenario).to_dict()
    own = world is None
    w = World.from_scenario(d, supersample=supersample) if world is None else world
    try:
        return _run(d, w, law, start, max_iterations)
    finally:
        if own:
            w.close()


def _intrinsics(d: dict[str, Any], key: str, t: float = 0.0) -> Intrinsics:
    """K of `[key]` at time `t`: a `[camera] zoom` (times, fku, fkv, optional u0, v0) is
    interpolated piecewise linearly and held outside its times, as the simulator's."""
    c = d[key]
    k = [float(c["fku"]), float(c["fkv"]), float(c["u0"]), float(c["v0"])]
    zoom = c.get("zoom")
    if zoom:
        for i, name in enumerate(("fku", "fkv", "u0", "v0")):
            if zoom.get(name) is not None:
                k[i] = float(np.interp(t, zoom["times"], zoom[name]))
    return Intrinsics(*k)


def _session(d: dict[str, Any], world: World, law: str | None, pose: np.ndarray, max_iterations: int | None) -> tuple[Any, np.ndarray, float]:
    """The `ImageServo` on the reference image (K* at F*), the first frame (K at `pose`) and dt."""
    target: Any = world.target
    points = world.target_points
    if target not in ("dots", "tags") or points is None or world.scenario is None:
        raise InvalidInput("world: expected a World.from_scenario (its target is the scenario's)")
    K, K_ref, K_hat = _intrinsics(d, "camera"), _intrinsics(d, "reference_camera"), _intrinsics(d, "estimate")
    options = session_options(d, law)
    if max_iterations is not None:
        options["stop"]["max_iterations"] = int(max_iterations)
    world.set_K(K_ref)
    reference = world.render(np.eye(4))
    args: dict[str, Any] = {}
    if target == "dots":  # the clicks a user would make: near the dots' true pixels
        args["reference_points"], _ = world.project(points, np.eye(4))
    elif d["object"].get("family") is not None:
        args["family"] = d["object"]["family"]
    if options.get("depths", "reference") == "reference":
        probe = ImageServo(reference, target, K_hat, **args, law="none", depths=1.0) if target == "tags" else None
        ids = probe.ids if probe is not None else np.arange(len(points))
        args["reference_depths"] = _reference_depths(world, ids, reference, K_ref)
    world.set_K(K)
    if target == "dots":
        args["first_points"], _ = world.project(points, pose)
    servo = ImageServo(reference, target, K_hat, **args, **options)
    return servo, world.render(pose), float(options["dt"])


def _run(d: dict[str, Any], world: World, law: str | None, start: Any, max_iterations: int | None) -> MujocoRun:
    if start is None:
        s = d["start"]
        start = geometry.pose_from_position_thetau(s["position"], np.radians(s["rotation_deg"]))
    pose = np.asarray(start, dtype=float)
    servo, image, dt = _session(d, world, law, pose, max_iterations)
    zooms = bool(d["camera"].get("zoom"))
    rows: dict[str, list[Any]] = {"pose": [], "twist": [], "err": [], "found": [], "K": []}
    clock = {"render": 0.0, "servo": 0.0}
    while True:
        t0 = _time.perf_counter()
        step = servo.step(image)
        clock["servo"] += _time.perf_counter() - t0
        rows["pose"].append(pose.copy())
        k = world.K
        rows["K"].append((k.fku, k.fkv, k.u0, k.v0))
        rows["twist"].append(np.asarray(step.twist, dtype=float))
        rows["err"].append(float(step.telemetry.get("invariant_error", np.nan)))
        rows["found"].append(np.asarray(step.found).copy())
        if not step.running:
            break
        pose = pose @ geometry.exp_twist(rows["twist"][-1], dt)
        t0 = _time.perf_counter()
        if zooms:  # the lens at the time of the next frame
            world.set_K(_intrinsics(d, "camera", dt * len(rows["pose"])))
        image = world.render(pose)
        clock["render"] += _time.perf_counter() - t0
    n = len(rows["pose"])
    return MujocoRun(
        summary=_summary(d, servo, step, rows), time=dt * np.arange(n), pose=np.array(rows["pose"]),
        twist=np.array(rows["twist"]), K=np.array(rows["K"]), invariant_error=np.array(rows["err"]), found=np.array(rows["found"]),
        last_image=image, seconds_per_iteration={k: v / n for k, v in clock.items()},
    )


def _summary(d: dict[str, Any], servo: Any, step: Any, rows: dict[str, list[Any]]) -> dict[str, Any]:
    """`RunResult.summary`'s keys: those the loop knows filled, the others None (`within_tolerance`
    is the scene's truth against `[stop]`'s tolerances)."""
    start_t, start_r = pose_error(rows["pose"][0])
    final_t, final_r = pose_error(rows["pose"][-1])
    twists = np.array(rows["twist"][:-1]).reshape(-1, 6)
    certainty = servo.certainty() or {}
    summary: dict[str, Any] = {key["name"]: None for key in summary_fields()}
    summary.update({
        "name": d.get("name"), "engine": "mujoco", "status": step.verdict, "message": step.reason,
        "iterations": servo.iterations, "basis": list(servo.basis), "basis_switches": servo.basis_switches,
        "final_translation_error": final_t, "final_rotation_error": final_r, "final_invariant_error": rows["err"][-1],
        "start_translation_error": start_t, "start_rotation_error": start_r,
        "peak_linear_speed": float(np.linalg.norm(twists[:, :3], axis=1).max(initial=0.0)),
        "peak_angular_speed": float(np.linalg.norm(twists[:, 3:], axis=1).max(initial=0.0)),
        "translation_uncertainty": certainty.get("translation_bound"),
        "rotation_uncertainty": certainty.get("rotation_bound"),
    })
    stop = d.get("stop", {})
    summary["within_tolerance"] = bool(
        final_t <= stop.get("max_translation_uncertainty", 0.005) and np.degrees(final_r) <= stop.get("max_rotation_uncertainty_deg", 0.5)
    )
    summary["stop_rule"] = d.get("control", {}).get("stop_rule")  # None: the session's default
    summary["prop1"] = summary["prop2"] = None  # the simulator's verdicts on K(t); not computed here
    for key in ("pixel_sigma", "reference_pixel_sigma", "translation_sigma", "rotation_sigma", "floor_pixel_sigma"):
        summary[key] = certainty.get(key)
    return summary
