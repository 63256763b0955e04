"""Runs per second of a MuJoCo sweep on worker processes, and the size of a recording (issue 31,
"Measured": runs per second of a MuJoCo sweep on 2 cores; item 5's recordings).

How to run (from the repository root, with the package and the mujoco and record extras)::

    python benches/mujoco_sweep.py            # 8 runs of 60 iterations
    python benches/mujoco_sweep.py --quick    # 4 runs of 10 iterations (make bench-quick)

(a) `vsinv.sim.run_sweep` of `mujoco-lens-12-6` over `control.gain` on `--processes` worker
processes (default 2: `vsinv.sim.run_batch` spawns them for the `[world] engine = "mujoco"`
rows), against its peer in the same run: the same runs one after the other in this process
(`vsinv.run_scenario`). Runs per second of each and their ratio, twice: the first sweep
spawns the workers (each imports vsinv and MuJoCo, opens an EGL context; `vsinv._batch_mujoco`
keeps them), the second reuses them. The workers render with one llvmpipe thread each on 2
cores (`LP_NUM_THREADS`, set by the pool unless exported: export LP_NUM_THREADS=2 to see the
workers' renders with a thread per core each). The split of one run here (render, servo step =
detection and law, per iteration) and a worker's start-up (spawn to the first World) are printed
first, with the load average.

(b) `vsinv.recording.write_recording` of one MuJoCo run and of the kinematic `vision-12-6`
with `[vision]` (images with sensor noise): bytes per iteration of the MCAP file.

Agreement first: every row of the sweep must equal the summary of the same scenario run alone
(status, iterations, final errors: MuJoCo's CPU renders are deterministic, so exactly); the
script exits 1 otherwise. Without mujoco or EGL it says what to install and exits 0.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np  # noqa: E402

import vsinv  # noqa: E402
import vsinv.sim  # noqa: E402

KEYS = ("status", "iterations", "final_translation_error", "final_rotation_error", "final_invariant_error")


def base(iterations: int) -> dict:
    d = vsinv.load_scenario("mujoco-lens-12-6").to_dict()
    d["stop"]["max_iterations"] = iterations
    return d


def single_runs(d: dict, sweep: vsinv.sim.SweepResult) -> list[dict]:
    """The sweep's runs one after the other here: each scenario as the sweep built it."""
    out = []
    for i, gain in enumerate(sweep.columns["control.gain"]):
        s = {**d, "control": {**d["control"], "gain": float(gain)},
             "noise": {**(d.get("noise") or {}), "seed": int(sweep.columns["seed"][i])}}
        out.append(vsinv.run_scenario(s, record=False).summary)
    return out


def agree(sweep: vsinv.sim.SweepResult, alone: list[dict]) -> list[str]:
    bad = []
    for i, summary in enumerate(alone):
        for k in KEYS:
            got, want = sweep.columns[k][i].item(), summary[k]
            if got != want:
                bad.append(f"run {i} {k}: sweep {got!r}, alone {want!r}")
    return bad


def split(d: dict) -> dict[str, float]:
    """Seconds per iteration of one run here: MuJoCo's render and the servo step."""
    import vsinv.mujoco as vm

    return vm.run_loop(d, record=False).seconds_per_iteration


def _first_world() -> float:
    """In a fresh worker: seconds to import vsinv.mujoco and open the first World (EGL)."""
    t0 = time.perf_counter()
    import vsinv.mujoco as vm

    vm.World.from_scenario("mujoco-lens-12-6").close()
    return time.perf_counter() - t0


def start_up() -> tuple[float, float]:
    """A spawned worker's start-up: seconds from submitting to its first World, and of that the
    import and first World inside the worker."""
    import concurrent.futures as cf
    import multiprocessing

    t0 = time.perf_counter()
    with cf.ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:
        inside = pool.submit(_first_world).result()
        return time.perf_counter() - t0, inside


def recording_sizes(iterations: int) -> dict[str, float]:
    from vsinv.recording import write_recording

    sizes = {}
    for name in ("mujoco-lens-12-6", "vision-12-6"):
        d = vsinv.load_scenario(name).to_dict()
        d["stop"]["max_iterations"] = iterations
        result = vsinv.run_scenario(d)
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "run.mcap")
            write_recording(result, path)
            sizes[name] = os.path.getsize(path) / len(result.time)
    return sizes


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="4 runs of 10 iterations")
    parser.add_argument("--processes", type=int, default=2, help="worker processes of the sweep (default 2)")
    args = parser.parse_args()
    import vsinv.mujoco as vm

    why = vm.available()
    if why is not None:
        print(f"skipped: {why}")
        return 0
    iterations, gains = (10, [0.5, 0.8, 1.2, 1.5]) if args.quick else (60, list(np.linspace(0.4, 1.6, 8)))
    d = base(iterations)
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())} ({os.cpu_count()} cores), "
          f"LP_NUM_THREADS here {os.environ.get('LP_NUM_THREADS', 'unset (a thread per core)')}")
    parts = split(d)
    spawn, inside = start_up()
    print("    one run here, per iteration: " + ", ".join(f"{k} {1e3 * v:.1f} ms" for k, v in parts.items()))
    print(f"    a worker's start-up: {spawn:.2f} s from submit to its first World ({inside:.2f} s of it importing "
          "vsinv.mujoco and opening the first World)")
    times = []
    for _ in range(2):  # the first sweep spawns the workers, the second reuses them
        t0 = time.perf_counter()
        sweep = vsinv.sim.run_sweep(d, {"control.gain": gains}, threads=args.processes, progress=False)
        times.append(time.perf_counter() - t0)
    t0 = time.perf_counter()
    alone = single_runs(d, sweep)
    t_alone = time.perf_counter() - t0
    bad = agree(sweep, alone)
    if bad:
        print("MISMATCH: the sweep's rows are not the single runs':\n  " + "\n  ".join(bad))
        return 1
    n = len(alone)
    its = int(sum(s["iterations"] for s in alone))
    print(f"(a) MuJoCo sweep of {n} runs ({its} iterations, {os.cpu_count()} cores), rows equal the single runs:")
    for label, t in (("first call (spawns)", times[0]), ("second call (kept pool)", times[1])):
        print(f"    run_sweep on {args.processes} processes, {label:24s} {t:6.2f} s  {n / t:6.2f} runs/s  "
              f"{its / t:7.1f} iterations/s  x{t_alone / t:.2f} serial")
    print(f"    one after the other here:  {t_alone:6.2f} s  {n / t_alone:6.2f} runs/s  {its / t_alone:7.1f} iterations/s")
    print(f"    load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    try:
        sizes = recording_sizes(iterations)
    except ImportError as e:
        print(f"(b) skipped: {e}")
        return 0
    print("(b) recording (MCAP) size per iteration:")
    for name, size in sizes.items():
        print(f"    {name:18s} {size / 1024:8.1f} kB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
