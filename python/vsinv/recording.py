"""Recordings a person can watch: a run written as an MCAP file that Foxglove (and Lichtblick,
`ros2 bag`, Rerun's MCAP import) opens, one message per topic and iteration.

Why MCAP and not Rerun's ``.rrd``: the writer is the ``mcap`` package (22 kB of pure Python; with
the ``lz4`` and ``zstandard`` it requires, about 6 MB), where Rerun's SDK is a 170 MB wheel and
Foxglove's SDK 19 MB; MCAP is ROS 2's default bag format, so the users of a servo library
already have a viewer for it, and its messages here are JSON in Foxglove's well-known schemas
(readable with any MCAP reader, no code generation). The extra is ``record``:
``pip install 'vsinv[record]'``.

Topics (log time = the run's time, nanoseconds from 0):

| topic | schema | what |
|---|---|---|
| ``/camera/image`` | ``foxglove.CompressedImage`` (PNG) | the camera's image (runs with images only) |
| ``/camera/detections`` | ``foxglove.ImageAnnotations`` | detected points (green circles), reference points (red) |
| ``/camera/calibration`` | ``foxglove.CameraCalibration`` | K(t) and the image size |
| ``/tf`` | ``foxglove.FrameTransforms`` | ``target`` (F*, the frame of the target's points) to ``camera`` and to ``reference``; with an arm, ``base`` (the arm's base link), every link of its chain ``arm/<link>`` (the URDF's link names) and ``flange`` (its ``robot.end_effector`` link) |
| ``/arm/joint_states`` | ``sensor_msgs/msg/JointState`` (JSON) | with an arm: the joints' names, positions and velocities (rad, m; per second) |
| ``/servo`` | ``vsinv.Step`` | iteration, twist (v, w), the errors, the verdict (``running`` until the last) |
| ``/summary`` | ``vsinv.Summary`` | the run's summary, once, at the last time |

The arm's frames: eye-in-hand, ``base`` hangs from ``target`` (``robot.base``, F* coordinates)
and the chain ``base -> arm/<link> -> ... -> flange`` from it, each link in the one before
(the arm's own kinematics at the recorded joints: a user's URDF or the built-in, as MuJoCo's
bodies are), so ``base -> flange`` composed
with ``robot.camera_mount`` is ``target -> camera``; eye-to-hand (``[world] eye_to_hand``), the
fixed camera is the world: ``base`` hangs from ``camera`` and ``base -> flange -> target_mount`` is
``camera -> target``. Foxglove has no JSON schema for joint states: the joints are JSON messages
with the fields of ROS 2's ``sensor_msgs/msg/JointState`` (``header``, ``name``, ``position``,
``velocity``, ``effort``) under that schema name, which Foxglove's Plot and Raw Message panels
read by field path and ROS users already know (``velocity`` empty on the last row, where no
command followed; ``effort`` empty: not recorded).

The images are rendered again from the recorded poses (a run keeps no images): the kinematic
world's `vsinv.vision.render` with the scenario's ``[vision]`` (the same image but for its noise draw),
MuJoCo's renders for ``[world] engine = "mujoco"`` (deterministic, with ``[vision]``'s blur and the
same noise draws: the frames the loop saw).
"""

from __future__ import annotations

import base64
import json
import math
import os
import struct
import zlib
from collections.abc import Iterator
from typing import Any, Optional, Union

import numpy as np

from ._core import InvalidInput, RunResult
from ._zoom import camera_k

__all__ = ["ARM_TOPICS", "TOPICS", "encode_png", "frames", "write_recording"]

#: The topics a recording has, in the order their channels are registered.
TOPICS = ("/camera/image", "/camera/detections", "/camera/calibration", "/tf", "/servo", "/summary")
#: The topics a recording of a run with an arm has besides `TOPICS`.
ARM_TOPICS = ("/arm/joint_states",)

_TIME = {"type": "object", "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}}}
_VEC3 = {"type": "object", "properties": {k: {"type": "number"} for k in "xyz"}}
_QUAT = {"type": "object", "properties": {k: {"type": "number"} for k in "xyzw"}}
_POINT2 = {"type": "object", "properties": {"x": {"type": "number"}, "y": {"type": "number"}}}
_COLOR = {"type": "object", "properties": {k: {"type": "number"} for k in ("r", "g", "b", "a")}}
_TRANSFORM = {
    "type": "object",
    "properties": {"timestamp": _TIME, "parent_frame_id": {"type": "string"}, "child_frame_id": {"type": "string"},
                   "translation": _VEC3, "rotation": _QUAT},
}
_CIRCLE = {"type": "object", "properties": {"timestamp": _TIME, "position": _POINT2, "diameter": {"type": "number"},
                                            "thickness": {"type": "number"}, "fill_color": _COLOR,
                                            "outline_color": _COLOR}}
_POINTS = {"type": "object", "properties": {"timestamp": _TIME, "type": {"type": "integer"},
                                            "points": {"type": "array", "items": _POINT2},
                                            "outline_color": _COLOR, "thickness": {"type": "number"}}}
_NUMBERS = {"type": "array", "items": {"type": "number"}}
#: The JSON schemas (Foxglove's, trimmed to the fields written; bytes as base64).
SCHEMAS: dict[str, dict[str, Any]] = {
    "foxglove.CompressedImage": {"type": "object", "properties": {
        "timestamp": _TIME, "frame_id": {"type": "string"},
        "data": {"type": "string", "contentEncoding": "base64"}, "format": {"type": "string"}}},
    "foxglove.ImageAnnotations": {"type": "object", "properties": {
        "circles": {"type": "array", "items": _CIRCLE}, "points": {"type": "array", "items": _POINTS},
        "texts": {"type": "array", "items": {"type": "object"}}}},
    "foxglove.CameraCalibration": {"type": "object", "properties": {
        "timestamp": _TIME, "frame_id": {"type": "string"}, "width": {"type": "integer"},
        "height": {"type": "integer"}, "distortion_model": {"type": "string"}, "D": _NUMBERS, "K": _NUMBERS,
        "R": _NUMBERS, "P": _NUMBERS}},
    "foxglove.FrameTransforms": {"type": "object", "properties": {
        "transforms": {"type": "array", "items": _TRANSFORM}}},
    "vsinv.Step": {"type": "object", "properties": {
        "iteration": {"type": "integer"}, "time": {"type": "number"}, "twist": _NUMBERS,
        "translation_error": {"type": "number"}, "rotation_error": {"type": "number"},
        "image_error": {"type": "number"}, "invariant_error": {"type": "number"},
        "visible": {"type": "integer"}, "verdict": {"type": "string"}}},
    "vsinv.Summary": {"type": "object"},
    "sensor_msgs/msg/JointState": {"type": "object", "properties": {
        "header": {"type": "object", "properties": {
            "stamp": {"type": "object", "properties": {"sec": {"type": "integer"}, "nanosec": {"type": "integer"}}},
            "frame_id": {"type": "string"}}},
        "name": {"type": "array", "items": {"type": "string"}}, "position": _NUMBERS, "velocity": _NUMBERS,
        "effort": _NUMBERS}},
}
_SCHEMA_OF = dict(zip(TOPICS + ARM_TOPICS, SCHEMAS))


def encode_png(image: Any) -> bytes:
    """A (height, width) uint8 grey image as PNG bytes (8-bit greyscale, no filter, zlib)."""
    a = np.ascontiguousarray(image)
    if a.dtype != np.uint8 or a.ndim != 2 or 0 in a.shape:
        raise InvalidInput(f"image: expected a non-empty (height, width) uint8 array, got {a.dtype} {a.shape}")
    h, w = a.shape
    raw = np.hstack([np.zeros((h, 1), np.uint8), a]).tobytes()  # filter type 0 a row

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    header = struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b"")


def frames(result: RunResult) -> Iterator[Optional[np.ndarray]]:
    """The image of each recorded iteration of `result` (None throughout for a run without
    images): MuJoCo's render of the pose for a MuJoCo run (with an arm: of the arm at the row's
    joints, the frame the loop saw), `vsinv.render` for a kinematic run
    with `[vision]` (`vsinv.vision.render`)."""
    d = result.scenario.to_dict()
    poses, times = result.pose, result.time
    if (d.get("world") or {}).get("engine") == "mujoco":
        from .mujoco import World
        from .mujoco._effects import camera_image

        with World.from_scenario(d) as world:
            for k in range(len(poses)):
                world.set_K(camera_k(d, "camera", float(times[k])))
                if world.arm is None:
                    yield camera_image(world, d, poses[k], k + 1)
                else:  # the arm at the row's joints: the camera it carries, or the fixed one
                    world.data.qpos[:] = result.joints[k]
                    yield camera_image(world, d, np.eye(4) if world.eye_to_hand else None, k + 1)
    elif d.get("vision") is not None:
        from ._core import render

        for k in range(len(poses)):
            yield render(result.scenario, pose=poses[k], time=float(times[k]))
    else:
        for _ in range(len(poses)):
            yield None


def _stamp(ns: int) -> dict[str, int]:
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}


def _quaternion(r: np.ndarray) -> dict[str, float]:
    """The unit quaternion (x, y, z, w) of a rotation matrix (w >= 0; Shepperd's method)."""
    t = float(np.trace(r))
    if t > 0.0:
        s = 2.0 * math.sqrt(1.0 + t)
        q = ((r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, 0.25 * s)
    else:
        i = int(np.argmax(np.diag(r)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(max(1.0 + r[i, i] - r[j, j] - r[k, k], 1e-300))
        v = [0.0, 0.0, 0.0]
        v[i], v[j], v[k] = 0.25 * s, (r[j, i] + r[i, j]) / s, (r[k, i] + r[i, k]) / s
        q = (v[0], v[1], v[2], (r[k, j] - r[j, k]) / s)
    sign = -1.0 if q[3] < 0.0 else 1.0
    return {"x": sign * q[0], "y": sign * q[1], "z": sign * q[2], "w": sign * q[3]}


def _transform(ns: int, child: str, pose: np.ndarray, parent: str = "target") -> dict[str, Any]:
    t = pose[:3, 3]
    return {"timestamp": _stamp(ns), "parent_frame_id": parent, "child_frame_id": child,
            "translation": {"x": float(t[0]), "y": float(t[1]), "z": float(t[2])},
            "rotation": _quaternion(pose[:3, :3])}


def _number(x: Any) -> Optional[float]:
    """A JSON number (None for NaN and infinities, which JSON has not)."""
    x = float(x)
    return x if math.isfinite(x) else None


def _json_safe(value: Any) -> Any:
    """`value` with NaN and infinities as None and NumPy scalars and arrays as Python's."""
    if isinstance(value, dict):
        return {str(k): _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_json_safe(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return _number(value)
    return value if value is None or isinstance(value, str) else str(value)


def _annotations(ns: int, pixels: np.ndarray, visible: np.ndarray, reference: np.ndarray) -> dict[str, Any]:
    green, red = {"r": 0.1, "g": 0.9, "b": 0.2, "a": 1.0}, {"r": 1.0, "g": 0.2, "b": 0.2, "a": 1.0}
    circles = [{"timestamp": _stamp(ns), "position": {"x": float(p[0]), "y": float(p[1])}, "diameter": 12.0,
                "thickness": 2.0, "fill_color": {"r": 0.0, "g": 0.0, "b": 0.0, "a": 0.0}, "outline_color": green}
               for p, seen in zip(pixels, visible) if seen and np.all(np.isfinite(p))]
    points = [{"timestamp": _stamp(ns), "type": 1, "thickness": 4.0, "outline_color": red,
               "points": [{"x": float(p[0]), "y": float(p[1])} for p in reference if np.all(np.isfinite(p))]}]
    return {"circles": circles, "points": points, "texts": []}


def _calibration(ns: int, d: dict[str, Any], t: float) -> dict[str, Any]:
    fx, fy, u0, v0 = camera_k(d, "camera", t)
    c = d["camera"]
    return {"timestamp": _stamp(ns), "frame_id": "camera", "width": int(c["width"]), "height": int(c["height"]),
            "distortion_model": "", "D": [], "K": [fx, 0.0, u0, 0.0, fy, v0, 0.0, 0.0, 1.0],
            "R": [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            "P": [fx, 0.0, u0, 0.0, 0.0, fy, v0, 0.0, 0.0, 0.0, 1.0, 0.0]}


def _step(result: RunResult, k: int, verdict: str) -> dict[str, Any]:
    return {"iteration": k, "time": float(result.time[k]), "twist": [_number(x) for x in result.twist[k]],
            "translation_error": _number(result.translation_error[k]),
            "rotation_error": _number(result.rotation_error[k]), "image_error": _number(result.image_error[k]),
            "invariant_error": _number(result.invariant_error[k]),
            "visible": int(np.count_nonzero(result.visible[k])), "verdict": verdict}


class _Arm:
    """The arm of a recorded run (`Scenario.arm()`): its frames and joint states at a row."""

    def __init__(self, result: RunResult, d: dict[str, Any]) -> None:
        arm = result.scenario.arm()
        limits = result.joint_limits
        if arm is None or limits is None:
            raise InvalidInput("result: a run with an arm has joint limits and a scenario arm")
        self.arm, self.names = arm, [str(n) for n in limits["names"]]
        self.parent = "camera" if (d.get("world") or {}).get("eye_to_hand") is not None else "target"
        self.base = np.asarray(arm.base, dtype=float)

    def transforms(self, ns: int, q: np.ndarray) -> list[dict[str, Any]]:
        """`base` in its parent (F*, or the fixed camera's frame eye-to-hand), then each link of
        the chain in the one before it (`ScenarioArm.link_poses`, the kinematics `Scenario.arm()`
        runs): base -> arm/<link> -> ... -> flange (the end effector)."""
        links = self.arm.link_poses(q)  # (name, pose in the base link), base link first
        out = [_transform(ns, "base", self.base, self.parent)]
        parent, before = "base", np.eye(4)
        for k, (name, pose) in enumerate(links[1:], 1):
            child = "flange" if k == len(links) - 1 else f"arm/{name}"
            pose = np.asarray(pose, dtype=float)
            out.append(_transform(ns, child, np.linalg.inv(before) @ pose, parent))
            parent, before = child, pose
        return out

    def joint_state(self, ns: int, q: np.ndarray, dq: Optional[np.ndarray]) -> dict[str, Any]:
        moving = dq is not None and bool(np.all(np.isfinite(dq)))
        return {"header": {"stamp": {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}, "frame_id": ""},
                "name": self.names, "position": [float(x) for x in q],
                "velocity": [float(x) for x in dq] if moving and dq is not None else [], "effort": []}


def write_recording(result: RunResult, path: Union[str, "os.PathLike[str]"]) -> int:
    """Writes `result` (a run with its rows: `run_scenario(..., record=True)`) to the MCAP file
    `path` (the topics of the module's table; zstd-compressed chunks); returns the number of
    messages written. Needs the ``record`` extra (``mcap``)."""
    if not isinstance(result, RunResult):
        raise TypeError(f"result: expected a vsinv.RunResult, got {type(result).__name__}")
    n = len(result.time)
    if n == 0:
        raise InvalidInput("result: the run kept no rows (run it with record=True)")
    try:
        from mcap.writer import Writer
    except ImportError as e:  # pragma: no cover - depends on the machine
        raise ImportError(f"recordings need the mcap package ({e}): pip install 'vsinv[record]'") from e
    d = result.scenario.to_dict()
    summary = result.summary
    arm = _Arm(result, d) if result.joint_limits is not None else None
    topics = TOPICS + (ARM_TOPICS if arm is not None else ())
    with open(os.fspath(path), "wb") as f:
        writer = Writer(f)
        writer.start(profile="", library="vsinv")
        channel = {}
        for topic in topics:
            name = _SCHEMA_OF[topic]
            sid = writer.register_schema(name=name, encoding="jsonschema",
                                         data=json.dumps(SCHEMAS[name]).encode())
            channel[topic] = writer.register_channel(topic=topic, message_encoding="json", schema_id=sid)
        count = 0

        def put(topic: str, ns: int, message: dict[str, Any]) -> None:
            nonlocal count
            data = json.dumps(message, allow_nan=False).encode()
            writer.add_message(channel_id=channel[topic], log_time=ns, data=data, publish_time=ns, sequence=count)
            count += 1

        reference = np.asarray(result.reference_pixels, dtype=float)
        for k, image in enumerate(frames(result)):
            ns = int(round(float(result.time[k]) * 1e9))
            if image is not None:
                png = base64.b64encode(encode_png(image)).decode()
                put("/camera/image", ns, {"timestamp": _stamp(ns), "frame_id": "camera", "data": png, "format": "png"})
            put("/camera/detections", ns, _annotations(ns, result.pixels[k], result.visible[k], reference))
            put("/camera/calibration", ns, _calibration(ns, d, float(result.time[k])))
            tf = [_transform(ns, "camera", result.pose[k]), _transform(ns, "reference", np.eye(4))]
            if arm is not None:
                q = np.asarray(result.joints[k], dtype=float)
                dq = None if result.joint_velocities is None else np.asarray(result.joint_velocities[k])
                tf += arm.transforms(ns, q)
                put("/arm/joint_states", ns, arm.joint_state(ns, q, dq))
            put("/tf", ns, {"transforms": tf})
            put("/servo", ns, _step(result, k, "running" if k + 1 < n else str(summary.get("status"))))
        last = int(round(float(result.time[-1]) * 1e9))
        put("/summary", last, _json_safe(summary))
        writer.finish()
    return count
