"""The bridge's image gate, live parameter changes and colour conversion, without ROS: which
images may be stepped on (frame, stamp, size; CameraInfo's size), what a parameter set changes,
and vsinv.vision.to_grey against OpenCV's cvtColor."""

from __future__ import annotations

import json
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

import vsinv
from vsinv.ros import BridgeSession, parse_parameters
from vsinv.ros.gate import ImageGate
from vsinv.ros.live import apply_change


def msg(sec: int, nanosec: int = 0, frame: str = "cam", width: int = 64, height: int = 48) -> SimpleNamespace:
    header = SimpleNamespace(frame_id=frame, stamp=SimpleNamespace(sec=sec, nanosec=nanosec))
    return SimpleNamespace(header=header, width=width, height=height)


def test_duplicates_and_images_out_of_order_are_refused() -> None:
    gate = ImageGate("cam")
    assert gate.check(msg(5)) is None
    gate.used(msg(5))
    assert "a duplicate" in gate.check(msg(5))
    assert "out of order" in gate.check(msg(4, 999_999_999))
    assert gate.check(msg(5, 1)) is None  # one nanosecond later
    gate.reset()
    assert gate.check(msg(1)) is None  # a new session: stamps start again


def test_a_wrong_frame_is_refused() -> None:
    named = ImageGate("cam")
    assert "frame_id 'other' is not the camera's 'cam'" in named.check(msg(1, frame="other"))
    assert "frame_id '' is not" in named.check(msg(1, frame=""))
    first = ImageGate("")  # unnamed: the first image used names it
    assert first.check(msg(1, frame="a")) is None
    first.used(msg(1, frame="a"))
    assert "frame_id 'b' is not the camera's 'a'" in first.check(msg(2, frame="b"))
    first.reset()
    assert first.check(msg(3, frame="b")) is None


def test_sizes_follow_camera_info_or_the_first_image() -> None:
    gate = ImageGate("cam")
    gate.used(msg(1))
    assert "image size 32x48 is not the first image's 64x48" in gate.check(msg(2, width=32))
    assert "camera_info size 640x480 is not the images' 64x48" in gate.camera_info(SimpleNamespace(width=640, height=480))
    assert gate.camera_info(SimpleNamespace(width=0, height=0)) is None  # no size: only the lens
    assert gate.camera_info(SimpleNamespace(width=64, height=48)) is None
    info = ImageGate("cam")
    assert info.camera_info(SimpleNamespace(width=640, height=480)) is None
    assert "image size 64x48 is not the CameraInfo's 640x480" in info.check(msg(1))


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> BridgeSession:
    path = str(tmp_path_factory.mktemp("gate") / "reference.png")
    vsinv.vision.save_image(np.zeros((48, 64), np.uint8), path)
    config = parse_parameters({"reference_image": path, "depth": 0.5, "law": "ibvs", "camera_frame": "cam",
                               "max_linear_speed": 0.2, "max_angular_speed": 1.0})
    return BridgeSession(config)


def test_a_refused_image_stops_with_a_zero_twist(session: BridgeSession) -> None:
    session.state = "running"
    out = session.refuse_frame("image frame_id 'x' is not the camera's 'cam'")
    assert out.twist is not None and not out.twist.any()
    status = json.loads(session.status_json())
    assert status["state"] == "stopped" and status["reason"].startswith("refused: image frame_id")


def test_parameter_changes(session: BridgeSession) -> None:
    assert apply_change(session, "max_linear_speed", 0.01) == (True, "max_linear_speed = 0.01, at once (bounded by the session's starting limit until the next session)")
    twist = session.limited(np.array([0.3, 0.4, 0.0, 0.0, 0.0, 0.5]))
    np.testing.assert_allclose(twist, np.array([0.3, 0.4, 0.0, 0.0, 0.0, 0.5]) * 0.01 / 0.5)  # scaled as a whole
    assert apply_change(session, "max_angular_speed", 0.1)[0]
    np.testing.assert_allclose(np.linalg.norm(session.limited(np.array([0.0, 0, 0, 0, 0, 1.0]))), 0.1)
    assert apply_change(session, "watchdog_timeout", 0.25)[0] and session.config.watchdog_timeout == 0.25
    ok, reason = apply_change(session, "gain", 2.0)
    assert ok and "next session" in reason and session.config.servo_options["gain"] == 2.0
    for name, value, why in (("target", "tags", "read at start only"), ("gain", -1.0, "positive"),
                             ("watchdog_timeout", "soon", "expected a number"), ("nope", 1.0, "not a parameter")):
        ok, reason = apply_change(session, name, value)
        assert not ok and why in reason, reason


@pytest.mark.parametrize("shape", [(720, 1280), (1080, 1920), (7, 5), (481, 643), (33, 37)])
def test_to_grey_is_opencvs_cvtcolor(shape: tuple[int, int]) -> None:
    cv2 = pytest.importorskip("cv2")
    rng = np.random.default_rng(3)
    colour = rng.integers(0, 256, (*shape, 3), dtype=np.uint8)
    np.testing.assert_array_equal(vsinv.vision.to_grey(colour), cv2.cvtColor(colour, cv2.COLOR_RGB2GRAY))
    np.testing.assert_array_equal(vsinv.vision.to_grey(colour, order="bgr"), cv2.cvtColor(colour, cv2.COLOR_BGR2GRAY))
    strided = colour[:, ::2]  # not contiguous: copied once
    np.testing.assert_array_equal(vsinv.vision.to_grey(strided), cv2.cvtColor(np.ascontiguousarray(strided), cv2.COLOR_RGB2GRAY))


@pytest.mark.parametrize("shape", [(1080, 1920), (481, 643), (7, 5), (33, 37), (1, 1), (513, 1)])
def test_to_grey_with_alpha_and_any_strides_is_opencvs_cvtcolor(shape: tuple[int, int]) -> None:
    """RGB, BGR, RGBA and BGRA, odd widths, and views that are not contiguous (a crop with
    padded rows, every other column, rows upside down, Fortran order, a channel-reversed view):
    each equal to OpenCV's cvtColor of the same pixels, to the bit."""
    cv2 = pytest.importorskip("cv2")
    rng = np.random.default_rng(shape[0] * 7 + shape[1])
    codes = {(3, "rgb"): cv2.COLOR_RGB2GRAY, (3, "bgr"): cv2.COLOR_BGR2GRAY, (4, "rgb"): cv2.COLOR_RGBA2GRAY,
             (4, "bgr"): cv2.COLOR_BGRA2GRAY}
    for channels in (3, 4):
        big = rng.integers(0, 256, (shape[0] + 3, 2 * shape[1] + 5, channels), dtype=np.uint8)
        views = {"contiguous": np.ascontiguousarray(big[: shape[0], : shape[1]]), "crop": big[1 : shape[0] + 1, 2 : shape[1] + 2],
                 "every other column": big[: shape[0], : 2 * shape[1] : 2], "upside down": big[shape[0] - 1 :: -1, : shape[1]][: shape[0]],
                 "fortran": np.asfortranarray(big[: shape[0], : shape[1]]),
                 "channels reversed": big[: shape[0], : shape[1], ::-1]}
        for name, view in views.items():
            for order in ("rgb", "bgr"):
                expected = cv2.cvtColor(np.ascontiguousarray(view), codes[(channels, order)])
                got = vsinv.vision.to_grey(view, order=order)  # type: ignore[arg-type]
                assert got.shape == view.shape[:2], (name, channels, order)
                np.testing.assert_array_equal(got, expected.reshape(view.shape[:2]), err_msg=f"{name} {channels} {order}")


@pytest.mark.parametrize("bad, what", [(np.zeros((4, 4, 2), np.uint8), r"shape \(4, 4, 2\)"), (np.zeros((4, 4, 5), np.uint8), r"shape \(4, 4, 5\)"), (np.zeros((4, 4, 3)), "dtype float64"),
                                       (np.zeros((0, 4, 3), np.uint8), "empty"), ([1, 2, 3], "list")])
def test_to_grey_refuses_other_arrays(bad: Any, what: str) -> None:
    with pytest.raises(vsinv.InvalidInput, match=what):
        vsinv.vision.to_grey(bad)
    with pytest.raises(vsinv.InvalidInput, match="invalid parameter `order`: expected 'rgb' or 'bgr'"):
        vsinv.vision.to_grey(np.zeros((2, 2, 3), np.uint8), order="rgba")  # type: ignore[arg-type]



def test_compressed_images_are_decoded_and_their_size_checked() -> None:
    """image_transport's compressed messages: the format string read (JPEG, PNG, or the
    data's signature when empty; compressedDepth and others refused), the pixels decoded in
    Rust as OpenCV decodes a PNG, the decoded size given to the gate (a CompressedImage has
    no width and height)."""
    cv2 = pytest.importorskip("cv2")
    from vsinv.ros.conversions import compressed_format, compressed_to_grey

    assert compressed_format("bgr8; jpeg compressed bgr8") == "jpeg" and compressed_format("jpeg") == "jpeg"
    assert compressed_format("mono8; png compressed mono8") == "png" and compressed_format("") is None
    for bad in ("16UC1; compressedDepth png", "tiff", "theora"):
        with pytest.raises(vsinv.InvalidInput, match="format"):
            compressed_format(bad)
    grey = np.random.default_rng(1).integers(0, 256, (48, 64), dtype=np.uint8)
    png = cv2.imencode(".png", grey)[1].tobytes()
    compressed = SimpleNamespace(format="mono8; png compressed mono8", data=png, header=msg(1).header)
    decoded = compressed_to_grey(compressed)
    np.testing.assert_array_equal(decoded, grey)
    with pytest.raises(vsinv.InvalidInput, match="the format says jpeg but the data is png"):
        compressed_to_grey(SimpleNamespace(format="jpeg", data=png))
    gate = ImageGate("cam")
    size = (decoded.shape[1], decoded.shape[0])
    assert gate.check(compressed, size) is None
    gate.used(compressed, size)
    assert gate.size() == (64, 48)
    later = SimpleNamespace(format="png", data=png, header=msg(2).header)
    assert "image size 32x48 is not the first image's 64x48" in gate.check(later, (32, 48))


def test_images_with_alpha_are_read_as_opencv_reads_them() -> None:
    """sensor_msgs/Image rgba8 and bgra8 (rows padded), to grey as cv2.cvtColor RGBA2GRAY /
    BGRA2GRAY of the same pixels."""
    cv2 = pytest.importorskip("cv2")
    from vsinv.ros.conversions import image_to_grey

    rng = np.random.default_rng(5)
    h, w, step = 31, 45, 4 * 45 + 8
    rows = rng.integers(0, 256, (h, step), dtype=np.uint8)
    pixels = np.ascontiguousarray(rows[:, : 4 * w].reshape(h, w, 4))
    for encoding, code in (("rgba8", cv2.COLOR_RGBA2GRAY), ("bgra8", cv2.COLOR_BGRA2GRAY)):
        image = SimpleNamespace(encoding=encoding, height=h, width=w, step=step, data=rows.tobytes())
        np.testing.assert_array_equal(image_to_grey(image), cv2.cvtColor(pixels, code))
    short = SimpleNamespace(encoding="rgba8", height=h, width=w, step=3 * w, data=rows.tobytes())
    with pytest.raises(vsinv.InvalidInput, match="does not fit"):
        image_to_grey(short)
