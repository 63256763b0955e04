"""`run`: a scenario's closed loop through MuJoCo's images (`ImageServo` on each render, its
twist moving the free camera, `[world] latency_frames` frames later), recorded in
`RunResult`'s schema (`RunResult.from_recording`): the same summary keys and columns as a
kinematic run with images in the loop."""

from __future__ import annotations

import time as _time
from typing import Any, Callable

import numpy as np

from .. import geometry
from .._core import RunResult, load_scenario
from ._arm_loop import run_arm
from ._effects import camera_image
from ._session import MujocoRun, _arrays, _intrinsics, _Options, _record, _session, _summary
from ._world import World


def run(scenario: Any, *, law: str | None = None, start: Any = None, supersample: int | None = None,
        max_iterations: int | None = None, world: World | None = None, record: bool = True,
        progress: Callable[[int, int], object] | None = None) -> RunResult:
    """Runs `scenario` (a `Scenario`, dict, built-in name or path) through MuJoCo's images and
    returns its `RunResult` (what `vsinv.run_scenario` returns for `[world] engine = "mujoco"`):
    the reference image rendered at F* with `[reference_camera]`'s K, the servo camera with
    `[camera]`'s, `ImageServo` with `[estimate]` as K_hat and `[control]`/`[stop]` as its
    session, from `start` (4x4; default the scenario's `[start]`), the twist of frame k applied
    after frame k + `[world] latency_frames`, each frame rendered with `[world] supersample`
    samples a side per pixel unless `supersample` overrides it. `law` overrides `[control] law`; `world` reuses a
    `World.from_scenario` of the same scenario; `record=False` keeps no rows (the summary
    only); `progress(done, total)` is called after each frame."""
    return run_loop(scenario, law=law, start=start, supersample=supersample, max_iterations=max_iterations,
                    world=world, record=record, progress=progress).result


def run_loop(scenario: Any, *, law: str | None = None, start: Any = None, supersample: int | None = None,
             max_iterations: int | None = None, world: World | None = None, record: bool = True,
             progress: Callable[[int, int], object] | None = None) -> MujocoRun:
    """`run`, with what only the MuJoCo loop records (`MujocoRun`: K per frame, timings)."""
    loaded = load_scenario(scenario)
    d = loaded.to_dict()
    own = world is None
    w = World.from_scenario(d, supersample=supersample) if world is None else world
    try:
        return _run(loaded, d, w, _Options(law, start, max_iterations, record, progress))
    finally:
        if own:
            w.close()


def _run(loaded: Any, d: dict[str, Any], world: World, o: _Options) -> MujocoRun:
    if world.arm is not None:
        return run_arm(loaded, d, world, o)  # eye-in-hand or eye-to-hand
    start = o.start
    if start is None:
        s = d["start"]
        start = geometry.pose_from_position_thetau(s["position"], np.radians(s["rotation_deg"]))
    pose = np.asarray(start, dtype=float)
    session = _session(d, world, o.law, pose, o.max_iterations)
    servo, image, dt = session.servo, session.first_image, session.dt
    latency = int(d.get("world", {}).get("latency_frames", 0))
    pending = [np.zeros(6)] * latency  # twists computed, not yet applied (oldest first)
    total = int(d.get("stop", {}).get("max_iterations") if o.max_iterations is None else o.max_iterations)
    zooms = bool(d["camera"].get("zoom"))
    rows: dict[str, list[Any]] = {k: [] for k in ("pose", "twist", "found", "K", "pixels", "telemetry", "truth")}
    clock = {"render": 0.0, "servo": 0.0}
    while True:
        t0 = _time.perf_counter()
        step = servo.step(image)
        clock["servo"] += _time.perf_counter() - t0
        _record(rows, world, pose, step, session.truth)
        if o.progress is not None:
            o.progress(len(rows["pose"]), total)
        if not step.running:
            break
        pending.append(rows["twist"][-1])
        pose = pose @ geometry.exp_twist(pending.pop(0), dt)
        t0 = _time.perf_counter()
        if zooms:  # the lens at the time of the next frame
            world.set_K(_intrinsics(d, "camera", dt * len(rows["pose"])))
        image = camera_image(world, d, pose, len(rows["pose"]) + 1)
        clock["render"] += _time.perf_counter() - t0
    n = len(rows["pose"])
    summary = _summary(d, o.law or d.get("control", {}).get("law", "invariant"), servo, step, rows)
    result = RunResult.from_recording(loaded, summary, _arrays(rows, servo, dt, o.record))
    return MujocoRun(result=result, K=np.array(rows["K"]), found=np.array(rows["found"]), last_image=image,
                     seconds_per_iteration={k: v / n for k, v in clock.items()})
