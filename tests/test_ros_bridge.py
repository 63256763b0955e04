"""The ROS 2 bridge's parts that need no ROS (vsinv.ros.params, conversions, session,
annotate, the entry point): bad parameters refused by name, the message conversions against
independent computations (OpenCV's grey conversion, quaternion algebra, the rigid motion
itself), and the session's stops (final verdict, bad frame, watchdog, request) with a zero
twist. The loop over ROS 2 topics is tests/test_ros_loop.py."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

import vsinv
from ros_yaml import flat
from vsinv.ros import BridgeSession, hand_eye_matrix, image_to_grey, lens_from_camera_info, parse_parameters
from vsinv.ros import twist_in_end_effector_frame, validate_pipeline
from vsinv.ros.annotate import annotate

SCENARIO = "vision-12-6"
OBJECT_Z = [0.60, 0.66, 0.56, 0.63, 0.54, 0.65, 0.62, 0.57, 0.64, 0.55, 0.61, 0.66]


@pytest.fixture(scope="module")
def views(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    folder = tmp_path_factory.mktemp("views")
    scenario = vsinv.load_scenario(SCENARIO)
    from vsinv.images import write_scenario_images

    write_scenario_images(scenario, folder)
    start, start_px, _ = vsinv.vision.render_view(scenario)
    ref_px = vsinv.images.read_points(folder / "reference.csv")
    return {"folder": folder, "reference": str(folder / "reference.png"), "ref_px": ref_px, "start": start, "start_px": start_px}


def good(views: dict[str, Any], **change: Any) -> dict[str, Any]:
    p: dict[str, Any] = {
        "reference_image": views["reference"], "target": "dots",
        "reference_points": [float(x) for x in views["ref_px"].ravel()],
        "first_points": [float(x) for x in views["start_px"].ravel()],
        "reference_depths": OBJECT_Z, "rz_task": "tau21", "dt": 0.01, "K_hat": [600.0, 600.0, 416.0, 312.0],
        "camera_frame": "camera_optical_frame",
    }
    p.update(change)
    return {k: v for k, v in p.items() if v is not None}


# ---------------------------------------------------------------------------------------------
# parameters


def test_good_parameters_are_read(views: dict[str, Any]) -> None:
    he = [0.1, 0.0, 0.05, 0.0, 0.0, 0.0, 1.0]
    c = parse_parameters(good(views, **{"stop.window": 20, "gain": 1, "output_frame": "end_effector", "hand_eye": he,
                                        "end_effector_frame": "tool0", "use_sim_time": False, "qos_overrides./x.depth": 3}))
    assert c.target == "dots" and c.reference_image.shape == (624, 832)
    np.testing.assert_array_equal(c.servo_options["reference_points"], views["ref_px"])
    assert c.servo_options["stop"] == {"window": 20} and c.servo_options["gain"] == 1.0
    assert c.K_hat == vsinv.Intrinsics(600.0, 600.0, 416.0, 312.0) and c.distortion is None
    np.testing.assert_array_equal(c.hand_eye, [[1, 0, 0, 0.1], [0, 1, 0, 0], [0, 0, 1, 0.05], [0, 0, 0, 1]])
    assert c.topics == {"image": "image", "camera_info": "camera_info", "twist": "~/twist", "status": "~/status",
                        "annotated": "~/annotated"}
    assert c.watchdog_timeout == 0.1 and not c.autostart  # MoveIt Servo's command timeout
    validate_pipeline(c)
    tags = parse_parameters({"reference_image": views["reference"], "tag_ids": [1, 2], "depth": 0.5, "law": "ibvs",
                             "camera_frame": "camera"})
    assert tags.target == "tags" and tags.servo_options["tag_ids"] == [1, 2] and tags.servo_options["depths"] == 0.5
    assert "decimation" not in tags.servo_options
    tags = parse_parameters({"reference_image": views["reference"], "decimation": 3, "depth": 0.5, "law": "ibvs",
                             "camera_frame": "camera"})
    assert tags.servo_options["decimation"] == 3


@pytest.mark.parametrize(
    "change, name",
    [
        ({"gian": 1.0}, "parameter gian: unknown; did you mean gain"),
        ({"gain": "fast"}, "parameter gain: expected a number"),
        ({"gain": True}, "parameter gain"),
        ({"gain": float("nan")}, "parameter gain: expected a finite number"),
        ({"gain": -1.0}, "parameter gain: must be finite and > 0, got -1"),  # the table's range, at parsing
        ({"adaptive_gain": [1.0, 2.0, 3.0]}, "parameter adaptive_gain: the gain for a large error"),
        ({"stop.window": 2.5}, "parameter stop.window: expected an integer"),
        ({"target": "circles"}, "parameter target: expected one of dots, tags"),
        ({"reference_image": None}, "parameter reference_image: required"),
        ({"reference_image": "/nonexistent/ref.png"}, "parameter reference_image: no such file"),
        ({"reference_points": [1.0, 2.0, 3.0]}, "parameter reference_points: expected a flat list"),
        ({"reference_points": None}, "parameter reference_points: target 'dots' needs"),
        ({"reference_points_file": "x.csv"}, "parameter reference_points_file: give either"),
        ({"family": "tag16h5"}, "parameter family: not a parameter of target 'dots'"),
        ({"reference_depths_file": "z.csv"}, "parameter reference_depths_file: give either"),
        ({"K_hat": [600.0, 600.0, 416.0]}, "parameter K_hat: expected [fx, fy, u0, v0]"),
        ({"K_hat": None, "distortion": [0.1, 0.0, 0.0, 0.0]}, "parameter distortion: needs K_hat"),
        ({"image_rectified": True}, "parameter image_rectified"),
        ({"output_frame": "end_effector"}, "parameter hand_eye: output_frame end_effector needs"),
        ({"output_frame": "end_effector", "hand_eye": [0.0] * 6 + [1.0]}, "parameter end_effector_frame"),
        ({"hand_eye": [0.0] * 6 + [1.0]}, "parameter hand_eye: only used with output_frame end_effector"),
        ({"output_frame": "end_effector", "end_effector_frame": "tool0", "hand_eye": [0.0] * 7}, "parameter hand_eye: the quaternion"),
        ({"output_frame": "end_effector", "end_effector_frame": "tool0", "hand_eye": [2.0] + [0.0] * 15}, "parameter hand_eye: not a rigid"),
        ({"output_frame": "tool"}, "parameter output_frame"),
        ({"camera_frame": ""}, "parameter camera_frame: output_frame camera needs"),
        ({"image_qos.reliability": "fast"}, "parameter image_qos.reliability: expected one of reliable, best_effort"),
        ({"image_qos.depth": 0}, "parameter image_qos.depth: expected 1..=100"),
        ({"status_period": 0.0}, "parameter status_period"),
        ({"watchdog_timeout": 0.0}, "parameter watchdog_timeout"),
        ({"twist_topic": " "}, "parameter twist_topic: empty"),
        ({"basis": [0, 1]}, "parameter basis"),
        ({"tag_ids": [1.5]}, "parameter tag_ids: expected an array of integers"),
        ({"decimation": 3}, "parameter decimation: not a parameter of target 'dots'"),
        ({"target": "tags", "reference_points": None, "decimation": 2.5}, "parameter decimation: expected an integer"),
    ],
)
def test_bad_parameters_are_refused_by_name(views: dict[str, Any], change: dict[str, Any], name: str) -> None:
    with pytest.raises(vsinv.InvalidInput) as e:
        parse_parameters(good(views, **change))
    assert name in str(e.value), str(e.value)


@pytest.mark.parametrize("change, name", [({"law": "ibvs", "rz_task": None, "gain_rz": 2.0}, 'gain_rz: not an argument of the "ibvs" law'),
                                           ({"stop.window": 0}, "invalid parameter `stop`: window and max_iterations must be >= 1"),
                                           ({"tracker.polarity": "grey"}, 'polarity: expected one of "light", "dark", "auto", got "grey"'),
                                           ({"reference_depths": [0.6]}, "reference_depths: expected 12 depths, got 1")])
def test_bad_law_options_are_refused_at_start(views: dict[str, Any], change: dict[str, Any], name: str) -> None:
    config = parse_parameters(good(views, **change))
    with pytest.raises(vsinv.InvalidInput, match="^parameters: " + name):
        validate_pipeline(config)
    # the same without K_hat: a stand-in lens checks the options before any CameraInfo
    config = parse_parameters(good(views, K_hat=None, **change))
    with pytest.raises(vsinv.InvalidInput, match=name):
        validate_pipeline(config)


@pytest.mark.parametrize("decimation", [0, 9])
def test_a_decimation_out_of_range_is_refused_at_start(views: dict[str, Any], decimation: int) -> None:
    config = parse_parameters({"reference_image": views["reference"], "decimation": decimation, "depth": 0.5,
                               "law": "ibvs", "K_hat": [600.0, 600.0, 416.0, 312.0], "camera_frame": "camera"})
    with pytest.raises(vsinv.InvalidInput, match=r"parameters: .*decimation: must be in 1..=8"):
        validate_pipeline(config)


# ---------------------------------------------------------------------------------------------
# conversions


def image_msg(array: np.ndarray, encoding: str, pad: int = 0) -> SimpleNamespace:
    h, w = array.shape[:2]
    rows = array.reshape(h, -1)
    step = rows.shape[1] + pad
    data = np.zeros((h, step), np.uint8)
    data[:, : rows.shape[1]] = rows
    return SimpleNamespace(encoding=encoding, height=h, width=w, step=step, data=data.tobytes())


def test_images_become_grey_as_opencv_converts_them() -> None:
    cv2 = pytest.importorskip("cv2")
    rgb = np.random.default_rng(3).integers(0, 256, (37, 53, 3), dtype=np.uint8)
    for pad in (0, 5):
        grey = image_to_grey(image_msg(rgb, "rgb8", pad))
        np.testing.assert_array_equal(grey, cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY))
        np.testing.assert_array_equal(image_to_grey(image_msg(rgb[:, :, ::-1].copy(), "bgr8", pad)), grey)
        np.testing.assert_array_equal(image_to_grey(image_msg(rgb[:, :, 0].copy(), "mono8", pad)), rgb[:, :, 0])
    # as vsinv.vision.load_image reads a colour file
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        cv2.imwrite(str(Path(d) / "c.png"), rgb[:, :, ::-1])
        np.testing.assert_array_equal(vsinv.vision.load_image(Path(d) / "c.png"), grey)
    # rclpy holds uint8[] fields as array.array('B')
    import array

    msg = image_msg(rgb, "rgb8")
    msg.data = array.array("B", msg.data)
    np.testing.assert_array_equal(image_to_grey(msg), grey)


@pytest.mark.parametrize("encoding", ["16UC1", "rgba16", "yuv422", "bayer_rggb8", ""])
def test_other_encodings_are_refused_by_name(encoding: str) -> None:
    msg = image_msg(np.zeros((4, 4), np.uint8), encoding)
    with pytest.raises(vsinv.InvalidInput, match=f"encoding {encoding!r} is not read"):
        image_to_grey(msg)


def test_inconsistent_images_are_refused() -> None:
    msg = image_msg(np.zeros((4, 6, 3), np.uint8), "rgb8")
    for change in ({"data": b"\0" * 10}, {"step": 10}, {"height": 0}):
        bad = SimpleNamespace(**{**vars(msg), **change})
        with pytest.raises(vsinv.InvalidInput, match="does not fit"):
            image_to_grey(bad)


def camera_info(**change: Any) -> SimpleNamespace:
    info = {"k": [600.0, 0.0, 416.0, 0.0, 610.0, 312.0, 0.0, 0.0, 1.0], "d": [0.1, -0.2, 0.001, 0.002, 0.05],
            "distortion_model": "plumb_bob", "p": [590.0, 0.0, 410.0, 0.0, 0.0, 595.0, 300.0, 0.0, 0.0, 0.0, 1.0, 0.0]}
    info.update(change)
    return SimpleNamespace(**info)


def test_camera_info_gives_k_hat_and_distortion() -> None:
    k, d = lens_from_camera_info(camera_info())
    assert k == vsinv.Intrinsics(600.0, 610.0, 416.0, 312.0)
    assert d.model == "plumb_bob" and np.allclose(d.coefficients, [0.1, -0.2, 0.001, 0.002, 0.05])
    k, d = lens_from_camera_info(camera_info(), rectified=True)
    assert k == vsinv.Intrinsics(590.0, 595.0, 410.0, 300.0) and not d.coefficients.any()
    k, d = lens_from_camera_info(camera_info(d=[], distortion_model=""))
    assert not d.coefficients.any()
    d8 = [0.1, -0.2, 0.001, 0.002, 0.05, 0.01, 0.0, 0.0]
    assert lens_from_camera_info(camera_info(d=d8, distortion_model="rational_polynomial"))[1].model == "rational_polynomial"
    with pytest.raises(vsinv.InvalidInput, match=r"camera_info: K is all zeros \(an uncalibrated camera\): calibrate it, or set the K_hat parameter"):
        lens_from_camera_info(camera_info(k=[0.0] * 9))
    # OpenCV's fisheye: 4 coefficients, and zeros are the equidistant projection, not a pinhole.
    k, d = lens_from_camera_info(camera_info(distortion_model="equidistant", d=[0.1, -0.02, 0.003, -0.0004]))
    assert d.model == "equidistant" and d.coefficients.tolist() == [0.1, -0.02, 0.003, -0.0004]
    assert lens_from_camera_info(camera_info(distortion_model="equidistant", d=[0.0] * 4))[1].model == "equidistant"
    with pytest.raises(vsinv.InvalidInput, match=r"camera_info\.d: .*equidistant.*4"):
        lens_from_camera_info(camera_info(distortion_model="equidistant", d=[0.1, 0.0, 0.0, 0.0, 0.0]))
    with pytest.raises(vsinv.InvalidInput, match="distortion_model 'fisheye'"):
        lens_from_camera_info(camera_info(distortion_model="fisheye", d=[0.1, 0.0, 0.0, 0.0]))


def quaternion_product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton's product of (x, y, z, w) quaternions."""
    av, aw, bv, bw = a[:3], a[3], b[:3], b[3]
    return np.append(aw * bv + bw * av + np.cross(av, bv), aw * bw - av @ bv)


def test_hand_eye_from_a_quaternion_rotates_as_the_quaternion() -> None:
    rng = np.random.default_rng(7)
    for _ in range(20):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        xyz = rng.normal(size=3)
        m = hand_eye_matrix("hand_eye", [*xyz, *((1.0 + 5e-4) * q)])  # normalised
        np.testing.assert_allclose(m[:3, 3], xyz)
        v = rng.normal(size=3)
        rotated = quaternion_product(quaternion_product(q, np.append(v, 0.0)), q * [-1, -1, -1, 1])[:3]
        np.testing.assert_allclose(m[:3, :3] @ v, rotated, atol=1e-12)
        np.testing.assert_array_equal(hand_eye_matrix("hand_eye", m.ravel()), m)
        with pytest.raises(vsinv.InvalidInput, match="parameter hand_eye: the quaternion"):
            hand_eye_matrix("hand_eye", [*xyz, *(2.0 * q)])
    half = np.radians(15.0)
    np.testing.assert_allclose(hand_eye_matrix("h", [0, 0, 0, 0, 0, np.sin(half), np.cos(half)])[:2, :2],
                               [[np.cos(2 * half), -np.sin(2 * half)], [np.sin(2 * half), np.cos(2 * half)]], atol=1e-15)


def test_the_end_effector_twist_moves_the_camera_as_the_camera_twist() -> None:
    """Holding the end effector twist moves the camera (rigidly mounted by X) exactly as
    holding the camera twist: E exp(V_e t) X = E X exp(V_c t), for any t."""
    rng = np.random.default_rng(11)
    for _ in range(20):
        q = rng.normal(size=4)
        x = hand_eye_matrix("X", [*rng.normal(size=3) * 0.2, *(q / np.linalg.norm(q))])
        e = vsinv.geometry.exp_twist(rng.normal(size=6), 1.0)
        twist = rng.normal(size=6)
        twist_ee = twist_in_end_effector_frame(twist, x)
        for t in (0.01, 0.3):
            np.testing.assert_allclose(e @ vsinv.geometry.exp_twist(twist_ee, t) @ x, e @ x @ vsinv.geometry.exp_twist(twist, t), atol=1e-12)


def test_annotated_image_marks_found_and_lost_points() -> None:
    grey = np.full((20, 30), 100, np.uint8)
    rgb = annotate(grey, np.array([[5.2, 6.7], [29.0, 0.0], [-50.0, 3.0], [np.nan, 1.0]]), np.array([True, False, True, True]), arm=2)
    assert rgb.shape == (20, 30, 3) and rgb.dtype == np.uint8
    assert tuple(rgb[7, 5]) == (0, 255, 0) and tuple(rgb[7, 3]) == (0, 255, 0) and tuple(rgb[9, 5]) == (0, 255, 0)
    assert tuple(rgb[0, 29]) == (255, 0, 0) and tuple(rgb[2, 29]) == (255, 0, 0)
    changed = (rgb != 100).any(axis=2)
    assert changed.sum() == 9 + 3 + 2  # the crosses, clipped; the off-image and NaN points draw nothing


# ---------------------------------------------------------------------------------------------
# the session


def session(views: dict[str, Any], **change: Any) -> BridgeSession:
    return BridgeSession(parse_parameters(good(views, **change)))


def test_the_session_steps_as_image_servo_does(views: dict[str, Any]) -> None:
    s = session(views)
    assert s.frame(views["start"], 0.0).twist is None  # idle: nothing to publish
    assert s.start(0.0) == (True, "running")
    out = s.frame(views["start"], 0.01)
    c = s.config
    direct = vsinv.ImageServo(c.reference_image, "dots", c.K_hat, **c.servo_options).step(views["start"])
    np.testing.assert_array_equal(out.twist, direct.twist)
    status = json.loads(s.status_json(latency=None))
    assert status["state"] == "running" and status["verdict"] == "running" and status["iterations"] == 1
    assert status["points"]["found"] == 12 and len(status["points"]["pixels"]) == 12
    assert set(status["errors"]) >= {"image_error", "invariant_error"}
    # in the end effector frame: the adjoint of the mount
    he = [0.05, 0.0, 0.1, 0.0, 0.0, 0.0, 1.0]
    s2 = session(views, output_frame="end_effector", end_effector_frame="tool0", hand_eye=he)
    s2.start(0.0)
    np.testing.assert_allclose(s2.frame(views["start"], 0.01).twist,
                               twist_in_end_effector_frame(direct.twist, hand_eye_matrix("h", he)), atol=1e-15)


def test_the_session_stops_with_a_zero_twist(views: dict[str, Any]) -> None:
    s = session(views, watchdog_timeout=0.5, **{"stop.max_iterations": 2})
    s.start(0.0)
    outs = [s.frame(views["start"], 0.01 * k) for k in range(1, 5)]
    assert outs[0].twist.any() and outs[1].twist.any()
    out = outs[2]  # the iteration limit, a final verdict
    assert outs[3].twist is None
    assert not out.twist.any() and s.state == "stopped" and s.reason.startswith("max_iterations")
    assert s.frame(views["start"], 0.03).twist is None  # stopped: nothing more
    assert s.start(0.1) == (True, "running") and s.pipeline.iterations == 0  # a new session
    # a blank first frame: the target is lost, an outcome (issue 28): stop with a zero twist
    out = s.frame(np.zeros((10, 10), np.uint8), 0.2)
    assert not out.twist.any() and s.state == "stopped" and s.reason.startswith("lost_features") and out.frame_used
    # a frame the pipeline refuses (not 8-bit grey): stop, not raise
    s.start(0.3)
    out = s.frame(np.zeros((10, 10)), 0.4)
    assert not out.twist.any() and s.state == "stopped" and "frame refused" in s.reason and out.frame_used
    # the watchdog, counted from the start and from the last image
    s.start(1.0)
    assert s.watchdog(1.4).twist is None
    assert not s.watchdog(1.6).twist.any() and s.reason.startswith("watchdog: no image for 0.600 s")
    s.start(2.0)
    s.frame(views["start"], 2.3)
    assert s.watchdog(2.7).twist is None and s.state == "running"
    assert not s.stop("stopped by request").twist.any() and s.state == "stopped"
    assert not s.reset().twist.any() and s.state == "idle" and s.pipeline is None
    s.refuse_frame(vsinv.InvalidInput("image: encoding 'yuv422' is not read"))
    assert "yuv422" in json.loads(s.status_json())["message"]


def test_the_lens_comes_from_camera_info_unless_given(views: dict[str, Any]) -> None:
    s = session(views, K_hat=None)
    ok, message = s.start(0.0)
    assert not ok and "no CameraInfo" in message and s.state == "idle"
    assert json.loads(s.status_json())["K_hat"] is None
    s.camera_info(lens_from_camera_info(camera_info(d=[], distortion_model="")))
    assert s.start(0.0)[0] and s.lens[0].fkv == 610.0
    assert json.loads(s.status_json())["K_hat"] == [600.0, 610.0, 416.0, 312.0]
    fixed = session(views)
    fixed.camera_info(lens_from_camera_info(camera_info()))
    assert fixed.lens[0] == vsinv.Intrinsics(600.0, 600.0, 416.0, 312.0)
    auto = session(views, autostart=True)
    assert auto.frame(views["start"], 0.0).twist is not None and auto.state == "running"


# ---------------------------------------------------------------------------------------------
# the entry point


def test_entry_point_without_ros(tmp_path: Path) -> None:
    """vsinv imports no rclpy; --help lists the parameters; without rclpy the command says where it comes from."""
    code = "import sys, vsinv, vsinv.ros, vsinv.ros.__main__; print('rclpy' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60).stdout.strip() == "False"
    done = subprocess.run([sys.executable, "-m", "vsinv.ros", "--help"], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0 and "reference_image" in done.stdout and "watchdog_timeout" in done.stdout
    blocked = "import sys; sys.modules['rclpy'] = None; from vsinv.ros.__main__ import main; sys.exit(main(['vsinv-ros']))"
    done = subprocess.run([sys.executable, "-c", blocked], capture_output=True, text=True, timeout=60)
    assert done.returncode == 2 and "rclpy is not importable" in done.stderr


def test_the_guides_parameters_file_is_read(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The ROS 2 guide's parameters file (docs/guides/ros2.md), with files of its own, passes
    the bridge's parser."""
    yaml = pytest.importorskip("yaml")
    import re

    guide = (Path(__file__).resolve().parent.parent / "docs/guides/ros2.md").read_text(encoding="utf-8")
    block = re.search(r"^```yaml\n(vsinv_ros:.*?)^```", guide, re.M | re.S)
    assert block, "the ROS 2 guide's parameters block"
    parameters = yaml.safe_load(block.group(1))["vsinv_ros"]["ros__parameters"]
    monkeypatch.chdir(tmp_path)
    vsinv.vision.save_image(np.zeros((48, 64), np.uint8), tmp_path / parameters["reference_image"])
    (tmp_path / parameters["reference_depths_file"]).write_text("z\n" + "0.5\n" * 16)

    c = parse_parameters(flat(parameters))
    assert c.target == "tags" and c.output_frame == "end_effector" and c.topics["twist"] == "/servo_node/delta_twist_cmds"
    np.testing.assert_allclose(c.hand_eye[:3, :3] @ [1, 0, 0], [0, 1, 0], atol=1e-6)  # 90 degrees about z
    assert len(c.servo_options["reference_depths"]) == 16


def test_bad_files_are_refused_by_parameter_name(views: dict[str, Any], tmp_path: Path) -> None:
    garbage = tmp_path / "garbage.png"
    garbage.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(10))
    text = tmp_path / "bad.csv"
    text.write_text("a,b\n1,2\n")
    cases = [
        ({"reference_image": str(garbage)}, "reference_image"),
        ({"reference_points": None, "reference_points_file": str(text)}, "reference_points_file"),
        ({"first_points": None, "first_points_file": str(tmp_path / "missing.csv")}, "first_points_file"),
        ({"reference_depths": None, "reference_depths_file": str(text)}, "reference_depths_file"),
        ({"K_hat": None, "calibration": str(text)}, "calibration"),
        ({"reference_calibration": str(garbage)}, "reference_calibration"),
    ]
    for change, name in cases:
        with pytest.raises(vsinv.InvalidInput) as e:
            parse_parameters(good(views, **change))
        message = str(e.value)
        assert message.startswith(f"parameter {name}: ") and message.count("parameter ") == 1, message


def test_lost_features_stop_with_a_zero_twist(views: dict[str, Any]) -> None:
    s = session(views)
    s.start(0.0)
    assert s.frame(views["start"], 0.01).twist.any()
    out = s.frame(np.full_like(views["start"], 30), 0.02)  # the dots gone
    assert s.state == "stopped" and s.reason.startswith("lost_features"), s.reason
    assert out.twist is not None and not out.twist.any() and out.frame_used
    status = json.loads(s.status_json())
    assert status["verdict"] == "lost_features" and status["points"]["found"] < 12


def test_a_new_camera_info_is_used_from_the_next_session(views: dict[str, Any]) -> None:
    s = session(views, K_hat=None)
    none = vsinv.vision.Distortion([0.0, 0.0, 0.0, 0.0])
    s.camera_info((vsinv.Intrinsics(600.0, 600.0, 416.0, 312.0), none))
    assert s.start(0.0)[0]
    s.camera_info((vsinv.Intrinsics(600.0, 600.0, 416.0, 312.0), none))  # the same lens again: nothing pending
    assert json.loads(s.status_json())["K_hat_next"] is None
    s.camera_info((vsinv.Intrinsics(500.0, 500.0, 416.0, 312.0), none))  # a new lens mid-run: shown, not used
    status = json.loads(s.status_json())
    assert status["K_hat"] == [600.0, 600.0, 416.0, 312.0] and status["K_hat_next"] == [500.0, 500.0, 416.0, 312.0]
    s.reset()
    assert s.start(1.0)[0]  # the next session: the new lens in use
    status = json.loads(s.status_json())
    assert status["K_hat"] == [500.0, 500.0, 416.0, 312.0] and status["K_hat_next"] is None


def test_every_default_is_of_its_parameters_type() -> None:
    """A default is what the node declares: of the parameter's ROS type (a target's count, which
    vsinv.TARGETS says as text, an integer), so a value set by the user of that type is taken."""
    from vsinv.ros.params import PARAMETERS, _typed

    for p in PARAMETERS:
        if p.default is not None:
            assert _typed(p, p.default) == p.default and type(_typed(p, p.default)) is type(p.default), p


def test_feature_parameters_are_read_with_their_kinds(views: dict[str, Any]) -> None:
    """The keypoint target's arguments (vsinv.TARGETS) as parameters: counts as integers (their
    defaults too), point_ids as identities; out of range refused at start by name."""
    base = {"reference_image": views["reference"], "target": "features", "camera_frame": "camera"}
    c = parse_parameters(base)
    assert c.target == "features" and c.servo_options["max_points"] == 150 and c.servo_options["min_tracked"] == 24
    c = parse_parameters({**base, "max_points": 40, "min_tracked": 12, "point_ids": [3, 1, 2]})
    assert (c.servo_options["max_points"], c.servo_options["min_tracked"], c.servo_options["point_ids"]) == (40, 12, [3, 1, 2])
    for change, words in (({"max_points": 40.0}, "parameter max_points: expected an integer"),
                          ({"point_ids": [1.5]}, "parameter point_ids: expected an array of integers"),
                          ({"tag_ids": [1]}, "parameter tag_ids: not a parameter of target 'features'"),
                          ({"reference_points": [1.0, 2.0]}, "parameter reference_points: not a parameter of target 'features'"),
                          ({"point_ids": [1]}, None)):
        if words is None:  # a features parameter with another target
            with pytest.raises(vsinv.InvalidInput, match="parameter point_ids: not a parameter of target 'dots'"):
                parse_parameters(good(views, **change))
            continue
        with pytest.raises(vsinv.InvalidInput) as e:
            parse_parameters({**base, **change})
        assert words in str(e.value), str(e.value)
    for change, words in (({"max_points": 5}, "max_points"), ({"min_tracked": 5000}, "min_tracked")):
        with pytest.raises(vsinv.InvalidInput, match="^parameters: .*" + words):
            validate_pipeline(parse_parameters({**base, **change}))
