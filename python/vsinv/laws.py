"""The control laws, one level below the session (:class:`vsinv.Servo`): the invariant law of
sec. 4 (eqs. (14), (17), (24)) and classic IBVS as controllers stepped with
``step(pixels, depths, visible=None)``, the invariant points and Jacobians they are built on,
the stability checks (Prop. 1, 2, 3), the reference path s*(t), the pose uncertainty, and the
laws' options (``LAW_OPTIONS``, the one declaration read by :class:`vsinv.Servo`, the scenario
schema, the CLI and the ROS parameters)."""

from ._core import (
    LAW_OPTIONS,
    IbvsController,
    InvariantController,
    InvariantPath,
    PoseUncertainty,
    StabilityReport,
    check_law_option,
    check_stability,
    choose_basis,
    interaction_matrix,
    invariant_jacobian,
    invariant_points,
    jacobian_factors,
    law_options_markdown,
    rz_coefficients,
    structure_ratio,
    tracking_bound,
)

__all__ = [
    "LAW_OPTIONS",
    "IbvsController",
    "InvariantController",
    "InvariantPath",
    "PoseUncertainty",
    "StabilityReport",
    "check_law_option",
    "check_stability",
    "choose_basis",
    "interaction_matrix",
    "invariant_jacobian",
    "invariant_points",
    "jacobian_factors",
    "law_options_markdown",
    "rz_coefficients",
    "structure_ratio",
    "tracking_bound",
]
