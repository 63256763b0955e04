"""The Franka Emika Panda with mass for MuJoCo (issue 31, item 2): the kinematics of vsinv's
`robots/panda.urdf` (Franka's modified DH table, so the site `tcp` is
`vsinv.kinematics.fk("panda", q)` and `flange` is panda_link8), Franka's published limits, and
identified inertial parameters.

Kinematics: Franka Emika, "Robot and interface specifications" / control parameters
(modified DH: a_{i-1}, d_i, alpha_{i-1} below; flange 0.107 m along the last axis; the Franka
hand's TCP 0.1034 m further, turned by -pi/4 about z, as robots/panda.urdf: 0.103 m).
Limits (same source, the datasheet): joint positions below, speeds 2.175 rad/s (joints 1-4)
and 2.61 rad/s (5-7), torques 87 N m (1-4) and 12 N m (5-7).
Masses, centres of mass and inertia tensors (about the centre of mass, in the link's DH frame):
C. Gaz, M. Cognetti, A. Oliva, P. Robuffo Giordano, A. De Luca, "Dynamic identification of the
Franka Emika Panda robot with retrieval of feasible parameters using penalty-based
optimization", IEEE RA-L 4(4), 2019 (the values Franka's own description carries).
Geometry: capsules along the DH segments, seen by the camera, not colliding (contype 0); each
body compensates its own weight (`gravcomp`, as the arm's controller does); each joint is
driven by a velocity actuator (gain `kv`, torque within the effort limit).
"""

from __future__ import annotations

import numpy as np

# Modified DH (a_{i-1}, d_i, alpha_{i-1}) of joints 1..7, as robots/panda.urdf.
PANDA_MDH = ((0.0, 0.333, 0.0), (0.0, 0.0, -np.pi / 2), (0.0, 0.316, np.pi / 2), (0.0825, 0.0, np.pi / 2),
             (-0.0825, 0.384, -np.pi / 2), (0.0, 0.0, np.pi / 2), (0.088, 0.0, np.pi / 2))
PANDA_FLANGE = 0.107  # m along z of link 7: panda_link8
PANDA_TCP = (0.103, -np.pi / 4)  # panda_hand_tcp in panda_link8: along z (m), about z (rad)
PANDA_LOWER = (-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973)  # rad
PANDA_UPPER = (2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973)  # rad
PANDA_SPEED = (2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61)  # rad/s
PANDA_EFFORT = (87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0)  # N m
PANDA_KV = (400.0, 400.0, 300.0, 300.0, 60.0, 60.0, 40.0)  # N m s / rad
# Gaz et al. 2019: mass (kg), centre of mass (m), inertia (ixx, ixy, ixz, iyy, iyz, izz; kg m^2).
PANDA_MASS = (4.970684, 0.646926, 3.228604, 3.587895, 1.225946, 1.666555, 0.735522)
PANDA_COM = ((3.875e-3, 2.081e-3, -4.762e-2), (-3.141e-3, -2.872e-2, 3.495e-3), (2.7518e-2, 3.9252e-2, -6.6502e-2),
             (-5.317e-2, 1.04419e-1, 2.7454e-2), (-1.1953e-2, 4.1065e-2, -3.8437e-2),
             (6.0149e-2, -1.4117e-2, -1.0517e-2), (1.0517e-2, -4.252e-3, 6.1597e-2))
PANDA_INERTIA = ((7.0337e-1, -1.39e-4, 6.772e-3, 7.0661e-1, 1.9169e-2, 9.117e-3),
                 (7.962e-3, -3.925e-3, 1.0254e-2, 2.811e-2, 7.04e-4, 2.5995e-2),
                 (3.7242e-2, -4.761e-3, -1.1396e-2, 3.6155e-2, -1.2805e-2, 1.083e-2),
                 (2.5853e-2, 7.796e-3, -1.332e-3, 1.9552e-2, 8.641e-3, 2.8323e-2),
                 (3.5549e-2, -2.117e-3, -4.037e-3, 2.9474e-2, 2.29e-4, 8.627e-3),
                 (1.964e-3, 1.09e-4, -1.158e-3, 4.354e-3, 3.41e-4, 5.433e-3),
                 (1.2516e-2, -4.28e-4, -1.196e-3, 1.0027e-2, -7.41e-4, 4.815e-3))
PANDA_JOINTS = tuple(f"panda_joint{i}" for i in range(1, 8))


def _v(x: object) -> str:
    """Numbers as MJCF text, to the last bit (repr round-trips)."""
    return " ".join(repr(float(t)) for t in np.ravel(np.asarray(x, dtype=float)))


def _child_position(i: int) -> np.ndarray:
    """Where joint i + 1 is in link i's frame: Rx(alpha_i) Tx(a_i) Tz(d_{i+1}) applied to 0."""
    a, d, alpha = PANDA_MDH[i + 1]
    return np.array([a, -np.sin(alpha) * d, np.cos(alpha) * d])


def _geoms(segments: list[tuple[np.ndarray, np.ndarray]], radius: float) -> str:
    grey = 'rgba="0.92 0.92 0.9 1" mass="0" contype="0" conaffinity="0"'
    out = "".join(f'<geom type="capsule" fromto="{_v(p)} {_v(q)}" size="{radius}" {grey}/>'
                  for p, q in segments if np.linalg.norm(q - p) > 1e-9)
    return out + f'<geom type="cylinder" size="{radius * 1.1} {radius}" rgba="0.2 0.2 0.22 1" mass="0" contype="0" conaffinity="0"/>'


def _link(i: int, inner: str) -> str:
    """Body of link i + 1 (joint i + 1 turns it) placed by the modified DH row i, holding `inner`."""
    a, d, alpha = PANDA_MDH[i]
    pos = np.array([a, -np.sin(alpha) * d, np.cos(alpha) * d])
    ixx, ixy, ixz, iyy, iyz, izz = PANDA_INERTIA[i]
    inertial = f'<inertial pos="{_v(PANDA_COM[i])}" mass="{PANDA_MASS[i]!r}" fullinertia="{_v([ixx, iyy, izz, ixy, ixz, iyz])}"/>'
    joint = (f'<joint name="{PANDA_JOINTS[i]}" axis="0 0 1" range="{PANDA_LOWER[i]!r} {PANDA_UPPER[i]!r}" '
             'damping="0.1" armature="0.1"/>')
    end = _child_position(i) if i < 6 else np.array([0.0, 0.0, PANDA_FLANGE])
    a_next = PANDA_MDH[i + 1][0] if i < 6 else 0.0
    corner = np.array([a_next, 0.0, 0.0])
    geoms = _geoms([(np.zeros(3), corner), (corner, end)], 0.06 if i < 4 else 0.045)
    return (f'<body name="panda_link{i + 1}" pos="{_v(pos)}" euler="{alpha!r} 0 0" gravcomp="1">'
            f"{joint}{inertial}{geoms}{inner}</body>")


def panda_chain(tool: str) -> str:
    """The bodies panda_link1..7 nested, `tool` in panda_link7's body (the flange panda_link8
    is `Tz(0.107)` in it)."""
    inner = tool
    for i in reversed(range(7)):
        inner = _link(i, inner)
    return inner


def panda_actuators() -> str:
    """Velocity actuators `v_<joint>` within the speed and torque limits."""
    return "".join(
        f'<velocity name="v_{j}" joint="{j}" kv="{kv}" ctrlrange="{-s} {s}" forcerange="{-e} {e}" forcelimited="true"/>'
        for j, kv, s, e in zip(PANDA_JOINTS, PANDA_KV, PANDA_SPEED, PANDA_EFFORT)
    )


def panda_mjcf(camera_fovy: float = 60.0, physics_dt: float = 0.002) -> str:
    """The MJCF text of the Panda on the world's origin (its base frame, panda_link0), gravity
    on, the physics step `physics_dt` (500 Hz by default), sites `flange` (panda_link8) and `tcp`
    (panda_hand_tcp: `vsinv.kinematics.fk("panda", q)`), a camera `wrist` at the TCP whose vsinv
    frame is the TCP's (MuJoCo's camera turned by pi about x), velocity actuators `v_<joint>`."""
    depth, turn = PANDA_TCP
    tcp_quat = _v([np.cos(turn / 2), 0.0, 0.0, np.sin(turn / 2)])
    # The camera: the TCP's frame turned by pi about x, q_tcp * (0, 1, 0, 0).
    cam_quat = _v([0.0, np.cos(turn / 2), np.sin(turn / 2), 0.0])
    z = PANDA_FLANGE + depth
    tool = (f'<site name="flange" pos="0 0 {PANDA_FLANGE!r}" size="0.01"/>'
            f'<site name="tcp" pos="0 0 {z!r}" quat="{tcp_quat}" size="0.01"/>'
            f'<camera name="wrist" pos="0 0 {z!r}" quat="{cam_quat}" fovy="{camera_fovy}"/>')
    inner = panda_chain(tool)
    actuators = panda_actuators()
    return f"""<mujoco model="panda-vsinv">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{physics_dt}" gravity="0 0 -9.81" integrator="implicitfast"/>
  <worldbody>
    <light name="top" pos="0 0 3" dir="0 0 -1" directional="true" diffuse="0.6 0.6 0.6"/>
    <geom name="base" type="cylinder" size="0.08 0.02" pos="0 0 -0.02" rgba="0.2 0.2 0.22 1" contype="0" conaffinity="0"/>
    {inner}
  </worldbody>
  <actuator>{actuators}</actuator>
</mujoco>"""
