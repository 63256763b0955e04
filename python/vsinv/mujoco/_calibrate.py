"""Eye-to-hand hand-eye calibration in MuJoCo, the path a user follows (issue 31, item 3): the
arm carries the dots to `count` stations around the reference view, the fixed camera renders
each, the dots' pose in the camera is measured from the image, and
`calibrate_hand_eye(..., setup="eye_to_hand")` turns the flange poses and the measured poses
into the camera-to-base transform, which the scenario then gives the controller
(`[world.eye_to_hand] camera_to_base`, `with_camera_to_base`). `calibrate_eye_to_hand` does it all.

The pose of the dots' frame F* in the camera from one image: `vsinv.vision.detect_dots`, each
model point matched to the nearest dot (within `MATCH_PX` pixels) of its projection where the
scenario's layout (`base`, `target_mount`) puts it (in the simulation the layout is exact; it
names the dots and never enters the estimate), the points' depths by the DLT resection of
`vsinv.calibration.reference_depths` (12 points not on one plane: no intrinsics), the points
in the camera frame `Z K^-1 (u, v, 1)` with the camera's own K (a calibrated camera), and the
rigid transform from F* to them by least squares (Arun, Huang and Blostein, PAMI 1987).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import calibration, geometry, vision
from .._core import InvalidInput
from ._arm_loop import goal_joints
from ._world import World

#: A model point's projection is matched to a dot at most this far away (pixels).
MATCH_PX = 20.0


@dataclass(frozen=True)
class HandEyeStations:
    """What a calibration run measured: the joints (n, dof), the flange's poses in the base
    frame (n, 4, 4: gripper-to-base), the dots' frame F* in the camera measured from each image
    (n, 4, 4: target-to-camera) and the truth of the latter (the scene's, for tests)."""

    joints: np.ndarray
    gripper_poses: np.ndarray
    target_poses: np.ndarray
    true_target_poses: np.ndarray


def rigid_fit(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The 4x4 rigid transform T minimising sum |T source_k - target_k|^2 ((n, 3) each), by the
    SVD of the cross-covariance (Arun et al. 1987, with the reflection guard)."""
    cs, ct = source.mean(axis=0), target.mean(axis=0)
    u, _, vt = np.linalg.svd((source - cs).T @ (target - ct))
    flip = np.diag([1.0, 1.0, np.sign(np.linalg.det(vt.T @ u.T))])
    rotation = vt.T @ flip @ u.T
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = rotation, ct - rotation @ cs
    return out


def target_pose(image: np.ndarray, points: np.ndarray, K: np.ndarray, predicted: np.ndarray) -> np.ndarray:
    """The pose of the points' frame in the camera (4x4) from `image`: dots detected, matched
    to `predicted` pixels (n, 2), depths by the DLT resection, then the rigid fit."""
    found = np.asarray(vision.detect_dots(image).centroids)
    if len(found) < len(points):
        raise InvalidInput(f"image: {len(found)} dots found, {len(points)} expected")
    gaps = np.linalg.norm(found[None, :, :] - predicted[:, None, :], axis=2)
    nearest = gaps.argmin(axis=1)
    if len(set(nearest.tolist())) < len(points) or gaps[np.arange(len(points)), nearest].max() > MATCH_PX:
        raise InvalidInput(f"image: the dots do not match the expected layout within {MATCH_PX} px")
    pixels = found[nearest]
    depths = np.asarray(calibration.reference_depths(points, pixels))
    rays = np.linalg.solve(K, np.vstack([pixels.T, np.ones(len(points))]))
    return rigid_fit(points, (rays * depths).T)


def station_joints(arm: Any, count: int, seed: int, angle_deg: float = 20.0, offset_m: float = 0.05) -> np.ndarray:
    """`count` joint vectors holding F* near the reference view: turned by up to `angle_deg`
    about a random axis and moved by up to `offset_m` (inverse kinematics from the goal joints)."""
    rng = np.random.default_rng(seed)
    goal = goal_joints(arm)
    home = np.asarray(arm.camera_pose(goal))  # F* in the camera, about the identity
    base_inv, mount_inv = np.linalg.inv(np.asarray(arm.base)), np.linalg.inv(np.asarray(arm.mount))
    out: list[np.ndarray] = []
    while len(out) < count:
        axis, shift = rng.normal(size=3), rng.normal(size=3)
        turn = axis / np.linalg.norm(axis) * np.radians(rng.uniform(0.5, 1.0) * angle_deg)
        move = shift / np.linalg.norm(shift) * rng.uniform(0.0, offset_m)
        centre = np.eye(4)
        centre[2, 3] = 0.6  # turn about the dots' middle, so they stay in view
        pose = home @ centre @ geometry.pose_from_position_thetau(move, turn) @ np.linalg.inv(centre)
        try:
            out.append(np.asarray(arm.ik(base_inv @ pose @ mount_inv, seed=goal)))
        except InvalidInput:
            continue
    return np.array(out)


def measure_stations(world: World, joints: np.ndarray) -> HandEyeStations:
    """Puts the arm of an eye-to-hand `world` at each of `joints`, renders the fixed camera and
    measures the dots' pose in it (`target_pose`)."""
    import mujoco

    if not world.eye_to_hand:
        raise InvalidInput("world: not an eye-to-hand world ([world.eye_to_hand])")
    arm, points, K = world.arm, np.asarray(world.target_points), np.asarray(world.K.matrix)
    base_inv, mount_inv = np.linalg.inv(np.asarray(arm.base)), np.linalg.inv(np.asarray(arm.mount))
    gripper, measured, truth = [], [], []
    for q in joints:
        world.data.qpos[:], world.data.qvel[:] = q, 0.0
        mujoco.mj_forward(world.model, world.data)
        true_pose = np.asarray(arm.camera_pose(q))  # F* in the camera: the scene's truth, here the layout
        cam = (true_pose[:3, :3] @ points.T).T + true_pose[:3, 3]  # (names the dots only)
        predicted = (K @ (cam / cam[:, 2:]).T).T[:, :2]
        measured.append(target_pose(world.render(np.eye(4)), points, K, predicted))
        gripper.append(base_inv @ true_pose @ mount_inv)  # the flange in the base: the arm's own fk(q)
        truth.append(true_pose)
    return HandEyeStations(np.asarray(joints), np.array(gripper), np.array(measured), np.array(truth))


def calibrate_eye_to_hand(world: World, count: int = 10, seed: int = 0, method: str = "tsai") -> tuple[Any, HandEyeStations]:
    """Eye-to-hand calibration of `world`'s fixed camera against its arm's base from `count`
    stations: (`HandEyeCalibration`, whose `matrix` is camera-to-base, and the `HandEyeStations`)."""
    stations = measure_stations(world, station_joints(world.arm, count, seed))
    result = calibration.calibrate_hand_eye(stations.gripper_poses, stations.target_poses, method=method,
                                            setup="eye_to_hand")
    return result, stations


def with_camera_to_base(d: dict[str, Any], matrix: Any) -> dict[str, Any]:
    """A copy of scenario dict `d` whose controller believes the camera-to-base transform
    `matrix` (4x4: `[world.eye_to_hand] camera_to_base`)."""
    position, thetau = geometry.thetau_from_pose(np.asarray(matrix, dtype=float))
    out = dict(d)
    out["world"] = dict(d["world"])
    out["world"]["eye_to_hand"] = dict(d["world"]["eye_to_hand"])
    out["world"]["eye_to_hand"]["camera_to_base"] = {
        "position": [float(x) for x in position], "rotation_deg": [float(x) for x in np.degrees(thetau)]}
    return out
