"""Issue 28's attack re-run as a set: each case of its text (the seven numbered findings and the
smaller ones) in a child process under a 6 GiB address-space cap and a 30 s timeout, one row
per case: the case, its outcome (the exception's class and the first line of its message,
``returned ...`` with what it returned, ``exit N`` when the child died, ``timeout``), the wall
time and the peak resident size of the child (``resource.getrusage(RUSAGE_CHILDREN)``, each case
alone in its child).

How to run (from the repository root, with the package installed)::

    python benches/hostile_rerun.py                 # about five minutes
    python benches/hostile_rerun.py --only tags     # the cases whose name holds "tags"
    python benches/hostile_rerun.py --json out.json # also write the rows as JSON

The hostile files are made in a temporary folder, removed afterwards (never committed).
"""

from __future__ import annotations

import argparse
import json
import struct
import subprocess
import sys
import tempfile
import zlib
from pathlib import Path

CAP = 6 << 30
TIMEOUT_S = 30.0

# The child: runs the case's code and prints the last expression's summary.
CHILD = """
import json, sys
import numpy as np
import vsinv
ns = {"vsinv": vsinv, "np": np}
try:
    exec(compile(sys.argv[1], "case", "exec"), ns)
    out = "returned " + str(ns.get("result", ""))[:120]
except BaseException as e:
    lines = str(e).strip().splitlines() or [""]
    out = f"{type(e).__name__}: {lines[0][:160]}"
print(json.dumps(out))
"""


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def _png(width: int, height: int, rows: bytes, extra: tuple[bytes, ...] = ()) -> bytes:
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", ihdr) + b"".join(extra) + _chunk(b"IDAT", rows) + _chunk(b"IEND", b"")


def stripes_png(side: int) -> bytes:
    """`side x side` one-pixel vertical stripes (about 270 KB for 16000)."""
    z = zlib.compressobj(6)
    first = b"\x00" + bytes([0, 255]) * (side // 2) + bytes(side % 2)
    up = b"\x02" + bytes(side)
    return _png(side, side, b"".join([z.compress(first)] + [z.compress(up) for _ in range(side - 1)]) + z.flush())


def iccp_bomb_png(inflated: int) -> bytes:
    """A 16 x 16 PNG whose colour profile (iCCP) inflates to `inflated` bytes."""
    z = zlib.compressobj(9)
    block = bytes(1 << 20)
    bomb = b"".join(z.compress(block) for _ in range(inflated >> 20)) + z.flush()
    rows = b"".join(b"\x00" + bytes(range(16 * v, 16 * v + 16)) for v in range(16))
    return _png(16, 16, zlib.compress(rows), (_chunk(b"iCCP", b"icc\x00\x00" + bomb),))


def nested_urdf(levels: int) -> str:
    return f'<?xml version="1.0"?>\n<robot name="r"><link name="base">{"<x>" * levels}{"</x>" * levels}</link></robot>\n'


ARM = "d = vsinv.load_scenario('arm-ur5-12-6').to_dict(); d['robot']['end_effector'] = 'tool0'\n"
LARGE = "img = np.zeros((16000, 16000), np.uint8); img[0, 0] = 255\n"
HUGE = "big = np.broadcast_to(np.uint8(0), (40000, 40000))\n"
POINTS = (
    "rng = np.random.default_rng(0)\n"
    "def pts(n): return np.column_stack([rng.uniform(-.15, .15, n), rng.uniform(-.12, .12, n), rng.uniform(.54, .66, n)])\n"
)
# A 1920 x 1080 frame of 7,973 small tag16h5 tags (30 ids), and one of 4,700 dark squares.
CLUTTER = """
import cv2
def field(family, side, gap, ids):
    d = cv2.aruco.getPredefinedDictionary({"tag16h5": cv2.aruco.DICT_APRILTAG_16h5, "tag36h11": cv2.aruco.DICT_APRILTAG_36h11}[family])
    img = np.full((1080, 1920), 220, np.uint8); k = 0
    for y in range(gap, 1080 - side - gap, side + gap):
        for x in range(gap, 1920 - side - gap, side + gap):
            img[y:y + side, x:x + side] = np.where(cv2.aruco.generateImageMarker(d, k % ids, side) > 0, 220, 30); k += 1
    return img
def squares():
    rng = np.random.default_rng(0); img = np.full((1080, 1920), 220, np.uint8)
    for y in range(4, 1060, 20):
        for x in range(4, 1900, 20):
            s = 12 + rng.integers(-3, 4); dx, dy = rng.integers(0, 4, 2); img[y+dy:y+dy+s, x+dx:x+dx+s] = 30
    return img
def timed(img, family):
    import time
    t = time.perf_counter(); r = vsinv.vision.detect_tags(img, family); return f"{len(r)} tags in {time.perf_counter() - t:.2f} s, stopped_early={r.stopped_early}"
"""
THREADS = """
import threading
sc = vsinv.load_scenario("vision-12-6")
ref, ref_px, _ = vsinv.vision.render_view(sc, reference=True)
start, start_px, _ = vsinv.vision.render_view(sc)
k = vsinv.Intrinsics(648.0, 570.0, 427.0, 304.0)
z = [0.60, 0.66, 0.56, 0.63, 0.54, 0.65, 0.62, 0.57, 0.64, 0.55, 0.61, 0.66]
servo = vsinv.ImageServo(ref, "dots", k, reference_points=ref_px, first_points=start_px, reference_depths=z, stop={"max_iterations": 10**6})
errors = {}
def work():
    for _ in range(100):
        try:
            servo.step(start)
        except Exception as e:
            errors[type(e).__name__] = errors.get(type(e).__name__, 0) + 1
ts = [threading.Thread(target=work) for _ in range(8)]
[t.start() for t in ts]; [t.join() for t in ts]
result = f"800 calls, errors {errors}"
"""


def cases(folder: Path) -> dict[str, str]:
    (folder / "stripes16000.png").write_bytes(stripes_png(16_000))
    (folder / "iccp500M.png").write_bytes(iccp_bomb_png(500 << 20))
    for levels in (20_000, 200_000):
        (folder / f"deep{levels}.urdf").write_text(nested_urdf(levels))
    toml = "object.points = [" + "[0.1, 0.2, 1.0]," * 2_000_000 + "]\n"
    (folder / "points2e6.toml").write_text(toml)
    c = {
        "1 detect_tags 16000^2 stripes PNG, decimation=1": "img = vsinv.vision.load_image('stripes16000.png'); result = vsinv.vision.detect_tags(img, decimation=1)",
        "1 detect_tags 16000^2 stripes PNG, default": "img = vsinv.vision.load_image('stripes16000.png'); result = vsinv.vision.detect_tags(img)",
        "1 detect_tags 40000^2 zero-stride view": HUGE + "result = vsinv.vision.detect_tags(big)",
        "1 detect_tags 14000^2 noise, default": "img = np.random.default_rng(0).integers(0, 256, (14000, 14000), dtype=np.uint8); result = vsinv.vision.detect_tags(img)",
        "2 URDF 20,000 levels, load_scenario": ARM + "d['robot']['urdf'] = 'deep20000.urdf'; result = vsinv.load_scenario(d)",
        "2 URDF 200,000 levels, load_scenario": ARM + "d['robot']['urdf'] = 'deep200000.urdf'; result = vsinv.load_scenario(d)",
        "3 max_iterations=1e7, recording on, rule never met": (
            "d = vsinv.load_scenario('lens-12-6').to_dict()\n"
            "d['stop'].update(max_iterations=10_000_000, pixel_error=1e-9, invariant_error=1e-12, tau21=1e-12)\n"
            "d['noise'].update(pixel_sigma=1.0); r = vsinv.run_scenario(d); result = r.summary['status']"
        ),
        "4 iCCP bomb (500 MB profile), load_image": "result = vsinv.vision.load_image('iccp500M.png').shape",
        "5 ImageServo shared by 8 threads, 800 calls": THREADS,
        "6 vision scenario, 20000x20000 camera": "d = vsinv.load_scenario('vision-12-6').to_dict(); d['camera'].update(width=20000, height=20000); result = vsinv.run_scenario(d).summary['status']",
        "6 tag rig with a 1e-9 m tag": "d = vsinv.load_scenario('tags-12-6').to_dict()\nfor t in d['object']['tags']: t['size'] = 1e-9\nresult = vsinv.run_scenario(d).summary['status']",
        "7 1e6 object points, 3 iterations": POINTS + "d = vsinv.load_scenario('lens-12-6').to_dict(); d['object']['points'] = pts(1_000_000); d['stop']['max_iterations'] = 3; result = vsinv.run_scenario(d).summary['status']",
        "7 1e5 points, vision scenario": POINTS + "d = vsinv.load_scenario('vision-12-6').to_dict(); d['object']['points'] = pts(100_000); result = vsinv.run_scenario(d).summary['status']",
        "7 TOML string, 2e6 points, missing field": "result = vsinv.sim.Scenario.from_toml(open('points2e6.toml').read())",
        "7 run_batch of 1e5 one-iteration scenarios": (
            "d = vsinv.load_scenario('lens-12-6').to_dict(); d['stop']['max_iterations'] = 1\n"
            "t = vsinv.sim.run_batch([d] * 100_000, progress=False); result = f\"{len(t['status'])} rows\""
        ),
        "7 detect_dots 40000^2": HUGE + "result = vsinv.vision.detect_dots(big)",
        "7 DotTracker 40000^2": HUGE + "result = vsinv.vision.DotTracker(big, np.array([[20000.0, 20000.0]]))",
        "7 DotTracker 16000^2 blank": LARGE + "result = vsinv.vision.DotTracker(img, np.array([[8000.0, 8000.0]]))",
        "7 DotTracker 16000^2 blank, polarity auto": LARGE + "result = vsinv.vision.DotTracker(img, np.array([[8000.0, 8000.0]]), polarity='auto')",
        "7 DotTracker 16000^2 blank, 50 clicks": LARGE + "result = vsinv.vision.DotTracker(img, np.full((50, 2), 4000.0) + np.arange(50)[:, None] * 150)",
        "7 detect_dots 16000^2 blank": LARGE + "result = vsinv.vision.detect_dots(img)",
        "7 detect_tags cluttered: 7,973 tag16h5 tags": CLUTTER + "result = timed(field('tag16h5', 12, 4, 30), 'tag16h5')",
        "7 detect_tags cluttered: 2,205 tag36h11 tags": CLUTTER + "result = timed(field('tag36h11', 24, 6, 587), 'tag36h11')",
        "7 detect_tags cluttered: 4,700 dark squares": CLUTTER + "result = timed(squares(), 'tag36h11')",
        "s fk with a joint of 1e300": "result = vsinv.kinematics.fk('ur5', [1e300, -1.2, 1.0, -0.5, 1.4, 0.3])",
        "s a verdict is final": (
            "sc = vsinv.load_scenario('lens-12-12'); _, ref, _ = vsinv.vision.render_view(sc, reference=True)\n"
            "z = np.array(sc.to_dict()['object']['points'])[:, 2]\n"
            "s = vsinv.Servo(ref, vsinv.Intrinsics(1200.0, 1200.0, 416.0, 312.0), reference_depths=z)\n"
            "v = [s.step(ref + np.random.default_rng(i).normal(0, 1e-3, ref.shape)).verdict for i in range(60)]\n"
            "result = sorted(set(v[v.index('converged'):]))"
        ),
        "s blank first frame, ImageServo.step": (
            "sc = vsinv.load_scenario('vision-12-6'); ref, ref_px, _ = vsinv.vision.render_view(sc, reference=True); start, start_px, _ = vsinv.vision.render_view(sc)\n"
            "s = vsinv.ImageServo(ref, 'dots', vsinv.Intrinsics(648.0, 570.0, 427.0, 304.0), reference_points=ref_px, first_points=start_px, reference_depths=[0.6] * 12)\n"
            "result = s.step(np.zeros_like(start)).verdict"
        ),
        "s NumPy scalars in a scenario dict": "d = vsinv.load_scenario('lens-12-6').to_dict(); d['control']['gain'] = np.float32(1); d['stop']['max_iterations'] = np.int64(5); result = vsinv.run_scenario(d).summary['status']",
        "s undistort_points tol=0": "dist = vsinv.vision.Distortion([-0.3, 0.1, 0.0, 0.0]); result = vsinv.vision.undistort_points(np.array([[100.0, 50.0]]), vsinv.Intrinsics(800.0, 800.0, 320.0, 240.0), dist, tol=0.0, max_iter=10**9)",
    }
    return c


# The launcher: one per case, so that its children's peak RSS (getrusage) is the case's alone.
LAUNCHER = """
import json, resource, subprocess, sys, time
def limit():
    resource.setrlimit(resource.RLIMIT_AS, ({cap}, {cap}))
t = time.perf_counter()
try:
    proc = subprocess.run([sys.executable, "-c", sys.argv[1], sys.argv[2]], capture_output=True, text=True,
                          timeout={timeout}, preexec_fn=limit)
    lines = proc.stdout.strip().splitlines()
    if proc.returncode == 0 and lines:
        outcome = json.loads(lines[-1])
    else:
        outcome = f"exit {{proc.returncode}}: " + (proc.stderr.strip().splitlines() or [""])[-1][:120]
except subprocess.TimeoutExpired:
    outcome = "timeout (> {timeout:.0f} s)"
wall = time.perf_counter() - t
print(json.dumps([outcome, wall, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0]))
"""


def run_case(code: str, folder: Path) -> tuple[str, float, float]:
    """The case's outcome, wall seconds and peak RSS (MiB) in a fresh child."""
    launcher = LAUNCHER.format(cap=CAP, timeout=TIMEOUT_S)
    proc = subprocess.run([sys.executable, "-c", launcher, CHILD, code], cwd=folder, capture_output=True,
                          text=True, timeout=TIMEOUT_S + 60)
    outcome, wall, peak = json.loads(proc.stdout.strip().splitlines()[-1])
    return outcome, wall, peak


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", default="")
    parser.add_argument("--json")
    parser.add_argument("--quick", action="store_true", help="the first case only (make bench-quick)")
    args = parser.parse_args()
    rows = []
    print("| case | outcome | wall s | peak RSS MiB |\n|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for name, code in cases(folder).items():
            if args.only not in name:
                continue
            outcome, wall, peak = run_case(code, folder)
            rows.append({"case": name, "outcome": outcome, "wall_s": round(wall, 2), "peak_rss_mib": round(peak, 1)})
            print(f"| {name} | {outcome} | {wall:.2f} | {peak:.0f} |", flush=True)
            if args.quick:
                break
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
