"""``vsinv.vision.to_grey`` against OpenCV's ``cv2.cvtColor``, same images, same run, on one core.

How to run (from the repository root, with the package and ``opencv-python-headless``
installed)::

    python benches/grey.py              # a few seconds; vsinv and OpenCV on one thread each
    python benches/grey.py --threads 0  # vsinv on its default pool (one thread per core)
    python benches/grey.py --calls 50   # best of 50 calls instead of 200

For each size (640 x 480, 1280 x 720, 1920 x 1080) and layout (RGB, BGR, RGBA, BGRA) one
random frame is converted by both libraries ``--calls`` times each; each cell is the best
(minimum) time of one call, output array included. OpenCV runs on one thread
(``cv2.setNumThreads(1)``); vsinv on ``--threads`` threads (default 1: ``RAYON_NUM_THREADS``,
read when vsinv's pool starts, is set before vsinv is imported). The ratio is vsinv time /
OpenCV time (below 1: vsinv is faster). Both outputs are compared byte for byte before timing.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

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
    parser.add_argument("--threads", type=int, default=1, help="vsinv's threads (0: one per core)")
    parser.add_argument("--quick", action="store_true", help="640 x 480 only, 3 calls a cell (make bench-quick)")
    args = parser.parse_args()
    sizes, calls = (SIZES[:1], 3) if args.quick else (SIZES, args.calls)
    if args.threads > 0:
        os.environ["RAYON_NUM_THREADS"] = str(args.threads)
    import cv2

    import vsinv

    cv2.setNumThreads(1)
    rng = np.random.default_rng(0)
    print(f"cores: {os.cpu_count()}, OpenCV {cv2.__version__} on 1 thread, vsinv on {args.threads or 'all'} thread(s)")
    print(f"{'size':>10} {'layout':>6} {'vsinv ms':>9} {'OpenCV ms':>10} {'ratio':>6}")
    layouts = {"RGB": (3, "rgb", cv2.COLOR_RGB2GRAY), "BGR": (3, "bgr", cv2.COLOR_BGR2GRAY),
               "RGBA": (4, "rgb", cv2.COLOR_RGBA2GRAY), "BGRA": (4, "bgr", cv2.COLOR_BGRA2GRAY)}
    for w, h in sizes:
        for name, (channels, order, code) in layouts.items():
            frame = rng.integers(0, 256, (h, w, channels), dtype=np.uint8)
            mine = lambda f: vsinv.vision.to_grey(f, order=order)  # noqa: E731
            theirs = lambda f: cv2.cvtColor(f, code)  # noqa: E731
            if not np.array_equal(mine(frame), theirs(frame)):
                raise SystemExit(f"{w}x{h} {name}: to_grey differs from cvtColor")
            t_mine, t_cv = best(mine, frame, calls), best(theirs, frame, calls)
            print(f"{w:>5}x{h:<4} {name:>6} {1e3 * t_mine:9.3f} {1e3 * t_cv:10.3f} {t_mine / t_cv:6.2f}")


if __name__ == "__main__":
    main()
