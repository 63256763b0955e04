"""vsinv against plain NumPy, side by side in one process.

How to run (from the repository root, with the package installed, e.g. ``make install``)::

    python benches/compare.py                     # full measurement, about 30 s
    python benches/compare.py --quick             # 3 timing rounds instead of 7
    python benches/compare.py --json results.json # also write the numbers as JSON

``make bench`` runs it after the criterion benchmarks. The script measures:

(i)   one control step for n = 12 points: ``vsinv.laws.InvariantController.step()`` called from
      Python against the NumPy implementation of the same law (``NumpyInvariantController``
      of ``benches/bench_step.py``, ``np.linalg.pinv`` as in eq. 14), on the synthetic scene
      of ``benches/bench_step.py`` / ``benches/vsinv.rs``;
(ii)  a full sec. 5.2 run: ``vsinv.run_scenario`` of ``lens-12-6`` with ``rz_task = "tau21"``
      (eq. 24's task, the one the NumPy law implements) against :func:`numpy_run`, the same
      closed loop written below in NumPy: the scene comes from the scenario's dictionary
      (object points, reference camera K*, servo camera K and image size, K_hat of
      ``[estimate]``, start pose, gains, speed limits, dt, stop thresholds); at every
      iteration the object points are projected from the current pose with K, a point is
      visible when it is in front of the camera and inside the image, the law uses the
      reference depths zeta*, the twist is scaled within the speed limits by one factor (as
      ``src/core/saturation.rs``) and integrated exactly (``pose @ exp(twist dt)``,
      SE(3) exponential), and the run stops with the invariant rule (``||s - s*|| < 1e-4``,
      ``|tau_21| < 1e-4``, ``tau_11 > 0``, ``tau_22 > 0``). The basis is the one vsinv reports
      in its run summary. Before timing, the script CHECKS that both loops take the same
      number of iterations (within 1) and end at the same final pose error (within 1e-6 m),
      and exits with an error otherwise;
(iii) a batch: ``vsinv.sim.run_batch`` of 1000 ``lens-12-6`` runs (one ``Scenario`` object
      repeated; conversion to configurations and the thread pool included) on 1 and 2
      threads, in runs per second.

Each timing is the median over rounds of ``timeit`` (``Timer.autorange`` picks the number
of calls per round, at least 0.2 s per round). The last column is NumPy time / vsinv time
(for the batch: the 2-thread speed-up).
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import statistics
import sys
import timeit

import numpy as np

import vsinv

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_step import GAIN, GAIN_RZ, NumpyInvariantController, check_same_twist, make_scene, write_json  # noqa: E402

SCENARIO = "lens-12-6"
BATCH_RUNS = 1000
MIN_DEPTH = 1e-6  # metres: closer to the camera plane counts as behind it (vsinv's scene)


def timed(fn, repeat: int) -> float:
    """Median seconds per call of fn() over `repeat` autoranged rounds."""
    timer = timeit.Timer(fn)
    number, _ = timer.autorange()
    return statistics.median(timer.repeat(repeat=repeat, number=number)) / number


# --------------------------------------------------------------------------- NumPy loop


def intrinsics_matrix(c: dict) -> np.ndarray:
    """K of eq. (4) from a scenario camera section (fku, fkv, u0, v0, skew_deg)."""
    theta = math.radians(c.get("skew_deg", 90.0))
    s, cot = (1.0, 0.0) if c.get("skew_deg", 90.0) == 90.0 else (math.sin(theta), math.cos(theta) / math.sin(theta))
    return np.array([[c["fku"], -c["fku"] * cot, c["u0"]], [0.0, c["fkv"] / s, c["v0"]], [0.0, 0.0, 1.0]])


def skew(w: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def exp_rotation(w: np.ndarray) -> np.ndarray:
    """Rodrigues: the rotation of the rotation vector w (radians)."""
    theta = np.linalg.norm(w)
    if theta < 1e-12:
        return np.eye(3) + skew(w)
    wx = skew(w / theta)
    return np.eye(3) + math.sin(theta) * wx + (1.0 - math.cos(theta)) * (wx @ wx)


def exp_se3(xi: np.ndarray) -> np.ndarray:
    """The 4x4 rigid motion exp(xi) of a twist xi = (v, w) held for one unit of time."""
    v, w = xi[:3], xi[3:]
    theta = np.linalg.norm(w)
    wx = skew(w)
    t2 = theta * theta
    if theta < 1e-5:
        b, c = 0.5 - t2 / 24.0, 1.0 / 6.0 - t2 / 120.0
    else:
        b, c = (1.0 - math.cos(theta)) / t2, (theta - math.sin(theta)) / (t2 * theta)
    m = np.eye(4)
    m[:3, :3] = exp_rotation(w)
    m[:3, 3] = (np.eye(3) + b * wx + c * (wx @ wx)) @ v
    return m


class NumpyLoop:
    """Everything the closed loop needs, read from a scenario dictionary (free-flying
    camera, fixed lens, still reference, reference depths zeta*, no noise, no occluders)."""

    def __init__(self, d: dict, basis) -> None:
        unsupported = [
            d["robot"]["kind"] != "free",
            d["control"]["law"] != "invariant",
            d["control"].get("depths", "reference") != "reference",
            d["noise"]["pixel_sigma"] != 0.0,
            d["stop"]["window"] != 1,
            "zoom" in d["camera"] and d["camera"]["zoom"] is not None,
            bool(d["object"].get("bodies")),
            "path" in d and d["path"] is not None,
        ]
        if any(unsupported):
            raise SystemExit(f"the NumPy loop only covers scenarios like lens-12-6: {d['name']} is not one")
        self.points = np.asarray(d["object"]["points"], dtype=float)
        self.k = intrinsics_matrix(d["camera"])
        self.width, self.height = float(d["camera"]["width"]), float(d["camera"]["height"])
        k_star = intrinsics_matrix(d["reference_camera"])
        ref_h = self.points @ k_star.T
        self.reference = ref_h[:, :2] / ref_h[:, 2:]
        self.zeta_star = self.points[:, 2].copy()  # reference depths (sec. 5.2)
        self.k_hat = intrinsics_matrix(d["estimate"])
        self.basis = np.array(basis)
        c = d["control"]
        self.gain, self.gain_rz, self.dt = c.get("gain", 1.0), c.get("gain_rz", 1.0), c["dt"]  # defaults when not given
        # Speed limits (src/core/saturation.rs): the whole twist scaled by one factor.
        self.max_linear = float(c.get("max_linear_speed", math.inf))
        self.max_angular = math.radians(float(c.get("max_angular_speed_deg", math.inf)))
        self.start = np.eye(4)
        self.start[:3, :3] = exp_rotation(np.radians(d["start"]["rotation_deg"]))
        self.start[:3, 3] = d["start"]["position"]
        s = d["stop"]
        self.max_iterations, self.invariant_tol, self.tau21_tol = s["max_iterations"], s["invariant_error"], s["tau21"]
        self.divergence = s["divergence_distance"]


def numpy_run(cfg: NumpyLoop) -> tuple[str, int, np.ndarray]:
    """The closed loop in NumPy; returns (status, iterations, final pose)."""
    ctl = NumpyInvariantController(cfg.reference, cfg.k_hat, tuple(cfg.basis), gain=cfg.gain, gain_rz=cfg.gain_rz)
    basis, others, s_star = ctl.basis, ctl.others, ctl.s_star
    ref_h = np.column_stack([cfg.reference, np.ones(len(cfg.reference))])
    q_star_inv = np.linalg.inv(ref_h[basis].T)
    kt = cfg.k.T
    pose = cfg.start.copy()
    iteration = 0
    while True:
        # Observe: camera coordinates R^T (X - t), pixels, visibility (front, inside the image).
        r, t = pose[:3, :3], pose[:3, 3]
        cam = (cfg.points - t) @ r
        z = cam[:, 2]
        front = z > MIN_DEPTH
        with np.errstate(divide="ignore", invalid="ignore"):
            ph = (cam @ kt) / z[:, None]
        ph[~front] = np.nan
        u, v = ph[:, 0], ph[:, 1]
        visible = front & (u >= 0.0) & (u < cfg.width) & (v >= 0.0) & (v < cfg.height)
        if not np.linalg.norm(t) <= cfg.divergence:
            return "diverged", iteration, pose
        if visible.sum() < 6 or not visible[basis].all():
            return "lost_features", iteration, pose
        # Invariant stop rule: ||s - s*||, tau_21 -> 0 with tau_11, tau_22 > 0 (T = Q Q*^-1).
        q_mat = ph[basis].T  # Q = [p1 p2 p3], homogeneous pixels as columns
        if visible[others].all():
            e = ph[others] @ np.linalg.inv(q_mat).T - s_star
            tau = q_mat @ q_star_inv
            if (
                np.linalg.norm(e) < cfg.invariant_tol
                and abs(tau[1, 0]) < cfg.tau21_tol
                and tau[0, 0] > 0.0
                and tau[1, 1] > 0.0
            ):
                return "converged", iteration, pose
        if iteration >= cfg.max_iterations:
            return "max_iterations", iteration, pose
        twist = ctl.step(ph[:, :2], cfg.zeta_star, visible)
        if not np.isfinite(twist).all():
            return "diverged", iteration, pose
        v, w = np.linalg.norm(twist[:3]), np.linalg.norm(twist[3:])
        twist = twist * min(1.0, cfg.max_linear / v if v > cfg.max_linear else 1.0, cfg.max_angular / w if w > cfg.max_angular else 1.0)
        pose = pose @ exp_se3(twist * cfg.dt)
        iteration += 1


def pose_errors(pose: np.ndarray) -> tuple[float, float]:
    """Translation (m) and rotation (rad) error from the goal F* (the identity)."""
    angle = math.acos(max(-1.0, min(1.0, (np.trace(pose[:3, :3]) - 1.0) / 2.0)))
    return float(np.linalg.norm(pose[:3, 3])), angle


# --------------------------------------------------------------------------- the three parts


def part_step(repeat: int) -> dict:
    s = make_scene(12)
    ctl = vsinv.laws.InvariantController(s.reference, s.k_hat, gain=GAIN, gain_rz=GAIN_RZ, basis=s.basis, rz_task="tau21")
    ref = NumpyInvariantController(s.reference, s.k_hat, s.basis, gain=GAIN, gain_rz=GAIN_RZ)
    pixels, depths = np.ascontiguousarray(s.pixels, dtype=np.float64), np.ascontiguousarray(s.depths)
    check_same_twist(12, ref.step(pixels, depths), ctl.step(pixels, depths))
    return {
        "vsinv_s": timed(lambda: ctl.step(pixels, depths), repeat),
        "numpy_s": timed(lambda: ref.step(pixels, depths), repeat),
    }


def eq24_scenario() -> dict:
    """The built-in run with the rotation about the optical axis on eq. (24)'s task tau_21, the
    one the NumPy law implements (the built-in's own default is the angle task)."""
    scenario = vsinv.load_scenario(SCENARIO).to_dict()
    scenario["control"]["rz_task"] = "tau21"
    return scenario


def part_run(repeat: int) -> dict:
    scenario = eq24_scenario()
    result = vsinv.run_scenario(scenario, record=False)
    summary = result.summary
    cfg = NumpyLoop(scenario, summary["basis"])
    status, iterations, pose = numpy_run(cfg)
    t_err, r_err = pose_errors(pose)
    d_iter = abs(iterations - summary["iterations"])
    d_pose = abs(t_err - summary["final_translation_error"])
    print(
        f"check {SCENARIO}: vsinv {summary['status']} after {summary['iterations']} iterations, "
        f"{summary['final_translation_error'] * 1e3:.6f} mm / {np.degrees(summary['final_rotation_error']):.6f} deg; "
        f"NumPy {status} after {iterations}, {t_err * 1e3:.6f} mm / {math.degrees(r_err):.6f} deg"
    )
    if status != summary["status"] or d_iter > 1 or not d_pose <= 1e-6:
        raise SystemExit(
            f"MISMATCH: the NumPy loop does not reproduce vsinv's {SCENARIO} run "
            f"(status {status} vs {summary['status']}, iterations differ by {d_iter}, "
            f"final translation errors differ by {d_pose:.3e} m; allowed: 1 iteration, 1e-6 m)"
        )
    return {
        "iterations_vsinv": summary["iterations"],
        "iterations_numpy": iterations,
        "final_translation_error_difference_m": d_pose,
        "vsinv_s": timed(lambda: vsinv.run_scenario(scenario, record=False), repeat),
        "numpy_s": timed(lambda: numpy_run(cfg), repeat),
    }


def part_batch(repeat: int) -> dict:
    scenario = vsinv.load_scenario(SCENARIO)
    scenarios = [scenario] * BATCH_RUNS
    out = vsinv.sim.run_batch(scenarios, threads=1)
    if not (out["status"] == "converged").all():
        raise SystemExit(f"batch: not every {SCENARIO} run converged: {set(out['status'])}")
    seconds = {t: timed(lambda t=t: vsinv.sim.run_batch(scenarios, threads=t), repeat) for t in (1, 2)}
    return {"runs": BATCH_RUNS, **{f"runs_per_s_{t}_threads": BATCH_RUNS / s for t, s in seconds.items()}}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="3 timing rounds instead of 7")
    parser.add_argument("--json", metavar="PATH", help="also write the results to PATH as JSON")
    args = parser.parse_args(argv)
    repeat = 3 if args.quick else 7

    step = part_step(repeat)
    run = part_run(repeat)
    batch = part_batch(repeat)

    print(f"\nmedian of {repeat} rounds; vsinv {vsinv.__version__}, NumPy {np.__version__}, Python {sys.version.split()[0]}")
    head = f"{'measurement':<44} {'vsinv':>12} {'NumPy':>12} {'NumPy/vsinv':>12}"
    print(head)
    print("-" * len(head))
    print(
        f"{'control step, n = 12 (us)':<44} {step['vsinv_s'] * 1e6:>12.2f} {step['numpy_s'] * 1e6:>12.2f} "
        f"{step['numpy_s'] / step['vsinv_s']:>12.1f}"
    )
    label = f"full {SCENARIO} run, {run['iterations_vsinv']} iterations (ms)"
    print(
        f"{label:<44} "
        f"{run['vsinv_s'] * 1e3:>12.3f} {run['numpy_s'] * 1e3:>12.3f} {run['numpy_s'] / run['vsinv_s']:>12.1f}"
    )
    r1, r2 = batch["runs_per_s_1_threads"], batch["runs_per_s_2_threads"]
    print(f"{f'batch of {BATCH_RUNS} {SCENARIO} runs, 1 thread (runs/s)':<44} {r1:>12.0f}")
    print(f"{f'batch of {BATCH_RUNS} {SCENARIO} runs, 2 threads (runs/s)':<44} {r2:>12.0f} {'':>12} {r2 / r1:>11.2f}x")

    if args.json:
        out = {
            "benchmark": "vsinv vs NumPy (benches/compare.py)",
            "unit": "seconds per call (median over rounds) unless stated",
            "rounds": repeat,
            "python": sys.version.split()[0],
            "numpy": np.__version__,
            "vsinv": vsinv.__version__,
            "machine": platform.machine(),
            "cpus": os.cpu_count(),
            "control_step_n12": {**step, "numpy_over_vsinv": step["numpy_s"] / step["vsinv_s"]},
            "full_run": {"scenario": SCENARIO, **run, "numpy_over_vsinv": run["numpy_s"] / run["vsinv_s"]},
            "batch": {"scenario": SCENARIO, **batch, "speedup_2_threads": r2 / r1},
        }
        write_json(args.json, out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
