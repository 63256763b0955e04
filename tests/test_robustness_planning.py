"""Robustness of the public Python API under hypothesis, plane + parallax, the invariant path,
depths from a translation and by resection.

The promise and the harness are described in tests/robustness_harness.py.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import vsinv
from robustness_harness import (
    ANY, CUR_PX, CUR_Z, FIRST_PX, FIRST_Z, INVALID, KSTAR, N, OBJ, RAISE, REF_PX, REF_Z, RETURN, SAME, TRANS_PX, V, arrays,
    basis_variants, call, covers, depth_variants, floats, fuzz, fuzz_settings, k_variants, manual_invariants, pixel_variants,
    returned,
)


# ---------------------------------------------------------------------------------------------
# planning and depths


@covers("estimate_plane_parallax", "PlaneParallax", "PlaneParallax.gamma", "PlaneParallax.epipole", "PlaneParallax.mu_e",
        "PlaneParallax.gamma_k", "PlaneParallax.residual", "PlaneParallax.candidates")
@fuzz_settings(120)
@given(st.data())
def test_plane_parallax(data: Any) -> None:
    args = {"current_pixels": CUR_PX, "reference_pixels": REF_PX, "basis": (0, 1, 2)}
    over = {"fewer": RAISE, "negative": ANY}
    digest = lambda p: (p.gamma, p.epipole, p.mu_e, p.gamma_k, p.residual)  # noqa: E731
    ref = vsinv.calibration.estimate_plane_parallax(**args)
    name, v, out = fuzz(data, vsinv.calibration.estimate_plane_parallax, args,
                        {"current_pixels": pixel_variants(CUR_PX, overrides=over),
                         "reference_pixels": pixel_variants(REF_PX, overrides=over), "basis": basis_variants(N)},
                        digest=digest, ref=ref, rtol=1e-9)
    if returned(out):
        for p in ("gamma", "epipole", "mu_e", "gamma_k", "residual", "candidates"):
            call(getattr, out, p, _api=f"PlaneParallax.{p}", _expect=RETURN)
        m = len(out.gamma_k)
        assert out.gamma.shape == (3,) and out.mu_e.shape == (m, 3) and out.candidates >= 1
        assert math.isclose(np.linalg.norm(out.epipole), 1.0, rel_tol=1e-9)


@covers("InvariantPath", "InvariantPath.duration", "InvariantPath.plane_parallax", "InvariantPath.sample")
@fuzz_settings(120)
@given(st.data())
def test_invariant_path(data: Any) -> None:
    args = {"current_pixels": CUR_PX, "reference_pixels": REF_PX, "duration": 10.0, "basis": (0, 1, 2)}
    over = {"fewer": RAISE, "negative": ANY}
    name, v, out = fuzz(data, vsinv.laws.InvariantPath, args,
                        {"current_pixels": pixel_variants(CUR_PX, overrides=over),
                         "reference_pixels": pixel_variants(REF_PX, overrides=over), "basis": basis_variants(N),
                         "duration": floats(10.0, overrides={"zero": INVALID, "negative": INVALID, "neghuge": INVALID,
                                                             "neginf": INVALID, "posinf": INVALID})},
                        api="InvariantPath", digest=lambda p: p.duration)
    path = out if returned(out) else vsinv.laws.InvariantPath(**args)
    assert call(getattr, path, "duration", _api="InvariantPath.duration") > 0
    assert isinstance(call(getattr, path, "plane_parallax", _api="InvariantPath.plane_parallax"), vsinv.calibration.PlaneParallax)
    t = data.draw(floats(5.0, overrides={"posinf": INVALID, "neginf": INVALID, "huge": ANY}), label="t")
    res = call(path.sample, t.value, _expect=RETURN if t.expect == SAME else t.expect, _names=("t",))
    if returned(res):
        q, dq = res
        assert q.shape == dq.shape == (N - 3, 3)
    if returned(out) and v.expect == SAME:  # the end of the path is the reference image
        q, _ = path.sample(path.duration)
        np.testing.assert_allclose(q, np.delete(manual_invariants(REF_PX, (0, 1, 2)), [0, 1, 2], axis=0), atol=1e-8)


@covers("depths_from_translation")
@fuzz_settings(120)
@given(st.data())
def test_depths_from_translation(data: Any) -> None:
    args = {"first_pixels": FIRST_PX, "second_pixels": TRANS_PX}
    ref = vsinv.calibration.depths_from_translation(**args)
    z, e, res = ref
    np.testing.assert_allclose(z / z.mean(), FIRST_Z / FIRST_Z.mean(), rtol=1e-6)
    over = {"fewer": RAISE, "negative": ANY, "zero": ANY, "bool": ANY}

    def check(out: Any) -> None:
        z, e, r = out
        assert z.shape == (len(z),) and e.shape == (3,) and (z > 0).all() and r >= 0

    fuzz(data, vsinv.calibration.depths_from_translation, args,
         {"first_pixels": pixel_variants(FIRST_PX, ANY, overrides=over), "second_pixels": pixel_variants(TRANS_PX, ANY, overrides=over)},
         ref=ref, rtol=1e-9, check=check)


@covers("reference_depths")
@fuzz_settings(120)
@given(st.data())
def test_reference_depths(data: Any) -> None:
    # The object in its own frame (any), seen in the reference view: its depths there.
    model = OBJ - OBJ.mean(axis=0)
    args = {"object_points": model, "reference_pixels": REF_PX, "K": None}
    ref = vsinv.calibration.reference_depths(**args)
    np.testing.assert_allclose(ref, REF_Z, rtol=1e-9)
    over = {"fewer": RAISE, "negative": ANY, "zero": RAISE, "bool": RAISE}
    # K=None is the DLT resection (the reference): the variants' own None is no invalid K here.
    ks = st.one_of(st.just(V(None, SAME, "none")), k_variants(KSTAR).map(
        lambda v: V(v.value, SAME if v.value is None else ANY if v.expect == SAME else v.expect, v.label)))
    fuzz(data, vsinv.calibration.reference_depths, args,
         {"object_points": arrays(model, overrides=over), "reference_pixels": pixel_variants(REF_PX, ANY, overrides=over), "K": ks},
         ref=ref, rtol=1e-9, check=lambda z: None if (z > 0).all() else pytest.fail(f"a depth <= 0 returned: {z}"))


@covers("ResectionDepths", "ResectionDepths.estimate")
@fuzz_settings(150)
@given(st.data())
def test_resection_depths(data: Any) -> None:
    rz = FIRST_Z / FIRST_Z.mean()
    args = {"first_pixels": FIRST_PX, "first_depths": rz, "reference_pixels": REF_PX, "reference_mean_depth": 1.0}
    over = {"fewer": RAISE, "negative": ANY}
    name, v, out = fuzz(data, vsinv.calibration.ResectionDepths, args,
                        {"first_pixels": pixel_variants(FIRST_PX, ANY, overrides=over), "first_depths": depth_variants(rz, {"nan": ANY}),  # NaN: no usable depth there
                         "reference_pixels": pixel_variants(REF_PX, ANY, overrides=over),
                         "reference_mean_depth": floats(1.0, overrides={"zero": INVALID, "negative": INVALID,
                                                                        "neghuge": INVALID, "neginf": INVALID,
                                                                        "posinf": INVALID})},
                        api="ResectionDepths", names={"first_depths": ("first_depths", "depths", "point")})
    est = vsinv.calibration.ResectionDepths(**args)
    ref = est.estimate(CUR_PX)
    np.testing.assert_allclose(ref / ref.mean(), CUR_Z / CUR_Z.mean(), rtol=1e-6)
    ones = np.ones(N, bool)
    fuzz(data, est.estimate, {"pixels": CUR_PX, "visible": None},
         {"pixels": pixel_variants(CUR_PX, ANY, overrides={"fewer": INVALID, "empty": INVALID}),
          "visible": st.sampled_from([V(None, SAME, "none"), V(ones.tolist(), SAME, "list"), V(ones, SAME, "array"),
                                      V(np.ones(2 * N, bool)[::2], SAME, "strided"), V(ones[:5], INVALID, "short"),
                                      V(np.arange(N) < 3, RAISE, "three"), V("abc", INVALID, "str"),
                                      V(np.ones(N, int), INVALID, "int")])},
         ref=ref, rtol=1e-6, check=lambda z: z.shape == (N,) or pytest.fail(str(z.shape)))
