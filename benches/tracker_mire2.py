"""DotTracker against ViSP's vpDot2 on the mire-2 sequence (Debian's visp-images-data, read in
place): the same five dots from the same clicks over the same 500 frames, timed in one run.

- vsinv in Rust: `cargo bench --bench tracker_mire2` (best of 10 passes, us per frame);
- vsinv from Python: `DotTracker.track` called once per frame in a Python loop (NumPy in,
  NumPy out: what a Python user pays), best of 5 passes;
- vpDot2: benches/vpdot2/vpdot2_mire2.cpp compiled against Debian's libvisp-dev (pkg-config
  visp), best of 10 passes. Skipped with a message when ViSP or the dataset is not installed.
Prints each time per frame and the ratios vpDot2 / vsinv."""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import vsinv

MIRE2 = Path("/usr/share/visp-images-data/ViSP-images/mire-2")
ROOT = Path(__file__).resolve().parent.parent
# The clicks of benches/tracker_mire2.rs (u, v).
CLICKS = [[87.0, 181.0], [213.0, 168.0], [162.0, 210.0], [244.0, 246.0], [91.0, 268.0]]
US = re.compile(r"([0-9.]+) us/frame")
LOST = re.compile(r"frames with a lost dot: ([0-9]+)")


def rust(quick: bool) -> tuple[float | None, int | None]:
    # Quick: the release build of `cargo test --release` (no bench profile to build), one run.
    cargo = ["cargo", "test", "--release", "-q"] if quick else ["cargo", "bench", "-q"]
    out = subprocess.run(
        [*cargo, "--bench", "tracker_mire2", "--", str(MIRE2)],
        cwd=ROOT, capture_output=True, text=True, check=True,
    ).stdout
    print(out.strip())
    m, lost = US.search(out), LOST.search(out)
    return (float(m.group(1)) if m else None), (int(lost.group(1)) if lost else None)


def python_loop(passes: int) -> tuple[float, int]:
    frames = [vsinv.vision.load_image(p) for p in sorted(MIRE2.glob("image.*.pgm"))]
    best = float("inf")
    for _ in range(passes):
        tracker = vsinv.vision.DotTracker(frames[0], CLICKS)
        lost = 0
        t0 = time.perf_counter()
        for frame in frames[1:]:
            lost += int(not tracker.track(frame)[1].all())
        best = min(best, (time.perf_counter() - t0) * 1e6 / (len(frames) - 1))
    print(f"vsinv DotTracker (Python loop): {len(CLICKS)} dots, {len(frames) - 1} frames, {best:.2f} us/frame, frames with a lost dot: {lost}")
    return best, lost


def vpdot2(passes: int) -> float | None:
    if shutil.which("pkg-config") is None or subprocess.run(["pkg-config", "--exists", "visp"]).returncode != 0:
        print("vpDot2: ViSP not installed (apt-get install libvisp-dev): comparison skipped")
        return None
    flags = subprocess.run(["pkg-config", "--cflags", "--libs", "visp"], capture_output=True, text=True, check=True).stdout.split()
    with tempfile.TemporaryDirectory() as tmp:
        exe = Path(tmp) / "vpdot2_mire2"
        subprocess.run(["g++", "-O2", "-o", str(exe), str(ROOT / "benches/vpdot2/vpdot2_mire2.cpp"), *flags], check=True)
        clicks = ";".join(f"{u:g},{v:g}" for u, v in CLICKS)
        out = subprocess.run([str(exe), str(MIRE2), clicks, str(passes)], capture_output=True, text=True, check=True).stdout
    print(out.splitlines()[0])
    m = US.search(out)
    return float(m.group(1)) if m else None


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="one pass each (make bench-quick)")
    quick = parser.parse_args().quick
    if not (MIRE2 / "image.0001.pgm").is_file():
        print(f"mire-2 not found under {MIRE2} (apt-get install visp-images-data): tracker benchmark skipped")
        return 0
    (rust_us, rust_lost), peer = rust(quick), vpdot2(1 if quick else 10)
    py_us, py_lost = python_loop(1 if quick else 5)
    # The agreement: both loops follow the five dots through every frame.
    if rust_lost != 0 or py_lost != 0:
        print(f"MISMATCH: frames with a lost dot: {rust_lost} (Rust), {py_lost} (Python loop), none expected")
        return 1
    if peer is not None:
        if rust_us:
            print(f"vpDot2 / vsinv (Rust): {peer / rust_us:.2f}x")
        print(f"vpDot2 / vsinv (Python loop): {peer / py_us:.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
