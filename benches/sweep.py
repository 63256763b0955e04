"""In-process sweeps against ``run_batch`` of the same runs, on 1 and 2 threads, in one run,
with each call's CPU time and run-queue wait per thread; and a sweep with images in the loop.

How to run (from the repository root, with the package installed)::

    python benches/sweep.py                  # about two minutes
    python benches/sweep.py --quick          # fewer runs and rounds
    python benches/sweep.py --json out.json  # also write the numbers as JSON
    python benches/sweep.py --baseline DIR   # also the vision sweep against another build (below)

The sweep is the one of the performance page: ``lens-12-6`` with ``focal_error`` on a grid
and ``roll_deg`` drawn uniformly (``--runs`` runs in all). Its peer is
``vsinv.sim.run_batch`` of the very scenarios the sweep runs (``vsinv.sweep.build_scenarios``,
written as JSON texts before the clock starts): the same Rust runs, each text parsed once
(all validated before any runs; up to 4,096 configurations kept until they run). The sweep
applies its keys in Rust to the base scenario read once and parses each run's scenario once. Before timing, the script checks that
both give the same table (every column, bit for bit).

Timing: the four calls (batch and sweep on 1 and 2 threads) alternate within each round so
that they share the machine's load; each figure is the fastest of the rounds. The machine's
load average is printed before and after. For each call in its fastest round, from
``/proc/self/task/*/schedstat`` (Linux): the CPU time of each thread that ran (the calling
thread and vsinv's rayon workers) and the time it waited runnable for a core (run-queue wait).
A 2-thread call whose workers wait for a core as long as they run had one core: the machine
was busy. CPU time per run unchanged from 1 to 2 threads rules out time lost to locks,
allocation or the GIL in the runs (those would add CPU time or leave a worker idle, not
waiting). Ratios: sweep time per run over batch time per run (1: as fast), and 2 threads over 1.

The vision sweep: ``vision-12-6`` (images rendered, dots tracked in the loop) with
``focal_error`` on a grid on one thread, against its runs one at a time (``run_scenario``),
and one iteration split into render + track (the vision run's iteration time less the same
scenario's without ``[vision]``), track (``DotTracker.track`` on a frame) and the rest (law,
world). It checks first that the sweep's rows equal the single runs'.

``--baseline DIR`` also times the vision sweep (8 runs) against another build, importable with
``PYTHONPATH=DIR`` (for example the wheel of an older commit installed with ``pip install
--target DIR``): each build runs it in a process of its own on one thread, the two
alternating for three rounds, and each prints its CPU time, iterations and a digest of its rows.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import platform
import subprocess
import sys
import time
from typing import Any, Callable

import numpy as np

import vsinv
from vsinv.sweep import Uniform, build_scenarios
from vsinv.sweep.plan import _plan

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_step import write_json  # noqa: E402

BASE = "lens-12-6"
GRID = 20  # focal_error values
VISION = "vision-12-6"


def vary() -> dict:
    return {"focal_error": np.linspace(-0.5, 1.0, GRID), "roll_deg": Uniform(-30.0, 30.0)}


def same_table(a: dict[str, Any], b: dict[str, Any], what: str) -> None:
    """Every column of ``b`` equal in ``a``, bit for bit (NaN where NaN); MISMATCH otherwise."""
    for key in b:
        x, y = np.asarray(a[key]), np.asarray(b[key])
        same = x.shape == y.shape and (x.tobytes() == y.tobytes() if x.dtype.kind == "f" else (x == y).all())
        if not same:
            raise SystemExit(f"MISMATCH: {what} differ in {key}")


def check(runs: int) -> list[str]:
    """The sweep's table equals run_batch's on the same scenarios; returns their JSON texts."""
    draws = runs // GRID
    texts = [json.dumps(d) for d in build_scenarios(BASE, vary(), draws=draws, seed=1)]
    sweep = vsinv.sim.run_sweep(BASE, vary(), draws=draws, seed=1, threads=2, progress=False).columns
    batch = vsinv.sim.run_batch(texts, threads=2, progress=False)
    same_table(sweep, batch, "run_sweep and run_batch of the same scenarios")
    converged = int((np.asarray(batch["status"]) == "converged").sum())
    print(f"check: run_sweep == run_batch on {len(texts)} runs, every column bit for bit ({converged} converged)")
    return texts


def thread_times() -> dict[int, tuple[int, int]]:
    """Per thread of this process: (CPU ns, run-queue wait ns), from /proc/self/task/*/schedstat."""
    out = {}
    for tid in os.listdir("/proc/self/task"):
        try:
            with open(f"/proc/self/task/{tid}/schedstat") as f:
                cpu, wait, _ = f.read().split()
        except (OSError, ValueError):
            continue
        out[int(tid)] = (int(cpu), int(wait))
    return out


def timed(fn: Callable[[], Any]) -> tuple[float, list[tuple[float, float]]]:
    """Wall seconds of ``fn()`` and, per thread that ran, (CPU s, run-queue wait s), busiest first."""
    before = thread_times()
    t0 = time.perf_counter()
    fn()
    wall = time.perf_counter() - t0
    after = thread_times()
    used = []
    for tid, (cpu, wait) in after.items():
        c0, w0 = before.get(tid, (0, 0))
        if cpu - c0 > 1e6:  # more than 1 ms of CPU in the call
            used.append(((cpu - c0) * 1e-9, (wait - w0) * 1e-9))
    return wall, sorted(used, reverse=True)


def planning_us(runs: int) -> float:
    """Microseconds a run the sweep's Python side takes to plan (columns sliced to lists)."""
    plan = _plan(BASE, vary(), 1, runs // GRID, 1)
    t0 = time.perf_counter()
    plan.runs(0, len(plan))
    return (time.perf_counter() - t0) / len(plan) * 1e6


def batch_and_sweep(args: argparse.Namespace, results: dict[str, Any]) -> None:
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
    best: dict[str, float] = {name: float("inf") for name in calls}
    threads_of: dict[str, list[tuple[float, float]]] = {}
    for _ in range(rounds):
        for name, fn in calls.items():
            wall, used = timed(fn)
            if wall < best[name]:
                best[name], threads_of[name] = wall, used
    load_after = os.getloadavg()

    n = len(texts)
    rate = {name: n / s for name, s in best.items()}
    print(f"\n{n} runs of {BASE} per call, fastest of {rounds} alternating rounds; "
          f"{os.cpu_count()} CPUs, load average {load_before[0]:.1f} before, {load_after[0]:.1f} after; "
          f"vsinv {vsinv.__version__}, Python {platform.python_version()}")
    head = f"{'call':<9} {'runs/s':>8} {'wall us/run':>12} {'CPU us/run':>11} {'threads that ran: CPU s / run-queue wait s':>45}"
    print(head)
    print("-" * len(head))
    for name in calls:
        cpu = sum(c for c, _ in threads_of[name])
        per = ", ".join(f"{c:.2f}/{w:.2f}" for c, w in threads_of[name])
        print(f"{name:<9} {rate[name]:>8.0f} {best[name] / n * 1e6:>12.1f} {cpu / n * 1e6:>11.1f} {per:>45}")
    for t in (1, 2):
        print(f"sweep / batch time a run, {t} thread{'s' if t > 1 else ''}: {rate[f'batch {t}'] / rate[f'sweep {t}']:.3f}")
    print(f"2 threads / 1: batch {rate['batch 2'] / rate['batch 1']:.2f}x, sweep {rate['sweep 2'] / rate['sweep 1']:.2f}x")
    print(f"the sweep's planning in Python: {planning_us(runs):.2f} us a run")
    results.update({
        "runs": n, "rounds": rounds, "load_before": load_before, "load_after": load_after,
        "runs_per_s": rate, "wall_s": best, "threads_cpu_wait_s": threads_of,
    })


def vision_sweep(args: argparse.Namespace, results: dict[str, Any]) -> None:
    values = np.linspace(-0.3, 0.6, 4 if args.quick else 8)
    vary_v = {"focal_error": values}
    load_before = os.getloadavg()
    c0 = time.process_time()
    wall, used = timed(lambda: results.setdefault(
        "_vision", vsinv.sim.run_sweep(VISION, vary_v, seed=3, threads=1, progress=False).columns))
    sweep_cpu = time.process_time() - c0
    table = results.pop("_vision")
    scenarios = build_scenarios(VISION, vary_v, seed=3)
    t0 = time.perf_counter()
    alone = [vsinv.run_scenario(s, record=False) for s in scenarios]
    wall_alone = time.perf_counter() - t0
    for i, r in enumerate(alone):
        s = r.summary
        if s["status"] != table["status"][i] or s["iterations"] != table["iterations"][i] \
                or s["final_translation_error"] != table["final_translation_error"][i]:
            raise SystemExit(f"MISMATCH: vision sweep run {i} differs from run_scenario of its scenario")
    its = int(np.sum(table["iterations"]))
    n = len(scenarios)

    # One iteration's split: the vision run against the same scenario without [vision].
    plain = dict(scenarios[0])
    plain.pop("vision")
    t0 = time.perf_counter()
    r_plain = vsinv.run_scenario(plain, record=False)
    t_plain = (time.perf_counter() - t0) / max(1, r_plain.summary["iterations"])
    t_vision = wall_alone / its
    image, pixels, _ = vsinv.vision.render_view(VISION)
    tracker = vsinv.vision.DotTracker(image, pixels)
    k = 200
    t0 = time.perf_counter()
    for _ in range(k):
        tracker.track(image)
    track_us = (time.perf_counter() - t0) / k * 1e6
    load_after = os.getloadavg()
    print(f"\nvision sweep: {n} runs of {VISION} ({its} iterations) on 1 thread, load average "
          f"{load_before[0]:.1f} before, {load_after[0]:.1f} after")
    print(f"  run_sweep: {wall:.2f} s, {n / wall:.2f} runs/s, CPU {sweep_cpu:.2f} s; "
          f"run_scenario one at a time: {wall_alone:.2f} s, {n / wall_alone:.2f} runs/s")
    print(f"  an iteration: {t_vision * 1e6:.0f} us with images, {t_plain * 1e6:.1f} us without "
          f"(law and world); render + track {(t_vision - t_plain) * 1e6:.0f} us, of which track "
          f"{track_us:.0f} us (DotTracker.track from Python)")
    results["vision"] = {
        "runs": n, "iterations": its, "sweep_s": wall, "runs_per_s": n / wall, "alone_s": wall_alone,
        "iteration_us": t_vision * 1e6, "plain_iteration_us": t_plain * 1e6, "track_us": track_us,
        "load_before": load_before, "load_after": load_after,
    }


def child_sweep() -> None:
    """The vision sweep of ``--baseline``, in this process's build (an older build spells
    ``run_sweep`` and its table otherwise): its CPU time, iterations and a digest of its rows,
    as one line of JSON."""
    run = vsinv.sim.run_sweep if hasattr(vsinv, "sim") else getattr(vsinv, "run_sweep")
    c0 = time.process_time()
    result = run(VISION, {"focal_error": np.linspace(-0.3, 0.6, 8)}, seed=3, threads=1, progress=False)
    cpu = time.process_time() - c0
    table = result.columns if hasattr(result, "columns") else getattr(result, "table")
    iterations = [int(x) for x in table["iterations"]]
    rows = [iterations, [str(x) for x in table["status"]], [float(x) for x in table["final_translation_error"]]]
    digest = hashlib.sha1(json.dumps(rows).encode()).hexdigest()[:12]
    print(json.dumps({"cpu_s": cpu, "iterations": sum(iterations), "digest": digest}))


def vision_builds(args: argparse.Namespace, results: dict[str, Any]) -> None:
    """The vision sweep (8 runs) in this build and in ``--baseline``'s, each in a process of
    its own on one thread, alternating for 3 rounds: CPU time a sweep and its rows' digest."""
    rounds: dict[str, list[dict[str, Any]]] = {"this build": [], "baseline": []}
    load_before = os.getloadavg()
    for _ in range(3):
        for name, path in (("baseline", args.baseline), ("this build", None)):
            env = dict(os.environ, RAYON_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
            if path:
                env["PYTHONPATH"] = path
            out = subprocess.run([sys.executable, __file__, "--child-sweep"], env=env, capture_output=True,
                                 text=True, check=True, timeout=600)
            rounds[name].append(json.loads(out.stdout.strip().splitlines()[-1]))
    load_after = os.getloadavg()
    print(f"\nvision sweep against {args.baseline} (8 runs of {VISION}, 3 alternating rounds, one process a "
          f"round; load average {load_before[0]:.1f} before, {load_after[0]:.1f} after):")
    for name, runs in rounds.items():
        print(f"  {name:10s} CPU a sweep " + " / ".join(f"{r['cpu_s']:.3f}" for r in runs) + " s, "
              f"{runs[0]['iterations']} iterations, rows {runs[0]['digest']}")
    ratios = [b["cpu_s"] / t["cpu_s"] for b, t in zip(rounds["baseline"], rounds["this build"])]
    summed = sum(float(r["cpu_s"]) for r in rounds["baseline"]) / sum(float(r["cpu_s"]) for r in rounds["this build"])
    print("  baseline / this build: " + ", ".join(f"{r:.2f}x" for r in ratios) + f"; {summed:.2f}x summed")
    results["vision_builds"] = {"rounds": rounds, "ratios": ratios, "summed": summed,
                                "load_before": load_before, "load_after": load_after}


def main(argv: list[str] | None = None) -> int:
    if argv is None and sys.argv[1:] == ["--child-sweep"]:
        child_sweep()
        return 0
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="1000 runs, 3 rounds; 4 vision runs")
    parser.add_argument("--runs", type=int, default=None, help="runs per call (default 2000; quick 1000)")
    parser.add_argument("--json", metavar="PATH", help="also write the results to PATH as JSON")
    parser.add_argument("--baseline", metavar="PYTHONPATH",
                        help="also the vision sweep against the build importable from PYTHONPATH (e.g. an older "
                             "wheel installed with pip install --target), alternating")
    args = parser.parse_args(argv)
    results: dict[str, Any] = {}
    if args.baseline:
        vision_builds(args, results)
    batch_and_sweep(args, results)
    vision_sweep(args, results)
    if args.json:
        write_json(args.json, results)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
