"""The accuracy a lens change leaves (issue 27, "Measured"): two cameras with different lenses
see the same pose, their detections disagree a little, and the invariant law stops where the
invariant points of the two detections agree. How far is that from the pose?

(i) ViSP's AprilTag benchmark pair (Debian's visp-images-data, read in place): the same scene
    at 640x480 (the reference) and 1920x1080 (the servo camera). Per family vsinv decodes, the
    corners of the tags found in both images (vsinv.vision.detect_tags, decimation 1 or 2, whichever
    finds more), the invariant error |s - s*| between them, and the pose offset it implies
    (J^+ (s - s*) of the invariant law, with the tag depths from the benchmark's cMo_*.txt and
    each image's K fitted to cMo and the 640x480 ground-truth corners).
(ii) MuJoCo (tests/mujoco_world.py): the box with dots and with tags, reference 45 degrees,
    servo 60 degrees, 400x300, each pixel MuJoCo's own (supersample 1: 4 samples, edge
    coverage in quarters) or the mean of a 3 x 3 block (supersample 3, a sensor's pixel
    integrating light, as tests/test_mujoco_world.py renders). (a) Static: both images taken at the reference pose; |s - s*| and the
    offset it implies (true K, true depths). (b) Closed loop: `vsinv.ImageServo` from N starts
    (K_hat 30 % off), the status each run ends with and the final pose error against the scene.

Run: `python benches/lens_change_accuracy.py [--starts N] [--iterations M] [--supersample 1,3]`.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

import vsinv

BENCHMARK = Path("/usr/share/visp-images-data/ViSP-images/AprilTag/benchmark")
FAMILIES = {"tag36h11": "tag36_11", "tag25h9": "tag25_09", "tag16h5": "tag16_05"}


def implied_offset(ref_px: np.ndarray, px: np.ndarray, K: vsinv.Intrinsics, depths: np.ndarray) -> tuple[float, float, float]:
    """|s - s*| of the invariant law between two detections, and the displacement (mm, degrees)
    J^+ (s - s*) it implies at the current detections."""
    servo = vsinv.Servo(ref_px, K, law="invariant", rz_task="tau21", depths=float(np.median(depths)))  # for its basis
    servo.step(px)
    law = vsinv.laws.InvariantController(ref_px, K, basis=servo.basis, rz_task="tau21")
    law.step(px, depths)
    offset = law.pose_uncertainty(px, depths, pixel_sigma=1e-9).offset
    return law.invariant_error, 1e3 * float(np.linalg.norm(offset[:3])), float(np.degrees(np.linalg.norm(offset[3:])))


def read_corners(path: Path) -> dict[int, np.ndarray]:
    rows = [line.split() for line in path.read_text().splitlines() if line.strip()]
    return {int(rows[i][0]): np.array(rows[i + 1 : i + 5], float) for i in range(0, len(rows), 5)}


def fit_k_640(folder: Path) -> tuple[np.ndarray, float]:
    """The 640x480 camera's (fx, fy, cx, cy), OpenCV's pixel convention, by linear least squares
    from the tag centres of cMo_*.txt to the centres of the ground-truth corners (ViSP's
    convention, +0.5 px), and the largest residual in pixels."""
    truth = read_corners(folder / "640x480" / "corners_tag36_11.txt")
    A, b = [], []
    for tag, px in truth.items():
        x, y, z = np.loadtxt(folder / "640x480" / f"cMo_{tag}.txt")[:3, 3]
        A += [[x / z, 0, 1, 0], [0, y / z, 0, 1]]
        b += list(px.mean(axis=0) - 0.5)
    sol = np.linalg.lstsq(np.array(A), np.array(b), rcond=None)[0]
    return sol, float(np.abs(np.array(A) @ sol - np.array(b)).max())


def tag_depth(folder: Path, tag: int) -> float:
    """The depth of a tag's centre (cMo), standing for its four corners (the tags are about
    0.14 m wide at 1.6-3 m: a few per cent)."""
    return float(np.loadtxt(folder / "640x480" / f"cMo_{tag}.txt")[2, 3])


def detect(path: Path, family: str) -> dict[int, np.ndarray]:
    image = vsinv.vision.load_image(path)
    best: dict[int, np.ndarray] = {}
    for decimation in (1, 2):
        tags = vsinv.vision.detect_tags(image, family, decimation=decimation)  # type: ignore[arg-type]
        if len(tags) > len(best):
            best = {int(i): c for i, c in zip(tags.ids, tags.corners)}
    return best


def benchmark_pair() -> list[str]:
    if not BENCHMARK.is_dir():
        return [f"(i) skipped: {BENCHMARK} is missing (apt-get install visp-images-data)"]
    K640, k_residual = fit_k_640(BENCHMARK)
    rows = []
    for family, stem in FAMILIES.items():
        low = detect(BENCHMARK / "640x480" / f"{stem}_640x480.png", family)
        high = detect(BENCHMARK / "1920x1080" / f"{stem}_1920x1080.png", family)
        common = sorted(set(low) & set(high))
        if len(common) < 2:
            rows.append(f"  {family:9} found {len(low)}/5 and {len(high)}/5: too few tags in both")
            continue
        ref_px = np.concatenate([low[t] for t in common])
        px = np.concatenate([high[t] for t in common])
        # The 1920x1080 camera's K: the 640x480 K mapped by the axis-aligned scale and shift
        # between the two images' detections (same pose, two pinholes: u' = a u + b, v' = c v + d).
        (a, b0), fit_u = _axis_map(ref_px[:, 0], px[:, 0])
        (c, d0), fit_v = _axis_map(ref_px[:, 1], px[:, 1])
        K = vsinv.Intrinsics(a * K640[0], c * K640[1], a * K640[2] + b0, c * K640[3] + d0)
        depths = np.repeat([tag_depth(BENCHMARK, t) for t in common], 4)
        err, mm, deg = implied_offset(ref_px, px, K, depths)
        rows.append(
            f"  {family:9} tags {len(low)}/5 at 640x480, {len(high)}/5 at 1920x1080, {len(common)} in both: "
            f"|s-s*| {err:.2e} ({err / np.sqrt(len(px)):.1e} per point)  implied offset {mm:7.3f} mm {deg:6.3f} deg "
            f"(pair map residual {max(fit_u, fit_v):.2f} px)"
        )
    rows.insert(0, f"(i) ViSP AprilTag benchmark, 640x480 reference -> 1920x1080 (K 640x480 fitted to cMo: "
                   f"{K640.round(1).tolist()}, residual {k_residual:.2f} px)")
    return rows


def _axis_map(x: np.ndarray, y: np.ndarray) -> tuple[tuple[float, float], float]:
    A = np.column_stack([x, np.ones_like(x)])
    sol = np.linalg.lstsq(A, y, rcond=None)[0]
    return (float(sol[0]), float(sol[1])), float(np.abs(A @ sol - y).max())


def mujoco_rows(starts: int, iterations: int, supersample: int = 1) -> list[str]:
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
    os.environ.setdefault("MUJOCO_GL", "egl")
    import mujoco_world as mw

    why = mw.available()
    if why is not None:
        return [f"(ii) skipped: {why}"]
    import mujoco_servo as ms

    lens = ms.Lens()
    rows = [f"(ii) MuJoCo, {lens.fovy_reference:.0f} -> {lens.fovy_servo:.0f} degrees, 400x300, supersample {supersample}"]
    session = {"gain": 2.5, "dt": 0.04, "stop": {"max_iterations": iterations, "max_translation_uncertainty": 1e-3, "max_rotation_uncertainty_deg": 0.2}}
    for target in ("dots", "tags"):
        world = mw.BoxWorld(target, supersample=supersample)
        K = vsinv.Intrinsics(*world.intrinsics(lens.fovy_servo))
        servo, _ = ms.pipeline(world, lens, "invariant", ms.REFERENCE_POSE, session)
        step = servo.step(world.render(ms.REFERENCE_POSE, lens.fovy_servo))
        depths = _mujoco_depths(world, ms, mw, servo, lens)
        found = step.found
        err, mm, deg = implied_offset(servo.reference_pixels[found], step.pixels[found], K, depths[found])
        rows.append(f"  {target:5} static pair at the goal: {found.sum()} points, |s-s*| {err:.2e} ({err / np.sqrt(found.sum()):.1e} per point)  implied offset {mm:7.3f} mm {deg:6.3f} deg")
        ends = [ms.run(world, lens, "invariant", s, k, session) for k, s in enumerate(ms.start_poses(world, lens, starts))]
        for e in ends:
            rows.append("    " + e.row())
        mm_all = np.array([e.error_mm for e in ends])
        deg_all = np.array([e.error_deg for e in ends])
        verdicts = {v: sum(e.verdict == v for e in ends) for v in sorted({e.verdict for e in ends})}
        rows.append(
            f"  {target:5} closed loop, {starts} starts: {verdicts}; final error median {np.median(mm_all):.3f} mm "
            f"(max {mm_all.max():.3f}), {np.median(deg_all):.3f} deg (max {deg_all.max():.3f})"
        )
        world.close()
    return rows


def _mujoco_depths(world, ms, mw, servo, lens) -> np.ndarray:  # type: ignore[no-untyped-def]
    """True depths of the session's points at the reference pose (servo camera)."""
    if world.target == "dots":
        return mw.project(ms.REFERENCE_POSE, world.intrinsics(lens.fovy_servo), world.dot_centres())[1]
    _, depths = ms.tag_reference_depths(world, world.render(ms.REFERENCE_POSE, lens.fovy_reference), world.intrinsics(lens.fovy_reference))
    return depths


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--starts", type=int, default=10)
    parser.add_argument("--iterations", type=int, default=200)
    parser.add_argument("--supersample", default="1,3", help="comma-separated MuJoCo supersampling factors")
    parser.add_argument("--quick", action="store_true", help="1 start of 20 iterations, no supersampling (make bench-quick)")
    args = parser.parse_args()
    if args.quick:
        args.starts, args.iterations, args.supersample = 1, 20, "1"
    for row in benchmark_pair():
        print(row, flush=True)
    for supersample in (int(k) for k in args.supersample.split(",")):
        for row in mujoco_rows(args.starts, args.iterations, supersample):
            print(row, flush=True)


if __name__ == "__main__":
    main()
