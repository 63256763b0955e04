"""Cost of one visual-servoing control step seen from Python, side by side.

For n = 6, 12, 50, 200 points this script measures, in one process:

(a) ``vsinv.laws.InvariantController(ref_pixels, K_hat).step(pixels, depths)``: the invariant
    five-dof law (eqs. 14, 17) plus the rz law (eq. 24) of Malis, INRIA RR-4309, computed
    by the Rust core;
(b) ``vsinv.laws.IbvsController(ref_pixels, K_hat).step(pixels, depths)``: classic pixel-space
    IBVS with the interaction matrix at the current points;
(c) a plain NumPy implementation of the same invariant law, written below
    (:class:`NumpyInvariantController`), vectorised over the points and using
    ``np.linalg.pinv`` as in the paper's formula.

Before timing, it checks for every n that (c) returns the same twist as (a)
(``np.allclose``, rtol 1e-6) and stops with an error otherwise.

The scene is the one of ``benches/vsinv.rs``: a grid about 0.6 m in front of the reference
camera with +-60 mm relief, the reference image taken with a 1200 px lens, the current
image with a 600 px lens from a camera translated by (0.05, -0.03, -0.08) m and rotated by
0.3 rad. Controllers are built once; only ``step`` is timed (steady state: the one-time
structure check of the first vsinv step happens during the equality check).

Each timing uses ``timeit``: ``Timer.autorange`` picks the number of calls per round (at
least 0.2 s per round), then ``repeat`` runs the rounds; the table shows the median time
per call in microseconds.

Usage::

    /tmp/venv/bin/python benches/bench_step.py [--quick] [--json results.json]

``--quick`` runs 3 rounds instead of 7; ``--json PATH`` also writes the results as JSON.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys
import timeit
from dataclasses import asdict, dataclass

import numpy as np

import vsinv

SIZES = (6, 12, 50, 200)
GAIN = 0.8
GAIN_RZ = 0.5
K_REFERENCE = (1200.0, 1200.0, 384.0, 288.0)
K_CURRENT = (600.0, 600.0, 384.0, 288.0)


# --------------------------------------------------------------------------- scene


def grid(n: int) -> tuple[int, int, float, float]:
    """Grid shape (columns, rows) and extent (width, height in metres) for n points."""
    shapes = {6: (3, 2, 0.30, 0.20), 12: (4, 3, 0.30, 0.24), 50: (10, 5, 0.36, 0.24), 200: (20, 10, 0.40, 0.30)}
    return shapes[n]


def object_points(n: int) -> np.ndarray:
    """n points on a grid centred 0.6 m in front of F*, relief in [-60, 60] mm, (n, 3)."""
    cols, rows, width, height = grid(n)
    c, r = np.meshgrid(np.arange(cols), np.arange(rows))
    x = width * (c.ravel() / (cols - 1) - 0.5)
    y = height * (r.ravel() / (rows - 1) - 0.5)
    i = np.arange(n)
    z = 0.6 + 0.06 * np.sin(1.7 * i + 0.4)
    return np.column_stack([x, y, z])


def rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues' formula."""
    k = axis / np.linalg.norm(axis)
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(angle) * kx + (1.0 - np.cos(angle)) * kx @ kx


@dataclass
class Scene:
    reference: np.ndarray  # (n, 2) reference pixels, 1200 px lens
    pixels: np.ndarray  # (n, 2) current pixels, 600 px lens
    depths: np.ndarray  # (n,) current depths
    basis: tuple[int, int, int]
    k_hat: np.ndarray  # (3, 3) estimated current intrinsics


def make_scene(n: int) -> Scene:
    obj = object_points(n)
    reference, _ = vsinv.geometry.project(obj, vsinv.Intrinsics(*K_REFERENCE))
    # Camera in F*: rotation R, centre t; camera coordinates are R^T (X - t).
    r = rotation(np.array([0.3, -0.5, 1.0]), 0.3)
    t = np.array([0.05, -0.03, -0.08])
    cam = (obj - t) @ r
    k = vsinv.Intrinsics(*K_CURRENT)
    pixels, depths = vsinv.geometry.project(np.ascontiguousarray(cam), k)
    return Scene(reference, pixels, depths, vsinv.laws.choose_basis(reference), k.matrix)


# --------------------------------------------------------------------------- NumPy law


class NumpyInvariantController:
    """The invariant control law of sec. 4 in plain NumPy (no feed-forward, still reference).

    Everything that depends only on the reference image is computed once, as vsinv does.
    Also imported by ``benches/compare.py`` (its NumPy closed loop).
    """

    def __init__(self, reference: np.ndarray, k_hat: np.ndarray, basis, gain: float = 1.0, gain_rz: float = 1.0):
        n = len(reference)
        self.basis = np.array(basis)
        self.others = np.array([i for i in range(n) if i not in basis])
        self.k2 = k_hat[:2, :2]
        self.k_inv = np.linalg.inv(k_hat)
        self.gain, self.gain_rz = gain, gain_rz
        ref_h = np.column_stack([reference, np.ones(n)])
        q_star = ref_h[self.basis].T  # Q* = [p1* p2* p3*]
        q_star_inv = np.linalg.inv(q_star)
        self.s_star = ref_h[self.others] @ q_star_inv.T  # (n-3, 3) invariant points q_k*
        self.adj_col0 = np.linalg.det(q_star) * q_star_inv[:, 0]  # adj(Q*)[:, 0]

    def pixel_interaction(self, pixels_h: np.ndarray, depths: np.ndarray) -> np.ndarray:
        """(n, 2, 6): K_hat[:2, :2] @ L(x, y, Z) with (x, y, 1) = K_hat^-1 p."""
        m = pixels_h @ self.k_inv.T
        x, y, iz = m[:, 0], m[:, 1], 1.0 / depths
        zero = np.zeros_like(x)
        L = np.stack(
            [
                np.stack([-iz, zero, x * iz, x * y, -(1.0 + x * x), y], axis=-1),
                np.stack([zero, -iz, y * iz, 1.0 + y * y, -x * y, -x], axis=-1),
            ],
            axis=1,
        )
        return self.k2 @ L

    def step(self, pixels: np.ndarray, depths: np.ndarray, visible: np.ndarray | None = None) -> np.ndarray:
        """The twist (vx, vy, vz, wx, wy, wz) of eqs. (17) and (24).

        ``visible`` (optional, (n,) bool) drops hidden non-basis points from s and J, as
        vsinv's ``step(pixels, depths, visible)`` does; the basis points must be visible.
        """
        n = len(pixels)
        others, s_star = self.others, self.s_star
        if visible is not None and not visible[others].all():
            keep = visible[others]
            others, s_star = others[keep], s_star[keep]
        p = np.column_stack([pixels, np.ones(n)])
        q_mat = p[self.basis].T  # Q = [p1 p2 p3]
        q_inv = np.linalg.inv(q_mat)
        q = p[others] @ q_inv.T  # q_k = Q^-1 p_k, (n-3, 3)
        L = self.pixel_interaction(p, depths)
        l_basis = L[self.basis]  # (3, 2, 6)
        # L_k - q1k L_1 - q2k L_2 - q3k L_3, with a zero third row, then Q^-1 (...)[:, :5].
        combined = L[others] - np.einsum("kj,jrc->krc", q, l_basis)
        combined = np.concatenate([combined, np.zeros((len(others), 1, 6))], axis=1)
        J = (q_inv @ combined)[:, :, :5].reshape(-1, 5)  # (3(m), 5), m visible non-basis points
        eps = np.linalg.pinv(J) @ (q - s_star).ravel()
        mu = -self.gain * eps
        # rz law: eps_z = sum_j adj(Q*)[j, 0] v_j, and its derivative's coefficients a, c.
        eps_z = self.adj_col0 @ pixels[self.basis, 1]
        row = self.adj_col0 @ l_basis[:, 1, :]
        a, c = row[5], row[:5]
        wz = -(self.gain_rz * eps_z + c @ mu) / a
        return np.append(mu, wz)


# --------------------------------------------------------------------------- timing


@dataclass
class Row:
    n: int
    vsinv_invariant_us: float
    vsinv_ibvs_us: float
    numpy_invariant_us: float

    @property
    def ratio(self) -> float:
        return self.numpy_invariant_us / self.vsinv_invariant_us


def median_us(fn, repeat: int) -> float:
    """Median time per call of fn() in microseconds over `repeat` autoranged rounds."""
    timer = timeit.Timer(fn)
    number, _ = timer.autorange()
    rounds = timer.repeat(repeat=repeat, number=number)
    return statistics.median(rounds) / number * 1e6


def check_same_twist(n: int, ours: np.ndarray, reference: np.ndarray) -> None:
    if not np.allclose(ours, reference, rtol=1e-6, atol=1e-12):
        raise SystemExit(
            f"MISMATCH for n = {n}: the NumPy law disagrees with vsinv\n"
            f"  numpy: {ours}\n  vsinv: {reference}\n  diff:  {ours - reference}"
        )


def run(repeat: int) -> list[Row]:
    rows = []
    for n in SIZES:
        s = make_scene(n)
        # The NumPy reference implements the paper's rz law, eq. (24): the same task here.
        inv = vsinv.laws.InvariantController(
            s.reference, s.k_hat, gain=GAIN, gain_rz=GAIN_RZ, basis=s.basis, rz_task="tau21"
        )
        ibvs = vsinv.laws.IbvsController(s.reference, s.k_hat)
        ref_np = NumpyInvariantController(s.reference, s.k_hat, s.basis, gain=GAIN, gain_rz=GAIN_RZ)
        pixels, depths = np.ascontiguousarray(s.pixels, dtype=np.float64), np.ascontiguousarray(s.depths)

        check_same_twist(n, ref_np.step(pixels, depths), inv.step(pixels, depths))
        ibvs.step(pixels, depths)

        rows.append(
            Row(
                n=n,
                vsinv_invariant_us=median_us(lambda: inv.step(pixels, depths), repeat),
                vsinv_ibvs_us=median_us(lambda: ibvs.step(pixels, depths), repeat),
                numpy_invariant_us=median_us(lambda: ref_np.step(pixels, depths), repeat),
            )
        )
    return rows


def print_table(rows: list[Row]) -> None:
    head = f"{'n':>5} {'vsinv invariant (us)':>21} {'vsinv IBVS (us)':>16} {'NumPy invariant (us)':>21} {'NumPy/vsinv':>12}"
    print(head)
    print("-" * len(head))
    for r in rows:
        print(
            f"{r.n:>5} {r.vsinv_invariant_us:>21.2f} {r.vsinv_ibvs_us:>16.2f} "
            f"{r.numpy_invariant_us:>21.2f} {r.ratio:>12.1f}"
        )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="3 timing rounds instead of 7")
    parser.add_argument("--json", metavar="PATH", help="also write the results to PATH as JSON")
    args = parser.parse_args(argv)
    repeat = 3 if args.quick else 7

    rows = run(repeat)
    print(f"all twists agree (NumPy vs vsinv, rtol 1e-6); median of {repeat} rounds per call")
    print_table(rows)

    if args.json:
        out = {
            "benchmark": "control step, Python API",
            "unit": "microseconds per call (median over rounds)",
            "rounds": repeat,
            "python": sys.version.split()[0],
            "numpy": np.__version__,
            "vsinv": vsinv.__version__,
            "machine": platform.machine(),
            "results": [{**asdict(r), "numpy_over_vsinv": r.ratio} for r in rows],
        }
        write_json(args.json, out)
    return 0


def write_json(path: str, payload: dict) -> None:
    """Write a benchmark's results as indented JSON and say so."""
    with open(path, "w", encoding="utf-8") as f:
        json.dump(payload, f, indent=2)
        f.write("\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    sys.exit(main())
