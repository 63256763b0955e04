"""The simulated arms' kinematics: forward kinematics and damped least-squares inverse
kinematics."""

from ._core import IkSolution, fk, ik

__all__ = ["IkSolution", "fk", "ik"]
