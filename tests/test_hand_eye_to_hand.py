"""Eye-to-hand calibration (issue 31, item 3): the camera fixed in the base frame, the target on
the flange, ``calibrate_hand_eye(..., setup="eye_to_hand")`` returns camera-to-base.

Checked against OpenCV on synthetic stations with a known camera-to-base ``Y`` and
target-to-flange ``T`` (``hand_eye_stations.eye_to_hand_stations``):

- ``cv2.calibrateHandEye`` fed the inverted gripper poses (R_base2gripper, t_base2gripper), the
  reduction its documentation gives for eye-to-hand: the same method gives the same ``Y`` to
  1e-9, exact or noisy (the tolerance of tests/test_hand_eye.py), and exact poses give the
  truth to 1e-9.
- ``cv2.calibrateRobotWorldHandEye`` (Shah, Li), an independent formulation ``A X = Z B`` that
  solves for both unknowns: fed ``C_i`` as world-to-camera and ``G_i`` as base-to-gripper (the
  roles of the frames swapped), its gripper-to-camera is ``Y^-1`` and its base-to-world ``T^-1``;
  exact poses: all agree with each other and the truth to 1e-9 (measured ~1e-13).

OpenCV 5 dropped ``calibrateHandEye``: skipped then, as in tests/test_hand_eye.py.
"""

from __future__ import annotations

import numpy as np
import pytest

import vsinv

cv2 = pytest.importorskip("cv2")
if not hasattr(cv2, "calibrateHandEye"):
    pytest.skip("cv2.calibrateHandEye is missing (OpenCV 5): pip install 'opencv-python-headless>=4.8,<5'",
                allow_module_level=True)

from hand_eye_stations import CV_METHODS, NOISE_LEVELS, assert_within_noise, errors, eye_to_hand_stations, homogeneous, rigid  # noqa: E402


def inverted(g: np.ndarray) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """(R_base2gripper, t_base2gripper) of gripper-to-base poses: (R^T, -R^T t)."""
    r = [gi[:3, :3].T for gi in g]
    return r, [-ri @ gi[:3, 3] for ri, gi in zip(r, g)]


def opencv(g: np.ndarray, c: np.ndarray, method: str) -> np.ndarray:
    r_b2g, t_b2g = inverted(g)
    r, t = cv2.calibrateHandEye(r_b2g, t_b2g, list(c[:, :3, :3]), list(c[:, :3, 3]), method=CV_METHODS[method])
    return homogeneous(r, t)


@pytest.mark.parametrize("method", list(CV_METHODS))
@pytest.mark.parametrize("seed", range(5))
def test_exact_poses_give_the_camera_in_the_base_as_opencv(method: str, seed: int) -> None:
    g, c, y, _ = eye_to_hand_stations(np.random.default_rng(seed), 12)
    ours = vsinv.calibration.calibrate_hand_eye(g, c, method=method, setup="eye_to_hand")
    theirs = opencv(g, c, method)
    assert (ours.method, ours.setup) == (method, "eye_to_hand")
    assert np.abs(ours.matrix - theirs).max() < 1e-9
    assert np.abs(ours.matrix - y).max() < 1e-9
    assert ours.residuals.shape == (66, 2) and ours.pairs.shape == (66, 2)
    assert ours.max_rotation_deg < 1e-6 and ours.max_translation_m < 1e-9
    # Read as eye-in-hand, the same poses fit nothing: the set-up is not a detail.
    wrong = vsinv.calibration.calibrate_hand_eye(g, c, method=method)
    assert wrong.setup == "eye_in_hand" and wrong.max_rotation_deg > 1.0


@pytest.mark.parametrize("method", list(CV_METHODS))
@pytest.mark.parametrize("noise", NOISE_LEVELS, ids=lambda n: f"{n[0]}deg-{n[1] * 1000:g}mm")
def test_noisy_poses_within_the_noise_beside_opencv(method: str, noise: tuple[float, float]) -> None:
    rot_sd = noise[0]
    rng = np.random.default_rng(21)
    ours_err, theirs_err = [], []
    for _ in range(20):
        g, c, y, _ = eye_to_hand_stations(rng, 15, noise)
        ours = vsinv.calibration.calibrate_hand_eye(g, c, method=method, setup="eye_to_hand")
        theirs = opencv(g, c, method)
        assert np.abs(ours.matrix - theirs).max() < 1e-9
        ours_err.append(errors(ours.matrix, y))
        theirs_err.append(errors(theirs, y))
        assert 0.2 * rot_sd < ours.rms_rotation_deg < 6 * rot_sd
    # Within the noise of the truth: as in tests/test_hand_eye.py, with the lever of a rotation
    # error over the camera's distance to the base's origin (about 1.4 m) instead of 0.5 m.
    for err in (np.array(ours_err), np.array(theirs_err)):
        assert_within_noise(err, noise, lever_m=1.4)


ROBOT_WORLD = {
    name: getattr(cv2, f"CALIB_ROBOT_WORLD_HAND_EYE_{name.upper()}", None) for name in ("shah", "li")
}


@pytest.mark.skipif(not hasattr(cv2, "calibrateRobotWorldHandEye"), reason="cv2.calibrateRobotWorldHandEye is missing")
@pytest.mark.parametrize("robot_world", list(ROBOT_WORLD))
@pytest.mark.parametrize("seed", range(3))
def test_camera_in_the_base_agrees_with_opencv_robot_world(robot_world: str, seed: int) -> None:
    g, c, y, t = eye_to_hand_stations(np.random.default_rng(100 + seed), 12)
    # A X = Z B with A = C_i (world-to-camera: the target is OpenCV's world) and B = G_i
    # (OpenCV's base-to-gripper: the roles of base and gripper swapped), X = Y^-1, Z = T^-1.
    r_b2w, t_b2w, r_g2c, t_g2c = cv2.calibrateRobotWorldHandEye(
        list(c[:, :3, :3]), list(c[:, :3, 3]), list(g[:, :3, :3]), list(g[:, :3, 3]), method=ROBOT_WORLD[robot_world])
    theirs_y = np.linalg.inv(homogeneous(r_g2c, t_g2c))
    theirs_t = np.linalg.inv(homogeneous(r_b2w, t_b2w))
    assert np.abs(theirs_t - t).max() < 1e-9  # the mapping of the frames is right
    for method in CV_METHODS:
        ours = vsinv.calibration.calibrate_hand_eye(g, c, method=method, setup="eye_to_hand")
        assert np.abs(ours.matrix - theirs_y).max() < 1e-9, (method, np.abs(ours.matrix - theirs_y).max())


def test_compare_methods_and_diagnostics_eye_to_hand() -> None:
    g, c, y, _ = eye_to_hand_stations(np.random.default_rng(3), 10, (0.2, 0.001))
    agreement = vsinv.calibration.compare_hand_eye_methods(g, c, setup="eye_to_hand")
    assert agreement.setup == "eye_to_hand" and agreement.failures == {}
    assert set(agreement.calibrations) == {"tsai", "park", "daniilidis"}
    assert 0 < agreement.max_rotation_deg < 0.5 and 0 < agreement.max_translation_m < 0.02
    for name, cal in agreement.calibrations.items():
        assert (cal.method, cal.setup) == (name, "eye_to_hand")
        np.testing.assert_array_equal(
            cal.matrix, vsinv.calibration.calibrate_hand_eye(g, c, method=name, setup="eye_to_hand").matrix)
    cal = agreement.calibrations["park"]
    assert 20 < cal.axis_spread_deg <= 90 and cal.rotating_motions == cal.motions_used == 45
    assert repr(cal).startswith('HandEyeCalibration(method="park", setup="eye_to_hand"')
    assert 'setup="eye_to_hand"' in repr(agreement)


def test_degenerate_motions_and_bad_setups_are_refused() -> None:
    rng = np.random.default_rng(4)
    g, c, y, t = eye_to_hand_stations(rng, 6)
    with pytest.raises(vsinv.DegenerateGeometry, match="at least 3 poses"):
        vsinv.calibration.calibrate_hand_eye(g[:2], c[:2], setup="eye_to_hand")
    axis = np.array([0.2, -0.3, 0.9]) / np.linalg.norm([0.2, -0.3, 0.9])
    g1 = np.array([rigid(axis * a, rng.uniform(-0.2, 0.2, 3)) for a in np.linspace(0, 1.2, 6)])
    c1 = np.array([np.linalg.inv(y) @ gi @ t for gi in g1])
    with pytest.raises(vsinv.DegenerateGeometry, match=r"\(nearly\) parallel") as info:
        vsinv.calibration.compare_hand_eye_methods(g1, c1, setup="eye_to_hand")
    assert info.value.kind == "degenerate_motion" and info.value.count == 6
    bad = g.copy()
    bad[3, 0, 0] = 1.1
    with pytest.raises(vsinv.InvalidInput, match="not orthonormal") as pose:
        vsinv.calibration.calibrate_hand_eye(bad, c, setup="eye_to_hand")
    assert pose.value.argument == "gripper_poses" and pose.value.index == 3
    for setup in ("eye_on_hand", "", 3, b"eye_to_hand", ["eye_to_hand"]):
        with pytest.raises(vsinv.InvalidInput, match="setup") as err:
            vsinv.calibration.calibrate_hand_eye(g, c, setup=setup)
        assert err.value.argument == "setup"
        with pytest.raises(vsinv.InvalidInput, match="setup"):
            vsinv.calibration.compare_hand_eye_methods(g, c, setup=setup)
    assert vsinv.calibration.calibrate_hand_eye(g, c, setup="Eye-To-Hand").setup == "eye_to_hand"
