"""The arm of a user's MJCF file (`World.from_mjcf(..., arm_joints=, camera_site=)`, issue 31
item 2): the joints vsinv drives, the site whose frame is the camera's (vsinv's convention: x
right, y down, z forward), and a velocity actuator on each joint.

`camera_site` may be left out: vsinv then adds a site `AUTO_SITE` on the camera's body at the
camera's pose turned by pi about x (MuJoCo's camera looks down its -z with y up). A joint that no
actuator drives gets a velocity actuator `v_<joint>` (kv = M_jj / `_urdf.TAU` at the model's
initial joints, its control within the joint's `actuatorfrcrange` and the ctrlrange left free),
and vsinv says so (a `UserWarning`); a joint driven by an actuator that is not a velocity
actuator is refused naming `arm_joints` (vsinv commands joint velocities).
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .._core import InvalidInput
from . import _arms, _urdf

AUTO_SITE = "vsinv_camera_site"


def prepare(spec: Any, camera: str, arm_joints: tuple[str, ...], camera_site: str | None) -> str:
    """Checks the names in the spec, adds the camera's site if need be; returns the site's name."""
    import mujoco

    for j in arm_joints:
        joint = spec.joint(j)
        if joint is None:
            raise InvalidInput(f"arm_joints: no joint named {j!r} in the model")
        if joint.type not in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE):
            raise InvalidInput(f"arm_joints: joint {j!r} is not a hinge or a slide")
    if camera_site is not None:
        if spec.site(camera_site) is None:
            raise InvalidInput(f"camera_site: no site named {camera_site!r} in the model")
        return camera_site
    cam = spec.camera(camera)
    if cam is None:
        raise InvalidInput(f"camera: no camera named {camera!r} in the model")
    q = np.zeros(4)
    mujoco.mju_mulQuat(q, np.asarray(cam.quat, dtype=float), np.array([0.0, 1.0, 0.0, 0.0]))  # turned by pi about x
    cam.parent.add_site(name=AUTO_SITE, pos=cam.pos, quat=q, size=[0.005, 0.005, 0.005])
    return AUTO_SITE


def add_actuators(spec: Any, model: Any, arm_joints: tuple[str, ...], path: str) -> bool:
    """Velocity actuators on the arm's joints that no actuator drives (kv = M_jj / TAU at the
    model's initial joints); whether any was added. A joint driven otherwise is refused."""
    import mujoco

    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    added = []
    for j in arm_joints:
        jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, j)
        drives = [a for a in range(model.nu)
                  if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT and model.actuator_trnid[a, 0] == jid]
        if drives:
            a = drives[0]
            kv = model.actuator_gainprm[a, 0]
            if not (kv > 0 and model.actuator_biasprm[a, 1] == 0 and model.actuator_biasprm[a, 2] == -kv):
                raise InvalidInput(f"arm_joints: joint {j!r} is driven by actuator {model.actuator(a).name or a!r}, which is "
                                   "not a velocity actuator (vsinv commands joint velocities)")
            continue
        i = int(model.jnt_dofadr[jid])
        unit, column = np.zeros(model.nv), np.zeros(model.nv)
        unit[i] = 1.0
        mujoco.mj_mulM(model, data, column, unit)
        act = spec.add_actuator(name=f"v_{j}", target=j, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_velocity(kv=float(column[i] / _urdf.TAU))
        added.append(j)
    if added:
        warnings.warn(f"arm_joints: {path!r} has no actuator on {', '.join(added)}; vsinv added velocity actuators "
                      f"v_<joint> (kv = M_jj / {_urdf.TAU} s)", UserWarning, stacklevel=4)
    return bool(added)


class UserArm:
    """The arm vsinv drives in a user's model: its joints' dofs, their velocity actuators and the
    camera's site."""

    def __init__(self, model: Any, arm_joints: tuple[str, ...], site: str) -> None:
        import mujoco

        self.joints, self.site = tuple(arm_joints), site
        ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in arm_joints]
        self.dofs = np.array([model.jnt_dofadr[i] for i in ids], dtype=int)
        self.qpos = np.array([model.jnt_qposadr[i] for i in ids], dtype=int)
        self.actuators = np.array([next(a for a in range(model.nu) if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT
                                        and model.actuator_trnid[a, 0] == i) for i in ids], dtype=int)

    def jacobian(self, model: Any, data: Any) -> np.ndarray:
        """(6, n): the arm's joint velocities to the camera site's twist in its own frame."""
        return _arms.site_jacobian(model, data, self.site)[:, self.dofs]
