"""The keys a sweep varies: dotted scenario keys and the derived keys (lens_ratio, focal_error,
principal_point_error, roll_deg), applied to a copy of the base scenario."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any, Callable, Union

import numpy as np
import numpy.typing as npt

from .._core import InvalidInput

#: Keys computed from the scenario rather than set verbatim, in the order they are applied.
DERIVED_KEYS = ("lens_ratio", "focal_error", "principal_point_error", "roll_deg")

#: Top-level sections of a scenario (a dotted key must start with one of them).
SECTIONS = (
    "name",
    "description",
    "object",
    "reference_camera",
    "camera",
    "estimate",
    "start",
    "control",
    "robot",
    "noise",
    "stop",
    "path",
    "depth_estimation",
)

#: The fields of an estimate (K_hat) section.
_ESTIMATE_FIELDS = ("fku", "fkv", "u0", "v0", "skew_deg")


def _split(key: str) -> list[Union[str, int]]:
    """``"start.position.2"`` -> ``["start", "position", 2]``; raises on a malformed key."""
    if not isinstance(key, str) or not key:
        raise InvalidInput(f"vary key {key!r}: expected a non-empty string")
    if key in DERIVED_KEYS:
        return [key]
    parts = key.split(".")
    if any(p == "" for p in parts):
        raise InvalidInput(f"vary key {key!r}: empty segment")
    if parts[0] not in SECTIONS:
        raise InvalidInput(
            f"vary key {key!r}: unknown key {parts[0]!r}; expected a derived key "
            f"({', '.join(DERIVED_KEYS)}) or a dotted scenario key starting with one of {', '.join(SECTIONS)}"
        )
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


# rotations (theta-u vectors, radians) ---------------------------------------------------------


def _skew(w: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


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


def rotation_from_thetau(thetau: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Rodrigues' formula: the rotation matrix of a theta-u vector (radians)."""
    r = _real_array(thetau, "thetau", (3,))
    if np.abs(r).max() > 1e150 or not math.isfinite(float(np.linalg.norm(r))):
        raise InvalidInput(f"thetau: rotation angle too large, got {r.tolist()}")
    th = float(np.linalg.norm(r))
    if th < 1e-12:
        return np.eye(3) + _skew(r)
    k = _skew(r / th)
    return np.eye(3) + math.sin(th) * k + (1.0 - math.cos(th)) * (k @ k)


def thetau_from_rotation(rot: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """The theta-u vector (radians, angle in [0, pi]) of a rotation matrix; accurate near
    0 and near pi (where the axis comes from the symmetric part)."""
    r = _real_array(rot, "rot", (3, 3))
    if np.abs(r).max() > 1e6:
        raise InvalidInput(f"rot: not a rotation matrix (entries up to {np.abs(r).max():.3g})")
    v = 0.5 * np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    s = float(np.linalg.norm(v))
    c = 0.5 * (float(np.trace(r)) - 1.0)
    th = math.atan2(s, c)
    if th < 1e-12:
        return v
    if th < 0.5 * math.pi:
        return v * (th / s)
    # Near pi: R + R^T = 2 cos I + 2 (1 - cos) k k^T; take the best conditioned column.
    b = (0.5 * (r + r.T) - c * np.eye(3)) / (1.0 - c)
    i = int(np.argmax(np.diag(b)))
    k = b[:, i] / math.sqrt(max(b[i, i], 1e-300))
    k /= np.linalg.norm(k)
    if float(k @ v) < 0.0:
        k = -k
    return k * th


def _rz(deg: float) -> npt.NDArray[np.float64]:
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


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


def _quaternion_from_thetau_deg(tu_deg: Sequence[float]) -> tuple[float, float, float, float]:
    """Unit quaternion (w, x, y, z) of a theta-u vector in degrees (pure Python: this runs
    once per sweep run, where NumPy's per-call overhead on 3x3 arrays would dominate)."""
    x, y, z = (math.radians(float(v)) for v in tu_deg)
    th = math.sqrt(x * x + y * y + z * z)
    if th < 1e-15:
        return (1.0, 0.5 * x, 0.5 * y, 0.5 * z)
    s = math.sin(0.5 * th) / th
    return (math.cos(0.5 * th), x * s, y * s, z * s)


def _apply_roll(d: dict[str, Any], deg: float) -> None:
    # R' = R Rz(roll) as quaternions: q' = q (cos(a/2), 0, 0, sin(a/2)); back to theta-u
    # with the angle in [0, pi] (w >= 0).
    start = dict(d["start"])
    # rotation_deg (older files: rotation, read as degrees too)
    thetau_deg = start.pop("rotation", None) or start.get("rotation_deg", [0.0, 0.0, 0.0])
    w, x, y, z = _quaternion_from_thetau_deg(thetau_deg)
    h = 0.5 * math.radians(deg)
    c, s = math.cos(h), math.sin(h)
    w, x, y, z = w * c - z * s, x * c + y * s, y * c - x * s, z * c + w * s
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    n = math.sqrt(x * x + y * y + z * z)
    if n < 1e-15:
        start["rotation_deg"] = [0.0, 0.0, 0.0]
    else:
        scale = math.degrees(2.0 * math.atan2(n, w)) / n
        start["rotation_deg"] = [x * scale, y * scale, z * scale]
    d["start"] = start


_DERIVED: dict[str, Callable[[dict[str, Any], float], None]] = {
    "lens_ratio": _apply_lens_ratio,
    "focal_error": _apply_focal_error,
    "principal_point_error": _apply_principal_point_error,
    "roll_deg": _apply_roll,
}


def _apply(base: Mapping[str, Any], values: Mapping[str, Any], paths: Mapping[str, list[Union[str, int]]]) -> dict[str, Any]:
    """A new scenario dict: ``base`` with ``values`` applied (dotted keys, then derived keys)."""
    d = dict(base)
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
