"""AprilTags (tag36h11) through a sequence: time per frame of the whole-frame detection
(``vsinv.vision.detect_tags``), of the tracked frames (``vsinv.vision.TagTracker``: each tag followed from its
last corners, its edges measured again and its bits read there with no quad search, "edges") and
of the quad search in a crop around each tag (``TagTracker(follow=False)``, "crop"), when nothing
moved and under small motion, beside OpenCV's aruco detector on the same frames, in the same run.

How to run (from the repository root, with the package, ``opencv-python-headless`` and Debian's
``visp-images-data`` installed)::

    python benches/tags_tracked.py             # about a minute
    python benches/tags_tracked.py --quick     # 2 rounds instead of 5
    python benches/tags_tracked.py --threads 1 # both on one thread
    python benches/tags_tracked.py --json out.json

The frames are ViSP's ``AprilTag/benchmark/{640x480,1920x1080}/tag36_11_*.png`` (read from the
package's folder, never copied). "still": the same frame again and again; "moving": the frame
shifted by (0, 0), (2, 1), (4, 2), (2, 1) pixels in turn (the uncovered border white), about
2 px a frame. The tracker reads no whole frame while timed (``refresh=0``; the run checks that
every timed frame was tracked, and reports how far the tracked corners are from ``detect_tags``'s
on the same frames, "max diff px" ("crop diff" for ``follow=False``), how many tags one found and
not the other, "odd", and the share of the tracked tags that were followed by their edges,
"edges %");
"amortized" adds one whole read every 15 frames, the tracker's default ``refresh``. Timing as
``benches/tags_vs_opencv.py`` (minimum over rounds of the median time per call); the ratios are
vsinv's time over OpenCV's (``ArucoDetector(DICT_APRILTAG_36h11)``, subpixel refinement) on the
same frames (below 1: vsinv is faster).
"""

from __future__ import annotations

import argparse
import itertools
import os
import platform
import sys
from dataclasses import asdict, dataclass
from pathlib import Path

if "--threads" in sys.argv:  # before rayon's pool starts
    os.environ["RAYON_NUM_THREADS"] = sys.argv[sys.argv.index("--threads") + 1]

import cv2
import numpy as np

import vsinv

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_step import write_json  # noqa: E402
from vision import timed_min_of_medians  # noqa: E402

VISP = Path("/usr/share/visp-images-data/ViSP-images/AprilTag/benchmark")
SHIFTS = [(0, 0), (2, 1), (4, 2), (2, 1)]
REFRESH = 15


def shifted(image: np.ndarray, du: int, dv: int) -> np.ndarray:
    """The image moved by (du, dv) pixels (du, dv >= 0), the uncovered border white."""
    out = np.full_like(image, 255)
    out[dv:, du:] = image[: image.shape[0] - dv, : image.shape[1] - du]
    return out


@dataclass
class Row:
    image: str
    decimation: int
    tags: int
    whole_ms: float
    still_ms: float
    moving_ms: float
    crop_still_ms: float
    crop_moving_ms: float
    amortized_ms: float
    opencv_ms: float
    opencv_tags: int
    max_diff_px: float  # largest distance of a tracked corner from the whole frame's
    crop_diff_px: float  # the same, with the quad search in crops (follow=False)
    odd_tags: int  # tags found by one of tracked and whole frame but not the other
    edges_share: float  # of the tags of the tracked frames, those followed by their edges

    def ratio(self, ms: float) -> float:
        return ms / self.opencv_ms


@dataclass
class Checked:
    """A tracker run through frames, and how its tracked frames compare with ``detect_tags``."""

    tracker: vsinv.vision.TagTracker
    worst: float  # largest distance of a tracked corner from the whole frame's, pixels
    odd: int  # tags found in one but not the other, over the frames
    edges: int  # tags of the tracked frames followed by their edges
    reads: int  # tags of the tracked frames


def checked_tracker(frames: list[np.ndarray], decimation: int, follow: bool = True) -> Checked:
    """A tracker run twice through ``frames``, every frame after the first tracked."""
    tracker = vsinv.vision.TagTracker(decimation=decimation, refresh=0, follow=follow)
    worst, odd, edges, reads = 0.0, 0, 0, 0
    for k, frame in enumerate(frames + frames):
        got, whole = tracker.track(frame), vsinv.vision.detect_tags(frame, decimation=decimation)
        assert tracker.read_whole == (k == 0), f"frame {k} read whole"
        if k > 0:
            edges += tracker.reads.count("edges")
            reads += len(tracker.reads)
        index = {int(t): j for j, t in enumerate(whole.ids)}
        odd += len(set(got.ids) ^ set(whole.ids))
        for j, t in enumerate(got.ids):
            if int(t) in index:
                worst = max(worst, float(np.abs(got.corners[j] - whole.corners[index[int(t)]]).max()))
    return Checked(tracker, worst, odd, edges, reads)


def measure(rounds: int) -> list[Row]:
    params = cv2.aruco.DetectorParameters()
    params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    opencv = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11), params)
    rows = []
    for size, decimations in (("640x480", (1, 2)), ("1920x1080", (2, 3))):
        image = cv2.imread(str(VISP / size / f"tag36_11_{size}.png"), cv2.IMREAD_GRAYSCALE)
        frames = [shifted(image, du, dv) for du, dv in SHIFTS]
        for decimation in decimations:
            still, moving = checked_tracker([image], decimation), checked_tracker(frames, decimation)
            crop_still = checked_tracker([image], decimation, follow=False)
            crop_moving = checked_tracker(frames, decimation, follow=False)
            cycles = [itertools.cycle(frames) for _ in range(2)]
            t = timed_min_of_medians(
                {
                    "whole": lambda: vsinv.vision.detect_tags(image, decimation=decimation),
                    "still": lambda: still.tracker.track(image),
                    "moving": lambda: moving.tracker.track(next(cycles[0])),
                    "crop_still": lambda: crop_still.tracker.track(image),
                    "crop_moving": lambda: crop_moving.tracker.track(next(cycles[1])),
                    "opencv": lambda: opencv.detectMarkers(image),
                },
                rounds,
            )
            checked = [still, moving, crop_still, crop_moving]
            assert not any(c.tracker.read_whole for c in checked)
            _, ids, _ = opencv.detectMarkers(image)
            rows.append(
                Row(
                    image=f"benchmark {size}",
                    decimation=decimation,
                    tags=len(vsinv.vision.detect_tags(image, decimation=decimation)),
                    whole_ms=t["whole"] * 1e3,
                    still_ms=t["still"] * 1e3,
                    moving_ms=t["moving"] * 1e3,
                    crop_still_ms=t["crop_still"] * 1e3,
                    crop_moving_ms=t["crop_moving"] * 1e3,
                    amortized_ms=((REFRESH - 1) * t["moving"] + t["whole"]) / REFRESH * 1e3,
                    opencv_ms=t["opencv"] * 1e3,
                    opencv_tags=0 if ids is None else len(ids),
                    max_diff_px=max(still.worst, moving.worst),
                    crop_diff_px=max(crop_still.worst, crop_moving.worst),
                    odd_tags=sum(c.odd for c in checked),
                    edges_share=(still.edges + moving.edges) / max(still.reads + moving.reads, 1),
                )
            )
    return rows


def print_table(rows: list[Row]) -> None:
    head = (
        f"{'frames':<20} {'dec':>3} {'tags':>4} {'whole ms':>9} {'still ms':>9} {'moving ms':>9} "
        f"{'crop still':>10} {'crop moving':>11} {'amortized':>9} {'OpenCV ms':>9} {'CV tags':>7} "
        f"{'max diff px':>11} {'crop diff':>9} {'odd':>3} {'edges %':>7}  ratios to OpenCV: whole / still / moving"
    )
    print(head)
    print("-" * len(head))
    for r in rows:
        print(
            f"{r.image:<20} {r.decimation:>3} {r.tags:>4} {r.whole_ms:>9.2f} {r.still_ms:>9.3f} {r.moving_ms:>9.3f} "
            f"{r.crop_still_ms:>10.3f} {r.crop_moving_ms:>11.3f} {r.amortized_ms:>9.2f} {r.opencv_ms:>9.2f} "
            f"{r.opencv_tags:>7} {r.max_diff_px:>11.1e} {r.crop_diff_px:>9.1e} {r.odd_tags:>3} {100 * r.edges_share:>7.0f}  "
            f"{r.ratio(r.whole_ms):.2f} / {r.ratio(r.still_ms):.3f} / {r.ratio(r.moving_ms):.3f}"
        )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="2 rounds instead of 5")
    parser.add_argument("--threads", type=int, default=0, help="threads for both (0: the machine's)")
    parser.add_argument("--json", help="also write the numbers to this JSON file")
    args = parser.parse_args()
    if not VISP.is_dir():
        print(f"skipped: ViSP's AprilTag images are not installed ({VISP}): apt-get install visp-images-data")
        return 0
    if args.threads:
        cv2.setNumThreads(args.threads)
    threads = args.threads or os.cpu_count()
    print(f"tag36h11 tracked: vsinv {vsinv.__version__} vs OpenCV {cv2.__version__} aruco, "
          f"{threads} thread(s), {platform.processor() or platform.machine()}")
    rows = measure(2 if args.quick else 5)
    print_table(rows)
    if args.json:
        write_json(args.json, {"rows": [asdict(r) for r in rows]})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
