"""The simulated arms' kinematics: forward kinematics, damped least-squares inverse
kinematics, and the arm's damped least squares from a twist to joint velocities."""

from ._core import IkSolution, damped_least_squares, fk, ik

__all__ = ["IkSolution", "damped_least_squares", "fk", "ik"]
