"""The plan of a sweep: which runs (grid points x random draws x repeats), in which order,
with their noise seeds, checked before anything runs."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any, Optional

import numpy as np
import numpy.typing as npt

from .._core import InvalidInput, VsinvError, load_scenario, sweep_scenarios
from .columns import Column, _column, _item, _native
from .distributions import Distribution
from .keys import _check_key, _numeric_array


#: The most runs one sweep plans (its columns are allocated up front).
MAX_RUNS = 2**31


def _indices(values: npt.ArrayLike, name: str) -> npt.NDArray[np.uint64]:
    """Non-negative integers (as uint64), InvalidInput naming ``name`` otherwise."""
    a = _numeric_array(values, name, "non-negative integers")
    if a.dtype.kind == "f":
        bad = ~(np.isfinite(a) & (a == np.floor(a)) & (a >= 0) & (a < 2.0**64))
    else:
        bad = a < 0
    if bad.any():
        at = tuple(int(i) for i in np.argwhere(bad)[0])
        raise InvalidInput(f"{name}: expected non-negative integers, got {a[at]!r} at {at}")
    return a.astype(np.uint64)


def _mix64(x: npt.NDArray[np.uint64]) -> npt.NDArray[np.uint64]:
    """splitmix64's finaliser (vectorised; wraps modulo 2^64)."""
    with np.errstate(over="ignore"):
        z = x + np.uint64(0x9E3779B97F4A7C15)
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        return z ^ (z >> np.uint64(31))


def noise_seeds(seed: int, points: npt.ArrayLike, repeats: npt.ArrayLike) -> npt.NDArray[np.int64]:
    """The noise seed of each run: a 63-bit hash of ``(seed, point index, repetition)``."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InvalidInput(f"seed: expected a non-negative integer, got {seed!r}")
    p, k = _indices(points, "points"), _indices(repeats, "repeats")
    if p.shape != k.shape:
        raise InvalidInput(f"points and repeats: shapes differ, {p.shape} and {k.shape}")
    s = _mix64(np.full(p.shape, np.uint64(int(seed) % 2**64), dtype=np.uint64))
    z = _mix64(_mix64(s ^ p) ^ k)
    return (z >> np.uint64(1)).astype(np.int64)


# ---------------------------------------------------------------------------------------------
# the plan: which runs, in which order


@dataclass
class _Plan:
    base: dict[str, Any]
    grid_keys: tuple[str, ...]
    random_keys: tuple[str, ...]
    columns: dict[str, Column]  # varied keys, "repeat", "seed", one row per run
    points: npt.NDArray[np.int64]
    seed_varied: bool
    allow_outside_files: bool = False

    @property
    def keys(self) -> tuple[str, ...]:
        return self.grid_keys + self.random_keys

    def __len__(self) -> int:
        return int(self.points.shape[0])

    def values(self, i: int) -> dict[str, Any]:
        return {k: _item(self.columns[k], i) for k in self.keys}

    def scenario(self, i: int) -> dict[str, Any]:
        return self.scenarios(i, i + 1)[0]

    def runs(self, start: int, stop: int) -> tuple[list[str], list[list[Any]], Optional[list[int]]]:
        """Runs ``start`` to ``stop - 1`` as the Rust sweep takes them: the keys, one list of
        values per key, and the noise seeds (None when ``noise.seed`` is itself varied)."""
        values = [self.columns[k][start:stop].tolist() for k in self.keys]
        seeds = None if self.seed_varied else self.columns["seed"][start:stop].tolist()
        return list(self.keys), values, seeds

    def scenarios(self, start: int, stop: int) -> list[dict[str, Any]]:
        """The scenarios of runs ``start`` to ``stop - 1``: the base with the varied keys
        applied (dotted keys, then derived keys), then the noise seed."""
        return sweep_scenarios(self.base, *self.runs(start, stop))


def _plan(
    base: Any, vary: Mapping[str, Any], repeats: int, draws: Optional[int], seed: int,
    allow_outside_files: bool = False,
) -> _Plan:
    if not isinstance(vary, Mapping):
        raise InvalidInput(f"vary: expected a dict of key -> values, got {type(vary).__name__}")
    if isinstance(repeats, bool) or not isinstance(repeats, int) or repeats < 1:
        raise InvalidInput(f"repeats: expected an integer >= 1, got {repeats!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InvalidInput(f"seed: expected a non-negative integer, got {seed!r}")
    base_dict = load_scenario(base, allow_outside_files=allow_outside_files).to_dict()

    grid: dict[str, Column] = {}
    dists: dict[str, Distribution] = {}
    for key, spec in vary.items():
        _check_key(key)
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
                (one,) = sweep_scenarios(base_dict, [key], [[v]])
                load_scenario(one, allow_outside_files=allow_outside_files)
            except (VsinvError, ValueError, TypeError) as exc:
                msg = str(exc)
                if f"vary key {key!r}" in msg:
                    raise InvalidInput(msg[msg.index(f"vary key {key!r}"):]) from exc
                raise InvalidInput(f"vary key {key!r} = {v!r}: {msg}") from exc

    sizes = [len(c) for c in grid.values()]
    n_grid = math.prod(sizes)
    n_draws = draws if draws is not None else 1
    n_points = n_grid * n_draws
    n = n_points * repeats
    if n > MAX_RUNS:
        raise InvalidInput(
            f"repeats, draws, vary: {n} runs ({n_grid} grid points x {n_draws} draws x {repeats} repeats); "
            f"at most {MAX_RUNS} in one sweep"
        )
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
    return _Plan(base_dict, tuple(grid), tuple(dists), columns, points, seed_varied, allow_outside_files)


def build_scenarios(
    base: Any,
    vary: Mapping[str, Any],
    *,
    repeats: int = 1,
    draws: Optional[int] = None,
    seed: int = 0,
    allow_outside_files: bool = False,
) -> list[dict[str, Any]]:
    """The scenario dicts :func:`sweep` would run, in order (to inspect or run elsewhere)."""
    plan = _plan(base, vary, repeats, draws, seed, allow_outside_files)
    return plan.scenarios(0, len(plan))
