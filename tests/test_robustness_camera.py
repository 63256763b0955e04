"""Robustness of the public Python API under hypothesis, Intrinsics, Distortion, distort/undistort
and calibration files.

The promise and the harness are described in tests/robustness_harness.py.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import vsinv
from robustness_harness import (
    ANY, CUR_PX, INVALID, K, RAISE, RETURN, SAME, TYPE, V, arrays, call, covers, cv2, floats, fuzz, fuzz_settings,
    ints, k_variants, mutated_text, returned,
)


# ---------------------------------------------------------------------------------------------
# Intrinsics, Distortion and lenses


@covers("Intrinsics", "Intrinsics.from_matrix", "Intrinsics.fku", "Intrinsics.fkv", "Intrinsics.u0", "Intrinsics.v0",
        "Intrinsics.skew", "Intrinsics.matrix")
@fuzz_settings(150)
@given(st.data())
def test_intrinsics(data: Any) -> None:
    args = {"fku": 600.0, "fkv": 580.0, "u0": 384.0, "v0": 288.0, "skew": 1.5}
    ref = vsinv.Intrinsics(**args)
    strategies = {k: floats(v) for k, v in args.items()}
    name, v, out = fuzz(data, vsinv.Intrinsics, args, strategies, api="Intrinsics",
                        digest=lambda k: (k.fku, k.fkv, k.u0, k.v0, k.skew))
    if returned(out):
        k = out
        vals = [call(getattr, k, p, _api=f"Intrinsics.{p}") for p in ("fku", "fkv", "u0", "v0", "skew")]
        m = call(getattr, k, "matrix", _api="Intrinsics.matrix")
        fku, fkv, u0, v0, th = vals
        expect = np.array([[fku, -fku / math.tan(th), u0], [0, fkv / math.sin(th), v0], [0, 0, 1]])
        np.testing.assert_allclose(m, expect, rtol=1e-9, atol=1e-9 * max(1.0, abs(fku)))
        back = call(vsinv.Intrinsics.from_matrix, m, _api="Intrinsics.from_matrix", _names=("K",))
        if returned(back):
            np.testing.assert_allclose(back.matrix, m, rtol=1e-9, atol=1e-9 * abs(m).max())
        assert k == vsinv.Intrinsics(fku, fkv, u0, v0, th)
    # from_matrix on every variant of K
    kv = data.draw(k_variants(ref), label="from_matrix")
    if not isinstance(kv.value, vsinv.Intrinsics):
        out = call(vsinv.Intrinsics.from_matrix, kv.value, _api="Intrinsics.from_matrix", _expect=kv.expect,
                   _names=("K",), _where=kv.where)
        if kv.expect == SAME:
            assert out == ref


DIST = np.array([-0.3125, 0.109375, 0.00125, -0.0009765625, -0.015625])
DIST8 = np.array([0.1, -0.05, 0.001, -0.002, 0.01, 0.05, -0.01, 0.002])


def dist_variants() -> st.SearchStrategy[V]:
    bad_lengths = [V(np.zeros(3), INVALID, "3 coefficients"), V(np.zeros(6), INVALID, "6"), V(np.zeros(14), INVALID, "14")]
    return st.one_of(
        st.just(V(vsinv.vision.Distortion(DIST), SAME, "Distortion")),
        arrays(DIST, overrides={"lead_axis": SAME, "extra_axis": SAME, "fewer": ANY, "empty": INVALID, "bool": ANY},
               skip=("object_float",)),
        st.sampled_from(bad_lengths),
    )


@covers("Distortion", "Distortion.model", "Distortion.coefficients")
@fuzz_settings(120)
@given(st.data())
def test_distortion(data: Any) -> None:
    ref = vsinv.vision.Distortion(DIST)
    coeff = data.draw(st.sampled_from([DIST, DIST8, DIST[:4]]))
    model = data.draw(st.sampled_from([None, "plumb_bob", "rational_polynomial", "fisheye", "", 3]))
    strategies = {"coefficients": arrays(coeff, overrides={"lead_axis": ANY, "extra_axis": ANY, "empty": INVALID,
                                                            "fewer": ANY, "bool": ANY, "object_float": INVALID})}
    mexpect = TYPE if model == 3 else (ANY if model in (None, "plumb_bob", "rational_polynomial") else INVALID)
    name, v, out = fuzz(data, vsinv.vision.Distortion, {"coefficients": coeff, "model": None}, strategies, api="Distortion",
                        names={"coefficients": ("coefficients",)})
    out2 = call(vsinv.vision.Distortion, coeff, model, _api="Distortion", _expect=mexpect, _names=("model",))
    for d in (out, out2):
        if returned(d):
            m = call(getattr, d, "model", _api="Distortion.model")
            c = call(getattr, d, "coefficients", _api="Distortion.coefficients")
            assert m in ("plumb_bob", "rational_polynomial") and c.shape == ((5,) if m == "plumb_bob" else (8,))
            assert d == vsinv.vision.Distortion(c, m)
    assert ref == vsinv.vision.Distortion(DIST.tolist())


def cv_distort(px: np.ndarray, k: np.ndarray, d: np.ndarray) -> np.ndarray:
    norm = np.linalg.solve(k, np.column_stack([px, np.ones(len(px))]).T).T
    out, _ = cv2.projectPoints(norm, np.zeros(3), np.zeros(3), k, d)
    return out.reshape(-1, 2)


@covers("distort_points", "undistort_points")
@fuzz_settings(150)
@given(st.data())
def test_distort_undistort(data: Any) -> None:
    px = CUR_PX * 0.5 + 100.0  # inside the calibrated field
    which = data.draw(st.sampled_from(["distort_points", "undistort_points"]))
    fn = getattr(vsinv.vision, which)
    args: dict[str, Any] = {"pixels": px, "K": K, "distortion": vsinv.vision.Distortion(DIST)}
    strategies: dict[str, Any] = {"pixels": arrays(px, overrides={"lead_axis": INVALID}), "K": k_variants(),
                                  "distortion": dist_variants()}
    if which == "undistort_points":
        args.update(tol=1e-10, max_iter=50)
        strategies.update(tol=floats(1e-10, overrides={"zero": INVALID, "negative": INVALID, "neginf": INVALID}), max_iter=ints(50))
    ref = fn(**args)
    if which == "distort_points":
        np.testing.assert_allclose(ref, cv_distort(px, K.matrix, DIST), rtol=1e-9, atol=1e-6)
    else:
        np.testing.assert_allclose(vsinv.vision.distort_points(ref, K, DIST), px, atol=1e-6)
    fuzz(data, fn, args, strategies, names={"distortion": ("distortion", "coefficients")}, ref=ref, rtol=1e-12,
         check=lambda out: out.shape[1:] == (2,) or pytest.fail(str(out.shape)))


@covers("distort_points", "undistort_points")
@fuzz_settings(60)
@given(st.lists(st.tuples(st.floats(0, 640), st.floats(0, 480)), min_size=1, max_size=6),
       st.lists(st.floats(-0.2, 0.2), min_size=5, max_size=5))
def test_distortion_round_trip_against_opencv(pts: list[tuple[float, float]], coeffs: list[float]) -> None:
    px = np.array(pts)
    k = vsinv.Intrinsics(800.0, 790.0, 320.0, 240.0)
    d = np.array(coeffs) * np.array([1.0, 1.0, 0.05, 0.05, 1.0])
    dist = call(vsinv.vision.distort_points, px, k, d, _names=("point", "distortion"))
    if not returned(dist):
        assert "point" in str(dist)
        return
    np.testing.assert_allclose(dist, cv_distort(px, k.matrix, d), rtol=1e-9, atol=1e-6)
    back = call(vsinv.vision.undistort_points, dist, k, d, _names=("point", "distortion"))
    if returned(back):
        np.testing.assert_allclose(back, px, atol=1e-6)



FISHEYE = vsinv.vision.Distortion([-0.04, 0.01, -0.003, 0.0005], "equidistant")
FISH_K = K  # k_variants() vary the harness's K
FISH_RAYS = np.array([[0.1, -0.2, 1.0], [1.0, 0.5, 0.2], [0.6, -0.3, -0.25], [0.0, 0.0, 1.0]])  # two beyond 90 deg


@covers("distort_rays", "undistort_rays", "Distortion.max_angle")
@fuzz_settings(120)
@given(st.data())
def test_fisheye_rays(data: Any) -> None:
    """Rays (n, 3) through a fisheye lens, some beyond 90 degrees, and their pixels back: every
    bad variant of an argument is refused naming it, a harmless one gives the same answer."""
    top = call(getattr, FISHEYE, "max_angle", _api="Distortion.max_angle")
    assert math.radians(100) < top <= math.pi
    which = data.draw(st.sampled_from(["distort_rays", "undistort_rays"]))
    fn = getattr(vsinv.vision, which)
    first = FISH_RAYS if which == "distort_rays" else vsinv.vision.distort_rays(FISH_RAYS, FISH_K, FISHEYE)
    args: dict[str, Any] = {"rays" if which == "distort_rays" else "pixels": first, "K": FISH_K, "distortion": FISHEYE}
    strategies: dict[str, Any] = {"K": k_variants(), "distortion": st.just(V(FISHEYE, SAME, "Distortion"))}
    name = "rays" if which == "distort_rays" else "pixels"
    strategies[name] = arrays(first, overrides={"lead_axis": INVALID})
    if which == "undistort_rays":
        args.update(tol=1e-10, max_iter=50)
        strategies.update(tol=floats(1e-10, overrides={"zero": INVALID, "negative": INVALID, "neginf": INVALID}),
                          max_iter=ints(50))
    ref = fn(**args)
    if which == "undistort_rays":
        np.testing.assert_allclose(ref, FISH_RAYS / np.linalg.norm(FISH_RAYS, axis=1, keepdims=True), atol=1e-9)
    width = 2 if which == "distort_rays" else 3
    fuzz(data, fn, args, strategies, names={name: (name, "points", "rays", "point")}, ref=ref, rtol=1e-12,
         check=lambda out: out.shape[1:] == (width,) or pytest.fail(str(out.shape)))


CAL_FIXTURES = Path(__file__).parent / "fixtures" / "calibration"
CAL_FILES = sorted(p for p in CAL_FIXTURES.iterdir() if p.suffix in (".yaml", ".xml"))
@covers("load_calibration", "Calibration", "Calibration.intrinsics", "Calibration.distortion", "Calibration.image_size")
@fuzz_settings(150)
@given(data=st.data())
def test_load_calibration(tmp_path_factory: Any, data: Any) -> None:
    src = data.draw(st.sampled_from(CAL_FILES), label="file")
    kind, text = data.draw(mutated_text(src.read_text()), label="mutation")
    path = tmp_path_factory.mktemp("cal") / src.name
    path.write_text(text, encoding="utf-8", errors="surrogateescape")
    as_type = data.draw(st.sampled_from([str, Path]))
    out = call(vsinv.calibration.load_calibration, as_type(path), _expect=RETURN if kind == "same" else ANY,
               _names=(src.name, "calibration"))
    if returned(out):
        assert isinstance(out, vsinv.calibration.Calibration)
        k = call(getattr, out, "intrinsics", _api="Calibration.intrinsics")
        d = call(getattr, out, "distortion", _api="Calibration.distortion")
        w, h = call(getattr, out, "image_size", _api="Calibration.image_size")
        assert isinstance(k, vsinv.Intrinsics) and isinstance(d, vsinv.vision.Distortion)
        assert w > 0 and h > 0 and k.fku > 0 and k.fkv > 0
    for bad, expect in [(tmp_path_factory.getbasetemp(), ANY), ("/nonexistent/cal.yaml", RAISE), (None, TYPE), (3, TYPE),
                        ("", RAISE)]:
        call(vsinv.calibration.load_calibration, bad, _expect=expect, _names=("calibration", "path", str(bad)))
