"""The MuJoCo rows of a batch: `[world] engine = "mujoco"` scenarios run by `vsinv.mujoco` (MuJoCo
renders in Python, not in Rust's thread pool) in a pool of worker processes, each row the run's
summary in the batch table's columns (`vsinv.sim.run_batch` merges them with the Rust runner's).

The pool is kept between calls (a spawned worker takes about a second to import vsinv and
MuJoCo: a second batch does not pay it again) and each worker renders with `cores / processes`
llvmpipe threads (`LP_NUM_THREADS`, set in the worker before it loads EGL, unless the user set
it): Mesa's CPU renderer otherwise starts a thread per core in every worker, and the workers'
renders fight over the cores (benches/mujoco_sweep.py measures both).
"""

from __future__ import annotations

import atexit
import concurrent.futures as cf
import json
import math
import multiprocessing
import os
import sys
from collections.abc import Sequence
from typing import Any, Callable, Optional

import numpy as np

from ._core import InvalidInput, Scenario, VsinvError, load_scenario

#: The batch table's columns, in the Rust runner's order, and their kinds.
COLUMNS = (
    "status", "iterations", "final_translation_error", "final_rotation_error", "final_image_error",
    "final_invariant_error", "max_line_deviation", "observed_max_eps", "pixel_sigma", "translation_uncertainty",
    "rotation_uncertainty", "prop1", "prop2", "within_tolerance", "message",
)
_TEXT = ("status", "message")
_FLAGS = ("prop1", "prop2", "within_tolerance")


def mujoco_scenario(item: Any, allow_outside_files: bool, index: int) -> Optional[dict[str, Any]]:
    """Scenario `index` of a batch as a dict when its `[world] engine` is "mujoco", else None. A
    dict or JSON text that says "mujoco" and does not load raises `InvalidInput` naming
    "scenario {index}" (before anything runs); a name or path is loaded, and anything that does
    not load is left to the Rust runner, which names it."""
    if isinstance(item, Scenario):
        return item.to_dict() if item.engine == "mujoco" else None
    if isinstance(item, str) and item.lstrip().startswith("{"):
        if '"mujoco"' not in item:
            return None
        try:
            item = json.loads(item)
        except ValueError:
            return None  # the Rust runner says where the text is not JSON
    if isinstance(item, dict):
        if not isinstance(item.get("world"), dict) or item["world"].get("engine") != "mujoco":
            return None
        try:
            return load_scenario(item, allow_outside_files=allow_outside_files).to_dict()
        except VsinvError as e:
            raise InvalidInput(f"scenario {index}: {e}") from e
    if not isinstance(item, (str, os.PathLike)):
        return None
    try:
        loaded = load_scenario(item, allow_outside_files=allow_outside_files)
    except (VsinvError, ValueError, TypeError, OSError):
        return None
    return loaded.to_dict() if loaded.engine == "mujoco" else None


def row_of(summary: dict[str, Any]) -> dict[str, Any]:
    """A run's summary as one row of the batch table (None as NaN)."""
    row: dict[str, Any] = {}
    for key in COLUMNS:
        value = summary.get(key)
        if key in _TEXT:
            row[key] = "" if value is None else str(value)
        elif key in _FLAGS:
            row[key] = bool(value)
        elif key == "iterations":
            row[key] = int(value or 0)
        else:
            row[key] = math.nan if value is None else float(value)
    return row


def run_one(scenario: dict[str, Any], allow_outside_files: bool) -> dict[str, Any]:
    """One MuJoCo run's row (module level: a worker's task); a run that fails on the way is the
    row of status "error" and its message, as the Rust runner's."""
    from ._run import run_scenario

    try:
        result = run_scenario(scenario, record=False, allow_outside_files=allow_outside_files)
    except VsinvError as e:
        return row_of({"status": "error", "message": str(e)})
    return row_of(result.summary)


def run_rows(scenarios: Sequence[dict[str, Any]], processes: int, allow_outside_files: bool,
             done: Callable[[], None]) -> list[dict[str, Any]]:
    """The rows of `scenarios`, in order: here when `processes` is 1 or there is one run, else on
    `processes` worker processes (spawned, see `_start_method`); `done()`
    after each run. A worker's exception (or Ctrl-C) cancels what has not started and is raised."""
    try:
        from . import mujoco  # noqa: F401 - the extra, checked before anything runs
    except ImportError as e:  # pragma: no cover - depends on the machine
        raise InvalidInput(f"world.engine: \"mujoco\" needs the mujoco extra ({e}): pip install 'vsinv[mujoco]'") from e
    if processes <= 1 or len(scenarios) <= 1:
        rows = []
        for s in scenarios:
            rows.append(run_one(s, allow_outside_files))
            done()
        return rows
    out: list[Optional[dict[str, Any]]] = [None] * len(scenarios)
    pool = _pool(processes)
    futures = {pool.submit(run_one, s, allow_outside_files): i for i, s in enumerate(scenarios)}
    try:
        for future in cf.as_completed(futures):
            out[futures[future]] = future.result()
            done()
    except BaseException:
        # a worker's exception or Ctrl-C: what has not started is cancelled, the pool dropped
        # (its workers may be busy or gone), and a later batch starts a new one
        _drop_pool(processes)
        raise
    return [r for r in out if r is not None]


#: The kept worker pools, by their number of processes and start method.
_POOLS: dict[tuple[int, str], cf.ProcessPoolExecutor] = {}


def _pool(processes: int) -> cf.ProcessPoolExecutor:
    """The kept pool of `processes` workers for this start method (made on first use, again
    after a failure)."""
    method = _start_method()
    pool = _POOLS.get((processes, method))
    if pool is None:
        threads = max(1, (os.cpu_count() or 1) // processes)
        pool = cf.ProcessPoolExecutor(max_workers=processes, mp_context=multiprocessing.get_context(method),
                                      initializer=_worker_init, initargs=(threads,))
        _POOLS[(processes, method)] = pool
    return pool


def _drop_pool(processes: int) -> None:
    pool = _POOLS.pop((processes, _start_method()), None)
    if pool is not None:
        pool.shutdown(wait=False, cancel_futures=True)


@atexit.register
def _shutdown_pools() -> None:
    """The kept pools' workers end with this process."""
    while _POOLS:
        _, pool = _POOLS.popitem()
        pool.shutdown(wait=True, cancel_futures=True)


def _worker_init(threads: int) -> None:
    """A worker's start: `threads` llvmpipe render threads (Mesa reads `LP_NUM_THREADS` when EGL
    opens its first context, after this) unless the user chose."""
    os.environ.setdefault("LP_NUM_THREADS", str(threads))


def _start_method() -> str:
    """"spawn" (a fresh interpreter: no GL context or thread pool of this process is copied),
    or "fork" when the main module cannot be imported again (a script read from stdin)."""
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    return "fork" if path is not None and not os.path.exists(path) else "spawn"


def merge(n: int, table: Optional[dict[str, np.ndarray]], rust_rows: Sequence[int],
          rows: Sequence[dict[str, Any]], mujoco_rows: Sequence[int]) -> dict[str, np.ndarray]:
    """The batch table of `n` rows: the Rust runner's `table` at `rust_rows`, `rows` at
    `mujoco_rows`."""
    out: dict[str, np.ndarray] = {}
    for key in COLUMNS:
        values: list[Any] = [None] * n
        if table is not None:
            for i, v in zip(rust_rows, table[key]):
                values[i] = v.item() if hasattr(v, "item") else v
        for i, row in zip(mujoco_rows, rows):
            values[i] = row[key]
        if key in _TEXT:
            out[key] = np.array(values, dtype=str)
        elif key in _FLAGS:
            out[key] = np.array(values, dtype=bool)
        else:
            out[key] = np.array(values, dtype=np.int64 if key == "iterations" else np.float64)
    return out


def workers(threads: Optional[int]) -> int:
    """Worker processes for the MuJoCo runs: `threads`, or every core."""
    return max(1, threads or os.cpu_count() or 1)
