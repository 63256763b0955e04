"""Robustness of the public Python API under hypothesis, the SE(3) helpers (exponential of a
twist, theta-u poses) and hand-eye calibration (poses in, a pose out).

The promise and the harness are described in tests/robustness_harness.py.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

import vsinv
from robustness_harness import (
    ANY, INVALID, SAME, V, arrays, call, choices, covers, floats, fuzz, fuzz_settings, returned, rodrigues,
)


# ---------------------------------------------------------------------------------------------
# SE(3) helpers


@covers("exp_twist", "pose_from_position_thetau", "thetau_from_pose")
@fuzz_settings(150)
@given(st.data())
def test_se3_round_trips(data: Any) -> None:
    which = data.draw(st.sampled_from(["exp_twist", "pose_from_position_thetau", "thetau_from_pose"]))
    twist = np.array([0.1, -0.2, 0.05, 0.3, -0.1, 0.2])
    position, thetau = np.array([0.2, -0.1, 0.5]), np.array([0.3, -0.4, 1.2])
    p0 = vsinv.geometry.pose_from_position_thetau(position, thetau)
    if which == "exp_twist":
        args: dict[str, Any] = {"twist": twist, "dt": 0.5}
        strategies = {"twist": arrays(twist, overrides={"flat": SAME}), "dt": floats(0.5)}
    elif which == "pose_from_position_thetau":
        args = {"position": position, "thetau": thetau}
        strategies = {"position": arrays(position), "thetau": arrays(thetau)}
    else:
        args = {"pose": p0}
        bad_rot = p0.copy()
        bad_rot[:3, :3] *= 2.0
        bad_row = p0.copy()
        bad_row[3] = [0.0, 0.0, 1.0, 1.0]
        strategies = {"pose": st.one_of(arrays(p0, overrides={"zero": INVALID, "negative": INVALID, "fewer": INVALID,
                                                                  "empty": INVALID, "flat": INVALID, "huge": INVALID,
                                                                  "bool": INVALID, "tiny": INVALID, "float32": ANY}),
                                        st.sampled_from([V(bad_rot, INVALID, "scaled rotation"), V(bad_row, INVALID, "last row")]))}
    fn = getattr(vsinv.geometry, which)
    ref = fn(**args)
    name, v, out = fuzz(data, fn, args, strategies, ref=ref, rtol=1e-12)
    if not returned(out):
        return
    if which == "exp_twist":
        assert out.shape == (4, 4) and np.allclose(out[3], [0, 0, 0, 1])
        r = out[:3, :3]
        np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-9)
        tw = np.asarray(v.value if name == "twist" else twist, dtype=float).ravel()
        dt = float(v.value) if name == "dt" else 0.5
        if np.abs(tw * dt).max() < 1e3:
            np.testing.assert_allclose(r, rodrigues(tw[3:] * dt), atol=1e-9)
    elif which == "pose_from_position_thetau":
        pos = np.asarray(v.value if name == "position" else position, dtype=float)
        tu = np.asarray(v.value if name == "thetau" else thetau, dtype=float)
        np.testing.assert_allclose(out[:3, 3], pos, rtol=1e-15)
        if np.linalg.norm(tu) < 1e6:
            np.testing.assert_allclose(out[:3, :3], rodrigues(tu), atol=1e-9)
        if 1e-6 < np.linalg.norm(tu) < math.pi - 1e-6 and np.abs(pos).max() < 1e100:
            p, t = vsinv.geometry.thetau_from_pose(out)
            np.testing.assert_allclose(t, tu, atol=1e-9)
    else:
        p, t = out
        assert p.shape == (3,) and t.shape == (3,) and np.linalg.norm(t) <= math.pi + 1e-12


@covers("exp_twist", "thetau_from_pose", "pose_from_position_thetau")
@fuzz_settings(80)
@given(st.lists(st.floats(-3, 3), min_size=6, max_size=6), st.floats(-2, 2))
def test_exp_twist_composes(tw: list[float], dt: float) -> None:
    t = np.array(tw)
    a = call(vsinv.geometry.exp_twist, t, dt)
    b = call(vsinv.geometry.exp_twist, t, -dt)
    np.testing.assert_allclose(a @ b, np.eye(4), atol=1e-9)
    p, tu = call(vsinv.geometry.thetau_from_pose, a)
    back = call(vsinv.geometry.pose_from_position_thetau, p, tu)
    np.testing.assert_allclose(back, a, atol=1e-9)


@covers("thetau_from_rotations", "twist_adjoint")
@fuzz_settings(150)
@given(st.data())
def test_rotation_helpers(data: Any) -> None:
    which = data.draw(st.sampled_from(["thetau_from_rotations", "twist_adjoint"]))
    thetau = np.array([0.3, -0.4, 1.2])
    p0 = vsinv.geometry.pose_from_position_thetau(np.array([0.2, -0.1, 0.5]), thetau)
    if which == "thetau_from_rotations":
        rotations = np.stack([p0[:3, :3], np.eye(3)])
        args: dict[str, Any] = {"rotations": rotations}
        strategies = {"rotations": arrays(rotations, overrides={"zero": INVALID, "huge": INVALID, "tiny": INVALID})}
    else:
        args = {"pose": p0}
        strategies = {"pose": arrays(p0)}
    fn = getattr(vsinv.geometry, which)
    ref = fn(**args)
    name, v, out = fuzz(data, fn, args, strategies, ref=ref, rtol=1e-12)
    if not returned(out):
        return
    if which == "thetau_from_rotations":
        r = np.asarray(v.value, dtype=float)
        assert out.shape == (len(r), 3) and (np.linalg.norm(out, axis=1) <= math.pi + 1e-12).all()
        for tu, m in zip(out, r):
            np.testing.assert_allclose(rodrigues(tu), m, atol=1e-5)  # a rotation within 1e-6
    else:
        m = np.asarray(v.value, dtype=float)
        rot, t = m[:3, :3], m[:3, 3]
        xi = np.array([0.1, -0.2, 0.3, 0.4, -0.5, 0.6])
        want = np.concatenate([rot @ xi[:3] + np.cross(t, rot @ xi[3:]), rot @ xi[3:]])
        np.testing.assert_allclose(out @ xi, want, rtol=1e-12, atol=1e-12 * max(1.0, float(np.abs(m).max()) ** 2))


# ---------------------------------------------------------------------------------------------
# hand-eye calibration


def hand_eye_stations(n: int = 6, one_axis: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Gripper-to-base and exact target-to-camera poses for a fixed camera-to-gripper X; with
    ``one_axis`` the gripper rotates about one axis only (degenerate)."""
    def rigid(tu: Any, t: Any) -> np.ndarray:
        m = np.eye(4)
        m[:3, :3], m[:3, 3] = rodrigues(np.asarray(tu, dtype=float)), t
        return m

    x = rigid([0.1, -0.2, 1.2], [0.03, -0.02, 0.1])
    target = rigid([0.0, 0.0, 0.3], [0.6, 0.0, 0.0])
    g, c = [], []
    for k in range(n):
        tu = [0.0, 0.0, 0.4 * k] if one_axis else [0.5 * math.sin(1.3 * k), 0.5 * math.cos(0.7 * k + 1), 0.3 * math.sin(2.1 * k)]
        gk = rigid(tu, [0.4 + 0.05 * math.sin(k), 0.1 * math.cos(1.7 * k), 0.5])
        g.append(gk)
        c.append(np.linalg.inv(gk @ x) @ target)
    return np.array(g), np.array(c)


def pose_variants(valid: np.ndarray) -> st.SearchStrategy[V]:
    scaled, row, mirror = valid.copy(), valid.copy(), valid.copy()
    scaled[1, :3, :3] *= 1.01
    row[2, 3] = [0.0, 0.0, 0.5, 1.0]
    mirror[3, :3, 2] *= -1
    degenerate_g, _ = hand_eye_stations(len(valid), one_axis=True)
    return st.one_of(
        arrays(valid),
        st.sampled_from([V(scaled, INVALID, "scaled rotation"), V(row, INVALID, "last row"),
                         V(mirror, INVALID, "reflection"), V(degenerate_g, ANY, "one-axis gripper")]),
    )


def hand_eye_digest(out: Any) -> Any:
    if isinstance(out, vsinv.calibration.HandEyeAgreement):
        return {k: hand_eye_digest(v) for k, v in out.calibrations.items()}
    return (out.matrix, out.residuals, out.pairs, out.axis_spread_deg, out.method, out.setup)


def check_hand_eye(out: Any) -> None:
    cals = list(out.calibrations.values()) if isinstance(out, vsinv.calibration.HandEyeAgreement) else [out]
    for cal in cals:
        m = cal.matrix
        assert m.shape == (4, 4) and np.allclose(m[3], [0, 0, 0, 1])
        np.testing.assert_allclose(m[:3, :3] @ m[:3, :3].T, np.eye(3), atol=1e-9)
        assert cal.residuals.shape == cal.pairs.shape and np.isfinite(cal.residuals).all()
        assert 0.0 <= cal.axis_spread_deg <= 90.0 and cal.rms_rotation_deg >= 0 and cal.max_translation_m >= 0
        assert cal.rotating_motions >= 1 and cal.motions_used >= 1 and repr(cal)
    if isinstance(out, vsinv.calibration.HandEyeAgreement):
        assert out.max_rotation_deg >= 0 and out.max_translation_m >= 0 and isinstance(out.failures, dict)
        assert out.setup in ("eye_in_hand", "eye_to_hand")
        assert all(cal.setup == out.setup for cal in out.calibrations.values())
        assert repr(out)


HAND_EYE_MEMBERS = [
    f"HandEyeCalibration.{m}" for m in ("matrix", "method", "setup", "residuals", "pairs", "axis_spread_deg", "axis_eigenvalues",
                                         "rotating_motions", "motions_used", "rms_rotation_deg", "rms_translation_m",
                                         "max_rotation_deg", "max_translation_m")
] + [f"HandEyeAgreement.{m}" for m in ("calibrations", "failures", "setup", "max_rotation_deg", "max_translation_m")]


@covers("calibrate_hand_eye", "compare_hand_eye_methods", "HandEyeCalibration", "HandEyeAgreement", *HAND_EYE_MEMBERS)
@fuzz_settings(150)
@given(st.data())
def test_hand_eye_inputs(data: Any) -> None:
    g, c = hand_eye_stations()
    which = data.draw(st.sampled_from(["calibrate_hand_eye", "compare_hand_eye_methods"]))
    args: dict[str, Any] = {"gripper_poses": g, "target_poses": c}
    strategies = {"gripper_poses": pose_variants(g), "target_poses": pose_variants(c)}
    if which == "calibrate_hand_eye":
        args["method"] = "park"
        strategies["method"] = choices(["tsai", "park", "daniilidis", "Park_Martin", "TSAI"],
                                       ["horaud", "", 3, 1.5, b"tsai", ["tsai"]])
    args["setup"] = "eye_in_hand"
    strategies["setup"] = choices(["eye_in_hand", "eye_to_hand", "Eye-To-Hand", "EYE_IN_HAND", None],
                                  ["eye_on_hand", "", "in_hand", 0, b"eye_in_hand", ["eye_to_hand"]])
    fn = getattr(vsinv.calibration, which)
    ref = fn(**args)
    fuzz(data, fn, args, strategies, ref=ref, digest=hand_eye_digest, check=check_hand_eye)


@covers("calibrate_hand_eye")
def test_hand_eye_refusals_name_argument_and_pose() -> None:
    g, c = hand_eye_stations()
    bad = c.copy()
    bad[4, 1, 3] = np.nan
    err = call(vsinv.calibration.calibrate_hand_eye, g, bad, _expect=INVALID, _names=("target_poses",))
    assert err.kind == "invalid_pose" and err.argument == "target_poses" and err.index == 4
    assert "row 1, column 3" in str(err)
    g1, c1 = hand_eye_stations(one_axis=True)
    err = call(vsinv.calibration.calibrate_hand_eye, g1, c1)
    assert isinstance(err, vsinv.DegenerateGeometry) and err.kind == "degenerate_motion" and err.count == 6
    err = call(vsinv.calibration.calibrate_hand_eye, g[:2], c[:2])
    assert isinstance(err, vsinv.DegenerateGeometry) and "at least 3 poses" in str(err)
    still = np.array([np.eye(4)] * 4)
    err = call(vsinv.calibration.compare_hand_eye_methods, still, still)
    assert isinstance(err, vsinv.DegenerateGeometry) and "no gripper motion rotates" in str(err)
