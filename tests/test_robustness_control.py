"""Robustness of the public Python API under hypothesis, the controllers (constructors, steps,
state, pickling), the stability check, the pose uncertainty and the pixel noise meter.

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
from conftest import lens
from robustness_harness import (
    ANY, CUR_PX, CUR_Z, FIRST_PX, FIRST_Z, INVALID, K, KSTAR, N, RAISE, REF_PX, REF_Z, RETURN, SAME, TYPE, V, arrays, assert_same,
    basis_variants, call, choices, covers, depth_variants, floats, fuzz, fuzz_settings, ints, k_variants,
    manual_invariants, pixel_variants, returned,
)


# ---------------------------------------------------------------------------------------------
# controllers


def controller_kwargs(cls: type) -> tuple[dict[str, Any], dict[str, st.SearchStrategy[V]]]:
    speed = floats(0.25, overrides={"none": SAME, "nan": RAISE, "negative": INVALID, "zero": INVALID, "neghuge": INVALID,
                                    "neginf": INVALID})
    adaptive_bad = [((1.0, 2.0), INVALID), ((1.0, 2.0, 3.0, 4.0), INVALID), (("a", 1.0, 1.0), TYPE), ((np.nan, 1.0, 1.0), INVALID),
                    ((0.4, 4.0, 30.0), ANY), ((-1.0, 0.4, 30.0), INVALID), ("abc", TYPE), (1.0, TYPE)]
    adaptive = st.one_of(st.just(V((4.0, 0.4, 30.0), RETURN, "good")), st.just(V(None, RETURN, "none")),
                         st.sampled_from([V(x, e, repr(x)) for x, e in adaptive_bad]))
    common = {
        "reference_pixels": pixel_variants(REF_PX, overrides={"fewer": ANY, "empty": RAISE, "negative": ANY}),
        "K_hat": k_variants(KSTAR),
        "gain": floats(1.0, overrides={"zero": INVALID, "negative": INVALID, "neghuge": INVALID, "neginf": INVALID}),
        "adaptive_gain": adaptive,
        "max_linear_speed": speed,
        "max_angular_speed": speed,
    }
    args = {"reference_pixels": REF_PX, "K_hat": KSTAR, "gain": 1.0, "adaptive_gain": None, "max_linear_speed": None,
            "max_angular_speed": None}
    if cls is vsinv.laws.InvariantController:
        args.update(gain_rz=1.0, basis=(0, 1, 2), feedforward=True, min_structure_ratio=1e-3, rz_task="angle")
        common.update(gain_rz=common["gain"], basis=basis_variants(N),
                      feedforward=choices([True, False, np.bool_(True)], ["yes", None, 2.5, 1, 0], TYPE),
                      min_structure_ratio=floats(1e-3, overrides={"none": TYPE}),
                      rz_task=choices(["angle", "tau21"], ["tau", "", "ANGLE"]) )
    else:
        args.update(interaction="current", reference_depths=None)
        common.update(interaction=st.one_of(choices(["current"], ["sideways", "", "Current"]),
                                            st.sampled_from([V("desired", RAISE, "desired without depths"),
                                                             V("mean", RAISE, "mean without depths")])),
                      reference_pixels=pixel_variants(REF_PX, ANY, overrides={"fewer": ANY, "empty": RAISE, "negative": ANY,
                                                                              "zero": ANY, "bool": ANY}),
                      reference_depths=depth_variants(REF_Z, {k: ANY for k in ("none", "valid", "list", "strided", "readonly", "flat")}))
    return args, common


@covers("InvariantController", "IbvsController")
@fuzz_settings(200)
@given(st.data())
def test_controller_constructors(data: Any) -> None:
    cls = data.draw(st.sampled_from([vsinv.laws.InvariantController, vsinv.laws.IbvsController]))
    args, strategies = controller_kwargs(cls)
    name, v, out = fuzz(data, cls, args, strategies, api=cls.__name__,
                        names={"K_hat": ("K_hat", "intrinsics"), "adaptive_gain": ("adaptive_gain", "at_zero", "at_infinity", "slope")})
    if returned(out):
        tw = call(out.step, CUR_PX, CUR_Z, _api=f"{cls.__name__}.step", _names=("pixels", "depths"))
        if returned(tw):
            assert tw.shape == (6,)


def step_args(visible: bool, degenerate_expect: str, three_visible: str = RAISE) -> tuple[dict[str, Any], dict[str, st.SearchStrategy[V]]]:
    args: dict[str, Any] = {"pixels": CUR_PX, "depths": CUR_Z}
    strategies: dict[str, Any] = {
        "pixels": pixel_variants(CUR_PX, degenerate_expect,
                                 overrides={"fewer": INVALID, "empty": INVALID, "zero": degenerate_expect, "bool": degenerate_expect}),
        "depths": depth_variants(CUR_Z),
    }
    if visible:
        ones = np.ones(N, bool)
        args["visible"] = ones
        strategies["visible"] = st.one_of(
            st.sampled_from([V(ones, SAME, "all"), V(ones.tolist(), SAME, "list"), V(np.ones(2 * N, bool)[::2], SAME, "strided")]),
            st.sampled_from([V(np.ones(N, int), INVALID, "int"), V(np.ones(N - 1, bool), INVALID, "short"),
                             V(np.ones((N, 1), bool), INVALID, "2-d"), V(None, SAME, "none: all"), V("abc", INVALID, "str"),
                             V(np.zeros(N, bool), RAISE, "none visible"), V(np.arange(N) > 8, three_visible, "three visible")]),
        )
    return args, strategies


def controller(cls: type) -> Any:
    if cls is vsinv.laws.InvariantController:
        return vsinv.laws.InvariantController(REF_PX, KSTAR, basis=(0, 1, 2))  # the hidden points are not the basis
    return vsinv.laws.IbvsController(REF_PX, KSTAR)


@covers("InvariantController.step", "IbvsController.step")
@fuzz_settings(250)
@given(st.data())
def test_controller_steps(data: Any) -> None:
    cls = data.draw(st.sampled_from([vsinv.laws.InvariantController, vsinv.laws.IbvsController]))
    visible = data.draw(st.booleans())
    ctl = controller(cls)
    fn = ctl.step
    args, strategies = step_args(visible, RAISE if cls is vsinv.laws.InvariantController else ANY)
    ref = fn(**args)
    if visible:
        assert_same(ref, ctl.step(CUR_PX, CUR_Z), rtol=1e-12)
    fuzz(data, fn, args, strategies, ref=ref, rtol=1e-12, check=lambda tw: tw.shape == (6,) or pytest.fail(str(tw.shape)),
         names={"pixels": ("pixels", "points", "visible")})


@covers("InvariantController.step", "IbvsController.step")
@fuzz_settings(60)
@given(st.data())
def test_hidden_points_may_be_nan(data: Any) -> None:
    cls = data.draw(st.sampled_from([vsinv.laws.InvariantController, vsinv.laws.IbvsController]))
    ctl = controller(cls)
    hidden = data.draw(st.lists(st.sampled_from([3, 4, 5, 6, 7, 8, 9, 10, 11]), max_size=3, unique=True))
    vis = np.ones(N, bool)
    vis[hidden] = False
    px, z = CUR_PX.copy(), CUR_Z.copy()
    px[hidden] = data.draw(st.sampled_from([np.nan, np.inf, -1e300]))
    z[hidden] = data.draw(st.sampled_from([np.nan, -1.0, 0.0]))
    tw = call(ctl.step, px, z, vis)  # fewer points may leave a degenerate structure
    assert returned(tw) or isinstance(tw, vsinv.DegenerateGeometry), tw
    if returned(tw):
        assert tw.shape == (6,)


@covers("InvariantController.set_k_hat", "InvariantController.set_reference", "InvariantController.converged",
        "InvariantController.k_hat", "InvariantController.basis", "InvariantController.reference_invariants",
        "InvariantController.eps", "InvariantController.eps_z", "InvariantController.invariant_error",
        "InvariantController.tau_11", "InvariantController.tau_21", "InvariantController.tau_22",
        "InvariantController.t_matrix", "InvariantController.last_gain", "InvariantController.saturation",
        "IbvsController.pixel_error", "IbvsController.last_gain", "IbvsController.saturation")
@fuzz_settings(150)
@given(st.data())
def test_controller_state(data: Any) -> None:
    inv = controller(vsinv.laws.InvariantController)
    ibvs = controller(vsinv.laws.IbvsController)
    state = ["eps", "eps_z", "invariant_error", "tau_11", "tau_21", "tau_22", "t_matrix", "last_gain", "saturation"]
    # before a step: NotReady (invariant law) or None (IBVS)
    for p in state:
        call(getattr, inv, p, _api=f"InvariantController.{p}", _expect=RAISE)
        assert isinstance(getattr_or_exc(inv, p), vsinv.NotReady)
    for p in ("pixel_error", "last_gain", "saturation"):
        assert call(getattr, ibvs, p, _api=f"IbvsController.{p}", _expect=RETURN) is None
    assert call(inv.converged, _expect=RETURN) is False
    assert call(getattr, inv, "basis", _api="InvariantController.basis") == (0, 1, 2)
    s_star = call(getattr, inv, "reference_invariants", _api="InvariantController.reference_invariants")
    assert s_star.shape == (N - 3, 3)
    np.testing.assert_allclose(s_star, np.delete(manual_invariants(REF_PX, (0, 1, 2)), [0, 1, 2], axis=0), atol=1e-9)
    assert call(getattr, inv, "k_hat", _api="InvariantController.k_hat") == KSTAR
    # set_k_hat and set_reference with corrupted arguments
    what = data.draw(st.sampled_from(["set_k_hat", "set_reference", "converged"]))
    if what == "set_k_hat":
        fuzz(data, inv.set_k_hat, {"K_hat": K}, {"K_hat": k_variants(K)}, names={"K_hat": ("K_hat", "intrinsics")})
    elif what == "set_reference":
        rate = np.zeros_like(s_star)
        fuzz(data, inv.set_reference, {"s_star": s_star, "rate": rate},
             {"s_star": arrays(s_star, overrides={"zero": INVALID, "negative": INVALID, "fewer": INVALID, "empty": INVALID,
                                                  "huge": INVALID, "tiny": INVALID, "bool": INVALID, "float32": ANY}),
              "rate": st.one_of(arrays(rate, overrides={"fewer": INVALID, "empty": INVALID, "none": SAME, "bool": ANY}),
                                st.just(V(None, SAME, "none")))})
    else:
        fuzz(data, inv.converged, {"invariant_tol": 1e-4, "tau21_tol": 1e-4},
             {"invariant_tol": floats(1e-4, overrides={"nan": ANY}), "tau21_tol": floats(1e-4, overrides={"nan": ANY})})
    # after a step: every state property is finite
    tw = call(inv.step, CUR_PX, CUR_Z, _expect=ANY)
    if returned(tw):
        for p in state:
            call(getattr, inv, p, _api=f"InvariantController.{p}", _expect=RETURN)
        t = inv.t_matrix
        assert t.shape == (3, 3) and inv.eps.shape == (5,)
        assert math.isclose(inv.tau_11, t[0, 0]) and math.isclose(inv.tau_21, t[1, 0]) and math.isclose(inv.tau_22, t[1, 1])
    call(ibvs.step, CUR_PX, CUR_Z, _expect=RETURN)
    for p in ("pixel_error", "last_gain", "saturation"):
        x = call(getattr, ibvs, p, _api=f"IbvsController.{p}", _expect=RETURN)
        assert isinstance(x, float)
    rms = math.sqrt(np.mean(np.sum((CUR_PX - REF_PX) ** 2, axis=1)))
    assert math.isclose(ibvs.pixel_error, rms, rel_tol=1e-9) or math.isclose(ibvs.pixel_error, np.sqrt(np.mean((CUR_PX - REF_PX) ** 2)), rel_tol=1e-9)


def getattr_or_exc(obj: Any, name: str) -> Any:
    try:
        return getattr(obj, name)
    except Exception as exc:  # noqa: BLE001
        return exc


@covers("InvariantController", "IbvsController")
def test_controllers_pickle() -> None:
    import pickle

    for cls in (vsinv.laws.InvariantController, vsinv.laws.IbvsController):
        ctl = controller(cls)
        copy = call(pickle.loads, pickle.dumps(ctl), _api=f"{cls.__name__}.__reduce__", _expect=RETURN)
        assert_same(copy.step(CUR_PX, CUR_Z), ctl.step(CUR_PX, CUR_Z))


# ---------------------------------------------------------------------------------------------
# stability


@covers("check_stability", "StabilityReport", "StabilityReport.prop1", "StabilityReport.prop2", "StabilityReport.sigma",
        "StabilityReport.eigenvalues", "StabilityReport.tracking_bound", "tracking_bound")
@fuzz_settings(150)
@given(st.data())
def test_stability(data: Any) -> None:
    which = data.draw(st.sampled_from(["check_stability", "tracking_bound", "report"]))
    if which == "check_stability":
        sched = np.stack([K.matrix, lens(500.0).matrix])
        khat = st.one_of(k_variants(KSTAR).filter(lambda v: v.label not in ("negative focal", "negative")),
                         st.just(V(np.diag([-600.0, 600.0, 1.0]), RETURN, "negative focal: any signs")))
        one = k_variants(K).map(lambda v: V(v.value, ANY, v.label) if v.label == "lead_axis" else v)  # (1, 3, 3): a schedule
        kvar = st.one_of(one, arrays(sched, overrides={"zero": INVALID, "negative": INVALID, "fewer": ANY, "empty": ANY,
                                                                   "flat": INVALID, "bool": ANY, "tiny": ANY, "lead_axis": INVALID}),
                         st.just(V([K, lens(500.0)], RETURN, "list of Intrinsics")))
        fuzz(data, vsinv.laws.check_stability, {"K": K, "K_hat": KSTAR, "kappa": 1.0, "gain": 1.0},
             {"K": kvar, "K_hat": khat, "kappa": floats(1.0), "gain": floats(1.0)},
             names={"K": ("K", "intrinsics"), "K_hat": ("K_hat", "intrinsics")},
             check=lambda r: isinstance(r, vsinv.laws.StabilityReport) or pytest.fail(repr(r)))
    elif which == "tracking_bound":
        ref = vsinv.laws.tracking_bound(1.0, 0.5, 0.1)
        assert math.isclose(ref, 2 * 0.1 / (1.0 * 0.5))
        args = {"gain": 1.0, "sigma": 0.5, "max_b": 0.1}
        name, v, out = fuzz(data, vsinv.laws.tracking_bound, args,
                            {"gain": floats(1.0), "sigma": floats(0.5), "max_b": floats(0.1)}, ref=ref, rtol=1e-15, finite=False)
        if returned(out):  # documented: +inf when sigma <= 0 (no bound), else 2 max_b / (gain sigma)
            kw = {**args, name: float(v.value)}
            assert out >= 0 and not math.isnan(out)
            if kw["sigma"] <= 0:
                assert out == math.inf
            else:
                with np.errstate(all="ignore"):
                    expect = np.float64(2.0) * kw["max_b"] / (np.float64(kw["gain"]) * kw["sigma"])
                assert math.isclose(out, expect, rel_tol=1e-12) or (math.isinf(out) and not np.isfinite(expect))
    else:
        same = vsinv.laws.check_stability(K, K)
        assert call(getattr, same, "prop1", _api="StabilityReport.prop1") is True
        assert call(getattr, same, "prop2", _api="StabilityReport.prop2") is True
        sigma = call(getattr, same, "sigma", _api="StabilityReport.sigma")
        eig = call(getattr, same, "eigenvalues", _api="StabilityReport.eigenvalues")
        assert eig.shape == (5,) and eig.dtype == np.complex128 and (eig.real > 0).all()
        sched = vsinv.laws.check_stability([K, lens(500.0)], KSTAR)
        assert call(getattr, sched, "eigenvalues", _api="StabilityReport.eigenvalues").shape == (2, 5)
        v = data.draw(floats(0.1, overrides={"nan": RAISE}), label="max_b")
        out = call(same.tracking_bound, v.value, _expect=v.expect, _names=("max_b",))
        if returned(out) and v.expect == SAME:
            assert math.isclose(out, 2 * 0.1 / sigma)


# ---------------------------------------------------------------------------------------------
# pose uncertainty and the noise meter


@covers("InvariantController.pose_uncertainty", "IbvsController.pose_uncertainty", "PoseUncertainty",
        "PoseUncertainty.covariance", "PoseUncertainty.offset", "PoseUncertainty.translation_sigma",
        "PoseUncertainty.rotation_sigma", "PoseUncertainty.translation_bound", "PoseUncertainty.rotation_bound")
@fuzz_settings(150)
@given(st.data())
def test_pose_uncertainty(data: Any) -> None:
    cls = data.draw(st.sampled_from([vsinv.laws.InvariantController, vsinv.laws.IbvsController]))
    ctl = controller(cls)
    # IBVS's pose uncertainty is defined with three points (six equations, six unknowns); its step needs four.
    invariant = cls is vsinv.laws.InvariantController
    args, strategies = step_args(True, RAISE if invariant else ANY, RAISE if invariant else ANY)
    args.update(pixel_sigma=0.5, reference_sigma=0.25, averaged_images=4)
    strategies.update(
        pixel_sigma=floats(0.5, overrides={"zero": ANY, "negative": INVALID, "neghuge": INVALID, "neginf": INVALID,
                                           "huge": INVALID, "inf": INVALID}),
        reference_sigma=floats(0.25, overrides={"none": ANY, "zero": ANY, "negative": INVALID, "neghuge": INVALID,
                                                "neginf": INVALID, "huge": INVALID, "inf": INVALID}),
        averaged_images=ints(4, overrides={"zero": INVALID}),
    )
    ref = ctl.pose_uncertainty(**args)
    digest = lambda u: u.covariance if isinstance(u, vsinv.laws.PoseUncertainty) else u  # noqa: E731
    fuzz(data, ctl.pose_uncertainty, args, strategies, ref=ref, rtol=1e-12, digest=digest,
         api=f"{cls.__name__}.pose_uncertainty", names={"pixels": ("pixels", "points", "visible")}, finite=False)
    # the properties of the result, against NumPy
    cov = call(getattr, ref, "covariance", _api="PoseUncertainty.covariance")
    assert cov.shape == (6, 6) and np.allclose(cov, cov.T, rtol=1e-9, atol=0) and np.all(np.linalg.eigvalsh(cov) > -1e-18)
    offset = call(getattr, ref, "offset", _api="PoseUncertainty.offset")
    t_sigma = call(getattr, ref, "translation_sigma", _api="PoseUncertainty.translation_sigma")
    r_sigma = call(getattr, ref, "rotation_sigma", _api="PoseUncertainty.rotation_sigma")
    assert t_sigma == pytest.approx(np.sqrt(np.trace(cov[:3, :3])), rel=1e-12)
    assert r_sigma == pytest.approx(np.sqrt(np.trace(cov[3:, 3:])), rel=1e-12)
    sigmas = data.draw(floats(3.0, overrides={"zero": INVALID, "negative": INVALID, "neghuge": INVALID, "neginf": INVALID,
                                              "huge": ANY, "inf": INVALID, "none": TYPE}), label="sigmas")
    for name, sigma, part in (("translation_bound", t_sigma, offset[:3]), ("rotation_bound", r_sigma, offset[3:])):
        out = call(getattr(ref, name), sigmas.value, _api=f"PoseUncertainty.{name}", _expect=sigmas.expect,
                   _names=("sigmas",), _finite=False)
        if sigmas.expect == SAME:
            assert out == pytest.approx(3.0 * sigma + np.linalg.norm(part), rel=1e-12)


@covers("PixelNoiseMeter", "PixelNoiseMeter.push", "PixelNoiseMeter.sigma", "PixelNoiseMeter.clear")
@fuzz_settings(100)
@given(st.data())
def test_pixel_noise_meter(data: Any) -> None:
    capacity = data.draw(ints(8, overrides={"zero": INVALID}), label="capacity")
    meter = call(vsinv.vision.PixelNoiseMeter, capacity.value, _api="PixelNoiseMeter", _expect=capacity.expect,
                 _names=("capacity",))
    if not isinstance(meter, vsinv.vision.PixelNoiseMeter):
        return
    rng = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1), label="seed"))
    frames = [CUR_PX + rng.normal(0, 0.3, CUR_PX.shape) for _ in range(3)]
    ones = np.ones(N, bool)
    args, strategies = {"pixels": frames[0], "visible": ones}, step_args(True, ANY)[1]
    visible = st.sampled_from([V(ones, SAME, "all"), V(None, SAME, "none"), V(np.zeros(N, bool), RETURN, "none visible"),
                               V(np.ones(N, int), INVALID, "int"), V(np.ones(N - 1, bool), INVALID, "short"),
                               V("abc", INVALID, "str")])
    fuzz(data, meter.push, args, {"pixels": strategies["pixels"], "visible": visible},
         api="PixelNoiseMeter.push", names={"pixels": ("pixels", "points", "visible")}, finite=False)
    meter.clear()
    call(meter.clear, _api="PixelNoiseMeter.clear", _expect=RETURN)
    for f in frames:
        meter.push(f)
    # against NumPy: the second difference of the three frames
    d = frames[0] - 2 * frames[1] + frames[2]
    sigma = call(getattr, meter, "sigma", _api="PixelNoiseMeter.sigma")
    assert sigma == pytest.approx(np.sqrt(np.mean(d**2) / 6), rel=1e-12)


# ---------------------------------------------------------------------------------------------
# servo sessions

# gain is a law option (LAW_OPTIONS): given only when drawn, with the invariant law, since
# law "none" refuses it by name.
SERVO_ARGS: dict[str, Any] = {"reference_pixels": REF_PX, "K_hat": K, "law": "invariant", "reference_depths": REF_Z,
                              "depths": "reference", "dt": 0.04, "stop": None, "stop_rule": None}


def servo_strategies() -> dict[str, st.SearchStrategy[V]]:
    positive = {"zero": INVALID, "negative": INVALID, "neghuge": INVALID, "neginf": INVALID}
    return {
        # basis "auto": a collinear or duplicated point 0, 1, 2 need not be refused
        "reference_pixels": pixel_variants(REF_PX, ANY, overrides={"fewer": ANY, "empty": RAISE, "negative": ANY}),
        "K_hat": k_variants(K),
        "law": choices(["invariant", "ibvs", "none"], ["pbvs", "", "Invariant"]),
        "reference_depths": depth_variants(REF_Z, {"none": INVALID}),
        "depths": choices(["reference", "per_step", 0.6, vsinv.calibration.ResectionDepths(FIRST_PX, FIRST_Z, REF_PX, 0.6)],
                          ["ref", "", -1.0, math.nan, math.inf, 0.0]),
        "gain": floats(1.0, overrides={**positive, "none": RETURN}),  # a law option: None is its default
        "dt": floats(0.04, overrides=positive),
        "stop": choices([None, {"window": 3}, {"max_iterations": 10, "pixel_error": 1.0}, {"reference_pixel_sigma": 0.1}],
                        [{"windw": 1}, {"window": 0}, {"window": -1}, {"pixel_error": "a"}, {1: 2}]),
        "stop_rule": choices([None, "pixel", "invariant"], ["Pixel", ""]),
    }


@covers("Servo", "ServoStep", "Servo.step", "ServoStep.twist", "ServoStep.verdict", "ServoStep.reason",
        "ServoStep.running", "ServoStep.telemetry")
@fuzz_settings(200)
@given(st.data())
def test_servo_constructor(data: Any) -> None:
    names = {"K_hat": ("K_hat", "intrinsics"), "reference_depths": ("reference_depths", "depths"),
             "stop": ("stop", "window", "max_iterations")}
    name, v, servo = fuzz(data, vsinv.Servo, SERVO_ARGS, servo_strategies(), api="Servo", names=names)
    if not returned(servo):
        return
    per_step = CUR_Z if name == "depths" and isinstance(v.value, str) and v.value == "per_step" else None
    step = call(servo.step, CUR_PX, None, per_step, _api="Servo.step", _finite=False)
    if returned(step):
        assert step.twist.shape == (6,) and isinstance(step.verdict, str)
        assert step.running == (step.reason is None) and set(step.telemetry) >= {"iteration", "eps", "tau"}


@covers("Servo.step")
@fuzz_settings(200)
@given(st.data())
def test_servo_steps(data: Any) -> None:
    per_step = data.draw(st.booleans(), label="per_step")
    servo = vsinv.Servo(REF_PX, K, reference_depths=REF_Z, depths="per_step" if per_step else "reference")
    args: dict[str, Any] = {"pixels": CUR_PX, "visible": None, "depths": CUR_Z if per_step else None}
    ones = np.ones(N, bool)
    strategies: dict[str, Any] = {
        "pixels": pixel_variants(CUR_PX, ANY, overrides={"fewer": INVALID, "empty": INVALID, "zero": ANY, "bool": ANY}),
        "visible": st.one_of(
            st.sampled_from([V(None, RETURN, "none"), V(ones, RETURN, "all"), V(ones.tolist(), RETURN, "list")]),
            st.sampled_from([V(np.ones(N, int), INVALID, "int"), V(np.ones(N - 1, bool), INVALID, "short"),
                             V("abc", INVALID, "str"), V(np.zeros(N, bool), RETURN, "none visible: lost_features")]),
        ),
    }
    if per_step:
        strategies["depths"] = depth_variants(CUR_Z, {"zero": RAISE, "negative": RAISE, "none": INVALID})
    _, _, step = fuzz(data, servo.step, args, strategies, api="Servo.step", finite=False,
                      names={"pixels": ("pixels", "points", "visible")})
    if returned(step):
        assert step.twist.shape == (6,) and np.all(np.isfinite(step.twist))


@covers("Servo.basis", "Servo.basis_switches", "Servo.basis_held_images", "Servo.certainty", "Servo.iterations", "Servo.law", "Servo.pixel_sigma",
        "Servo.reference_pixels", "Servo.stop_rule")
@fuzz_settings(20)
@given(st.data())
def test_servo_state(data: Any) -> None:
    law = data.draw(st.sampled_from(["invariant", "ibvs", "none"]))
    servo = vsinv.Servo(REF_PX, K, law, reference_depths=REF_Z)
    steps = data.draw(st.integers(0, 4))
    for _ in range(steps):
        servo.step(CUR_PX)
    assert servo.law == law and len(servo.basis) == 3 and servo.reference_pixels.shape == (N, 2)
    assert servo.iterations == steps and servo.basis_switches == 0 and servo.basis_held_images == 0
    assert (servo.pixel_sigma is None) == (steps < 3)
    c = servo.certainty()
    # floor_pixel_sigma is None with the stall rule off (a plain Servo's default).
    assert c is None or all(math.isfinite(v) for k, v in c.items() if not (k == "floor_pixel_sigma" and v is None))
    assert servo.stop_rule in ("pixel", "invariant")


# ---------------------------------------------------------------------------------------------
# the laws' options (vsinv.laws.LAW_OPTIONS): the table, the check of a value, the Markdown


@covers("LAW_OPTIONS", "check_law_option", "law_options_markdown")
@fuzz_settings(100)
@given(st.data())
def test_law_options_check(data: Any) -> None:
    options = vsinv.laws.LAW_OPTIONS
    o = data.draw(st.sampled_from(options), label="option")
    if o["default"] is not None:  # a default is a value the check accepts
        assert call(vsinv.laws.check_law_option, o["name"], o["default"], _expect=RETURN, _finite=False) is None
    # a number for a number option (in its range or not), a word for a choice; other kinds of
    # values (a tuple for adaptive_gain) are the controllers' tests' concern
    if o["kind"] == "number":
        value = data.draw(st.one_of(st.integers(-10**30, 10**30), st.floats()), label="value")
    elif o["choices"]:
        value = data.draw(st.one_of(st.sampled_from(list(o["choices"])), st.text(max_size=6)), label="value")
    else:
        value = data.draw(st.sampled_from([None, (1.0, 0.5, 10.0), (0.0, 0.5, 10.0), (1.0, 0.5)]), label="value")
    out = call(vsinv.laws.check_law_option, o["name"], value, _expect=ANY, _names=(o["name"],), _finite=False)
    assert out is None or isinstance(out, vsinv.InvalidInput), out
    name = data.draw(st.text(max_size=12).filter(lambda n: n not in {x["name"] for x in options}), label="name")
    call(vsinv.laws.check_law_option, name, 1.0, _expect=INVALID, _names=("name",), _finite=False)
    table = vsinv.laws.law_options_markdown()
    assert all(f"`{x['name']}`" in table for x in options), table[:200]
