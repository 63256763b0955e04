"""The keypoint target's per-frame work (issue 32): time per frame of the tracks
(``vsinv.vision.track_points``: pyramidal Lucas-Kanade forward then backward, the
forward-backward check) beside OpenCV's ``cv2.calcOpticalFlowPyrLK`` doing the same two passes
(21 x 21 windows, 3 levels) on the same points of the same frames, in the same run; and of a
whole ``ImageServo.step`` of the target ``"features"`` (tracks, the epipolar check against the
reference, the session's step).

How to run (from the repository root, with the package, ``opencv-python-headless`` and Debian's
``visp-images-data`` installed)::

    python benches/features_tracking.py            # about half a minute
    python benches/features_tracking.py --quick    # 2 rounds instead of 5
    python benches/features_tracking.py --json out.json

The frames are ViSP's real ``mbt/cube/image*.pgm`` (640 x 480, a camera moving around a cube;
read from the package's folder, never copied) and the same frames upscaled to 1920 x 1080. The
points: OpenCV's ``goodFeaturesToTrack`` (up to 150, as the target's default), tracked from
frame k to frame k + 1. Timing: the minimum over rounds of the median time per call
(``benches/vision.py``); the ratio is vsinv's time over OpenCV's (below 1: vsinv is faster).
The agreement: median and 95th percentile of the distance between vsinv's and OpenCV's tracks
of the points both keep.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import cv2
import numpy as np

import vsinv

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_step import write_json  # noqa: E402
from vision import timed_min_of_medians  # noqa: E402

FRAMES = Path("/usr/share/visp-images-data/ViSP-images/mbt/cube")
LK = {"winSize": (21, 21), "maxLevel": 3, "criteria": (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 30, 0.01)}


def opencv_tracks(a: np.ndarray, b: np.ndarray, points: np.ndarray, max_error: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    p0 = points.astype(np.float32).reshape(-1, 1, 2)
    p1, st1, _ = cv2.calcOpticalFlowPyrLK(a, b, p0, None, **LK)
    back, st2, _ = cv2.calcOpticalFlowPyrLK(b, a, p1, None, **LK)
    ok = (st1.ravel() == 1) & (st2.ravel() == 1) & (np.linalg.norm(back - p0, axis=2).ravel() <= max_error)
    return p1.reshape(-1, 2).astype(float), ok


def frames(size: tuple[int, int] | None) -> list[np.ndarray]:
    out = []
    for k in range(0, 12):
        image = cv2.imread(str(FRAMES / f"image{k:04d}.pgm"), cv2.IMREAD_GRAYSCALE)
        out.append(image if size is None else cv2.resize(image, size, interpolation=cv2.INTER_LINEAR))
    return out


def measure(size: tuple[int, int] | None, rounds: int) -> dict:
    seq = frames(size)
    pairs = []
    for a, b in zip(seq, seq[1:]):
        pts = cv2.goodFeaturesToTrack(a, 150, 0.01, 10).reshape(-1, 2).astype(float)
        pairs.append((a, b, pts))
    state = {"k": 0}

    def ours() -> None:
        a, b, p = pairs[state["k"] % len(pairs)]
        state["k"] += 1
        vsinv.vision.track_points(a, b, p)

    def theirs() -> None:
        a, b, p = pairs[state["k"] % len(pairs)]
        state["k"] += 1
        opencv_tracks(a, b, p)

    times = timed_min_of_medians({"vsinv": ours, "opencv": theirs}, rounds)
    diffs, kept_ours, kept_cv = [], 0, 0
    for a, b, p in pairs:
        mine, found = vsinv.vision.track_points(a, b, p)
        cv, ok = opencv_tracks(a, b, p)
        both = found & ok
        kept_ours, kept_cv = kept_ours + int(found.sum()), kept_cv + int(ok.sum())
        diffs.extend(np.linalg.norm(mine[both] - cv[both], axis=1))
    h, w = seq[0].shape
    return {
        "size": f"{w}x{h}",
        "points": int(np.mean([len(p) for _, _, p in pairs])),
        "vsinv_ms": 1e3 * times["vsinv"],
        "opencv_ms": 1e3 * times["opencv"],
        "ratio": times["vsinv"] / times["opencv"],
        "kept_vsinv": kept_ours,
        "kept_opencv": kept_cv,
        "median_diff_px": float(np.median(diffs)),
        "p95_diff_px": float(np.percentile(diffs, 95)),
    }


def servo_step_ms(rounds: int) -> dict:
    """A whole ImageServo.step of the keypoint target, frame after frame of the sequence (the
    reference: its first frame; constant depths: the twist is not used)."""
    seq = frames(None)
    K = vsinv.Intrinsics(600.0, 600.0, 319.5, 239.5)
    servo = vsinv.ImageServo(seq[0], "features", K, depths=0.5, stop={"max_iterations": 10**6, "stall": False})
    servo.step(seq[0])  # the first frame: matched by descriptors (not timed)
    state = {"k": 1}

    def step() -> None:
        servo.step(seq[state["k"] % len(seq)])
        state["k"] += 1

    t = timed_min_of_medians({"step": step}, rounds)["step"]
    return {"size": "640x480", "points": len(servo.ids), "step_ms": 1e3 * t}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--json")
    args = parser.parse_args()
    if not FRAMES.is_dir():
        print(f"skipped: ViSP's images are not installed ({FRAMES}): apt install visp-images-data")
        return 0
    rounds = 2 if args.quick else 5
    rows = [measure(None, rounds), measure((1920, 1080), rounds)]
    print(f"{'size':>10} {'points':>6} {'vsinv ms':>9} {'OpenCV ms':>10} {'ratio':>6} {'kept':>10} {'median/p95 diff px':>20}")
    for r in rows:
        print(
            f"{r['size']:>10} {r['points']:6d} {r['vsinv_ms']:9.2f} {r['opencv_ms']:10.2f} {r['ratio']:6.2f} "
            f"{r['kept_vsinv']:4d}/{r['kept_opencv']:<5d} {r['median_diff_px']:9.4f}/{r['p95_diff_px']:.4f}"
        )
    step = servo_step_ms(rounds)
    print(f"ImageServo.step, target features, {step['size']}, {step['points']} points: {step['step_ms']:.2f} ms a frame")
    if args.json:
        write_json(args.json, {"tracks": rows, "image_servo_step": step})
    # The agreement with OpenCV's tracker: the same points kept (within 2 %), at the same place.
    bad = [r["size"] for r in rows
           if abs(r["kept_vsinv"] - r["kept_opencv"]) > 0.02 * r["kept_opencv"] or r["median_diff_px"] > 0.01]
    if bad:
        print(f"DISAGREEMENT with cv2.calcOpticalFlowPyrLK at {bad}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
