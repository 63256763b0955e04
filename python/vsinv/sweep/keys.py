"""The keys a sweep varies: dotted scenario keys and the derived keys (lens_ratio, focal_error,
principal_point_error, roll_deg). They are read and applied in Rust (``vsinv._core.sweep_scenarios``
and ``run_sweep_runs``, ``src/sim/sweep/``): the base scenario once, each run's keys on a copy of it,
parsed once. This module names them and keeps the package's rotation helpers."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt

from .._core import SWEEP_DERIVED_KEYS, InvalidInput, pose_from_position_thetau, sweep_scenarios, thetau_from_pose

#: Keys computed from the scenario rather than set verbatim, in the order they are applied.
DERIVED_KEYS: tuple[str, ...] = tuple(SWEEP_DERIVED_KEYS)


def _check_key(key: Any) -> None:
    """A malformed key raises (InvalidInput naming it); whether it exists is the schema's to say
    when a run's scenario is parsed."""
    if not isinstance(key, str) or not key:
        raise InvalidInput(f"vary key {key!r}: expected a non-empty string")
    sweep_scenarios({}, [key], [[]])


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
