"""Dot detection and tracking against OpenCV, side by side on the same images.

How to run (from the repository root, with the package and ``opencv-python-headless``
installed)::

    python benches/vision.py                 # under a minute
    python benches/vision.py --quick         # 2 rounds instead of 5
    python benches/vision.py --json out.json # also write the numbers as JSON

``make bench`` runs it after the criterion benchmarks. The images are the 832 x 624 views of
the built-in scenarios ``vision-12-6`` (6 mm servo lens: small dots) and ``vision-12-12``
(12 mm lens) rendered by ``vsinv.vision.render_view`` along their own closed-loop runs (the run's
recorded pose and time at a few iterations, so each image carries the sensor noise of the
simulator's image at that iteration); ``render_view`` also returns the true projections of
the dots' centres, the reference of every accuracy figure. On each image the script times:

(a) ``vsinv.vision.detect_dots(image)``: the full frame: local threshold (per tile, above the
    background around), 8-connected components, shape filters, intensity-weighted subpixel
    centroids;
(b) ``vsinv.vision.DotTracker(image, truth).track(image)``: the 12 dots searched in a 40 x 40 px
    window each around their predicted positions, in steady state (the tracker is started on
    the image from the true projections, as the simulator starts it from the projected
    points, and has tracked it once);
(c) OpenCV's full-frame detection: ``cv2.threshold`` with ``THRESH_OTSU``,
    ``cv2.connectedComponentsWithStats`` (8-connected) and its centroids of the components
    of at least 4 pixels (vsinv's ``min_area``), background label dropped.

Timing: the number of calls per repeat is the smallest power of two that takes at least
50 ms (as ``timeit.Timer.autorange`` does with 0.2 s); one round is
``Timer.repeat(5, number)`` and gives the median time per call; the rounds of
(a), (b) and (c) alternate so that they share the machine's load, and each cell shows the
minimum over the rounds of these medians. OpenCV runs on one thread (``cv2.setNumThreads``,
``--cv-threads`` to change it), like vsinv's detection and tracking. The ratios are vsinv
time / OpenCV time (below 1: vsinv is faster). vsinv's ``detect_dots`` and
``DotTracker.track`` run their Rust work with the GIL released (``py.detach`` in
``src/python/vision.rs``), as does ``cv2``; this script calls them from one thread.

Accuracy: each true projection is matched to the nearest detected centroid (error in
pixels, median and max over the visible dots); ``found`` counts the dots matched within 1 px
and ``extra`` the detections farther than 2 px from every dot (noise specks); ``Otsu`` is
the level OpenCV's threshold chose (vsinv's local threshold stays at least ``min_contrast``
grey levels above the background around each pixel). For the tracker, the error is that of each dot's own
result and ``found`` counts its ``found`` flags.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import timeit
from dataclasses import asdict, dataclass

import cv2
import numpy as np

import vsinv

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_step import write_json  # noqa: E402

SCENARIOS = ("vision-12-6", "vision-12-12")
ITERATIONS = (0, 100, 300)  # recorded iterations of each run whose views are measured, plus the last
MIN_AREA = 4
REPEAT = 5
MIN_REPEAT_S = 0.05  # seconds per repeat, at least


# --------------------------------------------------------------------------- detectors


def opencv_dots(image: np.ndarray) -> np.ndarray:
    """OpenCV's full-frame detection: Otsu's threshold, 8-connected components with stats,
    the centroids (m, 2) of the components of at least MIN_AREA pixels."""
    _, binary = cv2.threshold(image, 0, 255, cv2.THRESH_BINARY | cv2.THRESH_OTSU)
    _, _, stats, centroids = cv2.connectedComponentsWithStats(binary, connectivity=8)
    keep = stats[1:, cv2.CC_STAT_AREA] >= MIN_AREA
    return centroids[1:][keep]


# --------------------------------------------------------------------------- accuracy


@dataclass
class Accuracy:
    found: int  # dots matched within 1 px (tracker: found flags)
    extra: int  # detections farther than 2 px from every dot
    median_px: float
    max_px: float


def detection_accuracy(centroids: np.ndarray, truth: np.ndarray) -> Accuracy:
    if len(centroids) == 0:
        return Accuracy(0, 0, float("nan"), float("nan"))
    d = np.linalg.norm(centroids[None, :, :] - truth[:, None, :], axis=2)  # (dots, detections)
    nearest = d.min(axis=1)
    extra = int((d.min(axis=0) > 2.0).sum())
    return Accuracy(int((nearest < 1.0).sum()), extra, float(np.median(nearest)), float(nearest.max()))


def tracking_accuracy(pixels: np.ndarray, found: np.ndarray, truth: np.ndarray) -> Accuracy:
    e = np.linalg.norm(pixels[found] - truth[found], axis=1)
    if len(e) == 0:
        return Accuracy(0, 0, float("nan"), float("nan"))
    return Accuracy(int(found.sum()), 0, float(np.median(e)), float(e.max()))


# --------------------------------------------------------------------------- timing


def calls_per_repeat(timer: timeit.Timer) -> int:
    """The smallest power of two of calls that takes at least MIN_REPEAT_S."""
    number = 1
    while timer.timeit(number) < MIN_REPEAT_S:
        number *= 2
    return number


def timed_min_of_medians(fns: dict[str, object], rounds: int) -> dict[str, float]:
    """Seconds per call of each fn(): rounds alternate between the functions; a round is
    Timer.repeat(REPEAT, number) and gives its median; the result is the minimum over rounds."""
    timers = {name: timeit.Timer(fn) for name, fn in fns.items()}  # type: ignore[arg-type]
    numbers = {name: calls_per_repeat(t) for name, t in timers.items()}
    best = {name: float("inf") for name in fns}
    for _ in range(rounds):
        for name, t in timers.items():
            median = statistics.median(t.repeat(repeat=REPEAT, number=numbers[name])) / numbers[name]
            best[name] = min(best[name], median)
    return best


@dataclass
class Row:
    scenario: str
    iteration: int
    time_s: float
    dots: int  # visible dots in the image
    detect_us: float
    track_us: float
    opencv_us: float
    otsu_level: int  # OpenCV's threshold
    detect_accuracy: Accuracy
    track_accuracy: Accuracy
    opencv_accuracy: Accuracy

    @property
    def detect_over_opencv(self) -> float:
        return self.detect_us / self.opencv_us

    @property
    def track_over_opencv(self) -> float:
        return self.track_us / self.opencv_us


def measure(scenario: str, rounds: int) -> list[Row]:
    run = vsinv.run_scenario(scenario)
    last = len(run.time) - 1
    rows = []
    for i in sorted({*(i for i in ITERATIONS if i < last), last}):
        image, truth, visible = vsinv.vision.render_view(scenario, pose=run.pose[i], time=float(run.time[i]))
        assert image.shape == (624, 832) and image.dtype == np.uint8
        truth = truth[visible]
        tracker = vsinv.vision.DotTracker(image, truth)
        tracker.track(image)  # steady state: it has seen this image once
        pixels, found = tracker.track(image)
        detected = detection_accuracy(vsinv.vision.detect_dots(image).centroids, truth)
        tracked = tracking_accuracy(pixels, found, truth)
        # Before timing: every dot detected and tracked, none extra, within 0.5 px of its true
        # projection (measured: 0.13 px at most).
        n = len(truth)
        if (detected.found, detected.extra, tracked.found) != (n, 0, n) or not max(detected.max_px, tracked.max_px) <= 0.5:
            raise SystemExit(f"MISMATCH on {scenario} iteration {i}: detect_dots {detected}, DotTracker {tracked} ({n} dots)")
        t = timed_min_of_medians(
            {
                "detect": lambda: vsinv.vision.detect_dots(image),
                "track": lambda: tracker.track(image),
                "opencv": lambda: opencv_dots(image),
            },
            rounds,
        )
        rows.append(
            Row(
                scenario=scenario,
                iteration=i,
                time_s=float(run.time[i]),
                dots=int(visible.sum()),
                detect_us=t["detect"] * 1e6,
                track_us=t["track"] * 1e6,
                opencv_us=t["opencv"] * 1e6,
                otsu_level=int(cv2.threshold(image, 0, 255, cv2.THRESH_BINARY | cv2.THRESH_OTSU)[0]),
                detect_accuracy=detected,
                track_accuracy=tracked,
                opencv_accuracy=detection_accuracy(opencv_dots(image), truth),
            )
        )
    return rows


# --------------------------------------------------------------------------- output


def print_tables(rows: list[Row]) -> None:
    head = (
        f"{'scenario':<13} {'iter':>4} {'t (s)':>6} {'dots':>4} {'detect (us)':>11} {'track (us)':>10} "
        f"{'OpenCV (us)':>11} {'detect/CV':>9} {'track/CV':>8}"
    )
    print(head)
    print("-" * len(head))
    for r in rows:
        print(
            f"{r.scenario:<13} {r.iteration:>4} {r.time_s:>6.2f} {r.dots:>4} {r.detect_us:>11.1f} {r.track_us:>10.1f} "
            f"{r.opencv_us:>11.1f} {r.detect_over_opencv:>9.2f} {r.track_over_opencv:>8.3f}"
        )
    print()

    def cell(a: Accuracy, dots: int) -> str:
        return f"{a.found:>2}/{dots:<2} {a.extra:>5} {a.median_px:>7.3f} {a.max_px:>7.3f}"

    sub = f"{'found':>5} {'extra':>5} {'median':>7} {'max':>7}"
    head = (
        f"{'':<13} {'':>4} | {'vsinv detect_dots':^26} | {'vsinv DotTracker':^26} | "
        f"{'OpenCV Otsu + CC':^26} {'':>4}"
    )
    print("accuracy against the true projections (pixels)")
    print(head)
    print(f"{'scenario':<13} {'iter':>4} | {sub} | {sub} | {sub} {'Otsu':>4}")
    print("-" * len(head))
    for r in rows:
        print(
            f"{r.scenario:<13} {r.iteration:>4} | {cell(r.detect_accuracy, r.dots)} | "
            f"{cell(r.track_accuracy, r.dots)} | {cell(r.opencv_accuracy, r.dots)} {r.otsu_level:>4}"
        )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="2 timing rounds instead of 5")
    parser.add_argument("--cv-threads", type=int, default=1, help="OpenCV threads (default 1)")
    parser.add_argument("--json", metavar="PATH", help="also write the results to PATH as JSON")
    args = parser.parse_args(argv)
    rounds = 2 if args.quick else 5
    cv2.setNumThreads(args.cv_threads)

    rows = [row for scenario in SCENARIOS for row in measure(scenario, rounds)]
    print(
        f"832 x 624 images; per call: min over {rounds} rounds of the median of {REPEAT} repeats; "
        f"OpenCV {cv2.__version__} on {cv2.getNumThreads()} thread(s); ratios: vsinv / OpenCV"
    )
    print_tables(rows)
    speedups = [r.opencv_us / r.track_us for r in rows]
    print(f"\ntracking vs OpenCV full frame: {min(speedups):.1f}x to {max(speedups):.1f}x faster")

    if args.json:
        out = {
            "benchmark": "dot detection and tracking vs OpenCV, Python API",
            "unit": "microseconds per call (min over rounds of the median of repeats)",
            "rounds": rounds,
            "repeat": REPEAT,
            "python": sys.version.split()[0],
            "numpy": np.__version__,
            "opencv": cv2.__version__,
            "opencv_threads": cv2.getNumThreads(),
            "vsinv": vsinv.__version__,
            "machine": platform.machine(),
            "results": [
                {**asdict(r), "detect_over_opencv": r.detect_over_opencv, "track_over_opencv": r.track_over_opencv}
                for r in rows
            ],
        }
        write_json(args.json, out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
