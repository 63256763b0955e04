"""Keypoint matching across the lens change (issue 32, "Measured"): vsinv's `match_features`
(kornia-rs's SIFT, Lowe's ratio test, the fundamental matrix by RANSAC: src/vision/features/)
beside OpenCV used directly (its SIFT, Lowe's ratio 0.8, the MAGSAC fundamental matrix) on the
same image pairs in the same run: the textured box's reference image (f = 1200 px) and the servo
camera's first frame (f = 600 px) from each start of tests/test_features_mujoco.py, in MuJoCo's
images and in the project's renderer's (tests/feature_world.py). Per world and pipeline: the
matches kept (inliers, over all pairs), the wrong ones (more than 4 px from where the scene's
geometry puts the reference pixel: another scene point), those at the outline (the renderer's
world only: a reference keypoint whose ray misses the box, where the outline meets the uniform
background, no point of the scene, so no truth), the median error of the others (px; vsinv's
matches are refined to a fraction of a pixel, OpenCV's are SIFT's positions), and the time of one call (reference and frame
described and matched; the least median over rounds), both on one thread (OpenCV's
`setNumThreads(1)`, RAYON_NUM_THREADS=1 for vsinv); the ratio is vsinv's time over OpenCV's
(below 1: vsinv is faster).

Agreement first: vsinv's matches must hold no wrong match (the keypoint target's promise: a
point not found, never a wrong one); the script exits 1 otherwise.

How to run (from the repository root, with mujoco, opencv-python-headless and Debian's
visp-images-data installed)::

    MUJOCO_GL=egl python benches/features_matching.py           # ten starts, both worlds, about 5 minutes
    MUJOCO_GL=egl python benches/features_matching.py --quick   # start 0, MuJoCo's world, one round
"""

from __future__ import annotations

import argparse
import os
import sys
import time

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("RAYON_NUM_THREADS", "1")
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))

import feature_world as fw  # noqa: E402
import numpy as np  # noqa: E402
from opencv_matching import opencv_matches  # noqa: E402


def off_the_box(world, pixels: np.ndarray) -> np.ndarray:  # noqa: ANN001
    """Per reference pixel: its ray misses the box. MuJoCo's world has a floor there (a scene point);
    the project's renderer draws none (a uniform background), so such a keypoint is where the box's
    outline meets the background, no point of the scene: its match has no truth to be checked
    against."""
    import mujoco_world as mw
    import test_features_mujoco as t

    if isinstance(world, fw.TexturedBox):
        return np.zeros(len(pixels), bool)
    fx, fy, cx, cy = world.intrinsics(t.FOVY_REFERENCE)
    pose = t.REFERENCE_POSE
    rays = (pose[:3, :3] @ np.column_stack([(pixels[:, 0] - cx) / fx, (pixels[:, 1] - cy) / fy, np.ones(len(pixels))]).T).T
    return np.array([np.isnan(fw._hit_box(pose[:3, 3], ray, mw.HALF + 0.001)).any() for ray in rays], bool)


def timed(call, rounds: int) -> tuple[float, object]:  # noqa: ANN001
    """The least median (ms) over `rounds` rounds of three calls, and the last result."""
    medians = []
    for _ in range(rounds):
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            out = call()
            times.append(time.perf_counter() - t0)
        medians.append(float(np.median(times)))
    return 1e3 * min(medians), out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="start 0, MuJoCo's world, one round")
    parser.add_argument("--starts", type=int, default=10)
    args = parser.parse_args()
    why = fw.available()
    if why is not None:
        print(f"skipped: {why}")
        return 0
    import cv2
    import test_features_mujoco as t

    import vsinv

    cv2.setNumThreads(1)
    starts, rounds = (1, 1) if args.quick else (args.starts, 2)
    worlds = {"MuJoCo": fw.TexturedBox} if args.quick else {"MuJoCo": fw.TexturedBox, "renderer": fw.RenderedBox}
    print(f"load average {os.getloadavg()[0]:.2f}; {starts} starts, lens f = 1200 -> 600 px, one thread each")
    print("| world | pipeline | inliers (min-max) | wrong | at the outline | median error px | ms a pair | vsinv / OpenCV |")
    print("|---|---|---|---|---|---|---|---|")
    wrong_vsinv = 0
    for name, make in worlds.items():
        world = make(t.WIDTH, t.HEIGHT)
        reference = world.render(t.REFERENCE_POSE, t.FOVY_REFERENCE)
        rows = {"vsinv": ([], [], [], [], []), "OpenCV": ([], [], [], [], [])}
        for pose in t.start_poses(world, starts):
            frame = world.render(pose, t.FOVY_SERVO)
            calls = {"vsinv": lambda f=frame: vsinv.vision.match_features(reference, f),
                     "OpenCV": lambda f=frame: opencv_matches(reference, f)[:2]}
            for pipeline, call in calls.items():
                ms, (ref_px, px) = timed(call, rounds)
                error = np.linalg.norm(px - t.true_pixels(world, ref_px, pose), axis=1)
                off = off_the_box(world, ref_px)
                wrong = (error > t.WRONG_PX) & ~off
                kept, bad, outline, errors, times = rows[pipeline]
                kept.append(len(px))
                bad.append(int(wrong.sum()))
                outline.append(int(off.sum()))
                errors.extend(error[~wrong & ~off])
                times.append(ms)
        world.close()
        mean_ms = {p: float(np.mean(r[4])) for p, r in rows.items()}
        for pipeline, (kept, bad, outline, errors, _) in rows.items():
            ratio = f"{mean_ms['vsinv'] / mean_ms['OpenCV']:.2f}" if pipeline == "vsinv" else ""
            print(f"| {name} | {pipeline} | {min(kept)}-{max(kept)} | {sum(bad)} | {sum(outline)} | {np.median(errors):.3f} | "
                  f"{mean_ms[pipeline]:.1f} | {ratio} |", flush=True)
        wrong_vsinv += sum(rows["vsinv"][1])
    print(f"load average {os.getloadavg()[0]:.2f}")
    if wrong_vsinv:
        print(f"DISAGREEMENT: vsinv kept {wrong_vsinv} wrong matches")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
