"""Running a sweep: chunks through :func:`vsinv.sim.run_batch`, in this process or on any
:class:`concurrent.futures.Executor` (a bounded number in flight), with a progress bar."""

from __future__ import annotations

import json
import logging
import math
import os
import time
from collections.abc import Iterator, Mapping
from typing import TYPE_CHECKING, Any, Optional

import numpy as np

from .._batch import run_batch
from .._core import InvalidInput, VsinvError, load_scenario, run_sweep_runs, sweep_scenarios
from .._progress import Bar
from .columns import Column
from .plan import _Plan, _plan
from .result import SweepResult

if TYPE_CHECKING:
    import concurrent.futures as cf

log = logging.getLogger("vsinv")


def _run_chunk(
    base: dict[str, Any], keys: list[str], values: list[list[Any]], seeds: Optional[list[int]],
    threads: Optional[int] = None, allow_outside_files: bool = False,
) -> dict[str, Column]:
    """Run a chunk of a sweep's runs (module level: picklable, for executors): the base
    scenario, the varied keys, one list of values per key and the noise seeds, applied and run
    in Rust (``vsinv._core.run_sweep_runs``). A MuJoCo base (``[world] engine = "mujoco"``)
    runs through :func:`vsinv.sim.run_batch` (its worker processes). The sweep has its own
    bar: the chunk shows none."""
    world = base.get("world")
    if isinstance(world, dict) and world.get("engine") == "mujoco":
        texts = [json.dumps(d) for d in sweep_scenarios(base, keys, values, seeds)]
        return run_batch(texts, threads=threads, allow_outside_files=allow_outside_files, progress=None)
    return run_sweep_runs(base, keys, values, seeds, threads=threads, allow_outside_files=allow_outside_files)


def _executor_workers(executor: Optional[cf.Executor], threads: Optional[int]) -> int:
    if executor is None:
        return max(1, threads or os.cpu_count() or 1)
    n = getattr(executor, "_max_workers", None)  # Process/ThreadPoolExecutor
    return n if isinstance(n, int) and n > 0 else (os.cpu_count() or 1)


def _explain(plan: _Plan, start: int, stop: int, exc: BaseException) -> BaseException:
    """An error of a chunk with the run at fault (index and varied values), when it can be
    reproduced by building and validating the chunk's scenarios here."""
    for i in range(start, stop):
        try:
            load_scenario(plan.scenario(i), allow_outside_files=plan.allow_outside_files)
        except (VsinvError, ValueError) as inner:
            return InvalidInput(f"sweep run {i} ({plan.values(i)}, seed {int(plan.columns['seed'][i])}): {inner}")
    return exc


def _chunks(n: int, size: int) -> Iterator[tuple[int, int]]:
    for start in range(0, n, size):
        yield start, min(start + size, n)


def run_sweep(
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
    allow_outside_files: bool = False,
) -> SweepResult:
    """Run ``base`` (a built-in name, a TOML path, a dict or a Scenario) for every
    combination of the values in ``vary`` (see the module docstring for keys, grids,
    distributions, seeds and errors).

    - ``repeats``: runs per point, each with its own noise seed.
    - ``draws``: number of random samples (required when a distribution is given).
    - ``seed``: seeds the random draws and the noise seeds (same seed, same sweep).
    - ``executor``: a ``concurrent.futures.Executor`` to run the chunks on (None: here).
    - ``chunk_size``: runs per :func:`vsinv.sim.run_batch` call; default
      ``max(64, ceil(n / (4 * workers)))``, at most 1024 (each run in flight holds
      a few kB: the cap keeps memory flat).
    - ``threads``: rayon threads per chunk (None: all cores).
    - ``progress``: a tqdm bar over runs (None: when stderr is a terminal).
    - ``allow_outside_files``: let the scenario name files (``calibration``, ``robot.urdf``)
      outside the working directory (see :func:`vsinv.load_scenario`).
    """
    t0 = time.perf_counter()
    if threads is not None and (isinstance(threads, bool) or not isinstance(threads, int) or not 1 <= threads <= 1024):
        raise InvalidInput(f"threads: expected None or an integer from 1 to 1024, got {threads!r}")
    plan = _plan(base, vary, repeats, draws, seed, allow_outside_files)
    n = len(plan)
    workers = _executor_workers(executor, threads)
    if chunk_size is None:
        chunk_size = min(max(64, math.ceil(n / (4 * workers))), 1024)
    if isinstance(chunk_size, bool) or not isinstance(chunk_size, int) or chunk_size < 1:
        raise InvalidInput(f"chunk_size: expected an integer >= 1, got {chunk_size!r}")

    base_name = str(plan.base.get("name", ""))
    where = "this process" if executor is None else type(executor).__name__
    log.info("run_sweep %s: %d runs in chunks of %d on %s", base_name, n, chunk_size, where)
    bar = Bar(progress, n, f"sweep {base_name}")
    parts: dict[int, dict[str, Column]] = {}
    try:
        if executor is None:
            # The runs are built and run in Rust with the GIL released, a chunk at a time.
            for start, stop in _chunks(n, chunk_size):
                try:
                    parts[start] = _run_chunk(plan.base, *plan.runs(start, stop), threads, plan.allow_outside_files)
                except (VsinvError, ValueError) as exc:
                    raise _explain(plan, start, stop, exc) from exc
                bar.update(stop - start)
                log.debug("run_sweep: runs %d to %d done", start, stop - 1)
        else:
            _run_on(executor, plan, n, chunk_size, threads, max(2, 2 * workers), parts, bar)
    finally:
        bar.close()

    columns: dict[str, Column] = dict(plan.columns)
    ordered = [parts.pop(s) for s in sorted(parts)]
    for name in list(ordered[0]) if ordered else []:  # column by column: the chunks are freed as we go
        columns[name] = np.concatenate([p.pop(name) for p in ordered])
    elapsed = time.perf_counter() - t0
    if log.isEnabledFor(logging.INFO) and "status" in columns:
        converged = int(np.count_nonzero(np.asarray(columns["status"]) == "converged"))
        log.info("run_sweep %s: %d runs in %.3f s: %d converged", base_name, n, elapsed, converged)
    return SweepResult(
        columns=columns,
        grid_keys=plan.grid_keys,
        random_keys=plan.random_keys,
        base_name=base_name,
        repeats=repeats,
        seed=int(seed),
        elapsed_s=elapsed,
    )


def _run_on(
    executor: cf.Executor,
    plan: _Plan,
    n: int,
    chunk_size: int,
    threads: Optional[int],
    window: int,
    parts: dict[int, dict[str, Column]],
    bar: Bar,
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
                runs = plan.runs(*nxt)
                pending[executor.submit(_run_chunk, plan.base, *runs, threads, plan.allow_outside_files)] = nxt
            if not pending:
                return
            done, _ = cf.wait(pending, return_when=cf.FIRST_COMPLETED)
            for fut in done:
                start, stop = pending.pop(fut)
                try:
                    parts[start] = fut.result()
                except (VsinvError, ValueError) as exc:
                    raise _explain(plan, start, stop, exc) from exc
                bar.update(stop - start)
                log.debug("run_sweep: runs %d to %d done", start, stop - 1)
    finally:
        for fut in pending:
            fut.cancel()
