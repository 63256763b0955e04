"""Hand-eye calibration against OpenCV's ``cv2.calibrateHandEye``, side by side on the same
synthetic stations (issue 20, item 3: errors against ground truth at several noise levels,
for each method, beside OpenCV's).

How to run (from the repository root, with the package and ``opencv-python-headless>=4.8,<5``
installed: OpenCV 5 has no ``calibrateHandEye``)::

    python benches/hand_eye_vs_opencv.py                 # 200 trials per cell, about a minute
    python benches/hand_eye_vs_opencv.py --trials 50
    python benches/hand_eye_vs_opencv.py --stations 8    # fewer poses per calibration

Each trial draws a camera-to-gripper transform X (rotation 0.2-2.5 rad about a random axis,
translation within +-10 cm), a target fixed 0.5 m below the gripper, and ``--stations``
gripper poses tilted 10-40 degrees about random axes (within +-15 cm); the target-to-camera
poses are the exact ones times a random perturbation: a rotation vector normal per axis with
the noise level's degrees, a translation normal per axis with its millimetres (the camera's
pose estimate; the robot's poses are exact). Both libraries get the same poses (vsinv as
(n, 4, 4) arrays, OpenCV as lists of rotation matrices and translations, built before timing).

Columns: the rotation error (degrees) and translation error (mm) of X against the truth,
median and max over the trials, vsinv then OpenCV; the time ratio is vsinv's total time over
OpenCV's (below 1: vsinv is faster), both single calls in the same loop, same trials.
"""

from __future__ import annotations

import argparse
import sys
import time

from pathlib import Path

import numpy as np

import vsinv

try:
    import cv2
except ImportError:  # pragma: no cover
    cv2 = None
else:
    # The synthetic stations of the tests (tests/hand_eye_stations.py), the same draws.
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
    from hand_eye_stations import errors, stations

NOISE_LEVELS = [(0.0, 0.0), (0.1, 0.001), (0.5, 0.002), (1.0, 0.005)]
METHODS = {"tsai": "CALIB_HAND_EYE_TSAI", "park": "CALIB_HAND_EYE_PARK", "daniilidis": "CALIB_HAND_EYE_DANIILIDIS"}


def in_mm(error: tuple[float, float]) -> tuple[float, float]:
    """(degrees, metres) as (degrees, millimetres)."""
    return error[0], error[1] * 1000


def cell(method: str, noise: tuple[float, float], trials: int, n: int, seed: int) -> dict[str, float]:
    rng = np.random.default_rng(seed)
    ours, theirs = [], []
    t_ours = t_theirs = 0.0
    cv_method = getattr(cv2, METHODS[method])
    for _ in range(trials):
        g, c, x = stations(rng, n, noise)
        cv_args = (list(g[:, :3, :3]), list(g[:, :3, 3].copy()), list(c[:, :3, :3]), list(c[:, :3, 3].copy()))
        t0 = time.perf_counter()
        cal = vsinv.calibration.calibrate_hand_eye(g, c, method=method)
        t1 = time.perf_counter()
        r, t = cv2.calibrateHandEye(*cv_args, method=cv_method)
        t2 = time.perf_counter()
        t_ours += t1 - t0
        t_theirs += t2 - t1
        m = np.eye(4)
        m[:3, :3], m[:3, 3] = r, t.ravel()
        ours.append(in_mm(errors(cal.matrix, x)))
        theirs.append(in_mm(errors(m, x)))
    a, b = np.array(ours), np.array(theirs)
    return {
        "rot_med": np.median(a[:, 0]), "rot_max": a[:, 0].max(), "cv_rot_med": np.median(b[:, 0]),
        "cv_rot_max": b[:, 0].max(), "tr_med": np.median(a[:, 1]), "tr_max": a[:, 1].max(),
        "cv_tr_med": np.median(b[:, 1]), "cv_tr_max": b[:, 1].max(), "ratio": t_ours / t_theirs,
        "us_ours": t_ours / trials * 1e6, "us_cv": t_theirs / trials * 1e6,
    }


def agreement(n: int, seed: int) -> str | None:
    """Before timing: on noise-free stations every method of both libraries recovers the true
    mount (within 1e-6 degrees and 1e-6 mm); the first disagreement found, or None."""
    rng = np.random.default_rng(seed)
    g, c, x = stations(rng, n, (0.0, 0.0))
    cv_args = (list(g[:, :3, :3]), list(g[:, :3, 3].copy()), list(c[:, :3, :3]), list(c[:, :3, 3].copy()))
    for method in METHODS:
        r, t = cv2.calibrateHandEye(*cv_args, method=getattr(cv2, METHODS[method]))
        m = np.eye(4)
        m[:3, :3], m[:3, 3] = r, t.ravel()
        for who, found in (("vsinv", vsinv.calibration.calibrate_hand_eye(g, c, method=method).matrix), ("OpenCV", m)):
            rot_deg, tr_mm = in_mm(errors(found, x))
            if not (rot_deg < 1e-6 and tr_mm < 1e-6):
                return f"{who} {method} on noise-free stations: {rot_deg:.3g} deg, {tr_mm:.3g} mm from the true mount"
    return None


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--trials", type=int, default=200)
    parser.add_argument("--stations", type=int, default=15)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--quick", action="store_true", help="3 trials a cell, noise-free and one noise level (make bench-quick)")
    args = parser.parse_args()
    trials, levels = (3, NOISE_LEVELS[:2]) if args.quick else (args.trials, NOISE_LEVELS)
    if cv2 is None or not hasattr(cv2, "calibrateHandEye"):
        print("needs cv2.calibrateHandEye: pip install 'opencv-python-headless>=4.8,<5'")
        return 1
    mismatch = agreement(args.stations, args.seed)
    if mismatch:
        print(f"MISMATCH: {mismatch}")
        return 1
    print(f"vsinv {vsinv.__version__}, OpenCV {cv2.__version__}; {trials} trials of {args.stations} stations "
          f"per cell (noise on the target poses)\n")
    print("| method | noise (deg, mm) | rotation error, deg: median / max (vsinv) | (OpenCV) "
          "| translation error, mm: median / max (vsinv) | (OpenCV) | time per call, us (vsinv / OpenCV) | ratio |")
    print("|---|---|---|---|---|---|---|---|")
    for method in METHODS:
        for noise in levels:
            r = cell(method, noise, trials, args.stations, args.seed)
            print(f"| {method} | {noise[0]:g}, {noise[1] * 1000:g} "
                  f"| {r['rot_med']:.3g} / {r['rot_max']:.3g} | {r['cv_rot_med']:.3g} / {r['cv_rot_max']:.3g} "
                  f"| {r['tr_med']:.3g} / {r['tr_max']:.3g} | {r['cv_tr_med']:.3g} / {r['cv_tr_max']:.3g} "
                  f"| {r['us_ours']:.0f} / {r['us_cv']:.0f} | {r['ratio']:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
