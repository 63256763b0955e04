"""A user's URDF arm in a scenario's MuJoCo scene (issue 31, item 2): `[robot] kind = "urdf"`
with `urdf = "my_arm.urdf"` (a file, not a built-in name) and `[world] engine = "mujoco"`.

MuJoCo reads the URDF itself (`MjSpec.from_file`: the links' `<inertial>`, the joints' ranges,
`<dynamics damping>` and effort limits; visuals discarded, collision geometry kept). vsinv then
- refuses a moving link without mass (MuJoCo's "mass and inertia of moving bodies must be larger
  than mjMINVAL") with an `InvalidInput` naming `robot.urdf` and the link;
- keeps the links joined by fixed joints as bodies (`fusestatic` off: `robot.end_effector` may
  be one) and welds the joints off the chain from the root link to the end effector (a
  gripper's fingers: vsinv drives the chain the kinematic arm reads);
- hangs the arm's root link on the scene's base body (`robot.base` in F*), its names prefixed
  with `PREFIX`, puts the camera and its sites on the end effector as on a built-in arm
  (`_mounted.tool_xml`), compensates the links' weight (`gravcomp`, as the built-in arms do);
- adds a velocity actuator `v_<joint>` on each joint of the chain (a URDF describes none that
  MuJoCo reads) and says so (a `UserWarning`): its gain kv = M_jj / `TAU`, M_jj the joint's
  diagonal of MuJoCo's mass matrix at the start joints (a velocity time constant of `TAU`), its
  control within the joint's speed limit (`ScenarioArm.velocity`, set by
  `_mounted.set_joint_ranges`) and its torque within the URDF's effort limit (MuJoCo's joint
  `actfrcrange`).
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import numpy as np

from .._core import InvalidInput
from . import _mounted
from ._camera import PIXEL

#: MuJoCo's smallest mass and inertia of a moving body (`mjMINVAL`).
MINVAL = 1e-15
#: The prefix of the URDF's names in the scene (its links, joints and geoms).
PREFIX = "urdf/"
#: The added velocity actuators' time constant (s): kv = M_jj / TAU (one physics step at 500 Hz).
TAU = 0.002


def load(path: str) -> Any:
    """The URDF file `path` as MuJoCo reads it, static bodies kept (InvalidInput naming
    `robot.urdf` when MuJoCo cannot read it)."""
    import mujoco

    if not Path(path).is_file():
        raise InvalidInput(f"robot.urdf: no URDF file at {path!r}")
    try:
        spec = mujoco.MjSpec.from_file(str(path))
    except (ValueError, TypeError) as e:
        raise InvalidInput(f"robot.urdf: MuJoCo could not read {path!r} ({e})") from e
    spec.compiler.fusestatic = False
    return spec


def check_masses(spec: Any, path: str) -> None:
    """Every moving link has a mass: an `<inertial>` of positive mass, or collision geometry
    MuJoCo gives one from (its default density). A kinematics-only URDF is refused naming the
    first link without."""
    for body in spec.bodies:
        if not body.joints:
            continue
        massive = body.mass > MINVAL if body.explicitinertial else len(body.geoms) > 0
        if not massive:
            raise InvalidInput(
                f"robot.urdf: link {body.name!r} of {path!r} moves (joint {body.joints[0].name!r}) but has no mass: "
                "MuJoCo simulates an arm with mass; give each moving link an <inertial> (origin, mass, inertia)")


def _weld_off_chain(spec: Any, chain: list[str]) -> None:
    """Deletes the joints that are not on the chain (they become welds)."""
    for joint in list(spec.joints):
        if joint.name not in chain:
            spec.delete(joint)


def attach(scene: Any, arm: Any, width: int, height: int, focal: float) -> Any:
    """Puts the URDF arm `arm` (a `ScenarioArm` whose `source` is a file) into the scene spec
    `scene` (made from `_scene.scene`'s XML, whose base body `_mounted.BASE` is empty), its
    names prefixed with `PREFIX`, and returns the compiled model. Eye-to-hand, the target's
    body `_mounted.TARGET` (beside the base, at the mount) moves onto the end effector, its
    geoms outside the arm's group (the fixed camera sees them)."""
    import mujoco

    path = str(arm.source)
    urdf = load(path)
    check_masses(urdf, path)
    chain = list(arm.joint_names)
    _weld_off_chain(urdf, chain)
    roots = [b for b in urdf.bodies if b.name and b.parent is not None and b.parent.name == "world"]
    if len(roots) != 1:
        raise InvalidInput(f"robot.urdf: expected one root link in {path!r}, got {[b.name for b in roots]}")
    scene.body(_mounted.BASE).add_frame().attach_body(roots[0], PREFIX, "")
    ee = scene.body(PREFIX + arm.end_effector)
    if ee is None:
        raise InvalidInput(f"robot.end_effector: no link {arm.end_effector!r} in {path!r}")
    _tool(ee, arm, width, height, focal)
    names = set(_body_names(scene.body(_mounted.BASE)))
    for body in scene.bodies:
        if body.name in names:
            body.gravcomp = 1.0
            for geom in body.geoms:
                geom.group = _mounted.GROUP
    held = scene.body(_mounted.TARGET)  # eye-to-hand: the target's body, onto the end effector
    if held is not None:
        scene.copy_during_attach = True
        ee.add_frame().attach_body(held, PREFIX, "")
        scene.delete(held)
    model = _compile(scene, path)
    for joint, gain in zip(chain, _gains(model, arm)):
        act = scene.add_actuator(name=f"v_{joint}", target=PREFIX + joint, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_velocity(kv=float(gain))
    warnings.warn(f"robot.urdf: {path!r} describes no actuators MuJoCo reads; vsinv added velocity actuators "
                  f"v_<joint> on {', '.join(chain)} (kv = M_jj / {TAU} s at the start joints, within the URDF's "
                  "speed and effort limits)", UserWarning, stacklevel=3)
    return _compile(scene, path)


def _compile(spec: Any, path: str) -> Any:
    try:
        return spec.compile()
    except ValueError as e:  # MuJoCo's message names the element
        raise InvalidInput(f"robot.urdf: MuJoCo could not build {path!r} into the scene ({e})") from e


def _tool(ee: Any, arm: Any, width: int, height: int, focal: float) -> None:
    """The camera and its sites on the end effector's body, as `_mounted.tool_xml` writes them
    on a built-in arm (the end effector is the body's own frame)."""
    camera, believed = np.asarray(arm.mount, dtype=float), np.asarray(arm.believed_mount, dtype=float)
    for name, pose in ((_mounted.CAMERA_SITE, camera), (_mounted.BELIEVED_SITE, believed)):
        ee.add_site(name=name, pos=pose[:3, 3], quat=_quat(pose), size=[0.005, 0.005, 0.005])
    flip = np.diag([1.0, -1.0, -1.0, 1.0])
    ee.add_camera(name=_mounted.CAMERA, pos=camera[:3, 3], quat=_quat(camera @ flip), resolution=[width, height],
                  sensor_size=[width * PIXEL, height * PIXEL], focal_pixel=[focal, focal])


def _quat(pose: np.ndarray) -> list[float]:
    return [float(x) for x in _mounted.quat(pose).split()]


def _body_names(body: Any) -> list[str]:
    out = [body.name]
    for child in body.bodies:
        out += _body_names(child)
    return out


def _gains(model: Any, arm: Any) -> np.ndarray:
    """kv = M_jj / TAU of each chain joint at the start joints (MuJoCo's mass matrix)."""
    import mujoco

    data = mujoco.MjData(model)
    data.qpos[:] = arm.start
    mujoco.mj_forward(model, data)
    out = []
    for joint in arm.joint_names:
        unit, column = np.zeros(model.nv), np.zeros(model.nv)
        i = int(model.jnt_dofadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, PREFIX + joint)])
        unit[i] = 1.0
        mujoco.mj_mulM(model, data, column, unit)  # M e_i: column i of the mass matrix
        out.append(column[i])
    return np.array(out) / TAU
