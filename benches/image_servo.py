"""One `ImageServo` iteration at 832 x 624 (render excluded): the tag rig of the built-in
`tags-12-6` (three tags, twelve corners, detected afresh in every frame) and the twelve dots
of `vision-12-6` (tracked), both seen by the 6 mm camera along the first part of their run.

The frames are rendered first (poses from the scenario's own run, recorded), then the
pipeline is stepped over them; the time per step is the median over repeats of the mean over
the frames. Also printed, for scale in the same run: `detect_tags` alone and `DotTracker.track`
alone on the same frames. Run: `python benches/image_servo.py` (part of `make bench`).
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any, Callable

import numpy as np

import vsinv

FRAMES = 60
REPEATS = 7


def frames_of(name: str) -> tuple[vsinv.sim.Scenario, np.ndarray, np.ndarray, list[np.ndarray]]:
    """The scenario, its reference image and true pixels, and FRAMES images along its run."""
    scenario = vsinv.load_scenario(name)
    d = scenario.to_dict()
    d["stop"]["max_iterations"] = FRAMES
    poses = vsinv.run_scenario(d).pose
    ref, ref_px, _ = vsinv.vision.render_view(scenario, reference=True)
    images = [vsinv.vision.render_view(scenario, pose=p)[0] for p in poses[:FRAMES]]
    return scenario, ref, ref_px, images


def per_frame(step: Callable[[np.ndarray], Any], images: list[np.ndarray]) -> float:
    times = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        for image in images:
            step(image)
        times.append((time.perf_counter() - t0) / len(images))
    return statistics.median(times)


def main() -> None:
    global FRAMES, REPEATS
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="5 frames, 1 repeat (make bench-quick)")
    if parser.parse_args().quick:
        FRAMES, REPEATS = 5, 1
    k_hat = vsinv.Intrinsics(648.0, 570.0, 427.0, 304.0)
    rows = []
    _, ref, _, images = frames_of("tags-12-6")
    session = {"law": "ibvs", "depths": 0.65, "gain": 0.5, "stop": {"max_iterations": 10**6}}

    def tags_step() -> Callable[[np.ndarray], Any]:
        pipeline = vsinv.ImageServo(ref, "tags", k_hat, **session)
        return pipeline.step

    rows.append(("ImageServo, tags (3 tags, 12 corners)", per_frame(tags_step(), images)))
    rows.append(("  detect_tags alone", per_frame(vsinv.vision.detect_tags, images)))
    _, ref_d, ref_px, images_d = frames_of("vision-12-6")
    start_px = vsinv.vision.render_view(vsinv.load_scenario("vision-12-6"))[1]

    def dots_step() -> Callable[[np.ndarray], Any]:
        pipeline = vsinv.ImageServo(ref_d, "dots", k_hat, reference_points=ref_px, first_points=start_px, **session)
        return pipeline.step

    rows.append(("ImageServo, dots (12 tracked)", per_frame(dots_step(), images_d)))
    tracker = vsinv.vision.DotTracker(images_d[0], start_px)
    rows.append(("  DotTracker.track alone", per_frame(tracker.track, images_d)))
    print(f"one ImageServo iteration at 832 x 624, render excluded ({FRAMES} frames, median of {REPEATS})")
    for name, seconds in rows:
        print(f"  {name:<42} {seconds * 1e3:8.3f} ms")


if __name__ == "__main__":
    main()
