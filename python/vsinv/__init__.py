"""vsinv: visual servoing invariant to the camera's intrinsic parameters.

An implementation of E. Malis, "Visual servoing invariant to changes in camera intrinsic
parameters", INRIA RR-4309 (2001), with a Rust core.

Conventions: SI units (metres, radians, seconds), pixels for image points given as (n, 2)
arrays of (u, v); the camera twist is (vx, vy, vz, wx, wy, wz) in the current camera frame;
poses are 4x4 homogeneous matrices of the camera frame in F*, the frame of the reference image.

One API per level: the session at the top (:class:`Servo` on pixels, :class:`ImageServo` on
images, :func:`replay` of recorded frames, :func:`run_scenario` of a simulated one), and below it
:mod:`vsinv.laws` (the controllers, invariants, stability), :mod:`vsinv.vision` (detectors,
trackers, rendering, images, distortion), :mod:`vsinv.sim` (scenarios, batches, sweeps),
:mod:`vsinv.calibration` (hand-eye, calibration files, reference depths),
:mod:`vsinv.kinematics` (the arms), :mod:`vsinv.geometry` (SE(3), projection) and
:mod:`vsinv.errors` (the exceptions and their tables). Each name
lives in one of them; the top level re-exports the few a session needs.
"""

import logging

from . import calibration, errors, geometry, kinematics, laws, sim, vision
from . import plots, sweep  # helpers of RunResult and vsinv.sim (importable, not the API's levels)
from ._core import ImageServo, ImageStep, Intrinsics, Servo, ServoStep, __version__
from .errors import DegenerateGeometry, InvalidInput, NotReady, VsinvError
from .replaying import ReplayResult, replay
from .sim import RunResult, load_scenario, run_scenario
from .vision import frames

# The package logs on the "vsinv" logger (run starts and ends at INFO, details at DEBUG);
# quiet until the application configures logging (the library convention of the logging HOWTO).
logging.getLogger("vsinv").addHandler(logging.NullHandler())

# The session level; everything else is in the submodules (each name in exactly one).
__all__ = [
    "__version__",
    # the session
    "Servo",
    "ServoStep",
    "ImageServo",
    "ImageStep",
    "Intrinsics",
    "replay",
    "ReplayResult",
    "frames",
    # the main job: a simulated session
    "run_scenario",
    "load_scenario",
    "RunResult",
    # the errors
    "VsinvError",
    "InvalidInput",
    "DegenerateGeometry",
    "NotReady",
    # the levels below
    "laws",
    "vision",
    "sim",
    "calibration",
    "kinematics",
    "geometry",
    "errors",
]
