"""Table columns: the values of a varied key as a NumPy column (objects for lists), and back."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Optional

import numpy as np
import numpy.typing as npt

Column = npt.NDArray[Any]


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
