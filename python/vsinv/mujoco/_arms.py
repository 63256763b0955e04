"""Arms with mass for MuJoCo (issue 31, item 2): the UR5 of vsinv's `robots/ur5.urdf` and the
UR5e of `robots/ur5e.urdf` (the same standard DH kinematics, so `vsinv.kinematics.fk("ur5", q)`
and `fk("ur5e", q)` are the flange's pose in the base frame) with Universal Robots' published
masses and centres of mass, capsule geometry the camera can see, joint limits, and velocity
actuators limited to the published speed and effort limits.

Source of the numbers: Universal Robots, "DH parameters for calculations of kinematics and
dynamics" (https://www.universal-robots.com/articles/ur/application-installation/dh-parameters-for-calculations-of-kinematics-and-dynamics/).
UR5: d = 0.089159, 0, 0, 0.10915, 0.09465, 0.0823 m; a2 = -0.425, a3 = -0.39225 m;
m = 3.7, 8.393, 2.33, 1.219, 1.219, 0.1879 kg; centres of mass in the DH frames below. UR
publishes no inertia tensors for the UR5: each link's is that of a uniform solid cylinder of its
mass along its longest segment (radius 0.05 m), at its centre of mass.
UR5e: d = 0.1625, 0, 0, 0.1333, 0.0997, 0.0996 m; a2 = -0.425, a3 = -0.3922 m;
m = 3.761, 8.058, 2.846, 1.37, 1.3, 0.365 kg; the same centres of mass. That page gives no inertia
for the UR5e ("negligible"): the tensors (UR5E_INERTIA, about the centres of mass, axes of the DH
frames) are the diagonals of those in Universal Robots' ROS 2 description
(Universal_Robots_ROS2_Description, config/ur5e/physical_parameters.yaml, whose inertial frames
are the DH frames: its rotations are the DH alphas); its off-diagonal terms, at most 7.1 % of
the link's largest moment, are left out. Limits of both (the
datasheets): +-360 degrees, 180 degrees/s (UR5: 3.15 rad/s as robots/ur5.urdf), 150 N m on the
three size-3 joints and 28 N m on the wrists.
The bodies compensate their own weight (MuJoCo's `gravcomp`, as the arm's controller does) and
each joint is driven by a velocity actuator (gain `kv`, torque within the effort limit). The
geometry is seen (it can occlude a target) but does not collide (contype 0).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .._core import InvalidInput

# Standard DH (d, a, alpha) of the UR5, as robots/ur5.urdf.
UR5_DH = ((0.089159, 0.0, np.pi / 2), (0.0, -0.425, 0.0), (0.0, -0.39225, 0.0),
          (0.10915, 0.0, np.pi / 2), (0.09465, 0.0, -np.pi / 2), (0.0823, 0.0, 0.0))
UR5_MASS = (3.7, 8.393, 2.33, 1.219, 1.219, 0.1879)
UR5_COM = ((0.0, -0.02561, 0.00193), (0.2125, 0.0, 0.11336), (0.15, 0.0, 0.0265),
           (0.0, -0.0018, 0.01634), (0.0, 0.0018, 0.01634), (0.0, 0.0, -0.001159))
UR5_EFFORT = (150.0, 150.0, 150.0, 28.0, 28.0, 28.0)  # N m
UR5_SPEED = 3.15  # rad/s, every joint
UR5_KV = (300.0, 300.0, 150.0, 50.0, 50.0, 20.0)  # N m s / rad
# The UR5e (robots/ur5e.urdf): standard DH, masses, centres of mass (DH frames): Universal Robots'
# UR5e rows; inertia tensors (diagonal, about the centre of mass, axes of the DH frame): the
# diagonals of Universal Robots' ROS 2 description (see above).
UR5E_DH = ((0.1625, 0.0, np.pi / 2), (0.0, -0.425, 0.0), (0.0, -0.3922, 0.0),
           (0.1333, 0.0, np.pi / 2), (0.0997, 0.0, -np.pi / 2), (0.0996, 0.0, 0.0))
UR5E_MASS = (3.761, 8.058, 2.846, 1.37, 1.3, 0.365)
UR5E_COM = UR5_COM
UR5E_INERTIA = ((0.0070021, 0.00648091, 0.00657286), (0.01505885, 0.33388086, 0.33247207),
                (0.00399632, 0.07879254, 0.0784851), (0.00165491, 0.00135962, 0.00126279),
                (0.00135617, 0.00127827, 0.00096614), (0.00018694, 0.00018908, 0.00025756))
UR5E_SPEED = np.pi  # rad/s (180 degrees/s), every joint
JOINTS = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint")
LINKS = ("shoulder_link", "upper_arm_link", "forearm_link", "wrist_1_link", "wrist_2_link", "wrist_3_link")


@dataclass(frozen=True)
class UrArm:
    """A Universal Robots arm's published numbers: standard DH rows (d, a, alpha), masses,
    centres of mass (DH frames), principal inertias about them in the DH frames (None: a solid
    cylinder along the longest segment), speed (rad/s) and effort (N m) limits."""

    name: str
    dh: tuple[tuple[float, float, float], ...]
    mass: tuple[float, ...]
    com: tuple[tuple[float, float, float], ...]
    inertia: tuple[tuple[float, float, float], ...] | None
    speed: float
    effort: tuple[float, ...] = UR5_EFFORT
    kv: tuple[float, ...] = UR5_KV


UR5 = UrArm("ur5", UR5_DH, UR5_MASS, UR5_COM, None, UR5_SPEED)
UR5E = UrArm("ur5e", UR5E_DH, UR5E_MASS, UR5E_COM, UR5E_INERTIA, UR5E_SPEED)


def _dh(d: float, a: float, alpha: float) -> np.ndarray:
    """Tz(d) Tx(a) Rx(alpha)."""
    c, s = np.cos(alpha), np.sin(alpha)
    return np.array([[1, 0, 0, a], [0, c, -s, 0], [0, s, c, d], [0, 0, 0, 1.0]])


def _v(x: np.ndarray) -> str:
    return " ".join(f"{float(t):.9g}" for t in np.ravel(x))


def _cylinder_inertia(mass: float, length: float, radius: float = 0.05) -> np.ndarray:
    """Principal moments of a solid cylinder along z."""
    side = mass * (3 * radius**2 + length**2) / 12.0
    return np.array([side, side, mass * radius**2 / 2.0])


def _link(arm: UrArm, i: int, child: str) -> str:
    """The content of link i's body: joint i, its inertia and geometry, and `child` (the body of
    link i + 1, or the flange's site and camera)."""
    d, a, alpha = arm.dh[i]
    frame = _dh(d, a, alpha)  # DH frame i in the body's frame: where the next joint is
    com = (frame @ np.append(arm.com[i], 1.0))[:3]
    segments = [(np.zeros(3), np.array([0.0, 0.0, d])), (np.array([0.0, 0.0, d]), frame[:3, 3])]
    longest = max(float(np.linalg.norm(q - p)) for p, q in segments)
    radius = 0.045 if i < 3 else 0.035
    geoms = "".join(
        f'<geom type="capsule" fromto="{_v(p)} {_v(q)}" size="{radius}" rgba="0.6 0.63 0.68 1" mass="0" contype="0" conaffinity="0"/>'
        for p, q in segments if np.linalg.norm(q - p) > 1e-9
    )
    geoms += f'<geom type="cylinder" size="{radius * 1.1} {radius}" rgba="0.25 0.45 0.7 1" mass="0" contype="0" conaffinity="0"/>'
    if arm.inertia is None:
        # the cylinder's axis along the longest segment (one along x: z turned onto x about y)
        quat = "0.7071068 0 0.7071068 0" if abs(a) > abs(d) else "1 0 0 0"
        moments = _cylinder_inertia(arm.mass[i], max(longest, 0.05))
    else:  # the published tensor, axes of DH frame i: the body's turned by alpha about x
        quat = f"{np.cos(alpha / 2):.17g} {np.sin(alpha / 2):.17g} 0 0"
        moments = np.asarray(arm.inertia[i])
    inertial = f'<inertial pos="{_v(com)}" quat="{quat}" mass="{arm.mass[i]}" diaginertia="{_v(moments)}"/>'
    joint = f'<joint name="{JOINTS[i]}" axis="0 0 1" range="{-2 * np.pi} {2 * np.pi}" damping="0.1" armature="0.1"/>'
    return f"{joint}{inertial}{geoms}{child}"


def ur_chain(arm: UrArm, tool: str) -> str:
    """Link 0's body with links 1..5 nested (the body of link i + 1 sits at the DH frame i),
    `tool` in the last link's body (whose frame is DH frame 5 turned by q6: the flange is
    `Tz(d6)` in it)."""
    inner = _link(arm, 5, tool)
    for i in reversed(range(5)):
        d, a, alpha = arm.dh[i]
        pos = _dh(d, a, alpha)[:3, 3]
        inner = _link(arm, i, f'<body name="{LINKS[i + 1]}" pos="{_v(pos)}" euler="{alpha} 0 0" gravcomp="1">{inner}</body>')
    return f'<body name="{LINKS[0]}" gravcomp="1">{inner}</body>'


def ur_actuators(arm: UrArm) -> str:
    """Velocity actuators `v_<joint>` within the speed and effort limits."""
    return "".join(
        f'<velocity name="v_{j}" joint="{j}" kv="{kv}" ctrlrange="{-arm.speed!r} {arm.speed!r}" '
        f'forcerange="{-e} {e}" forcelimited="true"/>'
        for j, kv, e in zip(JOINTS, arm.kv, arm.effort)
    )


def _ur_mjcf(arm: UrArm, camera_fovy: float, physics_dt: float) -> str:
    d6 = arm.dh[5][0]
    tool = (f'<site name="flange" pos="0 0 {d6}" size="0.01"/>'
            f'<camera name="wrist" pos="0 0 {d6}" quat="0 1 0 0" fovy="{camera_fovy}"/>')
    return f"""<mujoco model="{arm.name}-vsinv">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{physics_dt}" gravity="0 0 -9.81" integrator="implicitfast"/>
  <worldbody>
    <light name="top" pos="0 0 3" dir="0 0 -1" directional="true" diffuse="0.6 0.6 0.6"/>
    <geom name="base" type="cylinder" size="0.075 0.02" pos="0 0 -0.02" rgba="0.25 0.45 0.7 1" contype="0" conaffinity="0"/>
    {ur_chain(arm, tool)}
  </worldbody>
  <actuator>{ur_actuators(arm)}</actuator>
</mujoco>"""


def ur5_mjcf(camera_fovy: float = 60.0, physics_dt: float = 0.002) -> str:
    """The MJCF text of the UR5 on the world's origin (its base frame), gravity on, the physics
    step `physics_dt` (500 Hz by default), a site `flange` (vsinv's `tool0`: the DH frame 6) and
    a camera `wrist` on it whose vsinv frame is the flange's (MuJoCo's camera turned by pi
    about x), velocity actuators `v_<joint>` on every joint."""
    return _ur_mjcf(UR5, camera_fovy, physics_dt)


def ur5e_mjcf(camera_fovy: float = 60.0, physics_dt: float = 0.002) -> str:
    """`ur5_mjcf` for the UR5e (robots/ur5e.urdf: `vsinv.kinematics.fk("ur5e", q)` is the site
    `flange`), with its published inertia tensors."""
    return _ur_mjcf(UR5E, camera_fovy, physics_dt)


def joint_velocities(model: Any, data: Any, site: str, twist: Any, damping: float = 0.02) -> np.ndarray:
    """Joint velocities (nv,) that move the site `site` by `twist` (6,: in the site's own frame,
    as a camera twist when the camera's vsinv frame is the site's): MuJoCo's Jacobian of the site
    (`mj_jacSite`, world frame) turned into the site's frame, then the kinematic arm's damped
    least squares (`vsinv.kinematics.damped_least_squares`)."""
    from ..kinematics import damped_least_squares

    return np.asarray(damped_least_squares(site_jacobian(model, data, site), np.asarray(twist, dtype=float), damping))


def site_jacobian(model: Any, data: Any, site: str) -> np.ndarray:
    """MuJoCo's Jacobian (6, nv) of `site` (`mj_jacSite`: world-frame rows), its rows turned into
    the site's frame: joint velocities to the site's twist (v, w) in its own frame."""
    import mujoco

    s = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, site)
    if s < 0:
        raise InvalidInput(f"site: no site named {site!r} in the model")
    jp, jr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
    mujoco.mj_kinematics(model, data)
    mujoco.mj_comPos(model, data)
    mujoco.mj_jacSite(model, data, jp, jr, s)
    R = data.site_xmat[s].reshape(3, 3)
    return np.vstack([R.T @ jp, R.T @ jr])
