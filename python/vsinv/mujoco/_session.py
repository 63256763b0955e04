"""What the MuJoCo loops share (`_loop` for a free camera, `_arm_loop` for a camera or a target
on an arm): the image session from a scenario (`_session`), its options, the rows each frame
records and the summary and columns of `RunResult` they make."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from .. import geometry
from .._core import LAW_OPTIONS, ImageServo, Intrinsics, InvalidInput, RunResult, check_stability
from .._zoom import camera_k
from ._effects import degraded
from ._world import World

# [stop] keys the image session reads (the others are the kinematic simulator's own).
_STOP_KEYS = ("max_iterations", "pixel_error", "invariant_error", "tau21", "window",
              "max_translation_uncertainty", "max_rotation_uncertainty_deg", "reference_pixel_sigma")


@dataclass
class MujocoRun:
    """A run through MuJoCo's images (`run_loop`): `result`, the `RunResult` (`run` returns it),
    and what only this loop records per frame: `K` (N, 4: fku, fkv, u0, v0 of the frame, which a
    `[camera] zoom` changes), `found` (N, n), the last image and the mean seconds per iteration
    of rendering and of the servo step."""

    result: RunResult
    K: np.ndarray
    found: np.ndarray
    last_image: np.ndarray = field(repr=False)
    seconds_per_iteration: dict[str, float] = field(default_factory=dict)

    @property
    def summary(self) -> dict[str, Any]:
        """`result.summary`."""
        return self.result.summary

    @property
    def pose(self) -> np.ndarray:
        """`result.pose` (N, 4, 4: the camera in F*)."""
        return self.result.pose

    @property
    def time(self) -> np.ndarray:
        """`result.time` (N,), seconds."""
        return self.result.time


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


def _truth_indices(world: World, servo_ids: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """For each of the session's points, its row of `world.target_points`: dots in order; a
    tag corner 4 t + c the corner of tag t nearest to where it was detected in the reference
    image."""
    points, scenario = world.target_points, world.scenario
    if points is None or scenario is None:
        raise InvalidInput("world: expected a World.from_scenario")
    if world.target == "dots":
        return np.arange(len(points))
    from .. import vision

    tags = vision.detect_tags(reference)
    corners = {int(i): c for i, c in zip(tags.ids, tags.corners)}
    truth = {int(t["id"]): k for k, t in enumerate(scenario["object"]["tags"])}
    rows = []
    for ident in servo_ids:
        tag, c = divmod(int(ident), 4)
        px, _ = world.project(points[4 * truth[tag] : 4 * truth[tag] + 4], np.eye(4))
        rows.append(4 * truth[tag] + int(np.argmin(np.linalg.norm(px - corners[tag][c], axis=1))))
    return np.array(rows, dtype=int)


@dataclass
class _Options:
    law: str | None
    start: Any
    max_iterations: int | None
    record: bool
    progress: Callable[[int, int], object] | None


def _intrinsics(d: dict[str, Any], key: str, t: float = 0.0) -> Intrinsics:
    """K of `[key]` at time `t` (`[camera] zoom` interpolated, as the simulator's)."""
    return Intrinsics(*camera_k(d, key, t))


@dataclass
class _Session:
    servo: Any
    first_image: np.ndarray
    dt: float
    truth: np.ndarray  # per session point, its row of world.target_points


def _session(d: dict[str, Any], world: World, law: str | None, pose: np.ndarray, max_iterations: int | None,
             first: Callable[[], np.ndarray] | None = None) -> _Session:
    """The `ImageServo` on the reference image (K* at F*), the first frame (K at `pose`; or
    `first()`, which puts the world at its start and renders), dt and which scene point each
    of the session's points is."""
    target: Any = world.target
    points = world.target_points
    if target not in ("dots", "tags") or points is None or world.scenario is None:
        raise InvalidInput("world: expected a World.from_scenario (its target is the scenario's)")
    K, K_ref, K_hat = _intrinsics(d, "camera"), _intrinsics(d, "reference_camera"), _intrinsics(d, "estimate")
    options = session_options(d, law)
    if max_iterations is not None:
        options["stop"]["max_iterations"] = int(max_iterations)
    world.set_K(K_ref)
    reference = degraded(d, world.render_reference(), 0)
    args: dict[str, Any] = {}
    if target == "dots":  # the clicks a user would make: near the dots' true pixels
        args["reference_points"], _ = world.project(points, np.eye(4))
    elif d["object"].get("tag_family") is not None:
        args["family"] = d["object"]["tag_family"]
    probe = ImageServo(reference, target, K_hat, **args, law="none", depths=1.0) if target == "tags" else None
    truth = _truth_indices(world, probe.ids if probe is not None else np.arange(len(points)), reference)
    if options.get("depths", "reference") == "reference":
        args["reference_depths"] = points[truth, 2].copy()  # F* is the world frame: depth is z
    world.set_K(K)
    if target == "dots":
        args["first_points"], _ = world.project(points, pose)
    servo = ImageServo(reference, target, K_hat, **args, **options)
    image = first() if first is not None else world.render(pose if world.free_camera else None)
    return _Session(servo, degraded(d, image, 1), float(options["dt"]), truth)


def _record(rows: dict[str, list[Any]], world: World, pose: np.ndarray, step: Any, truth: np.ndarray) -> None:
    """One frame's row: the pose, K, the law's twist, what was found and where, the telemetry,
    and the true pixels of the session's points."""
    points = world.target_points
    assert points is not None  # a World.from_scenario (checked by _session)
    rows["pose"].append(pose.copy())
    k = world.K
    rows["K"].append((k.fku, k.fkv, k.u0, k.v0))
    rows["twist"].append(np.asarray(step.twist, dtype=float))
    found = np.asarray(step.found, dtype=bool).copy()
    rows["found"].append(found)
    rows["pixels"].append(np.where(found[:, None], np.asarray(step.pixels, dtype=float), np.nan))
    rows["telemetry"].append(step.telemetry)
    rows["truth"].append(world.project(points[truth], pose)[0])


def _arrays(rows: dict[str, list[Any]], servo: Any, dt: float, record: bool) -> dict[str, np.ndarray]:
    """The recorded columns (`vsinv.sim.recorded_columns`) of the rows; none kept unless `record`."""
    pose = np.array(rows["pose"])
    tel = rows["telemetry"]
    twist = np.array(rows["twist"])
    twist[-1] = np.nan  # no step followed the last frame
    pixels = np.array(rows["pixels"])
    t_err, r_err = np.array([pose_error(p) for p in pose]).T
    out = {
        "time": dt * np.arange(len(pose)), "pose": pose, "twist": twist,
        "joints": np.array([np.concatenate(geometry.thetau_from_pose(p)) for p in pose]).reshape(-1, 6),
        "pixels": pixels, "visible": np.array(rows["found"]),
        "invariant_error": np.array([t["invariant_error"] for t in tel], dtype=float),
        "tracking_error": np.array([t["tracking_error"] for t in tel], dtype=float),
        "eps": np.array([t["eps"] for t in tel], dtype=float).reshape(-1, 5),
        "eps_z": np.array([t["eps_z"] for t in tel], dtype=float),
        "image_error": np.array([t["image_error"] for t in tel], dtype=float),
        "translation_error": t_err, "rotation_error": r_err,
        "detection_error": np.linalg.norm(pixels - np.array(rows["truth"]), axis=2),
    }
    if not record:
        out = {k: v[:0] for k, v in out.items()}
    out["reference_pixels"] = np.asarray(servo.reference_pixels, dtype=float)
    return out


def _stability(d: dict[str, Any], servo_gain: float) -> tuple[bool, bool]:
    """Props. 1-2 for K_hat against K(t) at the zoom's knots (kappa = 1), as the simulator's."""
    zoom = d["camera"].get("zoom")
    times = zoom["times"] if zoom else [0.0]
    schedule = np.array([_matrix(_intrinsics(d, "camera", t)) for t in times])
    report = check_stability(schedule, _intrinsics(d, "estimate"), 1.0, servo_gain)
    return bool(report.prop1), bool(report.prop2)


def _matrix(k: Intrinsics) -> np.ndarray:
    return np.array([[k.fku, 0.0, k.u0], [0.0, k.fkv, k.v0], [0.0, 0.0, 1.0]])


def _summary(d: dict[str, Any], law: str, servo: Any, step: Any, rows: dict[str, list[Any]]) -> dict[str, Any]:
    """`RunResult.summary` as the simulator fills it for a free camera with images in the loop
    (`within_tolerance` is the scene's truth against `[stop]`'s tolerances)."""
    poses = np.array(rows["pose"])
    start_t, start_r = pose_error(poses[0])
    final_t, final_r = pose_error(poses[-1])
    twists = np.array(rows["twist"][:-1]).reshape(-1, 6)
    last = rows["telemetry"][-1]
    certainty = servo.certainty() or {}
    detection = np.linalg.norm(np.array(rows["pixels"]) - np.array(rows["truth"]), axis=2)
    detection = detection[np.isfinite(detection)]
    control, stop = d.get("control", {}), d.get("stop", {})
    prop1, prop2 = _stability(d, float(control.get("gain", 1.0)))
    tau = [float(t) for t in last["tau"]]
    summary: dict[str, Any] = {
        "name": d["name"], "status": step.verdict, "message": step.reason or "",
        "iterations": int(servo.iterations), "stop_rule": _stop_rule(d, law),
        "prop1": prop1, "prop2": prop2, "within_tolerance": bool(
            final_t <= stop.get("max_translation_uncertainty", 0.005)
            and np.degrees(final_r) <= stop.get("max_rotation_uncertainty_deg", 0.5)),
        "basis": [int(i) for i in servo.basis], "basis_switches": int(servo.basis_switches),
        "final_translation_error": final_t, "final_rotation_error": final_r,
        "final_image_error": float(last["image_error"]), "final_invariant_error": float(last["invariant_error"]),
        "final_tau_11": tau[0], "final_tau_21": tau[1], "final_tau_22": tau[2],
        "start_translation_error": start_t, "start_rotation_error": start_r,
        "max_line_deviation": _line_deviation(poses[:, :3, 3]),
        "peak_linear_speed": float(np.linalg.norm(twists[:, :3], axis=1).max(initial=0.0)),
        "peak_angular_speed": float(np.linalg.norm(twists[:, 3:], axis=1).max(initial=0.0)),
        "detection_error_median": float(np.median(detection)) if detection.size else None,
        "detection_error_max": float(detection.max()) if detection.size else None,
        "translation_uncertainty": certainty.get("translation_bound"),
        "rotation_uncertainty": certainty.get("rotation_bound"),
    }
    for key in ("path_duration", "plane_parallax_residual", "tracking_sigma", "tracking_psi", "tracking_phi",
                "tracking_bound", "observed_max_eps", "min_manipulability"):
        summary[key] = None  # no planned path, no arm
    for key in ("pixel_sigma", "reference_pixel_sigma", "translation_sigma", "rotation_sigma", "floor_pixel_sigma"):
        summary[key] = certainty.get(key)
    return summary


def _stop_rule(d: dict[str, Any], law: str) -> str:
    """The image rule that applied: `[control] stop_rule`, or the law's default (pixels for
    IBVS, the invariant error otherwise)."""
    rule = d.get("control", {}).get("stop_rule")
    if rule is not None:
        return str(rule)
    return "pixel" if law == "ibvs" else "invariant"


def _line_deviation(positions: np.ndarray) -> float:
    """Largest distance of the camera centre from the segment between the start and F*'s origin."""
    a = positions[0]
    length2 = float(a @ a)
    if length2 == 0.0:
        return float(np.linalg.norm(positions, axis=1).max())
    s = np.clip(positions @ a / length2, 0.0, 1.0)
    return float(np.linalg.norm(positions - s[:, None] * a, axis=1).max())
