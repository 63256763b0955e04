"""A scenario's arm in its MuJoCo scene (issue 31, item 2): the built-in arm of `[robot]`
(`ur5`, `ur5e`, `panda`, with mass) placed at `robot.base` in F*, gravity along the base's -z,
the camera on the end effector through `robot.camera_mount` (eye-in-hand), a site where the
controller believes the camera is (`robot.mount_error`), velocity actuators, and the joint
ranges of the scenario's limits.

Names in the model: the camera `vsinv_wrist` (vsinv's frame is the site `vsinv_camera`'s, turned
by pi about x for MuJoCo), the site `vsinv_believed` (the camera frame the controller's twists
are in: its Jacobian, `mj_jacSite`, maps joint velocities to them), the arm's base body
`vsinv_arm`. The arm's geoms are in geom group `GROUP` (hidden in the reference image).
Eye-to-hand (`[world] eye_to_hand`): the same arm, its "camera" the target's frame F* on the end
effector (`target_mount`), the target's geoms in the body `vsinv_target` there, the fixed camera
the scene's free camera at the world's origin.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import geometry
from .._core import InvalidInput
from . import _arms, _panda
from ._camera import PIXEL

CAMERA = "vsinv_wrist"
CAMERA_SITE = "vsinv_camera"
BELIEVED_SITE = "vsinv_believed"
BASE = "vsinv_arm"
TARGET = "vsinv_target"
PAYLOAD_MASS = 0.3  # kg: the target an eye-to-hand arm carries (its geoms are massless)
PAYLOAD_DEPTH = 0.65  # m along F*'s axis: the payload's centre of mass
GROUP = 3
GRAVITY = 9.81


def _tz(z: float, yaw: float = 0.0) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0, 0.0], [s, c, 0.0, 0.0], [0.0, 0.0, 1.0, z], [0.0, 0.0, 0.0, 1.0]])


def _v(x: Any) -> str:
    return " ".join(repr(float(t)) for t in np.ravel(np.asarray(x, dtype=float)))


def quat(pose: Any) -> str:
    """MuJoCo's quaternion (w, x, y, z) of a rotation (the 3x3 block of `pose`)."""
    _, thetau = geometry.thetau_from_pose(np.asarray(pose, dtype=float))
    angle = float(np.linalg.norm(thetau))
    axis = np.asarray(thetau) / angle if angle > 0 else np.zeros(3)
    return _v([np.cos(angle / 2), *(np.sin(angle / 2) * axis)])


def end_effector(model: str, link: str) -> np.ndarray:
    """The end effector `link` of the built-in arm `model` in the body of its last moving link
    (UR: `tool0`, the flange Tz(d6); Panda: `panda_link8` Tz(0.107) or `panda_hand_tcp` 0.103 m
    further, turned by -pi/4 about z)."""
    if model in ("ur5", "ur5e") and link == "tool0":
        arm = _arms.UR5 if model == "ur5" else _arms.UR5E
        return _tz(arm.dh[5][0])
    if model == "panda" and link in ("panda_link8", "panda_hand_tcp"):
        flange = _tz(_panda.PANDA_FLANGE)
        return flange if link == "panda_link8" else flange @ _tz(*_panda.PANDA_TCP)
    known = "ur5, ur5e: tool0; panda: panda_link8, panda_hand_tcp"
    raise InvalidInput(f"robot.end_effector: {link!r} of {model!r} is not modelled in MuJoCo ({known})")


def is_builtin(arm: Any) -> bool:
    """Whether `arm` (a `ScenarioArm`) is a built-in arm (its MJCF written here), not a user's URDF."""
    return str(arm.source).startswith("builtin:")


def tool_xml(arm: Any, ee: np.ndarray, width: int, height: int, focal: float, payload: str = "") -> str:
    """What vsinv puts on the end effector `ee` (its pose in the body that carries it): the
    camera's site and the believed one, the camera (the free camera's sensor: `width` x `height`
    pixels, focal length `focal` pixels; `World.set_K` sets it) and, eye-to-hand, `payload` (the
    target's geoms, in F*) in a body `TARGET` at the mount (F* on the end effector)."""
    camera = ee @ np.asarray(arm.mount)
    believed = ee @ np.asarray(arm.believed_mount)
    flip = np.diag([1.0, -1.0, -1.0, 1.0])
    tool = (f'<site name="{CAMERA_SITE}" pos="{_v(camera[:3, 3])}" quat="{quat(camera)}" size="0.005"/>'
            f'<site name="{BELIEVED_SITE}" pos="{_v(believed[:3, 3])}" quat="{quat(believed)}" size="0.005"/>'
            f'<camera name="{CAMERA}" pos="{_v(camera[:3, 3])}" quat="{quat(camera @ flip)}" resolution="{width} {height}" '
            f'sensorsize="{width * PIXEL} {height * PIXEL}" focalpixel="{focal} {focal}"/>')
    return tool + payload_xml(camera, payload)


def payload_xml(at: np.ndarray, payload: str) -> str:
    """Eye-to-hand: the body `TARGET` holding `payload` (the target's geoms, in F*) at `at` (F* in
    the body carrying it): a 0.3 kg target whose weight the controller compensates, as the
    arm's own. Empty without a payload."""
    if not payload:
        return ""
    payload = payload.replace("<geom ", '<geom mass="0" ')
    inertial = f'<inertial pos="0 0 {PAYLOAD_DEPTH}" mass="{PAYLOAD_MASS}" diaginertia="0.005 0.005 0.01"/>'
    return f'<body name="{TARGET}" pos="{_v(at[:3, 3])}" quat="{quat(at)}" gravcomp="1">{inertial}{payload}</body>'


def arm_xml(arm: Any, width: int, height: int, focal: float, payload: str = "") -> tuple[str, str, np.ndarray]:
    """The worldbody XML of `arm` (a `ScenarioArm`: model, end effector, base, mount), its
    actuators' XML and the gravity vector in the world frame (the base's -z); `tool_xml` on
    its end effector. A user's URDF arm (`is_builtin` false) is the empty base body here, and
    eye-to-hand the target's body beside it at the mount (`payload_xml`): `_urdf.attach` puts
    the arm, its tool and its actuators in the base and moves the target onto the end effector."""
    base = np.asarray(arm.base)
    gravity = base[:3, :3] @ np.array([0.0, 0.0, -GRAVITY])
    if not is_builtin(arm):
        held = payload_xml(np.asarray(arm.mount), payload)
        return f'<body name="{BASE}" pos="{_v(base[:3, 3])}" quat="{quat(base)}"/>{held}', "", gravity
    tool = tool_xml(arm, end_effector(arm.model, arm.end_effector), width, height, focal, payload)
    here = "<!--tool-->"
    if arm.model == "panda":
        chain, actuators = _panda.panda_chain(here), _panda.panda_actuators()
    else:
        ur = _arms.UR5 if arm.model == "ur5" else _arms.UR5E
        chain, actuators = _arms.ur_chain(ur, here), _arms.ur_actuators(ur)
    chain = chain.replace("<geom ", f'<geom group="{GROUP}" ').replace(here, tool)  # the arm's geoms only
    body = f'<body name="{BASE}" pos="{_v(base[:3, 3])}" quat="{quat(base)}">{chain}</body>'
    return body, actuators, gravity


def set_joint_ranges(model: Any, arm: Any) -> None:
    """The joints' ranges and the actuators' speed limits are the scenario's (`robot.joint_min`,
    `joint_max`, `joint_velocity`, or the model's)."""
    model.jnt_range[:] = np.column_stack([arm.lower, arm.upper])
    model.actuator_ctrlrange[:] = np.column_stack([-np.asarray(arm.velocity), np.asarray(arm.velocity)])


def camera_jacobian(model: Any, data: Any) -> np.ndarray:
    """MuJoCo's Jacobian (6, nv) of the site where the controller believes the camera is, in
    that site's frame (`_arms.site_jacobian`): joint velocities to the camera twist (v, w)."""
    return _arms.site_jacobian(model, data, BELIEVED_SITE)
