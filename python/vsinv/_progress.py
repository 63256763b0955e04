"""Progress reports shared by :func:`vsinv.run_batch` and :func:`vsinv.run_sweep`: a tqdm bar
over runs, or a callable ``progress(done, total)``."""

from __future__ import annotations

import sys
from typing import Any, Callable, Optional, Union

Progress = Union[None, bool, Callable[[int, int], Any]]


class Bar:
    """A tqdm bar over ``total`` runs (nothing when disabled; None: when stderr is a terminal)."""

    def __init__(self, enabled: Optional[bool], total: int, desc: str) -> None:
        if enabled is None:
            enabled = sys.stderr.isatty()
        self.bar: Any = None
        self.done = 0
        if enabled:
            from tqdm import tqdm  # type: ignore[import-untyped, unused-ignore]

            self.bar = tqdm(total=total, desc=desc, unit="run", file=sys.stderr, dynamic_ncols=True)

    def update(self, n: int) -> None:
        """``n`` more runs finished."""
        self.done += n
        if self.bar is not None:
            self.bar.update(n)

    def __call__(self, done: int, total: int) -> None:
        """``done`` runs of ``total`` finished (as ``progress(done, total)``)."""
        self.update(done - self.done)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


class _Calls:
    """A user's ``progress(done, total)`` callable, with nothing to close."""

    def __init__(self, call: Callable[[int, int], Any]) -> None:
        self.call = call

    def __call__(self, done: int, total: int) -> None:
        self.call(done, total)

    def close(self) -> None:
        pass


def reporter(progress: Progress, total: int, desc: str) -> Union[Bar, _Calls, None]:
    """What reports the progress of ``total`` runs: a :class:`Bar` for None, True or False,
    the callable itself otherwise; None when nothing would be shown."""
    if progress is None or isinstance(progress, bool):
        bar = Bar(progress, total, desc)
        return bar if bar.bar is not None else None
    if not callable(progress):
        raise TypeError(
            f"progress: expected None, True, False or a callable progress(done, total), got {type(progress).__name__}"
        )
    return _Calls(progress)
