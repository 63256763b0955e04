"""The camera convention between vsinv and MuJoCo, and the K a MuJoCo camera implies.

vsinv's camera frame: x right, y down, z forward (the optical axis). MuJoCo's: x right, y up,
looking down -z. The two differ by a turn of pi about x: R_mujoco = R_vsinv diag(1, -1, -1), the
same origin. A pose is a 4x4 world-from-camera transform in vsinv's frame (for a scenario's world,
the world is F*, the reference camera's frame).

K of a MuJoCo camera (pixel (0, 0) the centre of the top-left pixel, as OpenCV and vsinv):
- with `fovy` only (no sensor size): square pixels, f = (H / 2) / tan(fovy / 2), the principal
  point at the image centre ((W - 1) / 2, (H - 1) / 2);
- with intrinsics (`sensorsize`, `focal`/`focalpixel`, `principal`/`principalpixel`):
  fx = focal_x W / sensor_w, fy = focal_y H / sensor_h, and MuJoCo's principal offset (p_x, p_y),
  in pixels, moves the principal point to ((W - 1) / 2 - p_x, (H - 1) / 2 - p_y) (measured on
  MuJoCo 4.0's renders: tests/test_mujoco_api.py checks it on dot centroids).
"""

from __future__ import annotations

from typing import Any

import numpy as np

# The sensor's pixel pitch (metres) of the cameras vsinv puts in a scene: 10 um, as the scenarios'
# lenses (f = 1200 px: 12 mm); MuJoCo's `sensorsize` is the image size times it.
PIXEL = 1e-5

FLIP = np.diag([1.0, -1.0, -1.0])


def mujoco_pose(pose: Any) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo's position and rotation matrix (3, 3) of a camera at the vsinv pose `pose`."""
    pose = np.asarray(pose, dtype=float)
    return pose[:3, 3].copy(), pose[:3, :3] @ FLIP


def vsinv_pose(position: Any, rotation: Any) -> np.ndarray:
    """The vsinv pose (4x4) of a MuJoCo camera at `position` with rotation matrix `rotation`."""
    pose = np.eye(4)
    pose[:3, :3] = np.asarray(rotation, dtype=float).reshape(3, 3) @ FLIP
    pose[:3, 3] = np.asarray(position, dtype=float)
    return pose


def k_of_fovy(fovy_deg: float, width: int, height: int) -> tuple[float, float, float, float]:
    """(fx, fy, cx, cy) of a MuJoCo camera with vertical field of view `fovy_deg` and no sensor size."""
    f = 0.5 * height / np.tan(np.radians(fovy_deg) / 2.0)
    return float(f), float(f), (width - 1) / 2.0, (height - 1) / 2.0


def k_of_intrinsics(intrinsic: Any, sensorsize: Any, width: int, height: int) -> tuple[float, float, float, float]:
    """(fx, fy, cx, cy) of a MuJoCo camera from its `cam_intrinsic` (focal x, y, principal x, y, in
    length units) and `cam_sensorsize` (width, height, same units)."""
    fx_len, fy_len, px_len, py_len = (float(v) for v in intrinsic)
    sx, sy = width / float(sensorsize[0]), height / float(sensorsize[1])
    return fx_len * sx, fy_len * sy, (width - 1) / 2.0 - px_len * sx, (height - 1) / 2.0 - py_len * sy


def intrinsics_of_k(K: tuple[float, float, float, float], width: int, height: int, pixel: float) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo's `cam_intrinsic` and `cam_sensorsize` for K = (fx, fy, cx, cy) on a sensor of
    `pixel`-sized square pixels (metres): the inverse of `k_of_intrinsics`."""
    fx, fy, cx, cy = (float(v) for v in K)
    intrinsic = np.array([fx, fy, (width - 1) / 2.0 - cx, (height - 1) / 2.0 - cy]) * pixel
    return intrinsic, np.array([width * pixel, height * pixel])
