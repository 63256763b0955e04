"""In-process sweeps against ``run_batch`` of the same runs, on 1 and 2 threads, in one run.

How to run (from the repository root, with the package installed)::

    python benches/sweep.py                  # about a minute
    python benches/sweep.py --quick          # fewer runs and rounds
    python benches/sweep.py --json out.json  # also write the numbers as JSON

The sweep is the one of the performance page: ``lens-12-6`` with ``focal_error`` on a grid
and ``roll_deg`` drawn uniformly (``--runs`` runs in all). Its peer is
``vsinv.sim.run_batch`` of the very scenarios the sweep runs (``vsinv.sweep.build_scenarios``,
written as JSON texts before the clock starts): the same Rust runs without the sweep's own
work (planning each run's scenario in Python and writing it as JSON, overlapped with the
previous chunk's runs). Before timing, the script checks that both give the same table
(status, iterations and final errors, bit for bit).

Timing: the four calls (batch and sweep on 1 and 2 threads) alternate within each round so
that they share the machine's load; each figure is the fastest of the rounds. The machine's
load average is printed before and after, and for each call the process's CPU time over
its wall time (`os.times`) in the fastest round: a 2-thread call that gets 1.0 had one core
(the machine was busy), and an unchanged CPU time per run on 2 threads rules out time lost
to locks or allocation in the runs. Ratios: sweep time per run over batch time per run (1:
as fast), and 2 threads over 1.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time

import numpy as np

import vsinv
from vsinv.sweep import Uniform, build_scenarios
from vsinv.sweep.execute import _texts
from vsinv.sweep.plan import _plan

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_step import write_json  # noqa: E402

BASE = "lens-12-6"
GRID = 20  # focal_error values


def vary() -> dict:
    return {"focal_error": np.linspace(-0.5, 1.0, GRID), "roll_deg": Uniform(-30.0, 30.0)}


def check(runs: int) -> list[str]:
    """The sweep's table equals run_batch's on the same scenarios; returns their JSON texts."""
    draws = runs // GRID
    texts = [json.dumps(d) for d in build_scenarios(BASE, vary(), draws=draws, seed=1)]
    sweep = vsinv.sim.run_sweep(BASE, vary(), draws=draws, seed=1, threads=2, progress=False).columns
    batch = vsinv.sim.run_batch(texts, threads=2, progress=False)
    for key in ("status", "iterations", "final_translation_error", "final_rotation_error"):
        a, b = np.asarray(sweep[key]), np.asarray(batch[key])
        if a.shape != b.shape or not (a == b).all():
            raise SystemExit(f"MISMATCH: run_sweep and run_batch of the same scenarios differ in {key}")
    converged = int((np.asarray(batch["status"]) == "converged").sum())
    print(f"check: run_sweep == run_batch on {len(texts)} runs ({converged} converged)")
    return texts


def planning_s(runs: int) -> float:
    """Seconds the sweep's Python side takes to plan and write ``runs`` scenarios."""
    plan = _plan(BASE, vary(), 1, runs // GRID, 1)
    t0 = time.perf_counter()
    _texts(plan.scenarios(0, len(plan)), plan.base)
    return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="1000 runs, 3 rounds")
    parser.add_argument("--runs", type=int, default=None, help="runs per call (default 2000; quick 1000)")
    parser.add_argument("--json", metavar="PATH", help="also write the results to PATH as JSON")
    args = parser.parse_args(argv)
    runs = args.runs or (1000 if args.quick else 2000)
    rounds = 3 if args.quick else 5
    texts = check(runs)
    draws = runs // GRID
    calls = {
        f"{what} {threads}": (
            (lambda t=threads: vsinv.sim.run_batch(texts, threads=t, progress=False))
            if what == "batch"
            else (lambda t=threads: vsinv.sim.run_sweep(BASE, vary(), draws=draws, seed=1, threads=t, progress=False))
        )
        for threads in (1, 2)
        for what in ("batch", "sweep")
    }
    load_before = os.getloadavg()
    best = {name: float("inf") for name in calls}
    cpu = {name: 0.0 for name in calls}  # CPU seconds of the fastest round
    for _ in range(rounds):
        for name, fn in calls.items():
            c0, t0 = os.times(), time.perf_counter()
            fn()
            c1, wall = os.times(), time.perf_counter() - t0
            if wall < best[name]:
                best[name], cpu[name] = wall, (c1.user - c0.user) + (c1.system - c0.system)
    plan_s = planning_s(runs)
    load_after = os.getloadavg()

    n = len(texts)
    rate = {name: n / s for name, s in best.items()}
    print(f"\n{n} runs of {BASE} per call, fastest of {rounds} alternating rounds; "
          f"{os.cpu_count()} CPUs, load average {load_before[0]:.1f} before, {load_after[0]:.1f} after; "
          f"vsinv {vsinv.__version__}, Python {platform.python_version()}")
    head = (f"{'threads':<8} {'run_batch runs/s':>17} {'run_sweep runs/s':>17} {'sweep / batch time':>19} "
            f"{'CPU/wall batch, sweep':>22} {'CPU us a run batch, sweep':>26}")
    print(head)
    print("-" * len(head))
    for t in (1, 2):
        b, s = rate[f"batch {t}"], rate[f"sweep {t}"]
        use = f"{cpu[f'batch {t}'] / best[f'batch {t}']:.2f}, {cpu[f'sweep {t}'] / best[f'sweep {t}']:.2f}"
        per_run = f"{cpu[f'batch {t}'] / n * 1e6:.0f}, {cpu[f'sweep {t}'] / n * 1e6:.0f}"
        print(f"{t:<8} {b:>17.0f} {s:>17.0f} {b / s:>19.2f} {use:>22} {per_run:>26}")
    print(f"{'2 / 1':<8} {rate['batch 2'] / rate['batch 1']:>16.2f}x {rate['sweep 2'] / rate['sweep 1']:>16.2f}x")
    print(f"the sweep's planning in Python: {plan_s / n * 1e6:.1f} us a run "
          f"(batch run on 1 thread: {best['batch 1'] / n * 1e6:.1f} us)")
    if args.json:
        write_json(args.json, {
            "runs": n, "rounds": rounds, "load_before": load_before, "load_after": load_after,
            "runs_per_s": rate, "cpu_s": cpu, "wall_s": best, "planning_us_per_run": plan_s / n * 1e6,
        })
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
