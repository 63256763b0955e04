"""Soak test: many simulated runs and controller steps in one process, resident memory printed
at intervals, and a check that it stays flat after warm-up.

- ``runs``: ``vsinv.sim.run_batch`` of the built-in ``lens-12-6`` in chunks of 5,000 (100,000 by
  default), plus ``vsinv.run_scenario`` with recording on every chunk (the NumPy arrays it
  returns are dropped), so that both the batch path and the recorded path are soaked.
- ``steps``: ``InvariantController.step`` and ``IbvsController.step`` alternately on one
  scene (1,000,000 steps by default), plus a new controller every 10,000 steps.

Memory is the process's resident set size (``/proc/self/statm`` where available, else
``resource.getrusage``'s peak), read after glibc's ``malloc_trim`` so that freed memory the
allocator keeps for later does not count as growth. The check: growth after warm-up (the first tenth of each
part: the allocator's pools and arenas, NumPy's caches) under ``--max-growth-mb`` (5 MB).
Exit code 1 when it grows more.

Usage::

    python benches/soak.py [--runs 100000] [--steps 1000000] [--max-growth-mb 5]
"""

from __future__ import annotations

import argparse
import ctypes
import os
import resource
import sys
import time

import numpy as np

import vsinv


def release_free_memory() -> None:
    """glibc keeps freed blocks in its arenas; ``malloc_trim`` hands them back to the system so
    that the resident size measures live memory (a leak), not the allocator's caching."""
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass


def resident_mb() -> float:
    try:
        with open("/proc/self/statm") as f:
            pages = int(f.read().split()[1])
        return pages * os.sysconf("SC_PAGE_SIZE") / 2**20
    except OSError:
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


class Monitor:
    """Prints resident memory at each mark and remembers the readings after warm-up."""

    def __init__(self, what: str) -> None:
        self.what = what
        self.readings: list[float] = []
        self.start = time.perf_counter()

    def mark(self, done: int) -> None:
        release_free_memory()
        mb = resident_mb()
        self.readings.append(mb)
        print(f"{self.what:>6} {done:>9,d}  resident {mb:8.1f} MB  ({time.perf_counter() - self.start:6.1f} s)", flush=True)

    def growth(self) -> float:
        """Growth after warm-up (the first tenth of the readings), MB."""
        warm = max(len(self.readings) // 10, 1) - 1
        return max(self.readings[warm:]) - self.readings[warm]


def soak_runs(total: int, chunk: int = 5000) -> float:
    scenario = vsinv.load_scenario("lens-12-6")
    monitor = Monitor("runs")
    done = 0
    while done < total:
        n = min(chunk, total - done)
        table = vsinv.sim.run_batch([scenario] * n)
        if not (table["status"] == "converged").all():
            raise SystemExit("soak: a lens-12-6 run did not converge")
        vsinv.run_scenario(scenario)  # recorded: arrays handed to NumPy, then dropped
        done += n
        monitor.mark(done)
    return monitor.growth()


def scene() -> tuple[np.ndarray, np.ndarray, np.ndarray, vsinv.Intrinsics]:
    grid = np.array([[x, y, 0.6 + 0.05 * np.sin(3 * x + 5 * y)] for x in (-0.15, -0.05, 0.05, 0.15) for y in (-0.1, 0.0, 0.1)])
    k_star, k = vsinv.Intrinsics(1200.0, 1200.0, 416.0, 312.0), vsinv.Intrinsics(600.0, 600.0, 416.0, 312.0)
    reference, z_star = vsinv.geometry.project(grid, k_star)
    moved = grid + np.array([0.03, -0.02, 0.05])
    current, _ = vsinv.geometry.project(moved, k)
    return reference, current, z_star, k


def soak_steps(total: int, every: int = 100_000) -> float:
    reference, current, z_star, k = scene()
    monitor = Monitor("steps")
    invariant = vsinv.laws.InvariantController(reference, k, basis="auto")
    ibvs = vsinv.laws.IbvsController(reference, k)
    for i in range(1, total + 1):
        (invariant if i % 2 else ibvs).step(current, z_star)
        if i % 10_000 == 0:
            invariant = vsinv.laws.InvariantController(reference, k, basis="auto")
            ibvs = vsinv.laws.IbvsController(reference, k)
        if i % every == 0:
            monitor.mark(i)
    return monitor.growth()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=100_000)
    parser.add_argument("--steps", type=int, default=1_000_000)
    parser.add_argument("--max-growth-mb", type=float, default=5.0)
    parser.add_argument("--quick", action="store_true", help="10,000 runs and 200,000 steps (make bench-quick)")
    args = parser.parse_args()
    if args.quick:
        args.runs, args.steps = 10_000, 200_000
    runs = soak_runs(args.runs)
    steps = soak_steps(args.steps)
    print(f"growth after warm-up: runs {runs:.2f} MB, steps {steps:.2f} MB (limit {args.max_growth_mb} MB)")
    return 0 if max(runs, steps) < args.max_growth_mb else 1


if __name__ == "__main__":
    sys.exit(main())
