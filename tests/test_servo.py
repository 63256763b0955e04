"""vsinv.Servo: the servo session from Python, with its own projection and no simulator."""

from __future__ import annotations

import numpy as np
import pytest

import vsinv

RELIEF = [0.0, 0.06, -0.04, 0.03, -0.06, 0.05, 0.02, -0.03, 0.04, -0.05, 0.01, 0.06]
POINTS = np.array([[-0.15 + 0.1 * (i % 4), -0.12 + 0.12 * (i // 4), 0.6 + RELIEF[i]] for i in range(12)])
K_STAR = vsinv.Intrinsics(1200, 1200, 384, 288)
K = vsinv.Intrinsics(600, 600, 384, 288)
K_HAT = vsinv.Intrinsics(650, 570, 395, 280)
START = [0.05, -0.04, -0.06, 0.1, -0.12, 0.3]


def view(pose: np.ndarray, k: vsinv.Intrinsics = K) -> tuple[np.ndarray, np.ndarray]:
    rot, centre = pose[:3, :3], pose[:3, 3]
    return vsinv.geometry.project((POINTS - centre) @ rot, k)


def reference() -> tuple[np.ndarray, np.ndarray]:
    return view(np.eye(4), K_STAR)


def run(servo: vsinv.Servo, per_step: bool = False, limit: int = 3000) -> tuple[vsinv.ServoStep, np.ndarray]:
    pose = vsinv.geometry.exp_twist(START)
    for _ in range(limit):
        pixels, depths = view(pose)
        step = servo.step(pixels, depths=depths if per_step else None)
        if not step.running:
            return step, pose
        pose = pose @ vsinv.geometry.exp_twist(step.twist * 0.04)
    raise AssertionError("the session never stopped")


def test_session_converges_across_a_lens_change_and_reports_why():
    px, z = reference()
    servo = vsinv.Servo(px, K_HAT, reference_depths=z)
    step, pose = run(servo)
    assert step.verdict == "converged" and step.reason == "stop rule met"
    assert np.linalg.norm(pose[:3, 3]) < 1e-3
    assert np.all(step.twist == 0.0)
    t = step.telemetry
    assert t["iteration"] == servo.iterations and t["invariant_error"] < 1e-4 and not t["law_ran"]
    c = servo.certainty()
    assert c is not None and c["translation_bound"] < 5e-3
    assert servo.law == "invariant" and servo.stop_rule == "invariant" and len(servo.basis) == 3


def test_first_twist_is_the_controllers():
    """The session's law is the InvariantController: the same twist from the same image."""
    px, z = reference()
    servo = vsinv.Servo(px, K_HAT, reference_depths=z, basis=(0, 5, 10))
    ctl = vsinv.laws.InvariantController(px, K_HAT, basis=(0, 5, 10))
    pixels, _ = view(vsinv.geometry.exp_twist(START))
    step = servo.step(pixels)
    assert step.running and step.telemetry["law_ran"]
    np.testing.assert_array_equal(step.twist, ctl.step(pixels, z))
    np.testing.assert_array_equal(step.telemetry["eps"], ctl.eps)


@pytest.mark.parametrize("source", ["per_step", "resection"])
def test_depth_sources(source):
    px, z = reference()
    if source == "resection":
        first, _ = view(vsinv.geometry.exp_twist([0.0, 0.0, -0.1, 0, 0, 0]))
        second, _ = view(vsinv.geometry.exp_twist([0.05, 0.0, -0.1, 0, 0, 0]))
        first_depths, _, _ = vsinv.calibration.depths_from_translation(first, second)
        depths: object = vsinv.calibration.ResectionDepths(first, first_depths, px, 0.6)
    else:
        depths = source
    servo = vsinv.Servo(px, K_HAT, depths=depths, reference_depths=z)
    step, pose = run(servo, per_step=source == "per_step")
    assert step.verdict == "converged", step.reason
    assert np.linalg.norm(pose[:3, 3]) < 2e-3


def test_ibvs_on_one_camera_with_a_constant_depth():
    px, _ = view(np.eye(4))
    servo = vsinv.Servo(px, K, "ibvs", depths=0.6, interaction="current")
    step, pose = run(servo)
    assert step.verdict == "converged" and servo.stop_rule == "pixel"
    assert np.linalg.norm(pose[:3, 3]) < 5e-3


def test_lost_features_and_the_iteration_limit():
    px, z = reference()
    servo = vsinv.Servo(px, K_HAT, reference_depths=z)
    pixels, _ = view(vsinv.geometry.exp_twist(START))
    visible = np.ones(12, bool)
    first = servo.basis
    visible[first[0]] = False  # a hidden basis point: the basis switches (issue 27)
    step = servo.step(pixels, visible=visible)
    assert step.verdict == "running" and first[0] not in servo.basis and servo.basis_switches == 1
    assert step.telemetry["basis"] == servo.basis and step.telemetry["basis_switches"] == 1
    step = servo.step(pixels, visible=np.arange(12) < 5)  # five points: fewer than the law's six
    assert step.verdict == "lost_features" and "5 of 12" in (step.reason or "")
    watch = vsinv.Servo(px, K_HAT, "none", reference_depths=z, stop={"max_iterations": 2})
    verdicts = [watch.step(pixels).verdict for _ in range(3)]
    assert verdicts == ["running", "running", "observed"]


@pytest.mark.parametrize("hold", [None, 0, 2])
def test_a_basis_point_missing_for_two_images_is_ridden_out_as_basis_hold_says(hold):
    """A basis point seen before and then missing: `basis_hold` images (default 3) keep the
    basis and repeat the last twist; 0 changes the basis at once."""
    px, z = reference()
    servo = vsinv.Servo(px, K_HAT, reference_depths=z, **({} if hold is None else {"basis_hold": hold}))
    pixels, _ = view(vsinv.geometry.exp_twist(START))
    first = servo.step(pixels)
    basis, visible = servo.basis, np.ones(12, bool)
    visible[basis[0]] = False
    twists = [servo.step(pixels, visible=visible).twist for _ in range(2)]
    if hold == 0:
        assert servo.basis_switches == 1 and basis[0] not in servo.basis and servo.basis_held_images == 0
    else:  # the default (3) and 2 both cover two images
        assert servo.basis == basis and servo.basis_switches == 0 and servo.basis_held_images == 2
        assert all(np.array_equal(t, first.twist) for t in twists)
    if hold == 2:  # a third image is past the hold: the basis changes
        servo.step(pixels, visible=visible)
        assert servo.basis_switches == 1 and basis[0] not in servo.basis


@pytest.mark.parametrize("bad", [-1, 1.5, "3"])
def test_a_bad_basis_hold_is_refused_by_name(bad):
    px, z = reference()
    with pytest.raises(vsinv.InvalidInput, match="^basis_hold: ") as err:
        vsinv.Servo(px, K_HAT, reference_depths=z, basis_hold=bad)
    assert err.value.argument == "basis_hold"


@pytest.mark.parametrize(
    ("law", "kwargs", "name"),
    [
        ("invariant", {"interaction": "desired"}, "interaction"),
        ("ibvs", {"rz_task": "tau21"}, "rz_task"),
        ("ibvs", {"feedforward": False}, "feedforward"),
        ("ibvs", {"gain_rz": 2.0}, "gain_rz"),
        ("none", {"adaptive_gain": (4.0, 0.4, 30.0)}, "adaptive_gain"),
    ],
)
def test_an_argument_of_another_law_is_refused_by_name(law, kwargs, name):
    px, z = reference()
    with pytest.raises(vsinv.InvalidInput, match=f'^{name}: not an argument of the "{law}" law') as err:
        vsinv.Servo(px, K_HAT, law, reference_depths=z, **kwargs)
    assert err.value.argument == name and err.value.kind == "invalid_argument"


def test_bad_input_is_refused_by_name():
    px, z = reference()
    with pytest.raises(vsinv.InvalidInput, match="stop.windw: unknown key") as err:
        vsinv.Servo(px, K_HAT, reference_depths=z, stop={"windw": 3})
    assert err.value.argument == "stop.windw"
    with pytest.raises(vsinv.InvalidInput, match='law: expected "invariant", "ibvs" or "none"'):
        vsinv.Servo(px, K_HAT, "pbvs", reference_depths=z)
    with pytest.raises(vsinv.InvalidInput, match="invalid parameter `depths`: the reference depth source needs the reference image's depths"):
        vsinv.Servo(px, K_HAT)  # the reference depth source without reference depths
    servo = vsinv.Servo(px, K_HAT, reference_depths=z)
    bad = px.copy()
    bad[4, 1] = np.nan
    with pytest.raises(vsinv.InvalidInput, match="pixels: non-finite value at row 4, column 1") as err:
        servo.step(bad)
    assert (err.value.argument, err.value.row, err.value.column) == ("pixels", 4, 1)
    with pytest.raises(vsinv.InvalidInput, match="pixels: expected 12 points"):
        servo.step(px[:7])
    with pytest.raises(vsinv.InvalidInput, match="invalid parameter `depths`: this session's depths come from Reference; pass none"):
        servo.step(px, depths=z)  # this session's depths are the reference's
    per_step = vsinv.Servo(px, K_HAT, depths="per_step")
    with pytest.raises(vsinv.InvalidInput, match="invalid parameter `depths`: this session takes depths each step"):
        per_step.step(px)
    with pytest.raises(vsinv.InvalidInput, match=r"visible: expected shape \(12,\)"):
        servo.step(px, visible=np.ones(3, bool))
