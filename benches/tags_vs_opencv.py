"""AprilTag detection (tag36h11) against OpenCV's aruco detector and pupil-apriltags (the AprilTag
library), side by side on the same images.

How to run (from the repository root, with the package, ``opencv-python-headless`` (with its
aruco module) and Debian's ``visp-images-data`` installed)::

    python benches/tags_vs_opencv.py                  # about a minute
    python benches/tags_vs_opencv.py --quick          # 2 rounds instead of 5, every detector on one thread
    python benches/tags_vs_opencv.py --threads 1      # both on one thread
    python benches/tags_vs_opencv.py --json out.json  # also write the numbers as JSON

``make bench`` runs it (it says so and stops when ViSP's images are not installed). The images
are ViSP's public AprilTag images (read from the package's folder, never copied):

- ``AprilTag.pgm`` (640 x 480, a real camera image of 12 tags) with its published corners
  (``ground_truth_detection.txt``);
- ``benchmark/640x480/tag36_11_640x480.png`` (5 tags) with ``corners_tag36_11.txt``;
- at 1920 x 1080: ``benchmark/1920x1080/tag36_11_1920x1080.png`` (no ground truth: the two
  detectors' corners are compared with each other) and ``AprilTag.pgm`` enlarged 2.25 times
  (``cv2.resize``, bilinear, 1440 x 1080) and centred on a 1920 x 1080 grey canvas, its ground
  truth mapped by the same enlargement (``u' = 2.25 (u + 0.5) - 0.5`` in OpenCV's convention).

ViSP's corner files follow the AprilTag library (pixel centres at +0.5, another corner order);
they are converted to OpenCV's order and convention as in ``tests/test_tags.py``, in which
``vsinv.vision.detect_tags`` reports its corners. OpenCV's detector is
``cv2.aruco.ArucoDetector(DICT_APRILTAG_36h11)`` with subpixel corner refinement
(``CORNER_REFINE_SUBPIX``, whose corners are in OpenCV's convention; ``CORNER_REFINE_APRILTAG``
is shown too: its corners are half a pixel off OpenCV's own convention, in the AprilTag
library's, and are moved back by 0.5 before their errors are taken). The AprilTag library itself
is ``pupil_apriltags.Detector(families="tag36h11")`` (its corners converted as in
``tests/tag_sets.py``), timed twice: at its default ``quad_decimate`` (2.0) and at 1.0 (the
quad search on the whole frame); both columns are skipped when pupil-apriltags is not installed.

Like with like: vsinv's decimation is the AprilTag library's (the top-left pixel of each
``d x d`` block, kornia-apriltag's copy of ``image_u8_decimate``), so vsinv at decimation 2 (the
``vsinv`` column, the row's decimation) is timed against pupil-apriltags at ``quad_decimate`` 2,
and vsinv at decimation 1 (``vsinv d1``, checked as the ``vsinv`` column is) against
``quad_decimate`` 1. vsinv also searches the coarser halvings of the image (for large tags) and
measures every corner again on the full image's edges; the AprilTag library refines its edges
on the full image too (``refine_edges``).

Timing: as ``benches/vision.py``: the number of calls per repeat is the smallest power of two
taking at least 50 ms; a round is ``Timer.repeat(5, number)`` and gives the median time per
call; the detectors alternate from round to round and each cell is the minimum over rounds of
the medians. Both detectors use the machine's cores by default (vsinv's through rayon inside
kornia-apriltag, OpenCV's through its own threads); ``--threads 1`` sets
``RAYON_NUM_THREADS=1``, ``cv2.setNumThreads(1)`` and pupil-apriltags' ``nthreads=1``.
``--quick`` (the CI run, ``make bench-quick``) means ``--threads 1`` unless ``--threads`` is
given: the AprilTag library's threaded quad search races on its union-find (AprilRobotics/apriltag
issues 184 and 387), and one CI run of this script died of it with SIGSEGV. The
ratios are vsinv time / peer time (below 1: vsinv is faster).

Accuracy: the distance of each published corner to the detector's corner of the same tag and
index (a wrong order shows as an error of a tag side), median and max over all corners;
``found`` counts the tags of the ground truth that were detected. Before timing, vsinv must find
every tag of the reference with its corners within 1.5 px, and each peer's corners of the tags it
finds must be within 1.5 px of the reference (its conversion checked), or the script exits with
``MISMATCH``.
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import sys
from dataclasses import asdict, dataclass
from pathlib import Path

import faulthandler

faulthandler.enable()  # a crash inside a peer's C code prints where it happened
if "--threads" in sys.argv:  # before rayon's pool starts
    os.environ["RAYON_NUM_THREADS"] = sys.argv[sys.argv.index("--threads") + 1]
elif "--quick" in sys.argv:  # --quick means --threads 1 (the docstring says why)
    os.environ["RAYON_NUM_THREADS"] = "1"

import cv2
import numpy as np

import vsinv

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_step import write_json  # noqa: E402
from vision import timed_min_of_medians  # noqa: E402

VISP = Path("/usr/share/visp-images-data/ViSP-images/AprilTag")
VISP_TO_OPENCV = [1, 0, 3, 2]
PUPIL_DECIMATIONS = (2.0, 1.0)  # pupil-apriltags' default quad_decimate, then the whole frame
SCALE = 2.25  # 640 x 480 -> 1440 x 1080


# --------------------------------------------------------------------------- images and truth


def visp_corners(path: Path, row_column: bool) -> dict[int, np.ndarray]:
    """A ViSP corners file in OpenCV's order and pixel convention (see tests/test_tags.py)."""
    lines = [line for line in path.read_text().splitlines() if line.strip()]
    out = {}
    for k in range(0, len(lines), 5):
        tag = int(re.search(r"(\d+)\s*$", lines[k]).group(1))  # type: ignore[union-attr]
        xy = np.array([[float(x) for x in lines[k + j].split()] for j in range(1, 5)])
        out[tag] = (xy[:, ::-1] if row_column else xy)[VISP_TO_OPENCV] - 0.5
    return out


def enlarged(image: np.ndarray, truth: dict[int, np.ndarray]) -> tuple[np.ndarray, dict[int, np.ndarray]]:
    """`image` enlarged SCALE times (bilinear), centred on a 1920 x 1080 canvas; its truth."""
    h, w = image.shape
    big = cv2.resize(image, (round(w * SCALE), round(h * SCALE)), interpolation=cv2.INTER_LINEAR)
    canvas = np.full((1080, 1920), int(np.median(image)), np.uint8)
    left, top = (1920 - big.shape[1]) // 2, (1080 - big.shape[0]) // 2
    canvas[top : top + big.shape[0], left : left + big.shape[1]] = big
    moved = {t: SCALE * (c + 0.5) - 0.5 + np.array([left, top]) for t, c in truth.items()}
    return canvas, moved


def images() -> list[tuple[str, np.ndarray, dict[int, np.ndarray] | None, int]]:
    """Name, image, ground truth (None: none published) and vsinv's decimation."""
    pgm = cv2.imread(str(VISP / "AprilTag.pgm"), cv2.IMREAD_GRAYSCALE)
    pgm_truth = visp_corners(VISP / "ground_truth_detection.txt", row_column=True)
    bench = cv2.imread(str(VISP / "benchmark/640x480/tag36_11_640x480.png"), cv2.IMREAD_GRAYSCALE)
    bench_truth = visp_corners(VISP / "benchmark/640x480/corners_tag36_11.txt", row_column=False)
    big_pgm, big_truth = enlarged(pgm, pgm_truth)
    big_bench = cv2.imread(str(VISP / "benchmark/1920x1080/tag36_11_1920x1080.png"), cv2.IMREAD_GRAYSCALE)
    return [
        ("AprilTag.pgm 640x480", pgm, pgm_truth, 2),
        ("benchmark 640x480", bench, bench_truth, 2),
        ("AprilTag.pgm x2.25 1920x1080", big_pgm, big_truth, 2),
        ("AprilTag.pgm x2.25 1920x1080, decimation 3", big_pgm, big_truth, 3),
        ("benchmark 1920x1080", big_bench, None, 2),
        ("benchmark 1920x1080, decimation 3", big_bench, None, 3),
    ]


# --------------------------------------------------------------------------- detectors


def opencv_detector(refine: int) -> cv2.aruco.ArucoDetector:
    params = cv2.aruco.DetectorParameters()
    params.cornerRefinementMethod = refine
    return cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11), params)


def opencv_tags(detector: cv2.aruco.ArucoDetector, image: np.ndarray, shift: float = 0.0) -> dict[int, np.ndarray]:
    corners, ids, _ = detector.detectMarkers(image)
    if ids is None:
        return {}
    return {int(i): c.reshape(4, 2).astype(np.float64) - shift for i, c in zip(ids.ravel(), corners)}


def pupil_detectors(threads: int) -> dict[float, object]:
    """pupil-apriltags' detectors, one per quad_decimate ({} when it is not installed); made once
    for the process (pupil-apriltags aborts when detectors are made and freed again and again)."""
    try:
        import pupil_apriltags
    except ImportError:
        return {}
    return {d: pupil_apriltags.Detector(families="tag36h11", nthreads=threads, quad_decimate=d) for d in PUPIL_DECIMATIONS}


def pupil_tags(detector, image: np.ndarray) -> dict[int, np.ndarray]:  # type: ignore[no-untyped-def]
    """pupil-apriltags' tags in OpenCV's order and convention (as tests/tag_sets.py converts them)."""
    return {int(t.tag_id): np.asarray(t.corners, np.float64)[VISP_TO_OPENCV] - 0.5 for t in detector.detect(image)}


def vsinv_tags(image: np.ndarray, decimation: int) -> dict[int, np.ndarray]:
    tags = vsinv.vision.detect_tags(image, decimation=decimation)
    return {int(i): c for i, c in zip(tags.ids, tags.corners)}


@dataclass
class Accuracy:
    found: int
    of: int
    median_px: float
    max_px: float


def accuracy(found: dict[int, np.ndarray], truth: dict[int, np.ndarray]) -> Accuracy:
    errors = [np.linalg.norm(found[t] - c, axis=1) for t, c in truth.items() if t in found]
    e = np.concatenate(errors) if errors else np.array([np.nan])
    return Accuracy(len(errors), len(truth), float(np.median(e)), float(np.max(e)))


# --------------------------------------------------------------------------- timing


@dataclass
class Row:
    image: str
    size: str
    vsinv_ms: float
    vsinv_d1_ms: float
    opencv_ms: float
    opencv_apriltag_ms: float
    vsinv: Accuracy
    vsinv_d1: Accuracy
    opencv: Accuracy
    opencv_apriltag: Accuracy
    pupil_ms: dict[str, float]
    pupil: dict[str, Accuracy]

    @property
    def ratio(self) -> float:
        return self.vsinv_ms / self.opencv_ms


def agreeing(name: str, peer: str, found: dict[int, np.ndarray], reference: dict[int, np.ndarray]) -> Accuracy:
    """The peer's accuracy; MISMATCH when a tag it finds is more than 1.5 px off the reference."""
    acc = accuracy(found, reference)
    if acc.found and not acc.max_px <= 1.5:
        raise SystemExit(f"MISMATCH on {name}: {peer}'s corners up to {acc.max_px:.3f} px off the reference")
    return acc


def measure(rounds: int, threads: int) -> list[Row]:
    pupils = pupil_detectors(threads)
    subpix = opencv_detector(cv2.aruco.CORNER_REFINE_SUBPIX)
    april = opencv_detector(cv2.aruco.CORNER_REFINE_APRILTAG)
    rows = []
    for name, image, truth, decimation in images():
        ours, theirs = vsinv_tags(image, decimation), opencv_tags(subpix, image)
        theirs_april = opencv_tags(april, image, shift=0.5)
        # Without ground truth, OpenCV's subpixel corners stand for it (agreement, not accuracy).
        reference = truth if truth is not None else theirs
        # Before timing: vsinv finds every tag of the reference, each corner within 1.5 px
        # (measured: 0.61 px at most).
        mine, mine_d1 = accuracy(ours, reference), accuracy(vsinv_tags(image, 1), reference)
        for d, a in ((decimation, mine), (1, mine_d1)):
            if a.found < a.of or not a.max_px <= 1.5:
                raise SystemExit(f"MISMATCH on {name}: vsinv (decimation {d}) found {a.found} of {a.of} tags, corners up to {a.max_px:.3f} px off")
        pupil_acc = {f"{d:g}": agreeing(name, f"pupil-apriltags (quad_decimate {d:g})", pupil_tags(p, image), reference) for d, p in pupils.items()}
        calls = {
            "vsinv": lambda: vsinv.vision.detect_tags(image, decimation=decimation),
            "vsinv d1": lambda: vsinv.vision.detect_tags(image, decimation=1),
            "opencv": lambda: subpix.detectMarkers(image),
            "opencv_apriltag": lambda: april.detectMarkers(image),
        }
        for d, p in pupils.items():
            calls[f"pupil {d:g}"] = lambda p=p: p.detect(image)
        t = timed_min_of_medians(calls, rounds)
        rows.append(
            Row(
                image=name if truth is not None else f"{name} (vs OpenCV subpix)",
                size=f"{image.shape[1]}x{image.shape[0]}",
                vsinv_ms=t["vsinv"] * 1e3,
                vsinv_d1_ms=t["vsinv d1"] * 1e3,
                opencv_ms=t["opencv"] * 1e3,
                opencv_apriltag_ms=t["opencv_apriltag"] * 1e3,
                vsinv=mine,
                vsinv_d1=mine_d1,
                opencv=accuracy(theirs, reference),
                opencv_apriltag=accuracy(theirs_april, reference),
                pupil_ms={d: t[f"pupil {d}"] * 1e3 for d in pupil_acc},
                pupil=pupil_acc,
            )
        )
    return rows


def print_table(rows: list[Row]) -> None:
    def acc(a: Accuracy) -> str:
        return f"{a.found}/{a.of} {a.median_px:.3f}/{a.max_px:.3f}"

    decimations = list(rows[0].pupil) if rows else []
    pupil_head = "".join(f" {'pupil d' + d + ' (ms)':>16} {'ratio':>6}" for d in decimations)
    if "1" in decimations:  # like with like: vsinv at decimation 1 against quad_decimate 1
        pupil_head += f" {'vsinv d1 (ms)':>13} {'ratio d1':>8}"
    pupil_acc_head = "".join(f" {'pupil d' + d:>20}" for d in decimations)
    head = (
        f"{'image':<45} {'vsinv (ms)':>10} {'OpenCV (ms)':>11} {'ratio':>6} {'CV april (ms)':>13}{pupil_head}  "
        f"{'vsinv found, median/max px':>27} {'OpenCV subpix':>20} {'OpenCV apriltag':>20}{pupil_acc_head}"
    )
    print(head)
    print("-" * len(head))
    for r in rows:
        pupil_cells = "".join(f" {r.pupil_ms[d]:>16.2f} {r.vsinv_ms / r.pupil_ms[d]:>6.2f}" for d in decimations)
        if "1" in decimations:
            pupil_cells += f" {r.vsinv_d1_ms:>13.2f} {r.vsinv_d1_ms / r.pupil_ms['1']:>8.2f}"
        pupil_accs = "".join(f" {acc(r.pupil[d]):>20}" for d in decimations)
        print(
            f"{r.image:<45} {r.vsinv_ms:>10.2f} {r.opencv_ms:>11.2f} {r.ratio:>6.2f} {r.opencv_apriltag_ms:>13.2f}{pupil_cells}  "
            f"{acc(r.vsinv):>27} {acc(r.opencv):>20} {acc(r.opencv_apriltag):>20}{pupil_accs}"
        )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="2 rounds instead of 5, on one thread unless --threads")
    parser.add_argument("--threads", type=int, default=0, help="threads for every detector (0: the machine's)")
    parser.add_argument("--json", help="also write the numbers to this JSON file")
    args = parser.parse_args()
    if not VISP.is_dir():
        print(f"skipped: ViSP's AprilTag images are not installed ({VISP}): apt-get install visp-images-data")
        return 0
    if args.quick and not args.threads:
        args.threads = 1  # RAYON_NUM_THREADS was set at import
    if args.threads:
        cv2.setNumThreads(args.threads)
    threads = args.threads or os.cpu_count()
    print(f"tag36h11: vsinv {vsinv.__version__} (kornia-apriltag) vs OpenCV {cv2.__version__} aruco and pupil-apriltags, "
          f"{threads} thread(s), {platform.processor() or platform.machine()}")
    rows = measure(2 if args.quick else 5, threads)
    print_table(rows)
    if args.json:
        write_json(args.json, {"threads": threads, "rows": [{**asdict(r), "ratio": r.ratio} for r in rows]})
    return 0


if __name__ == "__main__":
    sys.exit(main())
