"""Arms with mass for MuJoCo (issue 31, item 2): the UR5 of vsinv's `robots/ur5.urdf` (the same
standard DH kinematics, so `vsinv.kinematics.fk("ur5", q)` is the flange's pose in the base
frame) with Universal Robots' published masses and centres of mass, capsule geometry the camera
can see, joint limits, and velocity actuators limited to the published speed and effort limits.

Masses and centres of mass: Universal Robots, "DH parameters for calculations of kinematics and
dynamics" (UR5: m = 3.7, 8.393, 2.33, 1.219, 1.219, 0.1879 kg; centres of mass in the DH frames
below). UR publishes no inertia tensors for the UR5: each link's is that of a uniform solid
cylinder of its mass along its longest segment (radius 0.05 m), at its centre of mass.
The bodies compensate their own weight (MuJoCo's `gravcomp`, as the arm's controller does) and
each joint is driven by a velocity actuator (gain `kv`, torque within the effort limit). The
geometry is seen (it can occlude a target) but does not collide (contype 0).
"""

from __future__ import annotations

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
JOINTS = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint")
LINKS = ("shoulder_link", "upper_arm_link", "forearm_link", "wrist_1_link", "wrist_2_link", "wrist_3_link")


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


def _link(i: int, child: str) -> str:
    """The content of link i's body: joint i, its inertia and geometry, and `child` (the body of
    link i + 1, or the flange's site and camera)."""
    d, a, alpha = UR5_DH[i]
    frame = _dh(d, a, alpha)  # DH frame i in the body's frame: where the next joint is
    com = (frame @ np.append(UR5_COM[i], 1.0))[:3]
    segments = [(np.zeros(3), np.array([0.0, 0.0, d])), (np.array([0.0, 0.0, d]), frame[:3, 3])]
    longest = max(float(np.linalg.norm(q - p)) for p, q in segments)
    radius = 0.045 if i < 3 else 0.035
    geoms = "".join(
        f'<geom type="capsule" fromto="{_v(p)} {_v(q)}" size="{radius}" rgba="0.6 0.63 0.68 1" mass="0" contype="0" conaffinity="0"/>'
        for p, q in segments if np.linalg.norm(q - p) > 1e-9
    )
    geoms += f'<geom type="cylinder" size="{radius * 1.1} {radius}" rgba="0.25 0.45 0.7 1" mass="0" contype="0" conaffinity="0"/>'
    # the cylinder's axis along the longest segment (one along x: z turned onto x about y)
    quat = "0.7071068 0 0.7071068 0" if abs(a) > abs(d) else "1 0 0 0"
    inertial = (f'<inertial pos="{_v(com)}" quat="{quat}" mass="{UR5_MASS[i]}" '
                f'diaginertia="{_v(_cylinder_inertia(UR5_MASS[i], max(longest, 0.05)))}"/>')
    joint = f'<joint name="{JOINTS[i]}" axis="0 0 1" range="{-2 * np.pi} {2 * np.pi}" damping="0.1" armature="0.1"/>'
    return f"{joint}{inertial}{geoms}{child}"


def _chain(tool: str) -> str:
    """Link 0's body with links 1..5 nested: the body of link i + 1 sits at the DH frame i."""
    inner = _link(5, tool)
    for i in reversed(range(5)):
        d, a, alpha = UR5_DH[i]
        pos = _dh(d, a, alpha)[:3, 3]
        inner = _link(i, f'<body name="{LINKS[i + 1]}" pos="{_v(pos)}" euler="{alpha} 0 0" gravcomp="1">{inner}</body>')
    return f'<body name="{LINKS[0]}" gravcomp="1">{inner}</body>'


def ur5_mjcf(camera_fovy: float = 60.0, physics_dt: float = 0.002) -> str:
    """The MJCF text of the UR5 on the world's origin (its base frame), gravity on, the physics
    step `physics_dt` (500 Hz by default), a site `flange` (vsinv's `tool0`: the DH frame 6) and
    a camera `wrist` on it whose vsinv frame is the flange's (MuJoCo's camera turned by pi
    about x), velocity actuators `v_<joint>` on every joint."""
    d6 = UR5_DH[5][0]
    tool = (f'<site name="flange" pos="0 0 {d6}" size="0.01"/>'
            f'<camera name="wrist" pos="0 0 {d6}" quat="0 1 0 0" fovy="{camera_fovy}"/>')
    actuators = "".join(
        f'<velocity name="v_{j}" joint="{j}" kv="{kv}" ctrlrange="{-UR5_SPEED} {UR5_SPEED}" '
        f'forcerange="{-e} {e}" forcelimited="true"/>'
        for j, kv, e in zip(JOINTS, UR5_KV, UR5_EFFORT)
    )
    return f"""<mujoco model="ur5-vsinv">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{physics_dt}" gravity="0 0 -9.81" integrator="implicitfast"/>
  <worldbody>
    <light name="top" pos="0 0 3" dir="0 0 -1" directional="true" diffuse="0.6 0.6 0.6"/>
    <geom name="base" type="cylinder" size="0.075 0.02" pos="0 0 -0.02" rgba="0.25 0.45 0.7 1" contype="0" conaffinity="0"/>
    {_chain(tool)}
  </worldbody>
  <actuator>{actuators}</actuator>
</mujoco>"""


def joint_velocities(model: Any, data: Any, site: str, twist: Any, damping: float = 0.02) -> np.ndarray:
    """Joint velocities (nv,) that move the site `site` by `twist` (6,: in the site's own frame,
    as a camera twist when the camera's vsinv frame is the site's): MuJoCo's Jacobian of the site
    (`mj_jacSite`, world frame) turned into the site's frame, then the kinematic arm's damped
    least squares (`vsinv.kinematics.damped_least_squares`)."""
    import mujoco

    from ..kinematics import damped_least_squares

    s = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, site)
    if s < 0:
        raise InvalidInput(f"site: no site named {site!r} in the model")
    jp, jr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
    mujoco.mj_kinematics(model, data)
    mujoco.mj_comPos(model, data)
    mujoco.mj_jacSite(model, data, jp, jr, s)
    R = data.site_xmat[s].reshape(3, 3)
    return np.asarray(damped_least_squares(np.vstack([R.T @ jp, R.T @ jr]), np.asarray(twist, dtype=float), damping))
