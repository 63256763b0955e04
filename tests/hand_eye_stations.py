"""Synthetic hand-eye stations with a known camera-to-gripper transform X, shared by
tests/test_hand_eye.py and benches/hand_eye_vs_opencv.py (rotations by OpenCV's Rodrigues)."""

from __future__ import annotations

import cv2
import numpy as np


# OpenCV's hand-eye methods that vsinv implements, by vsinv's name.
CV_METHODS = {
    "tsai": cv2.CALIB_HAND_EYE_TSAI,
    "park": cv2.CALIB_HAND_EYE_PARK,
    "daniilidis": cv2.CALIB_HAND_EYE_DANIILIDIS,
}
# (rotation noise in degrees, translation noise in metres) of each target pose.
NOISE_LEVELS = [(0.1, 0.001), (0.5, 0.002), (1.0, 0.005)]


def homogeneous(r: np.ndarray, t: np.ndarray) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3], m[:3, 3] = r, np.asarray(t).ravel()
    return m


def opencv(g: np.ndarray, c: np.ndarray, method: str) -> np.ndarray:
    """``cv2.calibrateHandEye`` on gripper-to-base poses ``g`` and target-to-camera poses ``c``."""
    r, t = cv2.calibrateHandEye(list(g[:, :3, :3]), list(g[:, :3, 3]), list(c[:, :3, :3]), list(c[:, :3, 3]),
                                method=CV_METHODS[method])
    return homogeneous(r, t)


def assert_within_noise(errs: np.ndarray, noise: tuple[float, float], lever_m: float) -> None:
    """The (rotation deg, translation m) errors of many draws against the truth are within the
    noise of one target pose: median below it and maximum below three times it, a rotation
    error adding its lever (``lever_m``, the distance it acts over) to the translation's."""
    rot_sd, trans_sd = noise
    rot_noise = np.sqrt(3) * rot_sd
    trans_noise = np.sqrt(3) * (trans_sd + np.radians(rot_sd) * lever_m)
    assert np.median(errs[:, 0]) < rot_noise and errs[:, 0].max() < 3 * rot_noise, errs[:, 0]
    assert np.median(errs[:, 1]) < trans_noise and errs[:, 1].max() < 3 * trans_noise, errs[:, 1]


def rigid(rotvec: np.ndarray, t: np.ndarray) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = cv2.Rodrigues(np.asarray(rotvec, dtype=float).reshape(3, 1))[0]
    m[:3, 3] = t
    return m


def random_rotvec(rng: np.random.Generator, angle_rad: float) -> np.ndarray:
    axis = rng.normal(size=3)
    return axis / np.linalg.norm(axis) * angle_rad


def stations(rng: np.random.Generator, n: int, noise: tuple[float, float] = (0.0, 0.0)):
    """``n`` stations around a target 0.5 m below the gripper: gripper-to-base poses tilted up
    to 40 degrees about random axes, the exact target-to-camera poses for a random X, then
    each target pose perturbed by a random rotation of ``noise[0]`` degrees (normal per axis)
    and a translation of ``noise[1]`` metres (normal per axis). Returns (G, C, X)."""
    x = rigid(random_rotvec(rng, rng.uniform(0.2, 2.5)), rng.uniform(-0.1, 0.1, 3))
    target_in_base = rigid(random_rotvec(rng, 0.3), np.array([0.6, 0.0, 0.0]))
    g, c = [], []
    for _ in range(n):
        gi = gripper_pose(rng)
        g.append(gi)
        c.append(perturbed(rng, np.linalg.inv(gi @ x) @ target_in_base, noise))
    return np.array(g), np.array(c), x


def gripper_pose(rng: np.random.Generator) -> np.ndarray:
    """A gripper-to-base pose 0.5 m above a point 0.6 m in front of the base, looking down and
    tilted 10 to 40 degrees about a random axis, moved up to 0.15 m along each axis."""
    looking_down = rigid(np.array([np.pi, 0.0, 0.0]), np.array([0.6, 0.0, 0.5]))
    tilt = rigid(random_rotvec(rng, np.radians(rng.uniform(10, 40))), rng.uniform(-0.15, 0.15, 3))
    return looking_down @ tilt


def perturbed(rng: np.random.Generator, pose: np.ndarray, noise: tuple[float, float]) -> np.ndarray:
    """``pose`` moved by a random rotation of ``noise[0]`` degrees and a translation of
    ``noise[1]`` metres (normal per axis, in its own frame); unchanged (no draw) without noise."""
    rot_sd, trans_sd = noise
    if rot_sd > 0 or trans_sd > 0:
        return pose @ rigid(rng.normal(0.0, np.radians(rot_sd), 3), rng.normal(0.0, trans_sd, 3))
    return pose


def errors(found: np.ndarray, truth: np.ndarray) -> tuple[float, float]:
    """(rotation in degrees, translation in metres) between two transforms."""
    r = found[:3, :3].T @ truth[:3, :3]
    # atan2(sin, cos) of the angle: accurate at small angles too (arccos of the trace is not).
    sin = np.linalg.norm([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]]) / 2
    angle = np.degrees(np.arctan2(sin, (np.trace(r) - 1) / 2))
    return float(angle), float(np.linalg.norm(found[:3, 3] - truth[:3, 3]))


def eye_to_hand_stations(rng: np.random.Generator, n: int, noise: tuple[float, float] = (0.0, 0.0)):
    """``n`` eye-to-hand stations: a camera fixed in the base frame (camera-to-base ``Y``, about
    1.1 m in front of the base looking back at the workspace), a target on the flange
    (target-to-flange ``T``, 0.1 m beyond it), the gripper poses of ``stations`` (tilted up to 40
    degrees about random axes), and what the camera sees, ``C_i = Y^-1 G_i T``, perturbed as in
    ``stations``. Returns (G, C, Y, T)."""
    y = rigid(np.array([0.0, -np.pi / 2, 0.0]) + random_rotvec(rng, 0.3), np.array([1.3, 0.0, 0.4]) + rng.uniform(-0.1, 0.1, 3))
    t = rigid(random_rotvec(rng, rng.uniform(0.0, 0.5)), np.array([0.0, 0.0, 0.1]) + rng.uniform(-0.03, 0.03, 3))
    g, c = [], []
    for _ in range(n):
        gi = gripper_pose(rng)
        g.append(gi)
        c.append(perturbed(rng, np.linalg.inv(y) @ gi @ t, noise))
    return np.array(g), np.array(c), y, t
