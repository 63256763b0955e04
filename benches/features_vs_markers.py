"""The keypoint target against tags and dots on the same object and the same lens change (issue 32,
"Measured"): MuJoCo's box of side 0.2 m (tests/mujoco_world.py) carrying photographs
(tests/feature_world.py, the keypoint target), three AprilTags or twelve white dots on the same
three faces; the reference image with f = 1200 px, the servo camera f = 600 px at 640 x 480 and
K_hat 20 % off (tests/test_features_mujoco.py's lens change); the same starts, the same session
(benches/features_mujoco.py's), the reference depths from the scene. Prints, per target, how
many runs ended `converged`, and the median and largest final pose error against the reference
pose by the scene's truth.

How to run (from the repository root, with mujoco, opencv-python-headless and Debian's
visp-images-data installed)::

    MUJOCO_GL=egl python benches/features_vs_markers.py            # 5 starts a target, about 15 CPU minutes
    MUJOCO_GL=egl python benches/features_vs_markers.py --starts 10
    MUJOCO_GL=egl python benches/features_vs_markers.py --quick    # 1 start of 30 frames a target

Agreement first: before any run, each target's points found in the first frame of start 0 must
be within 1 px of where the scene's geometry puts them (the script exits 1 otherwise). The tag
and dot boxes are rendered 2 x 2 supersampled (a dot's centroid and a tag's corners move by a few
hundredths of a pixel with MuJoCo's one sample a pixel: docs/guides/mujoco.md); the photographs
are rendered as the keypoint target's own tests render them.
"""

from __future__ import annotations

import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

os.environ.setdefault("MUJOCO_GL", "egl")

import feature_world as fw  # noqa: E402
import numpy as np  # noqa: E402

MARKER_SUPERSAMPLE = 2


def marker_lens(t):  # noqa: ANN001, ANN201 - the keypoint test module
    """The keypoint target's lens change as tests/mujoco_servo.py's `Lens`."""
    import mujoco_servo as ms

    focal_error = t.K_HAT.fku / t.F_SERVO - 1.0
    centre = ((t.WIDTH - 1) / 2, (t.HEIGHT - 1) / 2)
    return ms.Lens(t.FOVY_REFERENCE, t.FOVY_SERVO, focal_error, (t.K_HAT.u0 - centre[0], t.K_HAT.v0 - centre[1]))


def marker_first_frame_gap(world, lens, start: np.ndarray, session: dict) -> float:  # noqa: ANN001
    """The largest distance (px) in the first frame from a found tag corner or dot to the nearest
    one the scene puts there."""
    import mujoco_servo as ms
    import mujoco_world as mw

    servo, first = ms.pipeline(world, lens, "invariant", start, session)
    step = servo.step(first)
    points = world.dot_centres() if world.target == "dots" else np.concatenate(list(world.tag_corners().values()))
    truth, _ = mw.project(start, world.intrinsics(lens.fovy_servo), points)
    found = step.pixels[step.found]
    return float(np.linalg.norm(found[:, None, :] - truth[None, :, :], axis=2).min(axis=1).max())


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--starts", type=int, default=5)
    parser.add_argument("--quick", action="store_true", help="1 start of 30 frames a target")
    args = parser.parse_args()
    why = fw.available()
    if why is not None:
        print(f"skipped: {why}")
        return 0
    import features_mujoco as fm
    import mujoco_servo as ms
    import mujoco_world as mw
    import test_features_mujoco as t

    ms.REFERENCE_POSE = t.REFERENCE_POSE  # the keypoint target's reference pose for the markers too
    session = {**fm.SESSION, "stop": {**fm.SESSION["stop"], "max_iterations": 30}} if args.quick else fm.SESSION
    count = 1 if args.quick else args.starts
    lens = marker_lens(t)
    photos = fw.TexturedBox(t.WIDTH, t.HEIGHT)
    reference = photos.render(t.REFERENCE_POSE, t.FOVY_REFERENCE)
    starts = t.start_poses(photos, count)
    markers = {m: mw.BoxWorld(m, width=t.WIDTH, height=t.HEIGHT, supersample=MARKER_SUPERSAMPLE) for m in ("tags", "dots")}
    print(f"load average {os.getloadavg()[0]:.2f}; {count} starts, lens f = {t.F_REFERENCE:.0f} -> {t.F_SERVO:.0f} px")
    gaps = {m: marker_first_frame_gap(w, lens, starts[0], session) for m, w in markers.items()}
    probe = fm.run(photos, reference, starts[0], {**session, "stop": {**session["stop"], "max_iterations": 1}})
    print("agreement, first frame of start 0: " + ", ".join(f"{m} within {g:.3f} px" for m, g in gaps.items())
          + f"; keypoints {probe['wrong']} wrong")
    if max(gaps.values()) > 1.0 or probe["wrong"]:
        print("MISMATCH: a target's first-frame points are not where the scene puts them")
        return 1
    rows: dict[str, list[tuple[str, float, float]]] = {"features": [], "tags": [], "dots": []}
    for k, start in enumerate(starts):
        r = fm.run(photos, reference, start, session)
        rows["features"].append((r["verdict"], r["mm"], r["deg"]))
        for m, w in markers.items():
            e = ms.run(w, lens, "invariant", start, k, session)
            rows[m].append((e.verdict, e.error_mm, e.error_deg))
        print(f"start {k}: " + "; ".join(f"{m} {v[-1][0]} {v[-1][1]:.2f} mm {v[-1][2]:.3f} deg" for m, v in rows.items()), flush=True)
    print("\n| target | converged | final translation median / max | final rotation median / max |\n|---|---|---|---|")
    for m, v in rows.items():
        mm, deg = np.array([r[1] for r in v]), np.array([r[2] for r in v])
        done = sum(r[0] == "converged" for r in v)
        print(f"| {m} | {done} of {len(v)} | {np.median(mm):.2f} / {mm.max():.2f} mm | {np.median(deg):.3f} / {deg.max():.3f} deg |")
    print(f"load average {os.getloadavg()[0]:.2f}")
    photos.close()
    for w in markers.values():
        w.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
