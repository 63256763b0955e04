"""Conversions between ROS messages and vsinv's arrays, on the messages' fields only (any
object with them will do, so that they are tested without ROS): a sensor_msgs/Image to a grey
array, a sensor_msgs/CameraInfo to K_hat and the distortion, a grey array to an rgb8 image's
bytes, the hand-eye transform from its parameter, and a camera twist into the end effector
frame.

Conventions: REP 103 / REP 105 (the camera optical frame: z forward, x right, y down, which is
vsinv's camera frame), sensor_msgs/CameraInfo's K (3x3 row-major), D and distortion_model
(plumb_bob, rational_polynomial, equidistant: OpenCV's coefficient order; equidistant is
cv2.fisheye's k1, k2, k3, k4), tf2's quaternion order
(x, y, z, w).
"""

from __future__ import annotations

from typing import Any, Literal, Optional, cast

import numpy as np
import numpy.typing as npt

from .._core import Distortion, Intrinsics, InvalidInput, decode_image, to_grey, twist_adjoint

__all__ = [
    "ENCODINGS", "image_to_grey", "compressed_format", "compressed_to_grey", "lens_from_camera_info", "intrinsics_from_numbers", "hand_eye_matrix",
    "twist_in_end_effector_frame",
]

#: The image encodings the bridge reads (sensor_msgs/image_encodings), each to 8-bit grey.
ENCODINGS = ("mono8", "rgb8", "bgr8", "rgba8", "bgra8")

def image_to_grey(msg: Any) -> npt.NDArray[np.uint8]:
    """A sensor_msgs/Image (mono8, rgb8, bgr8, rgba8 or bgra8; rows of ``step`` bytes) as a
    (height, width) uint8 array (colour by Rec. 601 luma in Rust, alpha ignored:
    :func:`vsinv.vision.to_grey`); another encoding or inconsistent sizes are refused with
    InvalidInput."""
    encoding, height, width, step = str(msg.encoding), int(msg.height), int(msg.width), int(msg.step)
    if encoding not in ENCODINGS:
        raise InvalidInput(f"image: encoding {encoding!r} is not read (expected one of {', '.join(ENCODINGS)})")
    channels = 1 if encoding == "mono8" else len(encoding) - 1  # rgb8: 3, rgba8: 4
    try:
        data = np.frombuffer(msg.data, np.uint8)  # array.array('B') or bytes: no copy
    except TypeError:
        data = np.asarray(msg.data, dtype=np.uint8)
    if height < 1 or width < 1 or step < width * channels or data.size < height * step:
        raise InvalidInput(
            f"image: {width}x{height} {encoding} with rows of {step} bytes does not fit {data.size} bytes of data"
        )
    rows = data[: height * step].reshape(height, step)[:, : width * channels]
    if channels == 1:
        return np.ascontiguousarray(rows)
    return to_grey(rows.reshape(height, width, channels), order="bgr" if encoding.startswith("bgr") else "rgb")


def compressed_format(text: str) -> Optional[Literal["png", "jpeg"]]:
    """The compression a sensor_msgs/CompressedImage's ``format`` names: image_transport's
    ``"<encoding>; jpeg compressed <encoding>"`` or ``"...; png compressed ..."``, or the older
    plain ``"jpeg"``/``"png"``; an empty format leaves it to the data's signature (None).
    compressedDepth and other formats are refused with InvalidInput."""
    words = text.lower()
    if "compresseddepth" in words.replace(" ", ""):
        raise InvalidInput(f"compressed image: format {text!r} is a depth image (compressedDepth), not read")
    if "jpeg" in words or "jpg" in words:
        return "jpeg"
    if "png" in words:
        return "png"
    if not words.strip():
        return None
    raise InvalidInput(f"compressed image: format {text!r} is not read (expected jpeg or png)")


def compressed_to_grey(msg: Any) -> npt.NDArray[np.uint8]:
    """A sensor_msgs/CompressedImage (JPEG or PNG, :func:`compressed_format`) as a (height,
    width) uint8 array, decoded in Rust (:func:`vsinv.vision.decode_image`: the declared size checked
    against the pixel limit before decoding); undecodable, oversized or mislabelled data is
    refused with InvalidInput."""
    expected = compressed_format(str(msg.format))
    try:
        return decode_image(msg.data, expected)
    except InvalidInput as e:
        raise InvalidInput(f"compressed image ({msg.format!r}): {e}") from None


def lens_from_camera_info(msg: Any, rectified: bool = False) -> tuple[Intrinsics, Distortion]:
    """K_hat and the distortion of a sensor_msgs/CameraInfo: K and D (distortion_model
    plumb_bob, rational_polynomial, equidistant (OpenCV's fisheye, 4 coefficients), or empty
    D), or with ``rectified`` the rectified camera's P[:3, :3] and no distortion. An
    uncalibrated camera (K all zeros) is refused. An equidistant D of zeros is still a fisheye
    (theta_d = theta), not a pinhole."""
    if rectified:
        p = np.asarray(msg.p if hasattr(msg, "p") else msg.P, dtype=float).reshape(3, 4)
        return intrinsics_from_numbers("camera_info.p", p[:, :3].ravel()), Distortion([0.0, 0.0, 0.0, 0.0])
    k = np.asarray(msg.k if hasattr(msg, "k") else msg.K, dtype=float)
    if not np.any(k):
        raise InvalidInput("camera_info: K is all zeros (an uncalibrated camera): calibrate it, or set the K_hat parameter")
    intrinsics = intrinsics_from_numbers("camera_info.k", k)
    d = [float(x) for x in (msg.d if hasattr(msg, "d") else msg.D)]
    model = str(msg.distortion_model)
    if not d or (not any(d) and model != "equidistant"):
        return intrinsics, Distortion([0.0, 0.0, 0.0, 0.0])
    if model not in ("plumb_bob", "rational_polynomial", "equidistant"):
        raise InvalidInput(
            f"camera_info: distortion_model {model!r} is not read (plumb_bob, rational_polynomial or equidistant)"
        )
    try:
        return intrinsics, Distortion(d, cast(Literal["plumb_bob", "rational_polynomial", "equidistant"], model))
    except InvalidInput as e:
        raise InvalidInput(f"camera_info.d: {e}") from None


def intrinsics_from_numbers(name: str, values: npt.ArrayLike) -> Intrinsics:
    """Intrinsics from [fx, fy, u0, v0] or a 3x3 row-major matrix; others refused naming ``name``."""
    v = np.asarray(values, dtype=float).ravel()
    try:
        if v.size == 4:
            return Intrinsics(*(float(x) for x in v))
        if v.size == 9:
            return Intrinsics.from_matrix(v.reshape(3, 3))
    except InvalidInput as e:
        raise InvalidInput(f"parameter {name}: {e}") from None
    raise InvalidInput(f"parameter {name}: expected [fx, fy, u0, v0] or 9 numbers (3x3 row-major), got {v.size} numbers")


def _rotation_from_quaternion(q: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """The rotation of a unit quaternion (x, y, z, w)."""
    x, y, z, w = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def hand_eye_matrix(name: str, values: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """The 4x4 pose of the camera in the end effector frame from 16 numbers (row-major, a
    rotation and a last row 0 0 0 1, to 1e-6) or 7 (x, y, z, qx, qy, qz, qw: a unit quaternion
    to 1e-3, normalised); others refused naming ``name``."""
    v = np.asarray(values, dtype=float).ravel()
    if v.size == 7:
        norm = float(np.linalg.norm(v[3:]))
        if not abs(norm - 1.0) < 1e-3:
            raise InvalidInput(f"parameter {name}: the quaternion (qx, qy, qz, qw) has norm {norm:.3g}, not about 1")
        m = np.eye(4)
        m[:3, :3], m[:3, 3] = _rotation_from_quaternion(v[3:] / norm), v[:3]
        return m
    if v.size != 16:
        raise InvalidInput(f"parameter {name}: expected 16 numbers (4x4 row-major) or 7 (x, y, z, qx, qy, qz, qw), got {v.size}")
    m = v.reshape(4, 4)
    r = m[:3, :3]
    if not np.allclose(m[3], [0, 0, 0, 1], atol=1e-6) or not np.allclose(r.T @ r, np.eye(3), atol=1e-6) or np.linalg.det(r) < 0:
        raise InvalidInput(f"parameter {name}: not a rigid transform (a rotation, a translation and a last row 0 0 0 1)")
    return m.copy()


def twist_in_end_effector_frame(twist: npt.ArrayLike, hand_eye: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """The camera twist (v, w), camera frame, as the end effector's twist in its own frame for
    the camera pose ``hand_eye`` in it (R, t): w_e = R w, v_e = R v + t x w_e, the adjoint of
    the rigid mount (:func:`vsinv.geometry.twist_adjoint`, a rigid body's velocity field)."""
    t6 = np.asarray(twist, dtype=float)
    return twist_adjoint(hand_eye) @ t6
