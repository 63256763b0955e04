"""MuJoCo worlds for vsinv (the optional extra ``mujoco``: ``pip install 'vsinv[mujoco]'``).

:class:`World` puts a scenario's target and camera into a MuJoCo scene (or opens a user's MJCF
file) and renders grey images in vsinv's conventions; :func:`run` closes the loop of a scenario
through those images with :class:`vsinv.ImageServo` and returns a :class:`vsinv.RunResult`
(``vsinv.run_scenario`` calls it for ``[world] engine = "mujoco"``; with a built-in arm in
``[robot]`` the camera rides the arm, with mass, gravity and 500 Hz physics); :func:`ur5_mjcf`,
:func:`ur5e_mjcf` and :func:`panda_mjcf` are a UR5, a UR5e and a Panda with mass (vsinv's
kinematics, the makers' published masses, capsules, velocity actuators);
:func:`calibrate_eye_to_hand` calibrates an eye-to-hand world's fixed camera against its arm
from rendered stations, and :func:`with_camera_to_base` gives a scenario that transform. vsinv imports it only to run a ``[world] engine = "mujoco"`` scenario.
MuJoCo renders offscreen through EGL (``MUJOCO_GL=egl`` is set unless already set: import
``vsinv.mujoco`` before ``mujoco``, which reads it once, or set it yourself).
"""

from ._arms import joint_velocities, ur5_mjcf, ur5e_mjcf
from ._calibrate import HandEyeStations, calibrate_eye_to_hand, with_camera_to_base
from ._camera import FLIP, k_of_fovy, k_of_intrinsics
from ._loop import MujocoRun, run, run_loop
from ._panda import panda_mjcf
from ._views import Views
from ._world import MAX_MJCF_BYTES, MAX_RENDER_SIDE, MAX_SUPERSAMPLE, World, available

__all__ = [
    "FLIP",
    "HandEyeStations",
    "MAX_MJCF_BYTES",
    "MAX_RENDER_SIDE", "MAX_SUPERSAMPLE", "MujocoRun", "Views", "World", "available", "calibrate_eye_to_hand", "k_of_fovy", "k_of_intrinsics", "joint_velocities",
    "panda_mjcf", "run", "run_loop", "ur5_mjcf", "ur5e_mjcf", "with_camera_to_base",
]
