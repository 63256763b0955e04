""":func:`run_batch`: the Rust batch runner (``vsinv._core.run_batch``, which reports to a
callable) with the package's progress reports (a tqdm bar of :mod:`vsinv._progress`)."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any, Callable, Optional, Union

import numpy.typing as npt

from . import _batch_mujoco as _mujoco
from . import _core
from ._progress import Bar, Progress


def run_batch(
    scenarios: Iterable[Any],
    threads: Optional[int] = None,
    allow_outside_files: bool = False,
    progress: Progress = None,
) -> dict[str, npt.NDArray[Any]]:
    """Runs many scenarios (Scenario objects, dicts, JSON texts, built-in names or TOML paths)
    in parallel with the GIL released (recording off); returns the table as a dict of NumPy
    arrays, one row per scenario: status (str), iterations, the summary fields
    final_translation_error, final_rotation_error, final_image_error, final_invariant_error,
    max_line_deviation, observed_max_eps, pixel_sigma, translation_uncertainty,
    rotation_uncertainty (SI, NaN where not measured), prop1, prop2, within_tolerance, message (str). A scenario whose
    configuration is invalid raises before anything runs; a run that fails on the way has
    status "error" and its message. Scenarios of ``[world] engine = "mujoco"`` (the mujoco extra)
    run on ``threads`` worker processes (None: every core) through ``vsinv.mujoco``, their rows in
    the same table.

    ``progress``: a tqdm bar over runs (None: when stderr is a terminal; True, False), or a
    callable ``progress(done, total)`` called from the calling thread as runs finish (``done``
    increasing to ``total``). Ctrl-C or an exception of ``progress`` stops the batch and is
    raised. Works in a process forked after earlier batches (the pools are rebuilt).
    """
    call: Optional[Callable[[int, int], Any]]
    bar: Union[Bar, None] = None
    if progress is None or isinstance(progress, bool):
        if progress is False or (progress is None and not Bar.shown_by_default()):
            call = None
        else:
            scenarios = list(scenarios)  # the bar's total
            bar = Bar(True, len(scenarios), "batch")
            call = bar
    elif callable(progress):
        call = progress
    else:
        raise TypeError(
            f"progress: expected None, True, False or a callable progress(done, total), got {type(progress).__name__}"
        )
    try:
        return _run(scenarios, threads, allow_outside_files, call)
    finally:
        if bar is not None:
            bar.close()


def _run(scenarios: Iterable[Any], threads: Optional[int], allow_outside_files: bool,
         call: Optional[Callable[[int, int], Any]]) -> dict[str, npt.NDArray[Any]]:
    """The Rust runner's batch, with the `[world] engine = "mujoco"` scenarios taken out and run
    on worker processes (`vsinv._batch_mujoco`), their rows put back in place."""
    try:
        items = list(scenarios)
    except TypeError:  # the Rust runner names what it expected
        return _core.run_batch(scenarios, threads=threads, allow_outside_files=allow_outside_files, progress=call)
    found = _mujoco_rows(items, allow_outside_files)
    mujoco_rows = [i for i, d in enumerate(found) if d is not None]
    if not mujoco_rows:
        return _core.run_batch(items, threads=threads, allow_outside_files=allow_outside_files, progress=call)
    rust_rows = [i for i, d in enumerate(found) if d is None]
    n = len(items)

    def progress(done: int, _total: int) -> None:
        if call is not None:
            call(done, n)

    # The Rust runner checks `threads` and its scenarios (raising before anything runs) first.
    table = _core.run_batch([items[i] for i in rust_rows], threads=threads, allow_outside_files=allow_outside_files,
                            progress=progress if call is not None else None)
    finished = len(rust_rows)

    def one_done() -> None:
        nonlocal finished
        finished += 1
        if call is not None:
            call(finished, n)

    mujoco = [d for d in found if d is not None]
    rows = _mujoco.run_rows(mujoco, _mujoco.workers(threads), allow_outside_files, one_done)
    return _mujoco.merge(n, table if rust_rows else None, rust_rows, rows, mujoco_rows)


def _mujoco_rows(items: list[Any], allow_outside_files: bool) -> list[Optional[dict[str, Any]]]:
    """Per scenario, its dict when it is a MuJoCo scenario (else None); a name or text repeated
    through the batch is read once (a batch of 20,000 runs of one built-in reads it once)."""
    seen: dict[str, Optional[dict[str, Any]]] = {}
    found: list[Optional[dict[str, Any]]] = []
    for i, s in enumerate(items):
        if isinstance(s, str):
            if s not in seen:
                seen[s] = _mujoco.mujoco_scenario(s, allow_outside_files, i)
            found.append(seen[s])
        else:
            found.append(_mujoco.mujoco_scenario(s, allow_outside_files, i))
    return found

