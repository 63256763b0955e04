"""Inverse kinematics of the built-in arms: success rate and time per solve (issue 20, item 4).

For each arm (``ur5``, ``panda``), ``--n`` (default 1000) random joint vectors ``q`` uniform
within the limits (NumPy PCG64, seed 20) give reachable poses ``fk(q)``; each pose is solved
by ``vsinv.kinematics.ik(arm, pose)`` without a seed (the solver starts from the middle of the limits,
then its spread seeds: never from the true ``q``). A solve succeeds when it returns joints
within the limits whose pose is within 1e-9 m and 1e-9 rad of the target (checked with
``vsinv.kinematics.fk``). Time per solve: the wall time of the whole loop over the poses divided by
their number (one process, one thread, the Python call included).

The peer, when roboticstoolbox-python is installed: its ``ikine_LM`` (Levenberg-Marquardt,
Chan's damping; defaults: 30 iterations per search, up to 100 random restarts, tolerance
1e-6 on ``E = e^T W e / 2``, joint limits on) on the same poses, the same URDF files read by
its own parser, success as it reports it; and the residual its answers reach, measured the
same way; then again with ``tol=1e-20`` (a pose error of about 1e-10, vsinv's tolerance:
1e-10 m and 1e-10 rad).

Usage::

    python benches/ik.py [--n 1000] [--no-peer] [--json results.json]
"""

from __future__ import annotations

import argparse
import json
import platform
import time
import warnings
from pathlib import Path

import numpy as np

import vsinv

ROBOTS = Path(__file__).resolve().parent.parent / "robots"
ARMS = {"ur5": "tool0", "panda": "panda_hand_tcp"}
LIMITS = {
    "ur5": (np.full(6, -2 * np.pi), np.full(6, 2 * np.pi)),
    "panda": (np.array([-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973]),
              np.array([2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973])),
}


def pose_gap(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    d = np.linalg.inv(a) @ b
    return float(np.linalg.norm(d[:3, 3])), float(np.linalg.norm(vsinv.geometry.thetau_from_pose(d)[1]))


def poses(arm: str, n: int, rng: np.random.Generator) -> list[np.ndarray]:
    lo, hi = LIMITS[arm]
    return [vsinv.kinematics.fk(arm, rng.uniform(lo, hi)) for _ in range(n)]


def bench_vsinv(arm: str, targets: list[np.ndarray]) -> dict:
    lo, hi = LIMITS[arm]
    t0 = time.perf_counter()
    out = []
    for pose in targets:
        try:
            out.append(vsinv.kinematics.ik(arm, pose))
        except vsinv.InvalidInput:
            out.append(None)
    elapsed = time.perf_counter() - t0
    ok, worst, seeds, iterations = 0, 0.0, [], []
    for pose, s in zip(targets, out):
        if s is None:
            continue
        dt, dr = pose_gap(vsinv.kinematics.fk(arm, s.joints), pose)
        inside = bool(np.all(s.joints >= lo) and np.all(s.joints <= hi))
        if dt < 1e-9 and dr < 1e-9 and inside:
            ok += 1
            worst = max(worst, dt)
            seeds.append(s.seed)
            iterations.append(s.iterations)
    return {
        "success_rate": ok / len(targets),
        "ms_per_solve": 1e3 * elapsed / len(targets),
        "worst_position_residual_m": worst,
        "solved_from_first_seed": float(np.mean(np.array(seeds) == 0)) if seeds else 0.0,
        "median_seed": float(np.median(seeds)) if seeds else None,
        "max_seed": int(max(seeds)) if seeds else None,
    }


def bench_rtb(arm: str, targets: list[np.ndarray], **options: float) -> dict | None:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            import roboticstoolbox as rtb
            robot = rtb.Robot.URDF(str(ROBOTS / f"{arm}.urdf"), gripper=ARMS[arm])
    except ImportError:
        return None
    np.random.seed(0)  # ikine_LM draws its restarts from NumPy's global generator
    t0 = time.perf_counter()
    sols = [robot.ikine_LM(pose, **options) for pose in targets]
    elapsed = time.perf_counter() - t0
    ok, worst = 0, 0.0
    for pose, s in zip(targets, sols):
        if s.success:
            ok += 1
            dt, dr = pose_gap(robot.fkine(s.q).A, pose)
            worst = max(worst, dt, dr)
    return {
        "version": rtb.__version__,
        "options": options,
        "success_rate": ok / len(targets),
        "ms_per_solve": 1e3 * elapsed / len(targets),
        "worst_residual_m_or_rad": worst,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--n", type=int, default=1000)
    parser.add_argument("--no-peer", action="store_true")
    parser.add_argument("--json", type=Path)
    parser.add_argument("--quick", action="store_true", help="20 poses an arm (make bench-quick)")
    args = parser.parse_args()
    if args.quick:
        args.n = 20
    rng = np.random.default_rng(20)
    results = {"machine": platform.processor() or platform.machine(), "n": args.n, "arms": {}}
    for arm in ARMS:
        targets = poses(arm, args.n, rng)
        row = {"vsinv": bench_vsinv(arm, targets)}
        if not args.no_peer:
            row["rtb_ikine_LM"] = bench_rtb(arm, targets)
            if row["rtb_ikine_LM"] is None:
                print("roboticstoolbox is not installed (pip install roboticstoolbox-python): its ikine_LM skipped")
            row["rtb_ikine_LM_tight"] = bench_rtb(arm, targets, tol=1e-20)
        results["arms"][arm] = row
        v = row["vsinv"]
        line = (f"{arm:6s} vsinv.kinematics.ik: {100 * v['success_rate']:.1f} % solved, {v['ms_per_solve']:.3f} ms/solve, "
                f"worst residual {v['worst_position_residual_m']:.1e} m, first seed {100 * v['solved_from_first_seed']:.0f} %, "
                f"max seed {v['max_seed']}")
        r = row.get("rtb_ikine_LM")
        if r:
            line += (f" | rtb {r['version']} ikine_LM: {100 * r['success_rate']:.1f} % solved, "
                     f"{r['ms_per_solve']:.3f} ms/solve (x{r['ms_per_solve'] / v['ms_per_solve']:.1f}), "
                     f"worst residual {r['worst_residual_m_or_rad']:.1e}")
        t = row.get("rtb_ikine_LM_tight")
        if t:
            line += (f" | with tol=1e-20 (vsinv's 1e-10 m, rad): {100 * t['success_rate']:.1f} % solved, "
                     f"{t['ms_per_solve']:.3f} ms/solve (x{t['ms_per_solve'] / v['ms_per_solve']:.1f}), "
                     f"worst residual {t['worst_residual_m_or_rad']:.1e}")
        print(line, flush=True)
    if args.json:
        args.json.write_text(json.dumps(results, indent=1) + "\n")


if __name__ == "__main__":
    main()
