"""``vsinv.to_grey`` against OpenCV's ``cv2.cvtColor(..., COLOR_RGB2GRAY)``, same images, same run.

How to run (from the repository root, with the package and ``opencv-python-headless``
installed)::

    python benches/grey.py            # a few seconds
    python benches/grey.py --calls 50 # best of 50 calls instead of 200

For each size (640 x 480, 1280 x 720, 1920 x 1080) one random RGB frame is converted by both
libraries, alternately, ``--calls`` times; each cell is the best (minimum) time of one call.
OpenCV is timed twice: on one thread (``cv2.setNumThreads(1)``) and with its default thread
count; vsinv's ``to_grey`` uses its own thread count (see the ``threads`` column). The ratios are
vsinv time / OpenCV time (below 1: vsinv is faster). Both outputs are compared byte for byte
before timing.
"""

from __future__ import annotations

import argparse
import os
import time

import cv2
import numpy as np

import vsinv

SIZES = [(640, 480), (1280, 720), (1920, 1080)]


def best(f, frame: np.ndarray, calls: int) -> float:
    """The shortest of `calls` timed calls of `f(frame)`, in seconds."""
    times = []
    for _ in range(calls):
        t0 = time.perf_counter()
        f(frame)
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=200, help="calls per cell (best of them)")
    args = parser.parse_args()
    default_threads = cv2.getNumThreads()
    rng = np.random.default_rng(0)
    print(f"cores: {os.cpu_count()}, OpenCV {cv2.__version__} (default threads {default_threads})")
    print(f"{'size':>10} {'vsinv ms':>9} {'cv 1-thr ms':>12} {'ratio':>6} {'cv default ms':>14} {'ratio':>6}")
    for w, h in SIZES:
        frame = rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
        mine = lambda f: vsinv.to_grey(f)  # noqa: E731
        theirs = lambda f: cv2.cvtColor(f, cv2.COLOR_RGB2GRAY)  # noqa: E731
        if not np.array_equal(mine(frame), theirs(frame)):
            raise SystemExit(f"{w}x{h}: to_grey differs from cvtColor")
        cv2.setNumThreads(1)
        t_one = best(theirs, frame, args.calls)
        cv2.setNumThreads(default_threads)
        t_def = best(theirs, frame, args.calls)
        t_mine = best(mine, frame, args.calls)
        print(
            f"{w:>5}x{h:<4} {1e3 * t_mine:9.3f} {1e3 * t_one:12.3f} {t_mine / t_one:6.2f}"
            f" {1e3 * t_def:14.3f} {t_mine / t_def:6.2f}"
        )


if __name__ == "__main__":
    main()
