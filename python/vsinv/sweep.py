"""Parameter sweeps: many closed-loop runs of one scenario with some keys varied.

>>> from vsinv.sweep import sweep, Uniform
>>> res = sweep("lens-12-6", {"focal_error": np.linspace(-0.6, 2.0, 27)}, repeats=1)
>>> res.summary_by("focal_error")["convergence_rate"]
>>> res = sweep("noise-12-6", {"noise.pixel_sigma": [0.0, 0.5, 1.0]}, repeats=20)
>>> res = sweep("lens-12-6", {"focal_error": [0.0, 0.5], "roll_deg": Uniform(-120, 120)}, draws=50)
>>> res.write("sweep.parquet")                 # CSV when pyarrow is missing

**What is varied.** ``vary`` maps a key to either a sequence of values (a grid axis; the grid
is the Cartesian product of the axes, the last key varying fastest) or a distribution
(:class:`Uniform`, :class:`LogUniform`, :class:`Choice`) sampled ``draws`` times with
``numpy.random.default_rng(seed)``; every draw is combined with every grid point. A scalar is
a one-value axis. Every point is run ``repeats`` times with different noise seeds.

**Keys.** Any dotted scenario key (README, "Scenario files"): ``"noise.pixel_sigma"``,
``"control.gain"``, ``"estimate.skew_deg"``, ``"stop.max_iterations"``, ``"start.position.2"``
(an integer segment indexes a list). A ``camera`` or ``estimate`` section the base does not
have is filled with its default first (camera = reference camera, estimate = the servo camera
at t = 0), other missing sections are created empty. Derived keys:

- ``"lens_ratio"`` r: the servo camera's focal terms become the reference camera's times r
  (fku and fkv; a zoom schedule is scaled by the same factor). If the base has an estimate,
  its focal terms are scaled by the same factor as the servo camera's (K_hat keeps its
  relative error); without one K_hat keeps following the camera.
- ``"focal_error"`` e: K_hat's focal terms are the servo camera's at t = 0 times (1 + e):
  ``estimate.fku = camera.fku * (1 + e)``, same for fkv; K_hat's other fields are the base
  estimate's, or the camera's when the base has no estimate. e <= -1 gives an invalid K_hat.
- ``"principal_point_error"`` d: d pixels added to K_hat's u0 and v0 (K_hat = the camera
  when the base has no estimate).
- ``"roll_deg"`` a: an extra rotation about the optical axis at the start:
  ``R' = R Rz(a)`` with R the start rotation, written back as theta-u degrees.

Dotted keys are applied first (in the order given), then the derived keys in the order above,
then the noise seed.

**Noise seeds.** ``noise.seed`` of run (point p, repetition k) is a 63-bit hash of
``(seed, p, k)`` (column ``"seed"``), unless ``"noise.seed"`` is itself varied.

**Errors.** Unknown or malformed keys and values that make an invalid scenario (checked for
every grid value and for each distribution's bounds) raise :class:`vsinv.InvalidInput` naming
the key before anything runs.

**Execution.** Runs go through :func:`vsinv.run_batch` in chunks. Without an ``executor`` the
chunks run one after another in this process, each on all cores (rayon; ``threads`` is passed
through). With any :class:`concurrent.futures.Executor` (a ``ProcessPoolExecutor``, dask's
``client.get_executor()``, ...) the module-level :func:`_run_chunk` is submitted per chunk, a
bounded number at a time (memory stays flat), and the results are gathered in order. In worker
processes pass ``threads`` (e.g. ``os.cpu_count() // workers``) to avoid oversubscription.
"""

from __future__ import annotations

import csv
import importlib
import itertools
import json
import math
import os
import sys
import time
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Optional, Union

import numpy as np
import numpy.typing as npt

from ._core import InvalidInput, VsinvError, load_scenario, run_batch

if TYPE_CHECKING:
    import concurrent.futures as cf

__all__ = [
    "DERIVED_KEYS",
    "Choice",
    "Distribution",
    "LogUniform",
    "SweepResult",
    "Uniform",
    "build_scenarios",
    "sweep",
]

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

Column = npt.NDArray[Any]
_PathLike = Union[str, "os.PathLike[str]"]


# ---------------------------------------------------------------------------------------------
# distributions


class Distribution:
    """A random distribution of one varied key (sampled ``draws`` times)."""

    def sample(self, rng: np.random.Generator, n: int) -> Column:  # pragma: no cover - abstract
        raise NotImplementedError

    def bounds(self) -> list[Any]:
        """Values checked before the sweep runs (the extremes, or every choice)."""
        raise NotImplementedError  # pragma: no cover - abstract


def _finite(name: str, *values: float) -> None:
    if not all(isinstance(v, (int, float)) and math.isfinite(v) for v in values):
        raise InvalidInput(f"{name}: bounds must be finite numbers, got {values}")


@dataclass(frozen=True)
class Uniform(Distribution):
    """Uniform on ``[lo, hi)``."""

    lo: float
    hi: float

    def __post_init__(self) -> None:
        _finite("Uniform", self.lo, self.hi)
        if self.hi < self.lo:
            raise InvalidInput(f"Uniform: hi ({self.hi}) < lo ({self.lo})")

    def sample(self, rng: np.random.Generator, n: int) -> Column:
        return rng.uniform(float(self.lo), float(self.hi), size=n)

    def bounds(self) -> list[Any]:
        return [float(self.lo), float(self.hi)]


@dataclass(frozen=True)
class LogUniform(Distribution):
    """Log-uniform on ``[lo, hi)``, ``0 < lo <= hi`` (e.g. gains, noise levels)."""

    lo: float
    hi: float

    def __post_init__(self) -> None:
        _finite("LogUniform", self.lo, self.hi)
        if not 0 < self.lo <= self.hi:
            raise InvalidInput(f"LogUniform: needs 0 < lo <= hi, got lo={self.lo}, hi={self.hi}")

    def sample(self, rng: np.random.Generator, n: int) -> Column:
        return np.exp(rng.uniform(math.log(self.lo), math.log(self.hi), size=n))

    def bounds(self) -> list[Any]:
        return [float(self.lo), float(self.hi)]


@dataclass(frozen=True)
class Choice(Distribution):
    """One of ``values``, each with the same probability."""

    values: tuple[Any, ...]

    def __init__(self, values: Iterable[Any]) -> None:
        vals = tuple(_native(v) for v in values)
        if not vals:
            raise InvalidInput("Choice: needs at least one value")
        object.__setattr__(self, "values", vals)

    def sample(self, rng: np.random.Generator, n: int) -> Column:
        return _column(list(self.values))[rng.integers(0, len(self.values), size=n)]

    def bounds(self) -> list[Any]:
        return list(self.values)


# ---------------------------------------------------------------------------------------------
# helpers


def _native(value: Any) -> Any:
    """NumPy scalars and arrays as Python values (scenarios go through JSON)."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, tuple):
        return [_native(v) for v in value]
    return value


def _column(values: Sequence[Any]) -> Column:
    """Values as a 1-d column: a numeric/str/bool array, or an object array for lists."""
    vals = [_native(v) for v in values]
    if any(isinstance(v, (list, dict)) or v is None for v in vals):
        col = np.empty(len(vals), dtype=object)
        col[:] = [tuple(v) if isinstance(v, list) else v for v in vals]
        return col
    return np.asarray(vals)


def _item(col: Column, i: int) -> Any:
    v = col[i]
    if isinstance(v, tuple):
        return [_native(x) for x in v]
    return _native(v)


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


def _camera_at_start(d: Mapping[str, Any]) -> dict[str, Any]:
    """The servo camera at t = 0 (a zoom schedule interpolated at t = 0) as an estimate dict."""
    cam = dict(d.get("camera") or d["reference_camera"])
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


def rotation_from_thetau(thetau: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Rodrigues' formula: the rotation matrix of a theta-u vector (radians)."""
    r = np.asarray(thetau, dtype=float).reshape(3)
    th = float(np.linalg.norm(r))
    if th < 1e-12:
        return np.eye(3) + _skew(r)
    k = _skew(r / th)
    return np.eye(3) + math.sin(th) * k + (1.0 - math.cos(th)) * (k @ k)


def thetau_from_rotation(rot: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """The theta-u vector (radians, angle in [0, pi]) of a rotation matrix; accurate near
    0 and near pi (where the axis comes from the symmetric part)."""
    r = np.asarray(rot, dtype=float).reshape(3, 3)
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
    ref = d["reference_camera"]
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
        est = dict(est)
        est["fku"] = float(est["fku"]) * su
        est["fkv"] = float(est["fkv"]) * sv
        d["estimate"] = est


def _apply_focal_error(d: dict[str, Any], e: float) -> None:
    cam0 = _camera_at_start(d)
    est = dict(d["estimate"]) if d.get("estimate") is not None else dict(cam0)
    est["fku"] = float(cam0["fku"]) * (1.0 + e)
    est["fkv"] = float(cam0["fkv"]) * (1.0 + e)
    d["estimate"] = est


def _apply_principal_point_error(d: dict[str, Any], px: float) -> None:
    est = dict(d["estimate"]) if d.get("estimate") is not None else _camera_at_start(d)
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
    w, x, y, z = _quaternion_from_thetau_deg(start.get("rotation", [0.0, 0.0, 0.0]))
    h = 0.5 * math.radians(deg)
    c, s = math.cos(h), math.sin(h)
    w, x, y, z = w * c - z * s, x * c + y * s, y * c - x * s, z * c + w * s
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    n = math.sqrt(x * x + y * y + z * z)
    if n < 1e-15:
        start["rotation"] = [0.0, 0.0, 0.0]
    else:
        scale = math.degrees(2.0 * math.atan2(n, w)) / n
        start["rotation"] = [x * scale, y * scale, z * scale]
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


def _mix64(x: npt.NDArray[np.uint64]) -> npt.NDArray[np.uint64]:
    """splitmix64's finaliser (vectorised; wraps modulo 2^64)."""
    with np.errstate(over="ignore"):
        z = x + np.uint64(0x9E3779B97F4A7C15)
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        return z ^ (z >> np.uint64(31))


def noise_seeds(seed: int, points: npt.ArrayLike, repeats: npt.ArrayLike) -> npt.NDArray[np.int64]:
    """The noise seed of each run: a 63-bit hash of ``(seed, point index, repetition)``."""
    p = np.asarray(points, dtype=np.uint64)
    k = np.asarray(repeats, dtype=np.uint64)
    s = _mix64(np.full(p.shape, np.uint64(seed % 2**64), dtype=np.uint64))
    z = _mix64(_mix64(s ^ p) ^ k)
    return (z >> np.uint64(1)).astype(np.int64)


# ---------------------------------------------------------------------------------------------
# the plan: which runs, in which order


@dataclass
class _Plan:
    base: dict[str, Any]
    grid_keys: tuple[str, ...]
    random_keys: tuple[str, ...]
    paths: dict[str, list[Union[str, int]]]
    columns: dict[str, Column]  # varied keys, "repeat", "seed", one row per run
    points: npt.NDArray[np.int64]
    seed_varied: bool

    @property
    def keys(self) -> tuple[str, ...]:
        return self.grid_keys + self.random_keys

    def __len__(self) -> int:
        return int(self.points.shape[0])

    def values(self, i: int) -> dict[str, Any]:
        return {k: _item(self.columns[k], i) for k in self.keys}

    def scenario(self, i: int) -> dict[str, Any]:
        d = _apply(self.base, self.values(i), self.paths)
        if not self.seed_varied:
            noise = dict(d.get("noise") or {})
            noise["seed"] = int(self.columns["seed"][i])
            d["noise"] = noise
        return d

    def scenarios(self, start: int, stop: int) -> list[dict[str, Any]]:
        return [self.scenario(i) for i in range(start, stop)]


def _plan(
    base: Any, vary: Mapping[str, Any], repeats: int, draws: Optional[int], seed: int
) -> _Plan:
    if not isinstance(vary, Mapping):
        raise InvalidInput(f"vary: expected a dict of key -> values, got {type(vary).__name__}")
    if isinstance(repeats, bool) or not isinstance(repeats, int) or repeats < 1:
        raise InvalidInput(f"repeats: expected an integer >= 1, got {repeats!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InvalidInput(f"seed: expected a non-negative integer, got {seed!r}")
    base_dict = load_scenario(base).to_dict()

    grid: dict[str, Column] = {}
    dists: dict[str, Distribution] = {}
    paths: dict[str, list[Union[str, int]]] = {}
    for key, spec in vary.items():
        paths[key] = _split(key)
        if isinstance(spec, Distribution):
            dists[key] = spec
        elif isinstance(spec, (str, bytes, Mapping)):
            raise InvalidInput(f"vary key {key!r}: expected a sequence of values or a distribution, got {spec!r}")
        elif isinstance(spec, (Iterable, np.ndarray)):
            vals = list(spec)
            if not vals:
                raise InvalidInput(f"vary key {key!r}: no values")
            grid[key] = _column(vals)
        else:
            grid[key] = _column([spec])  # a scalar: a one-value axis
    if dists and draws is None:
        raise InvalidInput(f"draws: random keys ({', '.join(dists)}) need draws=N")
    if not dists and draws is not None:
        raise InvalidInput("draws: given without any random key (Uniform, LogUniform, Choice)")
    if draws is not None and (isinstance(draws, bool) or not isinstance(draws, int) or draws < 1):
        raise InvalidInput(f"draws: expected an integer >= 1, got {draws!r}")

    # Check every key alone (the error names the key), every grid value and the bounds.
    for key in vary:
        checks = list(grid[key]) if key in grid else dists[key].bounds()
        for v in checks:
            v = _native(v)
            v = list(v) if isinstance(v, tuple) else v
            try:
                load_scenario(_apply(base_dict, {key: v}, paths))
            except (VsinvError, ValueError, TypeError, KeyError) as exc:
                msg = str(exc) if not isinstance(exc, KeyError) else f"missing {exc}"
                if msg.startswith(f"vary key {key!r}"):
                    raise InvalidInput(msg) from exc
                raise InvalidInput(f"vary key {key!r} = {v!r}: {msg}") from exc

    sizes = [len(c) for c in grid.values()]
    n_grid = int(np.prod(sizes)) if sizes else 1
    n_draws = draws if draws is not None else 1
    n_points = n_grid * n_draws
    n = n_points * repeats
    rows = np.arange(n, dtype=np.int64)
    points = rows // repeats
    rep = rows % repeats
    g = points // n_draws
    dr = points % n_draws

    columns: dict[str, Column] = {}
    if grid:
        idx = np.unravel_index(g, tuple(sizes))
        for (key, col), ix in zip(grid.items(), idx):
            columns[key] = col[ix]
    rng = np.random.default_rng(int(seed))
    for key, dist in dists.items():
        columns[key] = np.asarray(dist.sample(rng, n_draws))[dr]
    columns["repeat"] = rep
    seed_varied = "noise.seed" in vary
    if seed_varied:
        columns["seed"] = np.asarray(columns["noise.seed"], dtype=np.int64)
    else:
        columns["seed"] = noise_seeds(int(seed), points, rep)
    return _Plan(base_dict, tuple(grid), tuple(dists), paths, columns, points, seed_varied)


def build_scenarios(
    base: Any,
    vary: Mapping[str, Any],
    *,
    repeats: int = 1,
    draws: Optional[int] = None,
    seed: int = 0,
) -> list[dict[str, Any]]:
    """The scenario dicts :func:`sweep` would run, in order (to inspect or run elsewhere)."""
    plan = _plan(base, vary, repeats, draws, seed)
    return plan.scenarios(0, len(plan))


# ---------------------------------------------------------------------------------------------
# the result


_RATE_COLUMNS = ("runs", "converged", "convergence_rate", "prop1_rate", "prop2_rate")
_MEDIANS = (
    ("final_translation_error_mm", "median_translation_error_mm"),
    ("final_rotation_error_deg", "median_rotation_error_deg"),
    ("final_invariant_error", "median_invariant_error"),
    ("iterations", "median_iterations"),
)


@dataclass
class SweepResult:
    """The runs of a sweep, one row per run.

    ``columns`` holds the varied keys (one column each, named by the key), ``"repeat"``
    (repetition index), ``"seed"`` (the run's noise seed) and every column of
    :func:`vsinv.run_batch` (status, iterations, final errors, prop1, prop2, ...).
    """

    columns: dict[str, Column]
    grid_keys: tuple[str, ...] = ()
    random_keys: tuple[str, ...] = ()
    base_name: str = ""
    repeats: int = 1
    seed: int = 0
    elapsed_s: float = field(default=float("nan"), compare=False)

    @property
    def keys(self) -> tuple[str, ...]:
        """The varied keys: grid keys, then random keys."""
        return self.grid_keys + self.random_keys

    def __len__(self) -> int:
        return len(self.columns["repeat"])

    def __getitem__(self, column: str) -> Column:
        return self.columns[column]

    def to_pandas(self) -> Any:
        """The runs as a ``pandas.DataFrame`` (needs pandas)."""
        try:
            pd: Any = importlib.import_module("pandas")
        except ImportError as exc:
            raise ImportError("SweepResult.to_pandas needs pandas: pip install pandas") from exc
        return pd.DataFrame({k: list(v) if v.dtype == object else v for k, v in self.columns.items()})

    def write(self, path: _PathLike) -> Path:
        """Write the runs to ``path``: Parquet (pyarrow) when it ends with ``.parquet`` and
        pyarrow is installed, else CSV (a ``.parquet`` path becomes ``.csv``). Returns the
        path written."""
        out = Path(path)
        if out.suffix == ".parquet":
            try:
                pa: Any = importlib.import_module("pyarrow")
                pq: Any = importlib.import_module("pyarrow.parquet")
            except ImportError:
                out = out.with_suffix(".csv")
            else:
                table = pa.table({k: pa.array(_exportable(v)) for k, v in self.columns.items()})
                meta = {
                    b"vsinv.base": self.base_name.encode(),
                    b"vsinv.grid_keys": ",".join(self.grid_keys).encode(),
                    b"vsinv.random_keys": ",".join(self.random_keys).encode(),
                    b"vsinv.repeats": str(self.repeats).encode(),
                    b"vsinv.seed": str(self.seed).encode(),
                }
                pq.write_table(table.replace_schema_metadata(meta), out)
                return out
        names = list(self.columns)
        cols = [_exportable(self.columns[k]) for k in names]
        with open(out, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(names)
            for row in zip(*cols):
                w.writerow(row)
        return out

    def summary_by(
        self, keys: Union[str, Sequence[str], None] = None, *, bins: Optional[int] = None
    ) -> dict[str, Column]:
        """Per group of runs with equal ``keys`` (default: the grid keys, else every varied
        key): ``runs``, ``converged`` (count), ``convergence_rate``, ``prop1_rate``,
        ``prop2_rate`` (fractions of runs where Prop. 1 / Prop. 2 holds) and the medians
        ``median_translation_error_mm``, ``median_rotation_error_deg``,
        ``median_invariant_error``, ``median_iterations`` (over every run of the group, NaN
        ignored). With ``bins``, a numeric key with more distinct values than ``bins`` is
        grouped into ``bins`` equal-width bins labelled by their centres (for random keys).
        Groups of grid keys come in the grid's order, others sorted by value. ``keys=()``
        gives one row for all runs."""
        if keys is None:
            keys = self.grid_keys or self.keys
        key_list = [keys] if isinstance(keys, str) else list(keys)
        for k in key_list:
            if k not in self.columns:
                raise KeyError(f"summary_by: no column {k!r} (columns: {', '.join(self.columns)})")
        labels = [_binned(self.columns[k], bins) for k in key_list]
        groups: dict[tuple[Any, ...], list[int]] = {}
        for i, key in enumerate(zip(*labels) if labels else itertools.repeat((), len(self))):
            groups.setdefault(tuple(_hashable(v) for v in key), []).append(i)
        order = list(groups)  # grid keys: the grid's order; otherwise sorted by value
        if bins is not None or any(k not in self.grid_keys for k in key_list):
            try:
                order.sort()
            except TypeError:
                pass
        out: dict[str, list[Any]] = {k: [] for k in key_list}
        for name in _RATE_COLUMNS + tuple(m for _, m in _MEDIANS):
            out[name] = []
        status = self.columns["status"]
        for group in order:
            idx = np.asarray(groups[group], dtype=np.int64)
            for k, v in zip(key_list, group):
                out[k].append(v)
            conv = int(np.count_nonzero(status[idx] == "converged"))
            out["runs"].append(len(idx))
            out["converged"].append(conv)
            out["convergence_rate"].append(conv / len(idx))
            out["prop1_rate"].append(float(np.mean(self.columns["prop1"][idx])))
            out["prop2_rate"].append(float(np.mean(self.columns["prop2"][idx])))
            for src, name in _MEDIANS:
                vals = np.asarray(self.columns[src][idx], dtype=float)
                out[name].append(float(np.median(vals[np.isfinite(vals)])) if np.isfinite(vals).any() else math.nan)
        return {k: _column(v) if k in key_list else np.asarray(v) for k, v in out.items()}


def _hashable(v: Any) -> Any:
    v = _native(v)
    return tuple(v) if isinstance(v, list) else v


def _binned(col: Column, bins: Optional[int]) -> Column:
    if bins is None or col.dtype.kind not in "fiu" or len(np.unique(col)) <= bins:
        return col
    lo, hi = float(np.min(col)), float(np.max(col))
    if hi <= lo:
        return col
    edges = np.linspace(lo, hi, bins + 1)
    i = np.clip(np.searchsorted(edges, col, side="right") - 1, 0, bins - 1)
    centres = 0.5 * (edges[:-1] + edges[1:])
    return centres[i]


def _exportable(col: Column) -> list[Any] | Column:
    """Object columns (list values) as strings, for CSV and Parquet."""
    if col.dtype == object:
        return [str(list(v)) if isinstance(v, tuple) else v for v in col]
    return col


# ---------------------------------------------------------------------------------------------
# running


def _run_chunk(scenarios: list[str], threads: Optional[int] = None) -> dict[str, Column]:
    """Run a chunk of scenarios written as JSON texts with :func:`vsinv.run_batch` (module
    level: picklable, for executors; texts pickle faster than nested dicts)."""
    return run_batch(scenarios, threads=threads)


def _texts(chunk: list[dict[str, Any]], base: Mapping[str, Any]) -> list[str]:
    """The chunk's scenarios as JSON texts. A run's dict shares the sections it does not
    change with ``base`` (same objects), so those are serialised once per chunk."""
    cache: dict[int, str] = {id(v): json.dumps(v) for v in base.values()}
    out = []
    for d in chunk:
        parts = []
        for k, v in d.items():
            text = cache.get(id(v)) if base.get(k) is v else None
            parts.append(json.dumps(k) + ":" + (text if text is not None else json.dumps(v)))
        out.append("{" + ",".join(parts) + "}")
    return out


def _executor_workers(executor: Optional[cf.Executor], threads: Optional[int]) -> int:
    if executor is None:
        return max(1, threads or os.cpu_count() or 1)
    n = getattr(executor, "_max_workers", None)  # Process/ThreadPoolExecutor
    return n if isinstance(n, int) and n > 0 else (os.cpu_count() or 1)


def _explain(plan: _Plan, start: int, chunk: list[dict[str, Any]], exc: BaseException) -> BaseException:
    """An error of a chunk with the run at fault (index and varied values), when it can be
    reproduced by validating the chunk's scenarios here."""
    for j, d in enumerate(chunk):
        try:
            load_scenario(d)
        except (VsinvError, ValueError) as inner:
            i = start + j
            return InvalidInput(f"sweep run {i} ({plan.values(i)}, seed {int(plan.columns['seed'][i])}): {inner}")
    return exc


class _Bar:
    def __init__(self, enabled: Optional[bool], total: int, desc: str) -> None:
        if enabled is None:
            enabled = sys.stderr.isatty()
        self.bar: Any = None
        if enabled:
            from tqdm import tqdm  # type: ignore[import-untyped, unused-ignore]

            self.bar = tqdm(total=total, desc=desc, unit="run", file=sys.stderr, dynamic_ncols=True)

    def update(self, n: int) -> None:
        if self.bar is not None:
            self.bar.update(n)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _chunks(n: int, size: int) -> Iterator[tuple[int, int]]:
    for start in range(0, n, size):
        yield start, min(start + size, n)


def sweep(
    base: Any,
    vary: Mapping[str, Any],
    *,
    repeats: int = 1,
    draws: Optional[int] = None,
    seed: int = 0,
    executor: Optional[cf.Executor] = None,
    chunk_size: Optional[int] = None,
    threads: Optional[int] = None,
    progress: Optional[bool] = None,
) -> SweepResult:
    """Run ``base`` (a built-in name, a TOML path, a dict or a Scenario) for every
    combination of the values in ``vary`` (see the module docstring for keys, grids,
    distributions, seeds and errors).

    - ``repeats``: runs per point, each with its own noise seed.
    - ``draws``: number of random samples (required when a distribution is given).
    - ``seed``: seeds the random draws and the noise seeds (same seed, same sweep).
    - ``executor``: a ``concurrent.futures.Executor`` to run the chunks on (None: here).
    - ``chunk_size``: runs per :func:`vsinv.run_batch` call; default
      ``max(64, ceil(n / (4 * workers)))``, at most 1024 (each run in flight holds
      a few kB: the cap keeps memory flat).
    - ``threads``: rayon threads per chunk (None: all cores).
    - ``progress``: a tqdm bar over runs (None: when stderr is a terminal).
    """
    t0 = time.perf_counter()
    plan = _plan(base, vary, repeats, draws, seed)
    n = len(plan)
    workers = _executor_workers(executor, threads)
    if chunk_size is None:
        chunk_size = min(max(64, math.ceil(n / (4 * workers))), 1024)
    if isinstance(chunk_size, bool) or not isinstance(chunk_size, int) or chunk_size < 1:
        raise InvalidInput(f"chunk_size: expected an integer >= 1, got {chunk_size!r}")

    bar = _Bar(progress, n, f"sweep {plan.base.get('name', '')}")
    parts: dict[int, dict[str, Column]] = {}
    try:
        if executor is None:
            # One chunk runs in Rust (GIL released) while the next one is built here.
            import concurrent.futures as cf

            with cf.ThreadPoolExecutor(max_workers=1) as runner:
                running: Optional[tuple[int, int, list[dict[str, Any]], cf.Future[dict[str, Column]]]] = None
                for start, stop in [*_chunks(n, chunk_size), (n, n)]:
                    chunk = plan.scenarios(start, stop) if start < n else []
                    if running is not None:
                        r_start, r_stop, r_chunk, fut = running
                        try:
                            parts[r_start] = fut.result()
                        except (VsinvError, ValueError) as exc:
                            raise _explain(plan, r_start, r_chunk, exc) from exc
                        bar.update(r_stop - r_start)
                        running = None
                    if chunk:
                        running = (start, stop, chunk, runner.submit(_run_chunk, _texts(chunk, plan.base), threads))
        else:
            _run_on(executor, plan, n, chunk_size, threads, max(2, 2 * workers), parts, bar)
    finally:
        bar.close()

    columns: dict[str, Column] = dict(plan.columns)
    ordered = [parts.pop(s) for s in sorted(parts)]
    for name in list(ordered[0]) if ordered else []:  # column by column: the chunks are freed as we go
        columns[name] = np.concatenate([p.pop(name) for p in ordered])
    return SweepResult(
        columns=columns,
        grid_keys=plan.grid_keys,
        random_keys=plan.random_keys,
        base_name=str(plan.base.get("name", "")),
        repeats=repeats,
        seed=int(seed),
        elapsed_s=time.perf_counter() - t0,
    )


def _run_on(
    executor: cf.Executor,
    plan: _Plan,
    n: int,
    chunk_size: int,
    threads: Optional[int],
    window: int,
    parts: dict[int, dict[str, Column]],
    bar: _Bar,
) -> None:
    """Submit the chunks to ``executor``, at most ``window`` in flight."""
    import concurrent.futures as cf

    todo = _chunks(n, chunk_size)
    pending: dict[cf.Future[dict[str, Column]], tuple[int, int]] = {}
    try:
        while True:
            while len(pending) < window:
                nxt = next(todo, None)
                if nxt is None:
                    break
                pending[executor.submit(_run_chunk, _texts(plan.scenarios(*nxt), plan.base), threads)] = nxt
            if not pending:
                return
            done, _ = cf.wait(pending, return_when=cf.FIRST_COMPLETED)
            for fut in done:
                start, stop = pending.pop(fut)
                try:
                    parts[start] = fut.result()
                except (VsinvError, ValueError) as exc:
                    raise _explain(plan, start, plan.scenarios(start, stop), exc) from exc
                bar.update(stop - start)
    finally:
        for fut in pending:
            fut.cancel()


def _attach() -> None:
    # ``from vsinv import sweep`` binds the function over the module attribute, so that
    # ``vsinv.sweep`` is this function: keep ``vsinv.sweep.Uniform`` etc. working.
    for obj in (Uniform, LogUniform, Choice, SweepResult, build_scenarios):
        setattr(sweep, obj.__name__, obj)


_attach()
