"""SE(3) and the pinhole: the exponential of a twist, theta-u rotations, the twist adjoint of a
rigid mount, and the projection of points to pixels."""

from ._core import (
    exp_twist,
    pose_from_position_thetau,
    project,
    thetau_from_pose,
    thetau_from_rotations,
    twist_adjoint,
)

__all__ = [
    "exp_twist",
    "pose_from_position_thetau",
    "project",
    "thetau_from_pose",
    "thetau_from_rotations",
    "twist_adjoint",
]
