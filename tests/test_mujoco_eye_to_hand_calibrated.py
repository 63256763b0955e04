"""Eye-to-hand with a calibrated camera-to-base transform (issue 31, item 3), the path a user
follows: the UR5e of `mujoco-eye-to-hand-12-6` carries the dots to stations, MuJoCo renders the
fixed camera's images, the dots' pose in the camera is measured from each
(`vsinv.mujoco._calibrate.target_pose`), `calibrate_hand_eye(..., setup="eye_to_hand")` gives
the camera-to-base transform, and the servo runs with it (`[world.eye_to_hand] camera_to_base`).

Independent checks: the scene's truth (the arm's base in the camera, which the calibration
never reads), OpenCV's `solvePnP` on the same pixels and `calibrateHandEye` on the inverted
gripper poses (OpenCV's documented eye-to-hand use) on the same stations. Skips without mujoco
or EGL (saying what to install).
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import vsinv  # noqa: E402
import vsinv.mujoco as vm  # noqa: E402
from vsinv import geometry  # noqa: E402
from vsinv.mujoco import _calibrate  # noqa: E402

pytestmark = pytest.mark.sim

_WHY_NOT = vm.available()
needs_mujoco = pytest.mark.skipif(_WHY_NOT is not None, reason=_WHY_NOT or "")
NAME = "mujoco-eye-to-hand-12-6"


def _gap(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """(translation m, rotation degrees) between two 4x4 poses."""
    d = np.linalg.inv(a) @ b
    return float(np.linalg.norm(a[:3, 3] - b[:3, 3])), float(np.degrees(np.linalg.norm(geometry.thetau_from_pose(d)[1])))


def test_rigid_fit_recovers_a_transform() -> None:
    """The least-squares rigid fit against a known transform (no MuJoCo needed)."""
    rng = np.random.default_rng(3)
    truth = geometry.pose_from_position_thetau([0.1, -0.2, 0.5], [0.3, -0.4, 1.2])
    source = rng.normal(size=(12, 3))
    target = source @ truth[:3, :3].T + truth[:3, 3]
    np.testing.assert_allclose(_calibrate.rigid_fit(source, target), truth, atol=1e-12)


@needs_mujoco
def test_calibrated_camera_to_base_agrees_with_the_truth_and_opencv() -> None:
    """10 stations: each measured pose of the dots within 1 mm and 0.2 degree of the truth and of
    OpenCV's solvePnP (iterative, from the same pixels' correspondences); the calibrated
    camera-to-base within what those pose errors imply of the truth (2 mm, 0.2 degree), and
    within 0.1 mm and 0.01 degree of OpenCV's calibrateHandEye (Tsai) on the same stations."""
    cv2 = pytest.importorskip("cv2")
    d = vsinv.load_scenario(NAME).to_dict()
    with vm.World.from_scenario(d) as world:
        result, st = vm.calibrate_eye_to_hand(world, count=10, seed=1)
        base = np.asarray(world.arm.base)
        K, points = np.asarray(world.K.matrix), np.asarray(world.target_points)
    station_t, station_r = zip(*(_gap(m, t) for m, t in zip(st.target_poses, st.true_target_poses)))
    print("station pose errors: max %.3f mm, %.4f deg" % (1e3 * max(station_t), max(station_r)))
    assert max(station_t) < 1e-3 and max(station_r) < 0.2
    for m, t in zip(st.target_poses, st.true_target_poses):  # OpenCV's PnP on the model's exact projection
        cam = points @ t[:3, :3].T + t[:3, 3]
        pixels = (cam[:, :2] / cam[:, 2:]) * [K[0, 0], K[1, 1]] + [K[0, 2], K[1, 2]]
        ok, rvec, tvec = cv2.solvePnP(points, pixels, K, None, flags=cv2.SOLVEPNP_ITERATIVE)
        assert ok
        oracle = np.eye(4)
        oracle[:3, :3], oracle[:3, 3] = cv2.Rodrigues(rvec)[0], tvec.ravel()
        assert max(_gap(oracle, t)) < 1e-6  # the oracle itself on exact pixels
        dt, dr = _gap(m, oracle)
        assert dt < 1e-3 and dr < 0.2, (dt, dr)
    truth = np.linalg.inv(base)  # camera-to-base: the camera's frame in the base frame
    dt, dr = _gap(np.asarray(result.matrix), truth)
    print("calibrated camera-to-base vs truth: %.3f mm, %.4f deg; residuals rms %.3f mm, %.4f deg"
          % (1e3 * dt, dr, 1e3 * result.rms_translation_m, result.rms_rotation_deg))
    assert dt < 2e-3 and dr < 0.2
    inverted = [np.linalg.inv(g) for g in st.gripper_poses]  # base-to-gripper: OpenCV's eye-to-hand
    R, t = cv2.calibrateHandEye([g[:3, :3] for g in inverted], [g[:3, 3] for g in inverted],
                                [c[:3, :3] for c in st.target_poses], [c[:3, 3] for c in st.target_poses],
                                method=cv2.CALIB_HAND_EYE_TSAI)
    opencv = np.eye(4)
    opencv[:3, :3], opencv[:3, 3] = R, t.ravel()
    dt, dr = _gap(np.asarray(result.matrix), opencv)
    assert dt < 1e-4 and dr < 0.01, (dt, dr)


@needs_mujoco
@pytest.mark.slow  # two closed loops of about 200 frames each: about 10 s idle, 30 s on a busy machine
def test_the_servo_with_the_calibrated_transform_converges() -> None:
    """The lens change eye-to-hand with the calibrated camera-to-base (from 10 stations)
    converges like the run with the true transform (within the scenario's tolerances, in at most
    20 % more frames); a camera-to-base turned 10 degrees off changes the run (the key is read)."""
    d = vsinv.load_scenario(NAME).to_dict()
    with vm.World.from_scenario(d) as world:
        result, _ = vm.calibrate_eye_to_hand(world, count=10, seed=1)
        true_run = vm.run_loop(d, world=world, max_iterations=400)
        calibrated = vm.run_loop(vm.with_camera_to_base(d, result.matrix), world=world,
                                 max_iterations=400).summary
        off = np.asarray(result.matrix) @ geometry.pose_from_position_thetau([0, 0, 0], [0, np.radians(10), 0])
        wrong = vm.run_loop(vm.with_camera_to_base(d, off), world=world, max_iterations=20)
    true = true_run.summary
    print("true transform:", true["status"], true["iterations"], 1e3 * true["final_translation_error"], "mm")
    print("calibrated:", calibrated["status"], calibrated["iterations"], 1e3 * calibrated["final_translation_error"], "mm")
    assert true["status"] == "converged" and calibrated["status"] == "converged", calibrated["message"]
    assert calibrated["final_translation_error"] < 5e-3 and np.degrees(calibrated["final_rotation_error"]) < 0.5
    assert calibrated["iterations"] <= 1.2 * true["iterations"] + 5
    gap = np.linalg.norm(wrong.result.pose[20, :3, 3] - true_run.result.pose[20, :3, 3])
    assert gap > 1e-3, gap  # 10 degrees of camera-to-base error moved the target elsewhere


def test_camera_to_base_is_read_and_checked() -> None:
    """`[world.eye_to_hand] camera_to_base` round-trips through the scenario and a non-finite
    value is refused naming the key and the position (no MuJoCo needed)."""
    d = vsinv.load_scenario(NAME).to_dict()
    good = vm.with_camera_to_base(d, geometry.pose_from_position_thetau([0.0, 1.0, 0.3], [0.5, 0.0, 0.0]))
    back = vsinv.load_scenario(good).to_dict()["world"]["eye_to_hand"]["camera_to_base"]
    np.testing.assert_allclose(back["position"], [0.0, 1.0, 0.3], atol=1e-12)
    np.testing.assert_allclose(back["rotation_deg"], [np.degrees(0.5), 0.0, 0.0], atol=1e-9)
    bad = vm.with_camera_to_base(d, np.eye(4))
    bad["world"]["eye_to_hand"]["camera_to_base"]["position"][2] = float("nan")
    with pytest.raises(vsinv.InvalidInput, match=r"world\.eye_to_hand\.camera_to_base\.position\[2\]"):
        vsinv.load_scenario(bad).arm()
