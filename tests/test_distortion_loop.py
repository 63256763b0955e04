"""Lens distortion in the simulator, checked against OpenCV: projections through the servo
lens (cv2.projectPoints), rendered images (cv2.remap of the pinhole rendering through
cv2.undistortPoints' map), and the run with the distortion known or not."""

from __future__ import annotations

import cv2
import numpy as np

import vsinv

BARREL = [-0.30, 0.10, 0.0005, -0.0008, -0.02]


def _barrel_dict(**vision: float) -> dict:
    d = vsinv.load_scenario("lens-12-6-barrel").to_dict()
    d["vision"] = {"noise_sigma": 0.0, "blur_sigma": 0.0, "dot_radius": 0.006, **vision}
    return d


def _start_pose(d: dict) -> np.ndarray:
    return vsinv.geometry.pose_from_position_thetau(d["start"]["position"], np.radians(d["start"]["rotation_deg"]))


def _camera_matrix(camera: dict) -> np.ndarray:
    return np.array([[camera["fku"], 0.0, camera["u0"]], [0.0, camera["fkv"], camera["v0"]], [0.0, 0.0, 1.0]])


def test_projections_through_the_lens_match_opencv() -> None:
    d = _barrel_dict()
    pose = _start_pose(d)
    _, pixels, visible = vsinv.vision.render_view(d, pose)
    assert visible.all()
    # X_c = R^T (X - c): OpenCV's rvec, tvec of F* in the camera frame.
    r, c = pose[:3, :3], pose[:3, 3]
    rvec, _ = cv2.Rodrigues(r.T)
    points = np.asarray(d["object"]["points"], dtype=np.float64)
    expected, _ = cv2.projectPoints(points, rvec, -r.T @ c, _camera_matrix(d["camera"]), np.array(BARREL))
    np.testing.assert_allclose(pixels, expected.reshape(-1, 2), atol=1e-9)


def test_rendering_through_the_lens_matches_opencv_remap() -> None:
    d = _barrel_dict()
    pose = _start_pose(d)
    distorted, pixels, _ = vsinv.vision.render_view(d, pose)
    pinhole_dict = _barrel_dict()
    del pinhole_dict["camera"]["distortion"]
    pinhole, _, _ = vsinv.vision.render_view(pinhole_dict, pose)
    # Each pixel of the distorted image shows the pinhole image at its undistorted position.
    h, w = distorted.shape
    k = _camera_matrix(d["camera"])
    grid = np.stack(np.meshgrid(np.arange(w), np.arange(h)), axis=-1).reshape(-1, 1, 2).astype(np.float64)
    ideal = cv2.undistortPoints(grid, k, np.array(BARREL), P=k).reshape(h, w, 2).astype(np.float32)
    remapped = cv2.remap(pinhole, ideal[..., 0], ideal[..., 1], cv2.INTER_LINEAR, borderValue=30)
    ours = vsinv.vision.detect_dots(distorted).centroids
    theirs = vsinv.vision.detect_dots(remapped).centroids
    assert len(ours) == len(theirs) == len(pixels)
    # Both lists are sorted by row then column of the centroids: match by nearest.
    gap = np.linalg.norm(ours[:, None, :] - theirs[None, :, :], axis=-1).min(axis=1)
    assert gap.max() < 0.05, gap
    # The dots sit where the lens projects their centres (the centroid of a squeezed disc is
    # a little off its projected centre).
    off = np.linalg.norm(ours[:, None, :] - pixels[None, :, :], axis=-1).min(axis=1)
    assert off.max() < 0.1, off
    # The dots cover the same area (sampling the pinhole image at the undistorted positions
    # integrates its coverage over the distorted pixels).
    ink = [float(np.sum(img.astype(np.float64) - 30.0)) for img in (distorted, remapped)]
    assert abs(ink[0] / ink[1] - 1.0) < 0.01, ink


def test_known_distortion_converges_and_unknown_does_not() -> None:
    known = vsinv.run_scenario("lens-12-6-barrel", record=False).summary
    assert known["status"] == "converged"
    assert known["final_translation_error"] < 1e-3 and np.degrees(known["final_rotation_error"]) < 0.1
    d = vsinv.load_scenario("lens-12-6-barrel").to_dict()
    d["estimate"] = {**{k: d["camera"][k] for k in ("fku", "fkv", "u0", "v0")}, "distortion": [0.0] * 5}
    unknown = vsinv.run_scenario(d, record=False).summary
    assert unknown["status"] != "converged"
    assert unknown["final_translation_error"] > 5e-3


BARREL_ROS_YAML = """image_width: 832
image_height: 624
camera_matrix: {rows: 3, cols: 3, data: [600.0, 0.0, 416.0, 0.0, 600.0, 312.0, 0.0, 0.0, 1.0]}
distortion_model: plumb_bob
distortion_coefficients: {rows: 1, cols: 5, data: [-0.30, 0.10, 0.0005, -0.0008, -0.02]}
"""


def _with_calibration(tmp_path, value: object) -> dict:
    d = vsinv.load_scenario("lens-12-6-barrel").to_dict()
    d["camera"] = {"calibration": value}
    return d


def test_a_calibration_file_in_a_camera_table_reads_like_its_numbers(tmp_path) -> None:
    (tmp_path / "servo.yaml").write_text(BARREL_ROS_YAML)
    d = _with_calibration(tmp_path, str(tmp_path / "servo.yaml"))
    # An absolute path in a dictionary: the caller's explicit choice (issue 16).
    from_file = vsinv.run_scenario(d, record=False, allow_outside_files=True).summary
    numbers = vsinv.run_scenario("lens-12-6-barrel", record=False).summary
    assert from_file["iterations"] == numbers["iterations"]
    assert from_file["final_translation_error"] == numbers["final_translation_error"]


def test_bad_calibration_entries_name_the_key(tmp_path) -> None:
    (tmp_path / "skewed.yaml").write_text(BARREL_ROS_YAML.replace("[600.0, 0.0, 416.0", "[600.0, 3.0, 416.0"))
    (tmp_path / "broken.yaml").write_text("camera_matrix: [1, 2\n")
    for value in [str(tmp_path / "missing.yaml"), str(tmp_path), str(tmp_path / "skewed.yaml"),
                  str(tmp_path / "broken.yaml"), 3, float("nan"), [1.0]]:
        try:
            vsinv.load_scenario(_with_calibration(tmp_path, value))
        except vsinv.InvalidInput as e:
            assert "camera.calibration" in str(e), (value, str(e))
        else:
            raise AssertionError(f"calibration = {value!r} was accepted")
    d = _with_calibration(tmp_path, str(tmp_path / "missing.yaml"))
    d["camera"]["fku"] = 600.0
    try:
        vsinv.load_scenario(d)
    except vsinv.InvalidInput as e:
        assert "camera.fku" in str(e) and "calibration" in str(e)
    else:
        raise AssertionError("fku with calibration was accepted")


def test_sweeps_of_the_lens_need_numbers_not_a_calibration_file(tmp_path) -> None:
    (tmp_path / "servo.yaml").write_text(BARREL_ROS_YAML)
    d = _with_calibration(tmp_path, str(tmp_path / "servo.yaml"))
    for key in ("focal_error", "principal_point_error"):
        try:
            vsinv.sim.run_sweep(d, {key: [0.1]}, progress=False, allow_outside_files=True)
        except vsinv.InvalidInput as e:
            assert "calibration" in str(e) and "camera" in str(e), str(e)
        else:
            raise AssertionError(f"{key} on a calibration file was accepted")
    # Keys that do not touch the intrinsics work as usual.
    res = vsinv.sim.run_sweep(d, {"control.gain": [1.0]}, progress=False, allow_outside_files=True)
    assert len(res) == 1
