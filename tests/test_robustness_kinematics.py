"""Robustness of the public Python API under hypothesis, the arms' kinematics (``fk``, ``ik``
and ``IkSolution``).

The promise and the harness are described in tests/robustness_harness.py.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

import vsinv
from robustness_harness import ANY, INVALID, arrays, call, choices, covers, floats, fuzz, fuzz_settings, returned

Q = np.array([0.1, -1.2, 1.0, -0.5, 1.4, 0.3])
SEED = Q + np.array([0.05, -0.04, 0.03, -0.02, 0.05, 0.01])
ARMS = choices(["ur5"], ["kuka", "", None, 5, b"ur5", ["ur5"]])
#: A pose must be a rigid motion: scaled, zeroed or flipped ones are refused.
NOT_RIGID = {"zero": INVALID, "negative": INVALID, "fewer": INVALID, "empty": INVALID, "flat": INVALID,
             "huge": INVALID, "bool": INVALID, "tiny": INVALID, "float32": ANY}


def check_solution(target: np.ndarray) -> Any:
    def check(out: Any) -> None:
        assert isinstance(out, vsinv.kinematics.IkSolution)
        q = out.joints
        assert q.shape == (6,) and np.all(np.abs(q) <= 2 * np.pi)
        d = np.linalg.inv(call(vsinv.kinematics.fk, "ur5", q)) @ target
        assert np.linalg.norm(d[:3, 3]) < 1e-9 and out.position_residual <= 1e-10
        assert out.rotation_residual <= 1e-10 and out.iterations >= 0 and out.seed >= 0
    return check


@covers("ik", "IkSolution", "IkSolution.joints", "IkSolution.position_residual", "IkSolution.rotation_residual",
        "IkSolution.iterations", "IkSolution.seed")
@fuzz_settings(120)
@given(st.data())
def test_ik(data: Any) -> None:
    pose = vsinv.kinematics.fk("ur5", Q)
    args: dict[str, Any] = {"arm": "ur5", "pose": pose, "seed": SEED}
    strategies = {
        "arm": ARMS,
        "pose": arrays(pose, overrides=NOT_RIGID),
        "seed": arrays(SEED, overrides={"none": ANY, "flat": ANY}),
    }
    ref = vsinv.kinematics.ik("ur5", pose, SEED)
    name, v, out = fuzz(data, vsinv.kinematics.ik, args, strategies, ref=ref, digest=lambda s: s.joints, rtol=1e-12)
    if returned(out):
        check_solution(np.asarray(v.value, dtype=float) if name == "pose" else pose)(out)


@covers("fk")
@fuzz_settings(100)
@given(st.data())
def test_fk(data: Any) -> None:
    args: dict[str, Any] = {"arm": "ur5", "joints": Q}
    strategies = {"arm": ARMS, "joints": arrays(Q)}
    name, v, out = fuzz(data, vsinv.kinematics.fk, args, strategies, ref=vsinv.kinematics.fk("ur5", Q), rtol=1e-12)
    if returned(out):
        assert out.shape == (4, 4)
        np.testing.assert_allclose(out[:3, :3] @ out[:3, :3].T, np.eye(3), atol=1e-9)


@covers("ik")
@fuzz_settings(20)
@given(st.lists(st.floats(-3, 3), min_size=3, max_size=3), st.lists(st.floats(-3, 3), min_size=3, max_size=3))
def test_ik_returns_or_refuses_any_pose(position: list[float], thetau: list[float]) -> None:
    """Any rigid motion: reached within 1e-9, or refused as unreachable naming the pose."""
    pose = vsinv.geometry.pose_from_position_thetau(position, thetau)
    out = call(vsinv.kinematics.ik, "ur5", pose)
    if returned(out):
        check_solution(pose)(out)


J_UR5 = np.array([[0.1, -0.3, 0.2, 0.0, 0.05, 0.0], [0.4, 0.0, 0.0, 0.1, 0.0, 0.02], [0.0, 0.4, 0.3, 0.1, 0.0, 0.0],
                  [0.0, 0.0, 0.0, 0.0, 1.0, 0.0], [0.0, 1.0, 1.0, 1.0, 0.0, 0.3], [1.0, 0.0, 0.0, 0.0, 0.1, 0.9]])
TWIST = np.array([0.05, -0.02, 0.03, 0.1, -0.2, 0.15])


@covers("damped_least_squares")
@fuzz_settings(100)
@given(st.data())
def test_damped_least_squares(data: Any) -> None:
    args: dict[str, Any] = {"jacobian": J_UR5, "twist": TWIST, "damping": 0.02}
    strategies = {
        "jacobian": arrays(J_UR5, overrides={"fewer": INVALID, "empty": INVALID}),
        "twist": arrays(TWIST, overrides={"fewer": INVALID, "empty": INVALID}),
        "damping": floats(0.02),
    }
    ref = vsinv.kinematics.damped_least_squares(J_UR5, TWIST)
    name, v, out = fuzz(data, vsinv.kinematics.damped_least_squares, args, strategies, ref=ref, rtol=1e-12)
    if returned(out):
        assert out.shape == (np.asarray(v.value).shape[1] if name == "jacobian" else 6,)


ARM_SCENARIO = vsinv.load_scenario("arm-ur5-12-6")


@covers("Scenario.arm", "ScenarioArm", "ScenarioArm.model", "ScenarioArm.source", "ScenarioArm.end_effector", "ScenarioArm.joint_names", "ScenarioArm.base", "ScenarioArm.mount", "ScenarioArm.believed_mount", "ScenarioArm.start", "ScenarioArm.lower", "ScenarioArm.upper", "ScenarioArm.velocity", "ScenarioArm.damping", "ScenarioArm.min_manipulability", "ScenarioArm.camera_pose", "ScenarioArm.manipulability", "ScenarioArm.joint_velocities", "ScenarioArm.link_poses", "ScenarioArm.ik")
@fuzz_settings(100)
@given(st.data())
def test_scenario_arm_joint_velocities(data: Any) -> None:
    """`Scenario.arm()` (None for a free camera) and its `joint_velocities(jacobian, joints,
    twist)`: every variant of an argument gives the canonical answer or InvalidInput naming it;
    `camera_pose` and `manipulability` refuse bad joints by name."""
    assert vsinv.load_scenario("lens-12-12").arm() is None
    arm = ARM_SCENARIO.arm()
    assert arm is not None
    q = np.asarray(arm.start)
    args: dict[str, Any] = {"jacobian": J_UR5, "joints": q, "twist": TWIST}
    strategies = {
        "jacobian": arrays(J_UR5, overrides={"fewer": INVALID, "empty": INVALID}),
        "joints": arrays(q, overrides={"fewer": INVALID, "empty": INVALID}),
        "twist": arrays(TWIST, overrides={"fewer": INVALID, "empty": INVALID}),
    }
    ref = arm.joint_velocities(J_UR5, q, TWIST)
    assert isinstance(arm, vsinv.sim.ScenarioArm) and len(arm.joint_names) == 6 and arm.model == "ur5"
    assert arm.end_effector == "tool0" and arm.damping > 0 and arm.min_manipulability >= 0
    assert arm.source == "builtin:ur5"
    for name in ("base", "mount", "believed_mount", "start", "lower", "upper", "velocity"):
        assert np.isfinite(getattr(arm, name)).all()
    fuzz(data, arm.joint_velocities, args, strategies, api="ScenarioArm.joint_velocities", ref=ref, rtol=1e-12,
         digest=lambda out: out[0] if isinstance(out, tuple) else out)
    for method in (arm.camera_pose, arm.manipulability, arm.link_poses):
        call(method, data.draw(st.sampled_from([q[:5], np.r_[q, 0.0], np.full(6, np.nan), "abc"])),
             _api=f"ScenarioArm.{method.__name__}", _expect=INVALID, _names=("joints",), _finite=False)
    # ik: the flange's pose at the start joints (base^-1 camera mount^-1) comes back to it;
    # a bad pose or seed is refused by name
    ee = np.linalg.inv(arm.base) @ arm.camera_pose(q) @ np.linalg.inv(arm.mount)
    np.testing.assert_allclose(np.linalg.inv(arm.base) @ arm.camera_pose(arm.ik(ee, seed=q)) @ np.linalg.inv(arm.mount),
                               ee, atol=1e-9)
    call(arm.ik, data.draw(st.sampled_from([ee[:3], np.full((4, 4), np.nan), "abc"])), _api="ScenarioArm.ik",
         _expect=INVALID, _names=("pose",), _finite=False)
    call(arm.ik, ee, seed=data.draw(st.sampled_from([q[:5], np.r_[q, 0.0], np.full(6, np.nan), "abc"])),
         _api="ScenarioArm.ik", _expect=INVALID, _names=("seed",), _finite=False)
