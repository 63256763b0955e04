"""The keys a sweep varies: dotted scenario keys and the derived keys (lens_ratio, focal_error,
principal_point_error, roll_deg), applied to a copy of the base scenario."""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from typing import Any, Callable, Union

import numpy as np
import numpy.typing as npt

from .._core import InvalidInput, pose_from_position_thetau, thetau_from_pose

#: Keys computed from the scenario rather than set verbatim, in the order they are applied.
DERIVED_KEYS = ("lens_ratio", "focal_error", "principal_point_error", "roll_deg")

#: The fields of an estimate (K_hat) section.
_ESTIMATE_FIELDS = ("fku", "fkv", "u0", "v0", "skew_deg")


def _split(key: str) -> list[Union[str, int]]:
    """``"start.position.2"`` -> ``["start", "position", 2]``; raises on a malformed key.
    Whether the key exists is the Rust schema's to say: :func:`._plan` applies it to the base
    scenario and parses the result, which names an unknown key (the schema has no copy here)."""
    if not isinstance(key, str) or not key:
        raise InvalidInput(f"vary key {key!r}: expected a non-empty string")
    if key in DERIVED_KEYS:
        return [key]
    parts = key.split(".")
    if any(p == "" for p in parts):
        raise InvalidInput(f"vary key {key!r}: empty segment")
    if parts[0].isdigit():
        raise InvalidInput(f"vary key {key!r}: expected a derived key ({', '.join(DERIVED_KEYS)}) or a dotted scenario key")
    return [int(p) if p.isdigit() else p for p in parts]


def _numbers_of(table: dict[str, Any], key: str) -> dict[str, Any]:
    """A camera table with its intrinsics as numbers: the derived keys scale them, which a
    calibration file does not allow."""
    if "fku" not in table or "fkv" not in table:
        raise InvalidInput(
            f"{key}: the lens and K_hat keys (lens_ratio, focal_error, principal_point_error) need fku, fkv, "
            "u0 and v0 as numbers, not calibration = \"file\""
        )
    return table


def _camera_at_start(d: Mapping[str, Any]) -> dict[str, Any]:
    """The servo camera at t = 0 (a zoom schedule interpolated at t = 0) as an estimate dict."""
    key = "camera" if d.get("camera") else "reference_camera"
    cam = _numbers_of(dict(d[key]), key)
    zoom = cam.get("zoom")
    if isinstance(zoom, Mapping) and zoom.get("times"):
        times = [float(t) for t in zoom["times"]]
        for f in ("fku", "fkv", "u0", "v0"):
            if zoom.get(f):
                cam[f] = float(np.interp(0.0, times, [float(v) for v in zoom[f]]))
    out = {f: cam[f] for f in _ESTIMATE_FIELDS if f in cam}
    out.setdefault("skew_deg", 90.0)
    return out


def _ensure_section(d: dict[str, Any], name: str) -> None:
    """Fill a missing ``camera`` / ``estimate`` section with its default (copied)."""
    if d.get(name) is not None:
        return
    if name == "camera":
        d["camera"] = {k: v for k, v in d["reference_camera"].items()}
    elif name == "estimate":
        d["estimate"] = _camera_at_start(d)
    else:
        d[name] = {}


def _set_dotted(d: dict[str, Any], key: str, path: list[Union[str, int]], value: Any) -> None:
    """Set ``d[path]`` = value, copying the containers on the way (``d`` is already a copy;
    the base scenario is shared, never modified)."""
    first = path[0]
    assert isinstance(first, str)
    if len(path) > 1:
        _ensure_section(d, first)
    node: Any = d
    for depth, seg in enumerate(path[:-1]):
        child = _child(node, seg, key, path[: depth + 1])
        if child is None and isinstance(node, dict):
            child = {}
        if isinstance(child, dict):
            child = dict(child)
        elif isinstance(child, list):
            child = list(child)
        else:
            where = ".".join(str(p) for p in path[: depth + 1])
            raise InvalidInput(f"vary key {key!r}: {where} is a {type(child).__name__}, not a table or a list")
        node[seg] = child
        node = child
    last = path[-1]
    if isinstance(node, list):
        _child(node, last, key, path)  # index check
    elif isinstance(last, int):
        raise InvalidInput(f"vary key {key!r}: {'.'.join(str(p) for p in path[:-1])} is not a list")
    node[last] = value


def _child(node: Any, seg: Union[str, int], key: str, upto: list[Union[str, int]]) -> Any:
    where = ".".join(str(p) for p in upto)
    if isinstance(node, list):
        if not isinstance(seg, int):
            raise InvalidInput(f"vary key {key!r}: {where}: expected a list index")
        if seg >= len(node):
            raise InvalidInput(f"vary key {key!r}: {where}: index out of range (length {len(node)})")
        return node[seg]
    if isinstance(node, dict):
        return node.get(seg) if isinstance(seg, str) else node.get(str(seg))
    raise InvalidInput(f"vary key {key!r}: {where}: not a table or a list")


# arrays, and rotations (theta-u vectors, radians) by the package's SE(3) functions -------------


def _numeric_array(value: npt.ArrayLike, name: str, expected: str) -> npt.NDArray[Any]:
    """``value`` as a NumPy array of booleans, integers or reals (InvalidInput naming ``name``
    and what was ``expected`` otherwise)."""
    try:
        a = np.asarray(value)
    except (TypeError, ValueError) as exc:
        raise InvalidInput(f"{name}: cannot be read as an array ({exc})") from exc
    if a.dtype.kind not in "biuf":
        raise InvalidInput(f"{name}: expected {expected}, got dtype {a.dtype}")
    return a


def _real_array(value: npt.ArrayLike, name: str, shape: tuple[int, ...]) -> npt.NDArray[np.float64]:
    """``value`` as a finite float array of ``shape`` (InvalidInput naming ``name`` otherwise)."""
    a = _numeric_array(value, name, "real numbers")
    if a.size != math.prod(shape):
        raise InvalidInput(f"{name}: expected shape {shape}, got {a.shape}")
    a = a.astype(np.float64).reshape(shape)
    bad = np.argwhere(~np.isfinite(a))
    if len(bad):
        at = bad[0]
        where = f"index {at[0]}" if len(shape) == 1 else f"row {at[0]}, column {at[1]}"
        raise InvalidInput(f"{name}: non-finite value at {where}")
    return a


#: The origin, for rotations as poses.
_ORIGIN = np.zeros(3)


def rotation_from_thetau(thetau: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """The rotation matrix of a theta-u vector (radians): the rotation block of
    :func:`vsinv.geometry.pose_from_position_thetau`."""
    r = _real_array(thetau, "thetau", (3,))
    return np.ascontiguousarray(pose_from_position_thetau(_ORIGIN, r)[:3, :3])


def thetau_from_rotation(rot: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """The theta-u vector (radians, angle in [0, pi]) of a rotation matrix (orthonormal with
    determinant +1 within 1e-6): :func:`vsinv.geometry.thetau_from_pose` of that rotation."""
    r = _real_array(rot, "rot", (3, 3))
    pose = np.eye(4)
    pose[:3, :3] = r
    try:
        return thetau_from_pose(pose)[1]
    except InvalidInput as exc:
        raise InvalidInput("rot: not a rotation matrix (orthonormal with determinant +1, within 1e-6)") from exc


# derived keys ---------------------------------------------------------------------------------


def _apply_lens_ratio(d: dict[str, Any], ratio: float) -> None:
    ref = _numbers_of(d["reference_camera"], "reference_camera")
    had_camera = d.get("camera") is not None
    cam = dict(d["camera"]) if had_camera else dict(ref)
    before = _camera_at_start(d)
    cam["fku"] = float(ref["fku"]) * ratio
    cam["fkv"] = float(ref["fkv"]) * ratio
    su = cam["fku"] / float(before["fku"])
    sv = cam["fkv"] / float(before["fkv"])
    zoom = cam.get("zoom")
    if isinstance(zoom, Mapping):
        zoom = dict(zoom)
        if zoom.get("fku"):
            zoom["fku"] = [float(v) * su for v in zoom["fku"]]
        if zoom.get("fkv"):
            zoom["fkv"] = [float(v) * sv for v in zoom["fkv"]]
        cam["zoom"] = zoom
    d["camera"] = cam
    est = d.get("estimate")
    if est is not None:
        est = _numbers_of(dict(est), "estimate")
        est["fku"] = float(est["fku"]) * su
        est["fkv"] = float(est["fkv"]) * sv
        d["estimate"] = est


def _apply_focal_error(d: dict[str, Any], e: float) -> None:
    cam0 = _camera_at_start(d)
    est = _numbers_of(dict(d["estimate"]), "estimate") if d.get("estimate") is not None else dict(cam0)
    est["fku"] = float(cam0["fku"]) * (1.0 + e)
    est["fkv"] = float(cam0["fkv"]) * (1.0 + e)
    d["estimate"] = est


def _apply_principal_point_error(d: dict[str, Any], px: float) -> None:
    est = _numbers_of(dict(d["estimate"]), "estimate") if d.get("estimate") is not None else _camera_at_start(d)
    est["u0"] = float(est["u0"]) + px
    est["v0"] = float(est["v0"]) + px
    d["estimate"] = est


@functools.lru_cache(maxsize=64)
def _start_rotation(thetau_deg: tuple[float, ...]) -> npt.NDArray[np.float64]:
    """The pose of a start rotation (theta-u degrees): a sweep asks for its base's on every run."""
    pose = pose_from_position_thetau(_ORIGIN, np.radians(np.asarray(thetau_deg, dtype=np.float64)))
    pose.setflags(write=False)
    return pose


def _apply_roll(d: dict[str, Any], deg: float) -> None:
    """R' = R Rz(roll), written back as theta-u degrees (angle in [0, 180])."""
    start = dict(d["start"])
    # rotation_deg (older files: rotation, read as degrees too)
    thetau_deg = start.pop("rotation", None) or start.get("rotation_deg", [0.0, 0.0, 0.0])
    rotation = _start_rotation(tuple(float(x) for x in thetau_deg))
    roll = pose_from_position_thetau(_ORIGIN, [0.0, 0.0, math.radians(deg)])
    start["rotation_deg"] = np.degrees(thetau_from_pose(rotation @ roll)[1]).tolist()
    d["start"] = start


_DERIVED: dict[str, Callable[[dict[str, Any], float], None]] = {
    "lens_ratio": _apply_lens_ratio,
    "focal_error": _apply_focal_error,
    "principal_point_error": _apply_principal_point_error,
    "roll_deg": _apply_roll,
}


def _check_start_varies(d: Mapping[str, Any], key: str, path: list[Union[str, int]]) -> None:
    """A key moving the start pose (``start.*``, ``roll_deg``) needs a scenario whose start is
    a pose: an arm placed by ``robot.joints`` has none (its start follows from the joints)."""
    if path[0] not in ("start", "roll_deg"):
        return
    robot = d.get("robot") or {}
    if d.get("start") is None and robot.get("kind") == "urdf" and robot.get("joints") is not None:
        raise InvalidInput(
            f"vary key {key!r}: this arm is placed by robot.joints, so its start pose is not a key to vary; "
            "place it by the camera pose instead ([start] position and rotation_deg, robot.ik_seed to pick "
            "the joints' branch; the joints then follow by inverse kinematics)"
        )


def _apply(base: Mapping[str, Any], values: Mapping[str, Any], paths: Mapping[str, list[Union[str, int]]]) -> dict[str, Any]:
    """A new scenario dict: ``base`` with ``values`` applied (dotted keys, then derived keys)."""
    d = dict(base)
    for key in values:
        _check_start_varies(d, key, paths.get(key) or [key])
    for key, value in values.items():
        if key not in _DERIVED:
            _set_dotted(d, key, paths[key], value)
    for key in DERIVED_KEYS:
        if key in values:
            v = values[key]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise InvalidInput(f"vary key {key!r}: expected a finite number, got {v!r}")
            _DERIVED[key](d, float(v))
    return d
