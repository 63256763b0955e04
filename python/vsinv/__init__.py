"""vsinv: visual servoing invariant to the camera's intrinsic parameters.

An implementation of E. Malis, "Visual servoing invariant to changes in camera intrinsic
parameters", INRIA RR-4309 (2001), with a Rust core.

Conventions: SI units (metres, radians, seconds), pixels for image points given as (n, 2)
arrays of (u, v); the camera twist is (vx, vy, vz, wx, wy, wz) in the current camera frame;
poses are 4x4 homogeneous matrices of the camera frame in F*, the frame of the reference image.
"""

from ._core import (
    DegenerateGeometry,
    IbvsController,
    Intrinsics,
    InvariantPath,
    PlaneParallax,
    ResectionDepths,
    RunResult,
    Scenario,
    InvalidInput,
    InvariantController,
    StabilityReport,
    VsinvError,
    __version__,
    check_stability,
    choose_basis,
    depths_from_translation,
    estimate_plane_parallax,
    interaction_matrix,
    invariant_jacobian,
    invariant_points,
    jacobian_factors,
    list_scenarios,
    load_scenario,
    project,
    run_batch,
    run_scenario,
    rz_coefficients,
    structure_ratio,
    tracking_bound,
)
from . import sweep
from .sweep import Choice, LogUniform, SweepResult, Uniform, run_sweep

__all__ = [
    "DegenerateGeometry",
    "IbvsController",
    "Intrinsics",
    "InvariantPath",
    "PlaneParallax",
    "ResectionDepths",
    "RunResult",
    "Scenario",
    "InvalidInput",
    "InvariantController",
    "StabilityReport",
    "VsinvError",
    "__version__",
    "check_stability",
    "choose_basis",
    "depths_from_translation",
    "estimate_plane_parallax",
    "interaction_matrix",
    "invariant_jacobian",
    "invariant_points",
    "jacobian_factors",
    "list_scenarios",
    "load_scenario",
    "project",
    "run_batch",
    "run_scenario",
    "rz_coefficients",
    "structure_ratio",
    "tracking_bound",
    "run_sweep",
    "sweep",
    "Uniform",
    "LogUniform",
    "Choice",
    "SweepResult",
]
