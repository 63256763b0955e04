"""Full-frame dot detection, vsinv against OpenCV, at 1920 x 1080 and 4096 x 3000.

How to run (from the repository root, with the package, ``opencv-python-headless`` and, for
the real images, Debian's ``visp-images-data``)::

    python benches/dots_vs_opencv.py           # about a minute
    python benches/dots_vs_opencv.py --quick   # fewer repeats

``make bench`` runs it. Images, each at both sizes:

- real: ViSP's ``mire-2/image.0001.pgm`` (five white dots on a box before a cluttered poster,
  384 x 288) and ``calibration/grid36-01.pgm`` (36 dark dots on paper, 640 x 480) tiled to the
  size (the camera's dots and clutter at their own scale, repeated);
- rendered: 300 anti-aliased discs (radius 5 to 15 px, level 220) drawn with OpenCV on a
  lighting gradient (30 to 90) with Gaussian noise (sigma 3), blurred (sigma 1).

Timed, on the same array:

(a) ``vsinv.detect_dots(image)`` with its defaults (``polarity="dark"`` for grid36): local
    threshold, runs, shape filters, centroids over a background plane; both cores (rayon),
    the GIL released;
(b) OpenCV, Otsu's threshold (``THRESH_OTSU``, ``THRESH_BINARY_INV`` for dark dots) and
    ``connectedComponentsWithStats`` (8-connected): the minimum any detector does;
(c) (b) and the grey-level moments (``cv2.moments`` of the blob's grey levels under its mask,
    over its bounding box) of every component of at least 4 pixels not touching the border:
    the same work as (a) (intensity-weighted centroids).

OpenCV uses its default threads (``cv2.getNumThreads()``). Each time is the median of
``repeats`` calls after one warm-up call; the ratio is OpenCV's time over vsinv's (above 1:
vsinv is faster). Accuracy (real images at native size, and the rendered image where the
truth is known): the distance from each vsinv dot to the centroid of OpenCV's blob under it
(grey moments with Otsu's threshold), median and max, and for rendered discs the error of
both against the drawn centres.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import cv2
import numpy as np

import vsinv

VISP = Path("/usr/share/visp-images-data/ViSP-images")
SIZES = [(1920, 1080), (4096, 3000)]


def tiled(image: np.ndarray, width: int, height: int) -> np.ndarray:
    reps = (-(-height // image.shape[0]), -(-width // image.shape[1]))
    return np.ascontiguousarray(np.tile(image, reps)[:height, :width])


def rendered(width: int, height: int, seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    u, v = np.meshgrid(np.arange(width), np.arange(height))
    canvas = (30.0 + 60.0 * (u / width) * 0.5 + 60.0 * (v / height) * 0.5).astype(np.float64)
    shift = 8
    layer = np.zeros((height, width), np.uint8)
    centres = []
    for _ in range(300):
        r = rng.uniform(5, 15)
        c = rng.uniform([r + 10, r + 10], [width - r - 10, height - r - 10])
        if centres and np.min(np.hypot(*(np.array(centres) - c).T)) < 2 * 15 + 6:
            continue
        centres.append(c)
        cv2.circle(layer, tuple(int(x) for x in np.round(c * (1 << shift))), int(round(r * (1 << shift))), 255, -1, cv2.LINE_AA, shift)
    image = canvas + (220.0 - canvas) * layer / 255.0
    image = cv2.GaussianBlur(image, (0, 0), 1.0) + rng.normal(0, 3, image.shape)
    return np.clip(np.round(image), 0, 255).astype(np.uint8), np.array(centres)


def opencv_blobs(image: np.ndarray, dark: bool, moments: bool) -> list[tuple[float, float]]:
    mode = (cv2.THRESH_BINARY_INV if dark else cv2.THRESH_BINARY) | cv2.THRESH_OTSU
    _, binary = cv2.threshold(image, 0, 255, mode)
    n, labels, stats, centroids = cv2.connectedComponentsWithStats(binary, connectivity=8)
    if not moments:
        return []
    h, w = image.shape
    out = []
    grey = 255 - image if dark else image
    for k in range(1, n):
        x, y, bw, bh, area = stats[k]
        if area < 4 or x == 0 or y == 0 or x + bw == w or y + bh == h:
            continue
        roi = grey[y : y + bh, x : x + bw] * (labels[y : y + bh, x : x + bw] == k)
        m = cv2.moments(roi)
        if m["m00"] > 0:
            out.append((x + m["m10"] / m["m00"], y + m["m01"] / m["m00"]))
    return out


def timed(f, repeats: int) -> float:
    f()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def speed(name: str, image: np.ndarray, dark: bool, repeats: int) -> None:
    polarity = "dark" if dark else "light"
    ours = timed(lambda: vsinv.detect_dots(image, polarity=polarity), repeats)
    bare = timed(lambda: opencv_blobs(image, dark, False), repeats)
    full = timed(lambda: opencv_blobs(image, dark, True), repeats)
    found = len(vsinv.detect_dots(image, polarity=polarity))
    h, w = image.shape
    print(
        f"{name:10s} {w:5d}x{h:<5d} vsinv {ours * 1e3:8.2f} ms ({found:5d} dots) | OpenCV Otsu+CC {bare * 1e3:8.2f} ms"
        f" (x{bare / ours:5.2f}) | +moments {full * 1e3:8.2f} ms (x{full / ours:5.2f})"
    )


def agreement(name: str, image: np.ndarray, dark: bool) -> None:
    ours = vsinv.detect_dots(image, polarity="dark" if dark else "light").centroids
    theirs = np.array(opencv_blobs(image, dark, True))
    if len(ours) == 0 or len(theirs) == 0:
        print(f"{name}: nothing to compare ({len(ours)} vs {len(theirs)})")
        return
    d = np.array([np.min(np.hypot(*(theirs - c).T)) for c in ours])
    d = d[d < 2.0]
    print(f"{name:24s} {len(ours):3d} vsinv dots, {len(d):3d} matched to an OpenCV blob: median {np.median(d):.3f} px, max {np.max(d):.3f} px")


def check_rendered() -> str | None:
    """Before timing: on the rendered 1920 x 1080 frame vsinv finds one dot a drawn disc, each
    within 0.5 px of the disc's centre (measured: 0.13 px at most, OpenCV's moments 0.12 px);
    what is wrong, or None."""
    image, centres = rendered(1920, 1080)
    ours = vsinv.detect_dots(image).centroids
    if len(ours) != len(centres):
        return f"rendered 1920x1080: {len(ours)} vsinv dots for {len(centres)} discs"
    worst = max(float(np.min(np.hypot(*(ours - c).T))) for c in centres)
    return f"rendered 1920x1080: a disc's centre {worst:.3f} px from vsinv's nearest dot (at most 0.5)" if worst > 0.5 else None


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="1920 x 1080 only, 5 rounds (make bench-quick)")
    args = parser.parse_args()
    repeats = 5 if args.quick else 15
    print(f"OpenCV {cv2.__version__}, {cv2.getNumThreads()} threads; ratio = OpenCV time / vsinv time")
    mismatch = check_rendered()
    if mismatch:
        print(f"MISMATCH: {mismatch}")
        return 1
    sources = []
    if VISP.is_dir():
        sources = [("mire-2", cv2.imread(str(VISP / "mire-2/image.0001.pgm"), 0), False),
                   ("grid36", cv2.imread(str(VISP / "calibration/grid36-01.pgm"), 0), True)]
    else:
        print("ViSP's images are not installed (apt-get install visp-images-data): rendered images only")
    for w, h in SIZES[:1] if args.quick else SIZES:
        for name, image, dark in sources:
            speed(name, tiled(image, w, h), dark, repeats)
        speed("rendered", rendered(w, h)[0], False, repeats)
    print("\nCentroid agreement with OpenCV's grey moments of the Otsu blob under each dot")
    for name, image, dark in sources:
        agreement(f"{name} (native size)", image, dark)
    if VISP.is_dir():
        frames = sorted((VISP / "mire-2").glob("image.*.pgm"))[::50]
        all_d = []
        for path in frames:
            image = cv2.imread(str(path), 0)
            ours = vsinv.detect_dots(image).centroids
            theirs = np.array(opencv_blobs(image, False, True))
            all_d += [float(np.min(np.hypot(*(theirs - c).T))) for c in ours]
        d = np.array(all_d)
        m = d[d < 2.0]
        print(f"mire-2 every 50th frame  {len(d)} vsinv dots, {len(m)} matched to an OpenCV blob: median {np.median(m):.3f} px,"
              f" max {np.max(m):.3f} px")
    image, centres = rendered(1920, 1080)
    ours = vsinv.detect_dots(image).centroids
    theirs = np.array(opencv_blobs(image, False, True))
    e_ours = [float(np.min(np.hypot(*(ours - c).T))) for c in centres]
    e_cv = [float(np.min(np.hypot(*(theirs - c).T))) for c in centres]
    print(f"rendered 1920x1080: {len(ours)} vsinv dots for {len(centres)} discs; error to the drawn centres:"
          f" vsinv median {np.median(e_ours):.3f} max {np.max(e_ours):.3f} px, OpenCV median {np.median(e_cv):.3f}"
          f" max {np.max(e_cv):.3f} px")
    return 0


if __name__ == "__main__":
    sys.exit(main())
