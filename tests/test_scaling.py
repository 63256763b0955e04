"""Scaling: every function whose cost grows with its input (points, image size) either answers
within a generous bound or refuses quickly with InvalidInput naming the argument. The bounds
are hang tests, not benchmarks (benches/ measures speed): each case runs in a subprocess
that is killed after a few seconds, so a hang fails the test instead of stalling the suite.
The complexities are documented in docs/reference/files-and-limits.md ("Input size: costs and limits")."""

import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest

import vsinv

N = 200_000  # object points / pixels of the large cases
SETUP = f"""
import numpy as np, vsinv
N = {N}
rng = np.random.default_rng(1)
K = vsinv.Intrinsics(800.0, 800.0, 320.0, 240.0)
px = rng.uniform(0, 640, (N, 2))
z = rng.uniform(0.5, 1.5, N)
px2 = px + rng.normal(0, 1, (N, 2))
pts = np.c_[rng.uniform(-0.3, 0.3, (N, 2)), rng.uniform(0.5, 1.0, N)]
"""

# Each case: the call, the bound in seconds, and the error it must raise (None: it answers).
CASES = {
    "choose_basis 10^6": ("vsinv.laws.choose_basis(rng.uniform(0, 640, (10**6, 2)))", None),
    "invariant_points auto": ("vsinv.laws.invariant_points(px, 'auto')", None),
    "invariant_jacobian auto": ("vsinv.laws.invariant_jacobian(px, z, K, 'auto')", None),
    "jacobian_factors auto": ("vsinv.laws.jacobian_factors(px, z, 'auto')", None),
    "structure_ratio auto": ("vsinv.laws.structure_ratio(px, z, K, 'auto')", None),
    "rz_coefficients auto": ("vsinv.laws.rz_coefficients(px2, z, px, K, 'auto')", None),
    "interaction_matrix": ("vsinv.laws.interaction_matrix(px, z, K)", None),
    "project": ("vsinv.geometry.project(pts, K)", None),
    "distort_points": ("vsinv.vision.distort_points(px, K, [0.1, 0.01, 0.001, 0.001])", None),
    "undistort_points": ("vsinv.vision.undistort_points(px, K, [0.1, 0.01, 0.001, 0.001])", None),
    "estimate_plane_parallax auto": ("vsinv.calibration.estimate_plane_parallax(px2, px, 'auto')", None),
    "InvariantPath auto": ("vsinv.laws.InvariantPath(px2, px, 1.0, 'auto').sample(0.5)", None),
    "depths_from_translation": ("vsinv.calibration.depths_from_translation(px * 1.01 - 3.2, px)", None),
    "ResectionDepths": ("vsinv.calibration.ResectionDepths(px2, z, px).estimate(px2)", None),
    "InvariantController auto + step": ("vsinv.laws.InvariantController(px, K, basis='auto').step(px2, z)", None),
    "IbvsController step": ("vsinv.laws.IbvsController(px, K).step(px2, z)", None),
    "detect_dots 8000x8000": (
        "img = np.zeros((8000, 8000), np.uint8); img[::97, ::89] = 255; vsinv.vision.detect_dots(img)",
        None,
    ),
    "DotTracker 8000x8000": (
        "img = np.zeros((8000, 8000), np.uint8); img[100:104, 100:104] = 255; img[7000:7004, 7000:7004] = 255\n"
        "vsinv.vision.DotTracker(img, [[101.0, 101.0], [7001.0, 7001.0]]).track(img)",
        None,
    ),
    "render 20000x20000": (
        "s = vsinv.load_scenario('vision-12-12').to_dict()\n"
        "s['camera'] = dict(s['camera'], width=20000, height=20000)\n"
        "vsinv.vision.render(s)",
        "camera.width",  # refused when the scenario loads (issue 28)
    ),
    "run_scenario 20000x20000 image": (
        "s = vsinv.load_scenario('vision-12-12').to_dict()\n"
        "for cam in ('camera', 'reference_camera'):\n"
        "    s[cam] = dict(s[cam], width=20000, height=20000)\n"
        "vsinv.run_scenario(s, record=False)",
        "camera.width",
    ),
    "run_scenario 200,000 points, basis auto": (
        "s = vsinv.load_scenario('lens-12-6').to_dict()\n"
        "obj = np.c_[rng.uniform(-0.1, 0.1, (N, 2)), rng.uniform(0.55, 0.65, N)]\n"
        "s['object'] = {'points': obj.tolist()}\n"
        "s.pop('basis', None)\n"
        "s['stop'] = dict(s.get('stop', {}), max_iterations=3)\n"
        "vsinv.run_scenario(s, record=False)",
        "object.points",  # at most 10,000 (issue 28)
    ),
    "run_scenario 10,000 points, basis auto": (
        "s = vsinv.load_scenario('lens-12-6').to_dict()\n"
        "obj = np.c_[rng.uniform(-0.1, 0.1, (10_000, 2)), rng.uniform(0.55, 0.65, 10_000)]\n"
        "s['object'] = {'points': obj.tolist()}\n"
        "s.pop('basis', None)\n"
        "s['stop'] = dict(s.get('stop', {}), max_iterations=3)\n"
        "vsinv.run_scenario(s, record=False)",
        None,
    ),
}
BOUND_S = 20.0  # generous: a shared CI machine; every case takes under 2 s here


def run_case(code: str, expect_error: str | None) -> tuple[float, str]:
    script = SETUP + textwrap.dedent(f"""
import time
t = time.perf_counter()
try:
{textwrap.indent(code, "    ")}
    outcome = "ok"
except vsinv.InvalidInput as e:
    outcome = "InvalidInput: " + str(e)
except Exception as e:
    outcome = type(e).__name__ + ": " + str(e)
print(time.perf_counter() - t)
print(outcome[:400])
""")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=BOUND_S + 30)
    assert done.returncode == 0, done.stderr[-2000:]
    elapsed, outcome = done.stdout.strip().split("\n", 1)
    return float(elapsed), outcome


@pytest.mark.parametrize("name", list(CASES))
def test_large_input_answers_or_is_refused_quickly(name: str) -> None:
    code, expect_error = CASES[name]
    elapsed, outcome = run_case(code, expect_error)
    assert elapsed < BOUND_S, f"{name}: {elapsed:.1f} s"
    if expect_error is None:
        assert outcome == "ok", f"{name}: {outcome}"
    else:
        assert outcome.startswith("InvalidInput") and expect_error in outcome, f"{name}: {outcome}"


def test_a_huge_convex_hull_is_refused_naming_the_argument_and_the_limit() -> None:
    t = np.linspace(0, 2 * np.pi, 10**6, endpoint=False)
    circle = np.c_[320 + 200 * np.cos(t), 240 + 200 * np.sin(t)]
    start = time.perf_counter()
    with pytest.raises(vsinv.InvalidInput, match=r"pixels.*10000"):
        vsinv.laws.choose_basis(circle)
    assert time.perf_counter() - start < 5.0


def test_auto_basis_validates_the_other_arguments_before_searching() -> None:
    # 10^6 points on a circle: the search would be refused as too large, so an error naming
    # the other argument shows that it was checked first.
    t = np.linspace(0, 2 * np.pi, 10**6, endpoint=False)
    circle = np.c_[320 + 200 * np.cos(t), 240 + 200 * np.sin(t)]
    k = vsinv.Intrinsics(800.0, 800.0, 320.0, 240.0)
    depths = np.ones(len(circle))
    calls = {
        "depths": lambda: vsinv.laws.invariant_jacobian(circle, depths[:-1], k, "auto"),
        "depth -1": lambda: vsinv.laws.jacobian_factors(circle, -depths, "auto"),
        "depth": lambda: vsinv.laws.structure_ratio(circle, depths[:5], k, "auto"),
        "reference_pixels": lambda: vsinv.laws.rz_coefficients(circle, depths, circle[:-1], k, "auto"),
        "gain": lambda: vsinv.laws.InvariantController(circle, k, gain=-1.0, basis="auto"),
        "path duration": lambda: vsinv.laws.InvariantPath(circle, circle, -1.0, "auto"),
        "current_pixels": lambda: vsinv.calibration.estimate_plane_parallax(circle[:-1], circle, "auto"),
    }
    for name, call in calls.items():
        with pytest.raises(vsinv.VsinvError) as err:
            call()
        assert "convex-hull" not in str(err.value), f"{name}: searched first: {err.value}"
        assert name.strip() in str(err.value), f"{name}: {err.value}"


def exhaustive_basis(px: np.ndarray) -> tuple[int, int, int]:
    """The first (i, j, k), i < j < k, in lexicographic order among those of largest area,
    areas by the exhaustive search's expression (NumPy, O(n^3) work in O(n^2) memory)."""
    i, j = np.triu_indices(len(px), 1)
    a, b = px[i], px[j]
    per_k = []
    for k in range(len(px)):
        c = px[k]
        area = np.abs((b[:, 0] - a[:, 0]) * (c[1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[0] - a[:, 0]))
        per_k.append(np.where(j < k, area, -1.0))
    areas = np.stack(per_k)  # (k, pair)
    ks, pairs = np.nonzero(areas == areas.max())
    return min((int(i[p]), int(j[p]), int(k)) for k, p in zip(ks, pairs))


def test_the_widest_triangle_matches_the_exhaustive_search_through_the_api() -> None:
    # Above the exhaustive threshold (200 points), random and integer (tied) pixels.
    rng = np.random.default_rng(4)
    sets = [rng.uniform(0, 640, (250, 2)), rng.integers(0, 8, (300, 2)).astype(float), rng.normal(300, 50, (260, 2))]
    for px in sets:
        assert vsinv.laws.choose_basis(px) == exhaustive_basis(px)


def test_a_long_search_releases_the_gil() -> None:
    rng = np.random.default_rng(2)
    px = rng.uniform(0, 640, (2 * 10**6, 2))
    span: dict[str, float] = {}

    def search() -> None:
        span["start"] = time.perf_counter()
        vsinv.laws.choose_basis(px)
        span["end"] = time.perf_counter()

    worker = threading.Thread(target=search)
    ticks = []
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
        time.sleep(0.001)
    worker.join()
    during = [t for t in ticks if span["start"] < t < span["end"]]
    # The main thread ran while the search did (with the GIL held it could not tick at all).
    assert len(during) >= 5, f"{len(during)} ticks during a {span['end'] - span['start']:.2f} s search"


def _urdf(chain: int, extra_links: int) -> str:
    """A serial arm of `chain` revolute joints along x, plus `extra_links` fixed links hanging off
    its base (a large file whose chain stays short)."""
    links = ['<link name="base"/>'] + [f'<link name="l{i}"/>' for i in range(chain)]
    joints = [
        f'<joint name="j{i}" type="revolute"><parent link="{"base" if i == 0 else f"l{i - 1}"}"/>'
        f'<child link="l{i}"/><origin xyz="{0.3 / chain:.6f} 0 0" rpy="0 0 0"/><axis xyz="0 {i % 2} {(i + 1) % 2}"/>'
        f'<limit lower="-3.1" upper="3.1" velocity="2.0" effort="10"/></joint>'
        for i in range(chain)
    ]
    links += [f'<link name="x{i}"/>' for i in range(extra_links)]
    joints += [
        f'<joint name="f{i}" type="fixed"><parent link="base"/><child link="x{i}"/></joint>' for i in range(extra_links)
    ]
    return '<robot name="big">' + "".join(links + joints) + "</robot>"


@pytest.mark.parametrize("chain, extra_links", [(6, 20_000), (2_000, 0)])
def test_large_urdf_answers_or_is_refused_quickly(tmp_path, chain: int, extra_links: int) -> None:
    # Cost: parsing is linear in the file (at most 8 MiB), a step linear in the chain's joints.
    (tmp_path / "big.urdf").write_text(_urdf(chain, extra_links))
    code = (
        f"import os; os.chdir({str(tmp_path)!r})\n"
        "s = vsinv.load_scenario('arm-ur5-12-6').to_dict()\n"
        f"s['robot'] = {{'kind': 'urdf', 'urdf': 'big.urdf', 'end_effector': 'l{chain - 1}', 'joints': [10.0] * {chain}}}\n"
        "s['stop'] = dict(s['stop'], max_iterations=3)\n"
        "vsinv.run_scenario(s, record=False)"
    )
    elapsed, outcome = run_case(code, None)
    assert elapsed < BOUND_S, f"{chain} joints, {extra_links} links: {elapsed:.1f} s"
    assert outcome == "ok" or outcome.startswith("InvalidInput"), outcome
