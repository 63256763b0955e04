"""Distributions of a random sweep axis: sampled ``draws`` times with ``numpy.random.default_rng(seed)``."""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._core import InvalidInput
from .columns import Column, _column, _native

__all__ = ["Choice", "Distribution", "LogUniform", "Uniform"]


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
        lo, hi = float(self.lo), float(self.hi)
        if math.isinf(hi - lo):  # the width overflows: lo (1 - u) + hi u has no term beyond lo or hi
            u = rng.random(size=n)
            return lo * (1.0 - u) + hi * u
        return rng.uniform(lo, hi, size=n)

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
        lo, hi = float(self.lo), float(self.hi)
        return np.clip(np.exp(rng.uniform(math.log(lo), math.log(hi), size=n)), lo, hi)  # exp(log(x)) may round past x

    def bounds(self) -> list[Any]:
        return [float(self.lo), float(self.hi)]


@dataclass(frozen=True)
class Choice(Distribution):
    """One of ``values``, each with the same probability."""

    values: tuple[Any, ...]

    def __init__(self, values: Iterable[Any]) -> None:
        if isinstance(values, (str, bytes)) or not isinstance(values, (Iterable, np.ndarray)):
            raise InvalidInput(f"Choice: values must be a sequence, got {type(values).__name__}")
        vals = tuple(_native(v) for v in values)
        if not vals:
            raise InvalidInput("Choice: needs at least one value")
        object.__setattr__(self, "values", vals)

    def sample(self, rng: np.random.Generator, n: int) -> Column:
        return _column(list(self.values))[rng.integers(0, len(self.values), size=n)]

    def bounds(self) -> list[Any]:
        return list(self.values)
