"""The result of a sweep: one row per run, summaries per value, export to Parquet or CSV."""

from __future__ import annotations

import csv
import importlib
import itertools
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional, Union

import numpy as np

from .._core import InvalidInput
from ..safe_files import replace_file, replace_text_file
from .columns import Column, _binned, _column, _exportable, _hashable

_PathLike = Union[str, "os.PathLike[str]"]


_RATE_COLUMNS = ("runs", "converged", "convergence_rate", "prop1_rate", "prop2_rate")
_MEDIANS = (
    ("final_translation_error", "median_translation_error"),
    ("final_rotation_error", "median_rotation_error"),
    ("final_invariant_error", "median_invariant_error"),
    ("iterations", "median_iterations"),
)


@dataclass
class SweepResult:
    """The runs of a sweep, one row per run.

    ``columns`` holds the varied keys (one column each, named by the key), ``"repeat"``
    (repetition index), ``"seed"`` (the run's noise seed) and every column of
    :func:`vsinv.sim.run_batch` (status, iterations, final errors, prop1, prop2, ...).
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
                replace_file(out, lambda f: pq.write_table(table.replace_schema_metadata(meta), f))
                return out
        names = list(self.columns)
        cols = [_exportable(self.columns[k]) for k in names]
        def write(fh: Any) -> None:
            w = csv.writer(fh)
            w.writerow(names)
            for row in zip(*cols):
                w.writerow(row)

        return replace_text_file(out, write)

    def summary_by(
        self, keys: Union[str, Sequence[str], None] = None, *, bins: Optional[int] = None
    ) -> dict[str, Column]:
        """Per group of runs with equal ``keys`` (default: the grid keys, else every varied
        key): ``runs``, ``converged`` (count), ``convergence_rate``, ``prop1_rate``,
        ``prop2_rate`` (fractions of runs where Prop. 1 / Prop. 2 holds) and the medians
        ``median_translation_error`` (m), ``median_rotation_error`` (rad),
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
                raise InvalidInput(f"summary_by: keys: no column {k!r} (columns: {', '.join(self.columns)})")
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
                vals = np.asarray(self.columns[src][idx], dtype=float) if src in self.columns else np.full(0, math.nan)
                out[name].append(float(np.median(vals[np.isfinite(vals)])) if np.isfinite(vals).any() else math.nan)
        return {k: _column(v) if k in key_list else np.asarray(v) for k, v in out.items()}
