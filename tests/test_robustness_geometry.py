"""Robustness of the public Python API under hypothesis, projection, invariant points, the
interaction matrix, the Jacobians, rz coefficients and the choice of basis.

The promise and the harness are described in tests/robustness_harness.py.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import vsinv
from robustness_harness import (
    ANY, CUR_PX, CUR_Z, K, N, OBJ, RAISE, REF_PX, SAME, arrays, basis_variants, call, covers, cv2, depth_variants,
    fuzz, fuzz_settings, k_variants, manual_invariants, pixel_variants, returned,
)


# ---------------------------------------------------------------------------------------------
# geometry: project, invariant points, Jacobians


def manual_project(points: np.ndarray, k: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    h = points @ k.T
    return h[:, :2] / h[:, 2:], points[:, 2]


@covers("project")
@fuzz_settings(120)
@given(st.data())
def test_project(data: Any) -> None:
    ref = vsinv.geometry.project(OBJ, K)
    np.testing.assert_allclose(ref[0], manual_project(OBJ, K.matrix)[0], rtol=1e-14)

    def check(out: Any) -> None:
        px, z = out
        assert px.dtype == np.float64 and z.dtype == np.float64
        assert px.shape == (len(z), 2) and z.ndim == 1
        assert (z > 0).all()

    name, v, out = fuzz(data, vsinv.geometry.project, {"points": OBJ, "K": K},
                        {"points": arrays(OBJ, overrides={"negative": RAISE}), "K": k_variants()}, ref=ref, check=check)
    if returned(out) and name == "points" and v.expect != SAME:
        pts = np.asarray(v.value, dtype=float)
        mpx, mz = manual_project(pts, K.matrix)
        np.testing.assert_allclose(out[0], mpx, rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(out[1], mz, rtol=0)


@covers("project")
@fuzz_settings(60)
@given(st.lists(st.tuples(st.floats(-5, 5), st.floats(-5, 5), st.floats(-2, 5)), min_size=0, max_size=8),
       st.floats(10, 5000), st.floats(10, 5000), st.floats(-500, 500), st.floats(-500, 500))
def test_project_against_numpy_and_opencv(pts: list[tuple[float, float, float]], fu: float, fv: float, u0: float, v0: float) -> None:
    k = vsinv.Intrinsics(fu, fv, u0, v0)
    p = np.array(pts, dtype=float).reshape(-1, 3)
    out = call(vsinv.geometry.project, p, k, _names=("point", "behind"))
    if (p[:, 2] <= 1e-9).any():
        # A point at or behind the camera, or (checked first if it comes first) one so close
        # to the camera plane that its pixel overflows.
        overflow = isinstance(out, vsinv.InvalidInput) and "out of range" in str(out)
        assert isinstance(out, vsinv.DegenerateGeometry) or overflow or (p[:, 2] > 0).all(), out
        return
    assert returned(out)
    np.testing.assert_allclose(out[0], manual_project(p, k.matrix)[0], rtol=1e-12, atol=1e-6)
    if len(p):
        cv, _ = cv2.projectPoints(p, np.zeros(3), np.zeros(3), k.matrix, None)
        np.testing.assert_allclose(out[0], cv.reshape(-1, 2), rtol=1e-9, atol=1e-6)


@covers("invariant_points")
@fuzz_settings(100)
@given(st.data())
def test_invariant_points(data: Any) -> None:
    ref = vsinv.laws.invariant_points(CUR_PX)
    np.testing.assert_allclose(ref, manual_invariants(CUR_PX, (0, 1, 2)), atol=1e-10)

    def check(q: np.ndarray) -> None:
        assert q.dtype == np.float64 and q.ndim == 2 and q.shape[1] == 3
        np.testing.assert_allclose(q.sum(axis=1), 1.0, atol=1e-6)

    name, v, out = fuzz(data, vsinv.laws.invariant_points, {"pixels": CUR_PX, "basis": (0, 1, 2)},
                        {"pixels": pixel_variants(CUR_PX), "basis": basis_variants(N)}, ref=ref, rtol=1e-12, check=check)
    if returned(out) and name == "basis" and not isinstance(v.value, str):
        b = tuple(int(i) for i in v.value)
        np.testing.assert_allclose(out, manual_invariants(CUR_PX, b), atol=1e-8)


def interaction_numpy(px: np.ndarray, z: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Espiau's point interaction matrix in pixels: K[:2,:2] L(x, y, Z)."""
    h = np.linalg.solve(k, np.column_stack([px, np.ones(len(px))]).T).T
    out = []
    for (x, y, _), zz in zip(h, z):
        ln = np.array([[-1 / zz, 0, x / zz, x * y, -(1 + x * x), y], [0, -1 / zz, y / zz, 1 + y * y, -x * y, -x]])
        out.append(k[:2, :2] @ ln)
    return np.array(out)


@covers("interaction_matrix")
@fuzz_settings(100)
@given(st.data())
def test_interaction_matrix(data: Any) -> None:
    ref = vsinv.laws.interaction_matrix(CUR_PX, CUR_Z, K)
    np.testing.assert_allclose(ref, interaction_numpy(CUR_PX, CUR_Z, K.matrix), rtol=1e-9, atol=1e-9)
    fuzz(data, vsinv.laws.interaction_matrix, {"pixels": CUR_PX, "depths": CUR_Z, "K": K},
         {"pixels": pixel_variants(CUR_PX, ANY, overrides={"zero": ANY, "empty": ANY, "bool": ANY}),
          "depths": depth_variants(CUR_Z), "K": k_variants()},
         ref=ref, check=lambda L: L.shape[1:] == (2, 6) or pytest.fail(f"shape {L.shape}"))


@covers("invariant_jacobian", "jacobian_factors", "structure_ratio")
@fuzz_settings(150)
@given(st.data())
def test_jacobians(data: Any) -> None:
    which = data.draw(st.sampled_from(["invariant_jacobian", "jacobian_factors", "structure_ratio"]))
    fn = getattr(vsinv.laws, which)
    args: dict[str, Any] = {"pixels": CUR_PX, "depths": CUR_Z, "basis": (0, 1, 2)}
    strategies = {"pixels": pixel_variants(CUR_PX), "depths": depth_variants(CUR_Z), "basis": basis_variants(N)}
    if which != "jacobian_factors":
        args["K"] = K
        strategies["K"] = k_variants()
    ref = fn(**args)

    def check(out: Any) -> None:
        if which == "invariant_jacobian":
            assert out.shape[1] == 5 and out.shape[0] % 3 == 0
        elif which == "jacobian_factors":
            assert out[0].shape[1] == 3 and out[1].shape[1] == 2 and out[0].shape[0] == out[1].shape[0]
        else:
            assert 0.0 <= out <= 1.0 + 1e-12

    fuzz(data, fn, args, strategies, ref=ref, rtol=1e-12, check=check)
    if which == "invariant_jacobian":  # J = [Phi K, Psi F(K)]: the first three columns
        phi, _ = vsinv.laws.jacobian_factors(CUR_PX, CUR_Z)
        np.testing.assert_allclose(ref[:, :3], phi @ K.matrix, rtol=1e-9, atol=1e-9)


@covers("rz_coefficients")
@fuzz_settings(100)
@given(st.data())
def test_rz_coefficients(data: Any) -> None:
    args = {"pixels": CUR_PX, "depths": CUR_Z, "reference_pixels": REF_PX, "K": K, "basis": (0, 1, 2)}
    ref = vsinv.laws.rz_coefficients(**args)

    def check(out: Any) -> None:
        a, c = out
        assert isinstance(a, float) and c.shape == (5,)

    fuzz(data, vsinv.laws.rz_coefficients, args,
         {"pixels": pixel_variants(CUR_PX, ANY, overrides={"zero": ANY, "bool": ANY}), "depths": depth_variants(CUR_Z),
          "reference_pixels": pixel_variants(REF_PX),
          "K": k_variants(), "basis": basis_variants(N)}, ref=ref, rtol=1e-12, check=check)


@covers("choose_basis")
@fuzz_settings(80)
@given(st.data())
def test_choose_basis(data: Any) -> None:
    ref = vsinv.laws.choose_basis(REF_PX)

    def check(b: tuple[int, int, int]) -> None:
        assert isinstance(b, tuple) and len(b) == 3 and list(b) == sorted(set(b))

    name, v, out = fuzz(data, vsinv.laws.choose_basis, {"pixels": REF_PX}, {"pixels": pixel_variants(REF_PX, ANY)}, ref=ref, check=check)
    if returned(out):
        px = np.asarray(v.value, dtype=float)
        assert max(out) < len(px)
        # the widest triangle: no other triple is wider (brute force, n <= 12)
        h = np.column_stack([px, np.ones(len(px))])
        with np.errstate(all="ignore"):  # huge pixels overflow the determinant
            area = abs(np.linalg.det(h[list(out)]))
            best = max(abs(np.linalg.det(h[[i, j, k]])) for i in range(len(px)) for j in range(i) for k in range(j))
        assert area >= best * (1 - 1e-9) - 1e-12 or not np.isfinite(best)


@covers("choose_basis", "invariant_points")
@fuzz_settings(60)
@given(st.lists(st.tuples(st.floats(-1e4, 1e4), st.floats(-1e4, 1e4)), min_size=0, max_size=9))
def test_arbitrary_pixel_clouds(pts: list[tuple[float, float]]) -> None:
    px = np.array(pts, dtype=float).reshape(-1, 2)
    call(vsinv.laws.choose_basis, px, _names=("pixels", "points", "collinear"))
    out = call(vsinv.laws.invariant_points, px, basis="auto", _names=("pixels", "points", "collinear", "basis"))
    if returned(out):
        b = vsinv.laws.choose_basis(px)
        np.testing.assert_allclose(out, manual_invariants(px, b), rtol=1e-6, atol=1e-6)
