"""Hand-eye calibration (issue 20, item 3) against OpenCV's ``cv2.calibrateHandEye`` on
synthetic stations with a known camera-to-gripper transform X.

OpenCV 5 dropped ``calibrateHandEye``: the tests need ``opencv-python-headless>=4.8,<5`` (the
``test`` extra) and skip with that hint otherwise. Both libraries take the same inputs
(gripper-to-base and target-to-camera poses) and use every pair of stations; OpenCV (>= 4.10)
leaves out of Tsai-Lenz the motions rotating outside 17.3-116.4 degrees, and so does vsinv.

- Exact poses: vsinv and OpenCV agree to 1e-9 (in fact to ~1e-15) and both give X.
- Noisy target poses (the camera's pose estimates; 0.1 degree and 1 mm up to 1 degree and
  5 mm): both stay within the noise of the truth, and still agree with each other to 1e-9,
  far below it (the same method on the same numbers).
"""

from __future__ import annotations

import numpy as np
import pytest

import vsinv

cv2 = pytest.importorskip("cv2")
if not hasattr(cv2, "calibrateHandEye"):
    pytest.skip("cv2.calibrateHandEye is missing (OpenCV 5): pip install 'opencv-python-headless>=4.8,<5'",
                allow_module_level=True)

from hand_eye_stations import CV_METHODS, NOISE_LEVELS, assert_within_noise, errors, opencv, rigid, stations  # noqa: E402


@pytest.mark.parametrize("method", list(CV_METHODS))
@pytest.mark.parametrize("seed", range(5))
def test_exact_poses_agree_with_opencv(method: str, seed: int) -> None:
    g, c, x = stations(np.random.default_rng(seed), 12)
    ours = vsinv.calibration.calibrate_hand_eye(g, c, method=method)
    theirs = opencv(g, c, method)
    assert ours.method == method
    assert np.abs(ours.matrix - theirs).max() < 1e-9
    assert np.abs(ours.matrix - x).max() < 1e-9
    assert ours.residuals.shape == (66, 2) and ours.pairs.shape == (66, 2)
    assert ours.max_rotation_deg < 1e-6 and ours.max_translation_m < 1e-9


@pytest.mark.parametrize("method", list(CV_METHODS))
@pytest.mark.parametrize("noise", NOISE_LEVELS, ids=lambda n: f"{n[0]}deg-{n[1] * 1000:g}mm")
def test_noisy_poses_within_the_noise_beside_opencv(method: str, noise: tuple[float, float]) -> None:
    rot_sd = noise[0]
    rng = np.random.default_rng(20)
    ours_err, theirs_err = [], []
    for _ in range(20):
        g, c, x = stations(rng, 15, noise)
        ours = vsinv.calibration.calibrate_hand_eye(g, c, method=method)
        theirs = opencv(g, c, method)
        # The same method on the same numbers: the two agree far below the noise.
        assert np.abs(ours.matrix - theirs).max() < 1e-9
        ours_err.append(errors(ours.matrix, x))
        theirs_err.append(errors(theirs, x))
        # The residuals of A X = X B show the noise: a pair of target poses, each off by about
        # sqrt(3) rot_sd.
        assert 0.2 * rot_sd < ours.rms_rotation_deg < 6 * rot_sd
    # Within the noise of the truth: the median error of X is below the noise of one target
    # pose (its RMS rotation, sqrt(3) rot_sd; its RMS translation plus the lever of its
    # rotation over the 0.5 m to the target), the largest below three times that.
    for err in (np.array(ours_err), np.array(theirs_err)):
        assert_within_noise(err, noise, lever_m=0.5)


def test_compare_methods_and_diagnostics() -> None:
    g, c, x = stations(np.random.default_rng(3), 10, (0.2, 0.001))
    agreement = vsinv.calibration.compare_hand_eye_methods(g, c)
    assert set(agreement.calibrations) == {"tsai", "park", "daniilidis"} and agreement.failures == {}
    assert 0 < agreement.max_rotation_deg < 0.5 and 0 < agreement.max_translation_m < 0.01
    for name, cal in agreement.calibrations.items():
        assert cal.method == name
        np.testing.assert_array_equal(cal.matrix, vsinv.calibration.calibrate_hand_eye(g, c, method=name).matrix)
    cal = agreement.calibrations["park"]
    assert 20 < cal.axis_spread_deg <= 90
    assert cal.axis_eigenvalues.shape == (3,) and abs(cal.axis_eigenvalues.sum() - 1) < 1e-12
    assert cal.rotating_motions == cal.motions_used == 45
    assert (cal.pairs[:, 0] < cal.pairs[:, 1]).all()
    assert repr(cal).startswith('HandEyeCalibration(method="park"')


def test_degenerate_motions_are_refused() -> None:
    rng = np.random.default_rng(4)
    g, c, x = stations(rng, 6)
    with pytest.raises(vsinv.DegenerateGeometry, match="at least 3 poses") as info:
        vsinv.calibration.calibrate_hand_eye(g[:2], c[:2])
    assert info.value.kind == "degenerate_motion" and info.value.count == 2
    # Rotations about one axis only (any translations).
    axis = np.array([0.2, -0.3, 0.9]) / np.linalg.norm([0.2, -0.3, 0.9])
    target_in_base = rigid(np.zeros(3), np.array([0.6, 0.0, 0.0]))
    g1 = np.array([rigid(axis * a, rng.uniform(-0.2, 0.2, 3)) for a in np.linspace(0, 1.2, 6)])
    c1 = np.array([np.linalg.inv(gi @ x) @ target_in_base for gi in g1])
    with pytest.raises(vsinv.DegenerateGeometry, match=r"the rotation axes of the gripper motions are \(nearly\) parallel: spread 0\.000 degrees < 1 degree"):
        vsinv.calibration.calibrate_hand_eye(g1, c1, method="park")
    with pytest.raises(vsinv.InvalidInput, match="invalid parameter `method`: unknown hand-eye method \"horaud\": expected 'tsai', 'park' or 'daniilidis'") as bad_method:
        vsinv.calibration.calibrate_hand_eye(g, c, method="horaud")
    assert bad_method.value.argument == "method"
