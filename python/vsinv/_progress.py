"""Progress reports shared by :func:`vsinv.sim.run_batch` and :func:`vsinv.sim.run_sweep`: a tqdm bar
over runs, or a callable ``progress(done, total)``. The Rust side only calls a callable it is
given (``vsinv._core.run_batch``); the bar is made here."""

from __future__ import annotations

import sys
from typing import Any, Callable, Optional, Union

Progress = Union[None, bool, Callable[[int, int], Any]]


class Bar:
    """A tqdm bar over ``total`` runs (nothing when disabled; None: when stderr is a terminal)."""

    def __init__(self, enabled: Optional[bool], total: int, desc: str) -> None:
        if enabled is None:
            enabled = Bar.shown_by_default()
        self.bar: Any = None
        self.done = 0
        if enabled:
            from tqdm import tqdm  # type: ignore[import-untyped, unused-ignore]

            self.bar = tqdm(total=total, desc=desc, unit="run", file=sys.stderr, dynamic_ncols=True)

    @staticmethod
    def shown_by_default() -> bool:
        """Whether ``enabled=None`` shows a bar (stderr is a terminal)."""
        return sys.stderr.isatty()

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
