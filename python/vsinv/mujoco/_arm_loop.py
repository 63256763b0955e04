"""The closed loop of a scenario whose camera rides a built-in arm with mass (issue 31, item 2):
the law at the camera rate (`[control] dt`, 25 Hz for dt = 0.04 s), the physics at 500 Hz
(`PHYSICS_DT`), gravity on. Each frame the law's twist (`[world] latency_frames` frames later)
becomes joint velocities through MuJoCo's Jacobian of the site where the controller believes the
camera is (`mj_jacSite`) and the kinematic arm's resolution (`ScenarioArm.joint_velocities`: its
damped least squares, joint-centring task on a redundant arm and joint speed limits, the Rust
code of the kinematic simulator), held on the velocity actuators for the frame's physics steps.
The run ends as the kinematic arm's does: `joint_limit` when a joint reaches its range,
`singular` below `robot.min_manipulability`.

Eye-to-hand (`[world] eye_to_hand`, issue 31 item 3): the camera is fixed at the world's origin
and the arm carries the target (its frame F* at `target_mount` on the end effector). The
reference image is rendered with the arm holding F* on the camera's frame (inverse kinematics),
the law's camera twist v becomes the target's twist -Ad(X) v in its own frame (X the camera's
pose in F*), then joint velocities through MuJoCo's Jacobian of the target's site.
"""

from __future__ import annotations

import time as _time
from typing import Any

import numpy as np

from .. import geometry
from .._core import InvalidInput, RunResult
from . import _mounted
from ._effects import degraded
from ._session import MujocoRun, _arrays, _intrinsics, _Options, _record, _session, _summary
from ._world import World

#: A joint this close to an end of its range (rad, m) has reached it.
LIMIT_MARGIN = 1e-3


def start_joints(arm: Any, start: Any) -> np.ndarray:
    """The start joints: `arm.start`, or given (n,), or those that put the camera at the 4x4
    pose `start` in F* (the inverse kinematics of the arm's own model, a user's URDF or the
    built-in, from `arm.start`)."""
    if start is None:
        return np.asarray(arm.start, dtype=float)
    start = np.asarray(start, dtype=float)
    if start.shape == (len(arm.joint_names),):
        return start.copy()
    if start.shape != (4, 4):
        raise InvalidInput(f"start: expected the camera's 4x4 pose or {len(arm.joint_names)} joints, got shape {start.shape}")
    ee = np.linalg.inv(np.asarray(arm.base)) @ start @ np.linalg.inv(np.asarray(arm.mount))
    return np.asarray(arm.ik(ee, seed=arm.start))


def _event(arm: Any, q: np.ndarray) -> tuple[str, str] | None:
    """(`joint_limit` or `singular`, why) when the arm must stop at `q`, else None."""
    lower, upper = np.asarray(arm.lower), np.asarray(arm.upper)
    at = np.flatnonzero((q <= lower + LIMIT_MARGIN) | (q >= upper - LIMIT_MARGIN))
    if at.size:
        i = int(at[0])
        return "joint_limit", f"joint {arm.joint_names[i]} reached its limit ({q[i]:.4f} in [{lower[i]:.4f}, {upper[i]:.4f}])"
    w = arm.manipulability(q)
    if w < arm.min_manipulability:
        return "singular", f"manipulability {w:.3e} below robot.min_manipulability"
    return None


class _Geometry:
    """The camera's pose in F* and the twist of the arm's "camera" site for a law twist:
    eye-in-hand, the camera rides the site (the twist as is); eye-to-hand, the site is the
    target's frame F* seen by the fixed camera at the world's origin, its pose P the inverse of
    the camera's pose X in F*, and the camera's relative twist v is the target's twist
    -Ad(X) v in its own frame (X = P^-1 carries the camera's frame to the target's: the
    camera-to-base transform, then the arm's kinematics)."""

    def __init__(self, world: World, d: dict[str, Any] | None = None) -> None:
        self.world = world
        self.camera_to_base = believed_camera_to_base(world, world.scenario if d is None else d)

    def pose(self) -> np.ndarray:
        if not self.world.eye_to_hand:
            return self.world.camera_pose()
        return np.linalg.inv(self.world.arm.camera_pose(self.world.data.qpos))

    def site_twist(self, twist: np.ndarray, pose: np.ndarray) -> np.ndarray:
        """The site's twist for the law's `twist`; eye-to-hand through the camera's pose in F*
        the controller believes (`pose`, the truth, with its camera-to-base replaced by
        `world.eye_to_hand.camera_to_base`)."""
        if not self.world.eye_to_hand:
            return twist
        if self.camera_to_base is not None:  # P = Y^-1 fk(q) mount = Y^-1 base^-1 P_true, X = P^-1
            pose = pose @ np.asarray(self.world.arm.base) @ self.camera_to_base
        return -np.asarray(geometry.twist_adjoint(pose)) @ twist

    def render(self) -> np.ndarray:
        return self.world.render(np.eye(4) if self.world.eye_to_hand else None)


def believed_camera_to_base(world: World, d: dict[str, Any] | None) -> np.ndarray | None:
    """Eye-to-hand: the camera-to-base transform Y the controller believes (4x4, the camera's
    frame in the arm's base frame: the run's scenario `d`'s `world.eye_to_hand.camera_to_base`,
    e.g. a hand-eye calibration's `matrix`); None when it gives none (the truth, `base` inverted)."""
    spec = ((d or {}).get("world") or {}).get("eye_to_hand") or {}
    c = spec.get("camera_to_base")
    if not world.eye_to_hand or c is None:
        return None
    return np.asarray(geometry.pose_from_position_thetau(c["position"], np.radians(c.get("rotation_deg", [0.0, 0.0, 0.0]))))


def goal_joints(arm: Any) -> np.ndarray:
    """Eye-to-hand: the joints that put the target's frame F* on the fixed camera's (the
    reference image's view), by the inverse kinematics of the arm's own model from the start joints."""
    ee = np.linalg.inv(np.asarray(arm.base)) @ np.linalg.inv(np.asarray(arm.mount))
    try:
        return np.asarray(arm.ik(ee, seed=arm.start))
    except InvalidInput as e:
        raise InvalidInput(f"world.eye_to_hand: the arm cannot hold the target at the reference view ({e})") from e


def _start_session(d: dict[str, Any], world: World, o: _Options, g: _Geometry) -> tuple[Any, np.ndarray]:
    """The session (reference image, first image) with the arm at its start joints."""
    import mujoco

    arm, m, data = world.arm, world.model, world.data
    start = start_joints(arm, None if world.eye_to_hand else o.start)
    if world.eye_to_hand and o.start is not None:  # the camera's start pose in F*: F* at its inverse
        start = start_joints(arm, np.linalg.inv(np.asarray(o.start, dtype=float)))

    def put(q: np.ndarray) -> None:
        data.qpos[:], data.qvel[:], data.ctrl[:] = q, 0.0, 0.0
        mujoco.mj_forward(m, data)

    def first() -> np.ndarray:
        put(start)
        return g.render()

    put(start)
    pose = g.pose()
    if world.eye_to_hand:
        put(goal_joints(arm))  # the reference image: the target at F* before the fixed camera
    return _session(d, world, o.law, pose, o.max_iterations, first if world.eye_to_hand else None), pose


def run_arm(loaded: Any, d: dict[str, Any], world: World, o: _Options) -> MujocoRun:
    """`_loop`'s run for a world whose camera (or, eye-to-hand, whose target) rides `world.arm`."""
    import mujoco

    arm, m, data = world.arm, world.model, world.data
    _mounted.set_joint_ranges(m, arm)
    g = _Geometry(world, d)
    session, pose = _start_session(d, world, o, g)
    servo, image, dt = session.servo, session.first_image, session.dt
    steps = max(1, round(dt / m.opt.timestep))
    latency = int(d.get("world", {}).get("latency_frames", 0))
    pending = [np.zeros(6)] * latency
    total = int(d.get("stop", {}).get("max_iterations") if o.max_iterations is None else o.max_iterations)
    zooms = bool(d["camera"].get("zoom"))
    rows: dict[str, list[Any]] = {k: [] for k in ("pose", "twist", "found", "K", "pixels", "telemetry", "truth", "q", "dq")}
    clock = {"render": 0.0, "servo": 0.0, "control": 0.0, "physics": 0.0}
    end: tuple[str, str] | None = None
    while True:
        t0 = _time.perf_counter()
        step = servo.step(image)
        clock["servo"] += _time.perf_counter() - t0
        _record(rows, world, pose, step, session.truth)
        rows["q"].append(data.qpos.copy())
        if o.progress is not None:
            o.progress(len(rows["pose"]), total)
        end = None if not step.running else _event(arm, data.qpos)
        if not step.running or end is not None:
            rows["dq"].append(np.full(m.nv, np.nan))
            break
        pending.append(rows["twist"][-1])
        t0 = _time.perf_counter()
        dq, _ = arm.joint_velocities(_mounted.camera_jacobian(m, data), data.qpos, g.site_twist(pending.pop(0), pose))
        clock["control"] += _time.perf_counter() - t0
        rows["dq"].append(np.asarray(dq))
        data.ctrl[:] = dq
        t0 = _time.perf_counter()
        for _ in range(steps):
            mujoco.mj_step(m, data)
        clock["physics"] += _time.perf_counter() - t0
        t0 = _time.perf_counter()
        if zooms:
            world.set_K(_intrinsics(d, "camera", dt * len(rows["pose"])))
        pose = g.pose()
        image = degraded(d, g.render(), len(rows["pose"]) + 1)
        clock["render"] += _time.perf_counter() - t0
    n = len(rows["pose"])
    summary = _summary(d, o.law or d.get("control", {}).get("law", "invariant"), servo, step, rows)
    if end is not None:
        summary["status"], summary["message"] = end
    summary["min_manipulability"] = float(min(arm.manipulability(q) for q in rows["q"]))
    arrays = _arrays(rows, servo, dt, o.record)
    q, dq = np.array(rows["q"]), np.array(rows["dq"])
    arrays["joints"] = q if o.record else q[:0]
    arrays["joint_velocities"] = dq if o.record else dq[:0]
    limits = {"names": list(arm.joint_names), "lower": np.asarray(arm.lower), "upper": np.asarray(arm.upper),
              "velocity": np.asarray(arm.velocity)}
    result = RunResult.from_recording(loaded, summary, arrays, limits)
    return MujocoRun(result=result, K=np.array(rows["K"]), found=np.array(rows["found"]), last_image=image,
                     seconds_per_iteration={k: v / n for k, v in clock.items()})

