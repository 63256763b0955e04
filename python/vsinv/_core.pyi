"""The compiled core of vsinv (Rust, PyO3). Its names are imported from the package's levels,
which re-export them: `vsinv`, `vsinv.laws`, `vsinv.vision`, `vsinv.sim`,
`vsinv.calibration`, `vsinv.kinematics`, `vsinv.geometry` and `vsinv.errors`."""

import array
import os
from typing import Any, Callable, Iterable, Literal, Sequence, TypedDict, Union, final

import numpy as np
import numpy.typing as npt
from typing_extensions import disjoint_base

#: The AprilTag families `detect_tags`, `TagTracker` and `ImageServo` read (Rust `TagFamily::NAMES`).
#: `TAG_FAMILIES` at run time (a test checks that the two agree).
_TagFamily = Literal[
    "tag36h11",
    "tag36h10",
    "tag25h9",
    "tag16h5",
    "tagStandard41h12",
    "tagStandard52h13",
    "tagCircle21h7",
    "tagCircle49h12",
    "tagCustom48h12",
]

#: The names of the AprilTag families every tag argument and scenario key accepts (Rust `TagFamily::NAMES`).
TAG_FAMILIES: tuple[str, ...]

#: The derived keys of a sweep, in the order they are applied (Rust `sim::sweep::DERIVED_KEYS`).
SWEEP_DERIVED_KEYS: tuple[str, ...]

#: The laws' options, declared once in the servo layer (Rust `servo::law::options::LAW_OPTIONS`):
#: name (the keyword of `Servo`, `ImageServo` and the controllers, the ROS parameter, the `vsinv
#: replay` flag), the laws that read it, kind, choices, default (None: unset), range, unit,
#: scenario key and unit, meaning. A test checks that the signatures below declare every one.
#: Keys: name, laws, kind ("number", "flag", "choice", "adaptive_gain"), choices, default, min,
#: max, min_open, max_open, range, unit, scenario_key, scenario_unit, doc.
LAW_OPTIONS: tuple[dict[str, Any], ...]

def check_law_option(name: str, value: object) -> None:
    """Checks a value of the law option `name` as `Servo` would: `InvalidInput` naming the option (or its part,
    `adaptive_gain.at_infinity`) for a value of another kind or out of its range."""

def law_options_markdown() -> str:
    """The table of the laws' options as Markdown (name, laws, values, default, unit, scenario
    key, meaning), for the reference pages of the docs."""

#: The targets, declared once in the vision layer (Rust `vision::targets::TARGETS`): name (the
#: `target` of `ImageServo`, `--target`, the ROS parameter `target`), meaning, the detector that
#: finds it (name, module, doc), its keyword arguments of `ImageServo` (another target's are
#: refused by name) and the scenario keys it reads. A test checks that `ImageServo` below declares
#: every name and argument. Keys: name, doc, detector, args (each: name, kind ("points", "choice",
#: "ids", "count", "tracker"), choices, min, max, default, required, doc), scenario_keys.
TARGETS: tuple[dict[str, Any], ...]

#: The dot tracker's settings, declared once in the vision layer (Rust
#: `vision::tracker::TRACKER_SETTINGS`): the keys of the dots' `tracker` argument of `ImageServo`,
#: the ROS parameters `tracker.*`, the command options `--search-radius`... Keys: name, kind
#: ("number", "count", "choice"), default, min, min_open, choices, unit, doc.
TRACKER_SETTINGS: tuple[dict[str, Any], ...]

#: The exception classes, declared once (Rust `src/python/errors.rs`, `CLASSES`): name, parent
#: (None: the root), builtin (the Python exception it also derives from), doc. A test checks the
#: classes below against it.
ERROR_CLASSES: tuple[dict[str, Any], ...]
#: Every `kind` an exception carries: kind, class (raised with it), doc.
ERROR_KINDS: tuple[dict[str, str], ...]
#: Every attribute of `VsinvError`: name, type, doc.
ERROR_ATTRIBUTES: tuple[dict[str, str], ...]

__version__: str
__all__ = [
    "ImageServo",
    "ImageStep",
    "VsinvError",
    "InvalidInput",
    "DegenerateGeometry",
    "NotReady",
    "Intrinsics",
    "InvariantController",
    "IbvsController",
    "Servo",
    "ServoStep",
    "StabilityReport",
    "PoseUncertainty",
    "PixelNoiseMeter",
    "project",
    "invariant_points",
    "invariant_jacobian",
    "structure_ratio",
    "interaction_matrix",
    "jacobian_factors",
    "rz_coefficients",
    "choose_basis",
    "check_stability",
    "tracking_bound",
    "Scenario",
    "ScenarioArm",
    "RunResult",
    "recorded_columns",
    "summary_fields",
    "load_scenario",
    "list_scenarios",
    "run_scenario",
    "run_batch",
    "SWEEP_DERIVED_KEYS",
    "sweep_scenarios",
    "run_sweep_runs",
    "PlaneParallax",
    "InvariantPath",
    "ResectionDepths",
    "estimate_plane_parallax",
    "depths_from_translation",
    "reference_depths",
    "render",
    "render_faces",
    "render_view",
    "degrade",
    "Dots",
    "detect_dots",
    "match_features",
    "track_points",
    "DotTracker",
    "Tags",
    "TagTracker",
    "TAG_FAMILIES",
    "detect_tags",
    "load_image",
    "decode_image",
    "save_image",
    "to_grey",
    "Distortion",
    "Calibration",
    "distort_points",
    "undistort_points",
    "distort_rays",
    "undistort_rays",
    "load_calibration",
    "exp_twist",
    "pose_from_position_thetau",
    "thetau_from_pose",
    "thetau_from_rotations",
    "twist_adjoint",
    "IkSolution",
    "fk",
    "ik",
    "damped_least_squares",
    "HandEyeCalibration",
    "HandEyeAgreement",
    "calibrate_hand_eye",
    "compare_hand_eye_methods",
    "LAW_OPTIONS",
    "check_law_option",
    "law_options_markdown",
    "TARGETS",
    "TRACKER_SETTINGS",
    "ERROR_CLASSES",
    "ERROR_KINDS",
    "ERROR_ATTRIBUTES",
    "__version__",
]

_ArrayLike = npt.ArrayLike
#: The names of ``TARGETS`` (a test checks they are the same).
_TargetName = Literal["dots", "tags", "features"]
_F64Array = npt.NDArray[np.float64]
_Basis = Union[tuple[int, int, int], Sequence[int], Literal["auto"]]

class VsinvError(Exception):
    """Base class of every vsinv error.

    The structured fields of the error are attributes, None where they do not apply (and on exceptions raised by Python code); match on them rather than on the message."""
    kind: str | None
    """The kind of error, one of ERROR_KINDS: 'non_finite', 'non_finite_point', 'shape', 'invalid_intrinsics', 'invalid_parameter', 'invalid_argument', 'too_few_points', 'collinear_basis', 'point_behind_camera', 'degenerate_structure', 'degenerate_estimate', 'scenario', 'invalid_image', 'urdf', 'distortion', 'calibration', 'rz_singular', 'unreachable', 'invalid_pose', 'degenerate_motion', 'not_ready'."""
    argument: str | None
    """The argument or parameter at fault ('pixels', 'gain', ...; an image's file path)."""
    index: int | None
    """The flat index of a non-finite value, or the point (or pose) at fault."""
    row: int | None
    """The row (point) of a non-finite entry of a 2-d array."""
    column: int | None
    """The column (coordinate) of a non-finite entry of a 2-d array."""
    expected: str | None
    """The size expected, in words ('12 points', 'shape (n, 2)')."""
    got: str | None
    """The size given."""
    needed: int | None
    """The fewest points the task takes."""
    count: int | None
    """The number of points (or poses) given."""
    reason: str | None
    """What is wrong."""
    basis: tuple[int, int, int] | None
    """The basis indices of a collinear basis."""
    image: str | None
    """'current' or 'reference': the image of a collinear basis."""
    ratio: float | None
    """The singular-value or area ratio that failed."""
    threshold: float | None
    """The threshold the ratio was held to."""
    depth: float | None
    """The depth of a point at or behind the camera."""
    estimate: str | None
    """What was being estimated (a degenerate estimate)."""
    hint: str | None
    """What usually causes a degenerate estimate."""
    key: str | None
    """The dotted scenario key at fault ('control.gain'); None for the whole document."""
    location: tuple[str | int, ...] | None
    """Where the error is, as data: keys and indices from the input's root, as the message names it (('control', 'gain'), ('pixels', 4, 1), ('object', 'points', 2); () for a whole scenario)."""
    file: str | None
    """The file at fault (a scenario, calibration or URDF file)."""
    field: str | None
    """The entry of a calibration file at fault ('camera_matrix.data')."""
    a_hat: float | None
    """The vanishing coefficient of the rz law (eq. 23)."""
    residual: float | None
    """The smallest position residual (m) inverse kinematics reached for an unreachable pose."""

class InvalidInput(VsinvError, ValueError):
    """Malformed input: NaN or infinity, wrong shape or dtype, invalid intrinsics or parameters, a bad scenario, image, URDF or calibration file."""

class DegenerateGeometry(VsinvError, ValueError):
    """Geometry the method cannot work with: collinear basis points, too few points, a planar object or equal depth estimates, points at or behind the camera, robot motions that do not determine a hand-eye calibration."""

class NotReady(VsinvError, RuntimeError):
    """A state read before it exists, e.g. a controller's eps before its first step (kind 'not_ready')."""

@final
class Intrinsics:
    """Intrinsic parameters of eq. (4): `Intrinsics(fku, fkv, u0, v0, skew=pi/2)`, pixels and
    radians. `skew` is the angle theta between the image axes."""

    def __new__(cls, fku: float, fkv: float, u0: float, v0: float, skew: float = ...) -> Intrinsics: ...
    @staticmethod
    def from_matrix(k: _ArrayLike) -> Intrinsics:
        """From a 3x3 upper-triangular matrix K with K[2] = (0, 0, 1)."""
    @property
    def fku(self) -> float:
        """f ku, the horizontal focal length in pixels."""
    @property
    def fkv(self) -> float:
        """f kv, the vertical focal length in pixels."""
    @property
    def u0(self) -> float:
        """u0, the principal point's column in pixels."""
    @property
    def v0(self) -> float:
        """v0, the principal point's row in pixels."""
    @property
    def skew(self) -> float:
        """theta, the angle between the image axes in radians (pi/2: no skew)."""
    @property
    def matrix(self) -> _F64Array:
        """K, a new (3, 3) array."""
    def __eq__(self, other: object, /) -> bool: ...
    def __reduce__(self) -> tuple[type[Intrinsics], tuple[float, float, float, float, float]]:
        """Pickling: the five parameters, restored exactly."""

_IntrinsicsLike = Union[Intrinsics, _ArrayLike]

def project(points: _ArrayLike, K: _IntrinsicsLike) -> tuple[_F64Array, _F64Array]:
    """Projects points (n, 3) given in the camera frame (metres) with intrinsics `K` (eqs. 1-3): returns (pixels (n,
    2), depths (n,))."""

def invariant_points(pixels: _ArrayLike, basis: _Basis = (0, 1, 2)) -> _F64Array:
    """The invariant points q_k = Q^-1 p_k of all n points (sec. 2.3), an (n, 3) array; Q is built from the three
    `basis` points, so q does not depend on the intrinsics."""

def invariant_jacobian(pixels: _ArrayLike, depths: _ArrayLike, K: _IntrinsicsLike, basis: _Basis = (0, 1, 2)) -> _F64Array:
    """The invariant Jacobian J (3(n-3), 5) of sec. 4.1 at the given pixels and depths: the motion of the non-basis
    invariant points per unit of (vx, vy, vz, wx, wy)."""

def structure_ratio(pixels: _ArrayLike, depths: _ArrayLike, K: _IntrinsicsLike, basis: _Basis = (0, 1, 2)) -> float:
    """sigma_5/sigma_1 of the depth-balanced invariant Jacobian: near 0 for a degenerate structure (a planar object,
    equal depths), where the law cannot tell motions apart."""

def interaction_matrix(pixels: _ArrayLike, depths: _ArrayLike, K: _IntrinsicsLike) -> _F64Array:
    """Pixel interaction matrices (n, 2, 6) of the points: dp_k/dt = L_k (v, w) (Espiau et al.)."""

def jacobian_factors(pixels: _ArrayLike, depths: _ArrayLike, basis: _Basis = (0, 1, 2)) -> tuple[_F64Array, _F64Array]:
    """The factors (Phi (3(n-3), 3), Psi (3(n-3), 2)) of sec. 4.1, with J = [Phi K, Psi F(K)]."""

def rz_coefficients(
    pixels: _ArrayLike, depths: _ArrayLike, reference_pixels: _ArrayLike, K: _IntrinsicsLike, basis: _Basis = (0, 1, 2)
) -> tuple[float, _F64Array]:
    """The coefficients (a, c (5,)) of eq. (23): d eps_z/dt = a w_z + c . (vx, vy, vz, wx, wy)."""

def choose_basis(pixels: _ArrayLike) -> tuple[int, int, int]:
    """Three points well spread in the image (the widest triangle; among equal areas the first
    (i, j, k) in index order), sorted. O(n log n); refuses (InvalidInput, `pixels`) point sets
    with more than 10,000 convex-hull vertices. Runs without the GIL."""


@final
class InvariantController:
    """The invariant visual-servoing law (sec. 4): eqs. (14), (17) and (24). Pickles with its
    configuration, K_hat and s*(t); a copy's next twist is the original's, but the state of
    the last step (eps, tau_11, ...) is not kept."""

    def __new__(
        cls,
        reference_pixels: _ArrayLike,
        K_hat: _IntrinsicsLike,
        gain: float = 1.0,
        gain_rz: float = 1.0,
        basis: _Basis = "auto",
        feedforward: bool = True,
        min_structure_ratio: float = 0.001,
        rz_task: Literal["angle", "tau21"] = "angle",
        adaptive_gain: tuple[float, float, float] | None = None,
        max_linear_speed: float | None = None,
        max_angular_speed: float | None = None,
    ) -> InvariantController: ...
    def step(self, pixels: _ArrayLike, depths: _ArrayLike, visible: npt.ArrayLike | None = None) -> _F64Array:
        """One control step from the current pixels (n, 2) and depth estimates (n,): the twist
        (vx, vy, vz, wx, wy, wz) in the camera frame, m/s and rad/s. `visible`, a bool array
        (n,) (None: all), hides points: their pixels and depths are ignored (may be NaN) and
        drop out of s and J_hat; the three basis points and three more must be visible (else
        DegenerateGeometry)."""
    def set_k_hat(self, K_hat: _IntrinsicsLike) -> None:
        """Replaces the estimated intrinsics K_hat (an Intrinsics or a 3x3 matrix), e.g. a zoom
        read-out during the servo; the next step uses them."""
    def set_reference(self, s_star: _ArrayLike, rate: _ArrayLike | None = None) -> None:
        """Sets a time-varying reference s*(t) ((n-3, 3) invariant points) and optionally its
        derivative ds*/dt (same shape) for the feed-forward term of eq. (17)."""
    def converged(self, invariant_tol: float = 1e-4, tau21_tol: float = 1e-4) -> bool:
        """Stop rule for different cameras: ||s - s*|| < invariant_tol, |tau_21| < tau21_tol,
        tau_11 > 0 and tau_22 > 0 (the last two exclude the rz = pi equilibrium)."""
    def pose_uncertainty(
        self,
        pixels: _ArrayLike,
        depths: _ArrayLike,
        pixel_sigma: float,
        reference_sigma: float | None = None,
        averaged_images: int = 1,
        visible: npt.ArrayLike | None = None,
    ) -> PoseUncertainty:
        """The pose uncertainty that pixel noise of `pixel_sigma` pixels (per coordinate; the
        reference image's `reference_sigma`, default the same) leaves at `pixels` (n, 2) with
        `depths` (n,), under the invariant stop rule (s and tau_21) with this controller's
        reference image, basis and K_hat; `averaged_images` current images were averaged.
        First order; the translation is in the depths' scale and K_hat is taken as right."""
    def __reduce__(self) -> tuple[type[InvariantController], tuple[Any, ...], tuple[_F64Array, _F64Array | None]]:
        """Pickling: the constructor's arguments (reference pixels, K_hat, gains, basis,
        feed-forward, min_structure_ratio, rz_task, adaptive gain, speed limits) and the
        reference s*(t) with its rate as set by `set_reference`. The next twist of the copy is
        that of the original; the state of the last step (eps, tau_11, ...) is not kept."""
    def __setstate__(self, state: tuple[_ArrayLike, _ArrayLike | None]) -> None:
        """Unpickling: restores the reference s*(t) and its rate, `(s_star, rate or None)`."""
    @property
    def k_hat(self) -> Intrinsics:
        """The estimated intrinsics K_hat used in the Jacobian."""
    @property
    def basis(self) -> tuple[int, int, int]:
        """The basis indices."""
    @property
    def reference_invariants(self) -> _F64Array:
        """The reference s*(t): (n-3, 3) invariant points of the non-basis points."""
    @property
    def eps(self) -> _F64Array:
        """Task function eps of eq. (14) at the last step, (5,)."""
    @property
    def eps_z(self) -> float:
        """eps_z = det(Q*) tau_21 at the last step."""
    @property
    def invariant_error(self) -> float:
        """||s - s*|| at the last step."""
    @property
    def tau_11(self) -> float:
        """tau_11 of T = Q Q*^-1 at the last step."""
    @property
    def tau_21(self) -> float:
        """tau_21 of T at the last step."""
    @property
    def tau_22(self) -> float:
        """tau_22 of T at the last step."""
    @property
    def t_matrix(self) -> _F64Array:
        """T = Q Q*^-1 (eq. 21) at the last step, (3, 3)."""
    @property
    def last_gain(self) -> float:
        """The lambda used at the last step (`gain`, or the adaptive gain at the invariant error)."""
    @property
    def saturation(self) -> float:
        """The factor the speed limits scaled the last twist by (1.0: within the limits)."""

@final
class IbvsController:
    """Classic pixel-space IBVS: v = -lambda L_hat^+ (p - p*). Pickles with its configuration;
    a copy's next twist is the original's, but the last step's pixel_error, last_gain and
    saturation are not kept."""

    def __new__(
        cls,
        reference_pixels: _ArrayLike,
        K_hat: _IntrinsicsLike,
        gain: float = 1.0,
        interaction: Literal["current", "desired", "mean"] = "current",
        reference_depths: _ArrayLike | None = None,
        adaptive_gain: tuple[float, float, float] | None = None,
        max_linear_speed: float | None = None,
        max_angular_speed: float | None = None,
    ) -> IbvsController: ...
    def step(self, pixels: _ArrayLike, depths: _ArrayLike, visible: npt.ArrayLike | None = None) -> _F64Array:
        """One control step from the current pixels (n, 2) and depths (n,): the twist (6,) in the
        camera frame. `visible`, a bool array (n,) (None: all), keeps only the flagged points
        (hidden points' pixels and depths are ignored and may be NaN); at least 4 must be
        visible (else DegenerateGeometry)."""
    def pose_uncertainty(
        self,
        pixels: _ArrayLike,
        depths: _ArrayLike,
        pixel_sigma: float,
        reference_sigma: float | None = None,
        averaged_images: int = 1,
        visible: npt.ArrayLike | None = None,
    ) -> PoseUncertainty:
        """The pose uncertainty that pixel noise of `pixel_sigma` pixels (per coordinate; the
        reference image's `reference_sigma`, default the same) leaves at `pixels` (n, 2) with
        `depths` (n,), under the pixel stop rule with this controller's reference image and
        K_hat (taken with the servo camera); `averaged_images` current images were averaged.
        First order; the translation is in the depths' scale and K_hat is taken as right."""
    def __reduce__(self) -> tuple[type[IbvsController], tuple[Any, ...]]:
        """Pickling: the constructor's arguments (reference pixels, K_hat, gain, interaction,
        reference depths, adaptive gain, speed limits). The next twist of the copy is that of
        the original; the last step's pixel_error, last_gain and saturation are not kept."""
    @property
    def pixel_error(self) -> float | None:
        """RMS pixel error at the last step (None before the first step)."""
    @property
    def last_gain(self) -> float | None:
        """The lambda used at the last step (None before the first step)."""
    @property
    def saturation(self) -> float | None:
        """The factor the speed limits scaled the last twist by (None before the first step)."""

@final
class Servo:
    """A servo session: the reference image, the law, the depth source and the stop rules; each
    `step(pixels, depths, visible)` returns the twist to send and the verdict.

    The keyword arguments are the session's (`reference_depths`, `depths`, `basis`, `stop`,
    `stop_rule`, `path_samples`, `basis_hold`, `dt`) and the laws' options
    (`vsinv.laws.LAW_OPTIONS`: `gain` to `max_angular_speed`; None or absent: the law's default);
    arguments of another law are refused by name. `basis_hold` (default 3) is how many
    consecutive images a missing basis point is ridden out, the basis kept and the last twist
    repeated with no stop judged; 0 changes the basis at once. A step runs the loop logic the
    simulator runs too: stop rules certified by the pose uncertainty, lost features, the rz = pi
    trap, the iteration limit, depth estimation, path following. A stop is final: once a step has
    returned one, every later step returns the same verdict with a zero twist.

    Works from several threads: each call holds the GIL, so calls take turns."""

    def __new__(
        cls,
        reference_pixels: _ArrayLike,
        K_hat: _IntrinsicsLike,
        law: Literal["invariant", "ibvs", "none"] = "invariant",
        *,
        reference_depths: _ArrayLike | None = None,
        depths: Literal["reference", "per_step"] | float | ResectionDepths = "reference",
        basis: tuple[int, int, int] | Sequence[int] | Literal["auto"] = "auto",
        gain: float = 1.0,
        gain_rz: float | None = None,
        rz_task: Literal["angle", "tau21"] | None = None,
        feedforward: bool | None = None,
        min_structure_ratio: float | None = None,
        interaction: Literal["current", "desired", "mean"] | None = None,
        adaptive_gain: tuple[float, float, float] | None = None,
        max_linear_speed: float | None = None,
        max_angular_speed: float | None = None,
        stop: dict[str, float | int | None] | None = None,
        stop_rule: Literal["pixel", "invariant"] | None = None,
        path_samples: int | None = None,
        basis_hold: int | None = None,
        dt: float = 0.04,
    ) -> Servo: ...
    def step(
        self, pixels: _ArrayLike, depths: _ArrayLike | None = None, visible: npt.ArrayLike | None = None
    ) -> ServoStep:
        """One step from the current pixels (n, 2): `depths` (n,) with `depths="per_step"` (None
        otherwise), `visible` a bool array (n,) of the points found (None: all). Returns a
        ServoStep: the twist to send (zero when stopping), the verdict and the telemetry. After a
        stop, every later step returns that stop again (zero twist)."""
    @property
    def iterations(self) -> int:
        """Control steps applied."""
    @property
    def basis(self) -> tuple[int, int, int]:
        """The basis in use (three point indices; it changes when a basis point is not visible)."""
    @property
    def basis_switches(self) -> int:
        """How many times the basis changed because one of its points was not visible."""
    @property
    def basis_held_images(self) -> int:
        """How many images were ridden out with a basis point missing: the basis kept and the last
        twist repeated (`basis_hold`)."""
    @property
    def law(self) -> Literal["invariant", "ibvs", "none"]:
        """The law: "invariant", "ibvs" or "none"."""
    @property
    def stop_rule(self) -> Literal["pixel", "invariant"]:
        """The image rule that decides convergence: "pixel" or "invariant"."""
    @property
    def reference_pixels(self) -> _F64Array:
        """The reference pixels (n, 2)."""
    @property
    def pixel_sigma(self) -> float | None:
        """The pixel noise measured on the last images (None before three), pixels."""
    def certainty(self) -> dict[str, float | None] | None:
        """What the images say about the pose, a dict of pixel_sigma, reference_pixel_sigma,
        translation_sigma, translation_bound in metres, rotation_sigma, rotation_bound in radians,
        floor_pixel_sigma in pixels: the disagreement floor, None with the stall rule off; None
        when it cannot be computed."""

@disjoint_base
class ServoStep:
    """What one `Servo.step` returns."""

    @property
    def twist(self) -> _F64Array:
        """The twist to send (vx, vy, vz, wx, wy, wz) in the camera frame, m/s and rad/s; zero
        when the verdict is to stop."""
    @property
    def verdict(
        self,
    ) -> Literal[
        "running", "converged", "settled", "lost_features", "rz_trap", "degenerate", "diverged", "max_iterations", "observed"
    ]:
        """"running", or why to stop: "converged", "settled", "lost_features", "rz_trap",
        "degenerate", "diverged", "max_iterations", "observed"."""
    @property
    def reason(self) -> str | None:
        """Why the session stops, in words (None while running)."""
    @property
    def running(self) -> bool:
        """Whether the loop goes on."""
    @property
    def telemetry(self) -> dict[str, Any]:
        """The figures of this step: a dict of iteration, invariant_error, image_error (pixels),
        tau (tau_11, tau_21, tau_22), eps_z, eps (5,), tracking_error, law_ran, basis (the
        three point indices in use) and basis_switches (how often a hidden basis point made
        the session change its basis); NaN where a figure does not apply."""

@final
class ImageServo:
    """The pipeline from image to twist: finds the target in the reference image (taken with any camera: no K* needed),
    then each `step(image)` detects or tracks it, matches the points by identity, undistorts them with `K_hat` and
    `distortion` and steps a `Servo` session.

    `target` is a name of `vsinv._core.TARGETS`, whose entry lists the keyword arguments it takes (another
    target's are refused by name). `target="dots"`: `reference_points` (n, 2) are approximate pixels of the dots in
    the reference image, `first_points` (n, 2) in the first frame (None: near those found in the reference image);
    `tracker` a dict of search_radius, max_search_radius, min_area, max_area_ratio, polarity. `target="tags"`:
    AprilTags of `family`, decoded in every frame (searched near their last corners first, the whole frame when
    one is lost), the corners of the tags `tag_ids` (None: every tag decoded in the reference image), corner c of
    tag t under identity 4 t + c: no clicks, correspondences by identity between any two cameras. `decimation`
    (1..=8, None: the detector's default) is the quad search's, as in `detect_tags`. `target="features"`: no
    markers, no clicks: a spread of `max_points` (default 150) SIFT keypoints of the reference image, keypoint i
    under identity i, matched in the first frame by descriptors checked by the fundamental matrix (no intrinsics
    needed), then tracked (Lucas-Kanade, forward-backward check) and checked against the reference again each
    frame; a point failing a check is not visible (never at a wrong place), and a point not found is looked for
    again in each frame where its found neighbours put it (aligned on its reference patch), so it comes back into
    view; the frame is matched afresh when fewer than `min_tracked` (default 24) remain; `point_ids` (None: all) keeps some of the points. The reference depths of natural
    keypoints are unknown: estimate them by appendix A (`depths=ResectionDepths(...)` over the points of a
    translation pair, those given to `point_ids`; `vsinv.vision.match_features` and `track_points` find them).

    `reference_K` and `reference_distortion` undistort the reference points. Every other keyword argument is the
    `Servo` session's (law, reference_depths, depths, basis, gain, ..., dt) and an unknown one is refused by name.
    A point not found in a frame is not visible for that step; a basis point missing for at most 3 consecutive frames
    keeps the basis (the last twist is repeated, no stop is judged), longer changes it. The stall rule is on unless
    `stop={"stall": False}`: real detections of one pose by two lenses disagree, so the run ends when the error
    stopped decreasing and the camera is still, `converged` if the bound (with the measured disagreement floor) is
    within the tolerance. A first frame where no point is found (blank, dark) is the verdict `lost_features` with a
    zero twist. As for `Servo`, a stop is final.

    Works from several threads: their calls take turns (each waits with the GIL released)."""

    def __new__(
        cls,
        reference_image: npt.NDArray[np.uint8],
        target: _TargetName,
        K_hat: _IntrinsicsLike,
        *,
        reference_points: _ArrayLike | None = None,
        first_points: _ArrayLike | None = None,
        tracker: dict[str, float | int | str] | None = None,
        family: _TagFamily | None = None,
        tag_ids: Sequence[int] | None = None,
        decimation: int | None = None,
        max_points: int | None = None,
        min_tracked: int | None = None,
        point_ids: Sequence[int] | None = None,
        distortion: Distortion | _ArrayLike | None = None,
        reference_K: _IntrinsicsLike | None = None,
        reference_distortion: Distortion | _ArrayLike | None = None,
        **options: Any,
    ) -> ImageServo: ...
    def step(self, image: npt.NDArray[np.uint8]) -> ImageStep:
        """One frame (an image: grey, or BGR/BGRA converted): the twist to send, the verdict, the
        telemetry, and per point the pixel found and whether it was found."""
    @property
    def ids(self) -> npt.NDArray[np.uint32]:
        """The points' identities, in the session's order (n,)."""
    @property
    def reference_pixels(self) -> _F64Array:
        """The reference pixels (n, 2), undistorted with reference_K when given."""
    @property
    def iterations(self) -> int:
        """Control steps applied."""
    @property
    def basis(self) -> tuple[int, int, int]:
        """The basis in use (it changes when a basis point is not visible)."""
    @property
    def basis_switches(self) -> int:
        """How many times the basis changed because one of its points was not visible."""
    @property
    def basis_held_images(self) -> int:
        """How many images were ridden out with a basis point missing: the basis kept and the last
        twist repeated (`basis_hold`)."""
    @property
    def pixel_sigma(self) -> float | None:
        """The pixel noise measured on the last frames (None before three), pixels."""
    def certainty(self) -> dict[str, float | None] | None:
        """What the frames say about the pose, as `Servo.certainty()` (pixel_sigma, reference_pixel_sigma,
        translation_sigma, translation_bound in metres, rotation_sigma, rotation_bound in radians: the accuracy
        ceiling, floor_pixel_sigma: the measured disagreement between reference and frame detections, pixels); None
        when it cannot be computed."""

@final
class ImageStep(ServoStep):
    """What one `ImageServo.step` returns: a `ServoStep` with the points found."""

    @property
    def found(self) -> npt.NDArray[np.bool_]:
        """Per point: found in this frame (n,)."""
    @property
    def pixels(self) -> _F64Array:
        """Per point: the pixel found (distorted, as detected), or its last known pixel (n, 2)."""
    @property
    def stopped_early(self) -> bool:
        """Whether the detector's search of this frame stopped at its bound on its work (a frame
        too cluttered to be searched whole, as `Tags.stopped_early`): a point not found may be
        in view."""

@final
class PoseUncertainty:
    """The camera displacement from the goal that the images still allow (first-order
    propagation of pixel noise through the law's Jacobian), in the current camera frame:
    translation in metres (in the depth estimates' scale), rotation in radians."""

    @property
    def covariance(self) -> _F64Array:
        """Covariance of (tx, ty, tz, rx, ry, rz) caused by the pixel noise, (6, 6)."""
    @property
    def offset(self) -> _F64Array:
        """J^+ (m - m*): the displacement the measured error itself implies, (6,)."""
    @property
    def translation_sigma(self) -> float:
        """RMS translation the noise leaves, metres: sqrt(trace Cov(t))."""
    @property
    def rotation_sigma(self) -> float:
        """RMS rotation the noise leaves, radians: sqrt(trace Cov(r))."""
    def translation_bound(self, sigmas: float = 3.0) -> float:
        """sigmas * translation_sigma + |offset_t|: how far from the goal the camera centre may be, metres."""
    def rotation_bound(self, sigmas: float = 3.0) -> float:
        """sigmas * rotation_sigma + |offset_r|, radians."""

@final
class PixelNoiseMeter:
    """The pixel noise of an image stream, measured from the images themselves: the second
    difference of each point over three consecutive images cancels motion linear in time,
    and E[d^2] = 6 sigma^2 for independent noise. `PixelNoiseMeter(capacity=32)`: a meter over
    the last `capacity` images (3 to 4096)."""

    def __new__(cls, capacity: int = 32) -> PixelNoiseMeter: ...
    def push(self, pixels: _ArrayLike, visible: npt.ArrayLike | None = None) -> None:
        """Adds an image's pixels (n, 2); another number of points starts the measurement again."""
    @property
    def sigma(self) -> float | None:
        """The standard deviation of a pixel coordinate, pixels; None until a point was seen in
        three consecutive images."""
    def clear(self) -> None:
        """Forgets the images."""
    def __len__(self) -> int: ...

@final
class StabilityReport:
    """Stability verdicts of Props. 1-2 and the sigma of Prop. 3."""

    @property
    def prop1(self) -> bool:
        """Prop. 1 (constant K): necessary and sufficient."""
    @property
    def prop2(self) -> bool:
        """Prop. 2 (K varying over the schedule): sufficient."""
    @property
    def sigma(self) -> float:
        """Smallest eigenvalue of A + A^T over the schedule (Prop. 3's sigma when positive)."""
    @property
    def eigenvalues(self) -> npt.NDArray[np.complex128]:
        """Eigenvalues of A: complex (5,) for one K, (m, 5) for a schedule of m matrices."""
    def tracking_bound(self, max_b: float) -> float:
        """Prop. 3: the bound psi/phi on ||eps|| when ||b(t)|| <= max_b; InvalidInput when
        Prop. 2 fails (sigma <= 0: no bound)."""

def check_stability(K: _IntrinsicsLike, K_hat: _IntrinsicsLike, kappa: float = 1.0, gain: float = 1.0) -> StabilityReport:
    """Props. 1-2 for the true intrinsics `K` (one camera, or a schedule of cameras), an estimate `K_hat` (a 3x3
    upper-triangular matrix or Intrinsics), the depth scale `kappa` and the gain."""

def tracking_bound(gain: float, sigma: float, max_b: float) -> float:
    """The bound psi/phi = 2 max_b / (gain sigma) of Prop. 3 (eq. 20) on ||eps|| while ||b(t)|| <= max_b;
    `InvalidInput` for gain <= 0, sigma <= 0 (Prop. 2 fails: no bound), max_b < 0 or a bound that overflows."""


@final
class Scenario:
    """A validated scenario (see the README for the schema)."""

    @staticmethod
    def from_toml(text: str, allow_outside_files: bool = False) -> Scenario:
        """From TOML text; the files it names must be in the working directory unless
        `allow_outside_files`."""
    @staticmethod
    def from_dict(d: dict[str, Any], allow_outside_files: bool = False) -> Scenario:
        """From a dictionary with the structure of a scenario file; the files it names must be in
        the working directory unless `allow_outside_files`."""
    @property
    def name(self) -> str:
        """The name."""
    @property
    def description(self) -> str:
        """The description."""
    @property
    def engine(self) -> Literal["kinematic", "mujoco"]:
        """The world that runs it (`[world] engine`): "kinematic" (vsinv's simulator) or "mujoco"
        (`vsinv.mujoco`, the mujoco extra)."""
    def to_dict(self) -> dict[str, Any]:
        """The scenario as a dictionary (every default filled in); edit it and pass it back to
        `run_scenario` or `Scenario.from_dict`."""
    def arm(self) -> ScenarioArm | None:
        """The arm of `[robot] kind = "urdf"` as the kinematic simulator reads it (its start joints
        solved from `[start]` if need be), or None for a free camera or a Cartesian robot: what
        a world that moves the arm itself (`vsinv.mujoco`) needs."""
    def to_toml(self) -> str:
        """The scenario as TOML text."""

@final
class ScenarioArm:
    """The arm of a scenario (`Scenario.arm()`): the built-in model or URDF, its base in F*, the
    camera's mount on the end effector, the start joints and the limits the kinematic simulator
    uses, and its resolution of camera twists into joint velocities."""

    @property
    def model(self) -> str:
        """`robot.urdf`: the built-in arm's name ('ur5', 'ur5e', 'panda') or the URDF's source."""
    @property
    def source(self) -> str:
        """Where the arm's model came from: `builtin:<name>` for a built-in arm, else the path of
        the URDF file `robot.urdf` (resolved from the scenario file's folder)."""
    @property
    def end_effector(self) -> str:
        """The link carrying the camera (`robot.end_effector`, or the model's default)."""
    @property
    def joint_names(self) -> list[str]:
        """The actuated joints' names, base to end effector."""
    @property
    def base(self) -> _F64Array:
        """The arm's base link in F* (4x4, `robot.base`)."""
    @property
    def mount(self) -> _F64Array:
        """The camera in the end effector's frame (4x4, `robot.camera_mount`): where it is."""
    @property
    def believed_mount(self) -> _F64Array:
        """The mount the controller believes (4x4: `camera_mount * mount_error`, or the mount):
        camera twists become joint velocities through it."""
    @property
    def start(self) -> _F64Array:
        """The start joints (rad; m for prismatic joints): `robot.joints`, or solved from `[start]`."""
    @property
    def lower(self) -> _F64Array:
        """Lower joint limits (rad, m)."""
    @property
    def upper(self) -> _F64Array:
        """Upper joint limits (rad, m)."""
    @property
    def velocity(self) -> _F64Array:
        """Joint speed limits (rad/s, m/s)."""
    @property
    def damping(self) -> float:
        """The largest damping factor of the least squares (`robot.damping`)."""
    @property
    def min_manipulability(self) -> float:
        """A run ends `singular` below this manipulability (`robot.min_manipulability`)."""
    def camera_pose(self, joints: _ArrayLike) -> _F64Array:
        """The camera's pose in F* (4x4) at `joints`: `base * fk(joints) * mount`."""
    def link_poses(self, joints: _ArrayLike) -> list[tuple[str, _F64Array]]:
        """Every link of the chain at `joints`, base link first, end effector last: (name, its pose
        in the base link's frame, 4x4), by this arm's own model (`fk` of each link)."""
    def ik(self, pose: _ArrayLike, seed: _ArrayLike | None = None) -> _F64Array:
        """Joints within the model's limits that put the end effector at `pose` (4x4, in the arm's
        base frame, as `camera_pose` is `base * fk * mount`), by this arm's own model (a user's
        URDF, or the built-in): the damped least squares of `kinematics.ik`, from `seed` (one
        value per joint; default the middle of the limits), then from spread seeds. Raises
        InvalidInput (kind 'unreachable') when no seed reaches the pose."""
    def manipulability(self, joints: _ArrayLike) -> float:
        """The manipulability sqrt(det(J J^T)) at `joints` (any frame's Jacobian gives it)."""
    def joint_velocities(self, jacobian: _ArrayLike, joints: _ArrayLike, twist: _ArrayLike) -> tuple[_F64Array, bool]:
        """Joint velocities (n,) for the camera `twist` (6,: in the camera frame the controller
        believes) at `joints`, where `jacobian` (6, n) is that camera frame's Jacobian from
        elsewhere (MuJoCo's `mj_jacSite`, rows turned into the camera frame): the kinematic arm's
        damped least squares, with its joint-centring task on a redundant arm, scaled as a whole
        within the joint speed limits; and whether the limits scaled them."""

_ScenarioLike = Union[Scenario, dict[str, Any], str, os.PathLike[str]]

class _Column(TypedDict):
    name: str
    unit: str
    shape: tuple[int | str, ...]
    dtype: Literal["float64", "bool"]
    recorded: Literal["always", "vision", "arm"]
    description: str

class _SummaryField(TypedDict):
    name: str
    unit: str
    description: str

def recorded_columns() -> list[_Column]:
    """The recorded columns (each a `RunResult` attribute and an `.npz` entry): name, unit (SI, `px`, `1`
    dimensionless, `bool`), shape (axis lengths, or `"N"` rows, `"n"` points, `"n_joints"` joints), dtype, which
    runs record it, description."""

def summary_fields() -> list[_SummaryField]:
    """The numbers of `RunResult.summary` (SI, `px`, `1`): name, unit, description."""

_PlotKind = Literal[
    "image_trajectories", "errors", "task_functions", "velocities", "pose_errors", "path3d", "joints", "joint_velocities"
]

@final
class RunResult:
    """The result of a run: `.summary` (a dict), the scenario, and the recorded columns (NumPy
    views of the simulator's buffers, one row per iteration), one attribute each as declared in
    `vsinv::sim::outcome::COLUMNS` (see `recorded_columns()`)."""

    columns: tuple[dict[str, Any], ...]
    """The declaration of the recorded columns (as `recorded_columns()`)."""
    @staticmethod
    def from_recording(
        scenario: _ScenarioLike,
        summary: dict[str, Any],
        arrays: dict[str, Any],
        joint_limits: dict[str, Any] | None = None,
    ) -> RunResult:
        """A run recorded outside the Rust simulator (`vsinv.mujoco.run`) as a `RunResult` of the
        same schema: `summary` with exactly the keys of a kinematic run's (each checked: a
        status of the simulator's, the scenario's name, numbers or None), `arrays` the recorded
        columns by name (every column that all runs record, shapes as declared with N rows from
        `time`, n points from `reference_pixels`, `n_joints` from `joints`; copied), and an
        arm's `joint_limits` (names, lower, upper, velocity) or None. Raises InvalidInput naming
        the key or column at fault."""
    @property
    def summary(self) -> dict[str, Any]:
        """The run's summary (status, iterations, final errors, ...), a dict."""
    @property
    def scenario(self) -> Scenario:
        """The scenario that was run."""
    @property
    def arrays(self) -> dict[str, npt.NDArray[Any]]:
        """The recorded arrays by name (those this run recorded)."""
    def plot(self, kind: _PlotKind, ax: Any = None) -> Any:
        """The figure ``kind`` (``vsinv.plots.PLOTS``) drawn into ``ax`` (a matplotlib Axes, or one
        per panel) or a new figure; returns the matplotlib Figure."""
    @property
    def time(self) -> _F64Array:
        """time (s, shape (N,))."""
    @property
    def pose(self) -> _F64Array:
        """camera pose in F* (4x4, translation in metres) (m, shape (N, 4, 4))."""
    @property
    def twist(self) -> _F64Array:
        """twist sent to the robot (vx, vy, vz, wx, wy, wz; NaN on the last row when no step followed) (m/s, rad/s, shape (N, 6))."""
    @property
    def joints(self) -> _F64Array:
        """joint positions (x, y, z, theta-u for the free-flying camera) (m, rad, shape (N, n_joints))."""
    @property
    def pixels(self) -> _F64Array:
        """measured pixels (NaN where not visible) (px, shape (N, n, 2))."""
    @property
    def visible(self) -> npt.NDArray[np.bool_]:
        """visibility of each point (bool, shape (N, n))."""
    @property
    def invariant_error(self) -> _F64Array:
        """||s - s*||, to the reference image (1, shape (N,))."""
    @property
    def tracking_error(self) -> _F64Array:
        """||s - s*(t)||, to the moving reference of a planned path (NaN outside the invariant law) (1, shape (N,))."""
    @property
    def eps(self) -> _F64Array:
        """task function eps (NaN for IBVS) (m, rad, shape (N, 5))."""
    @property
    def eps_z(self) -> _F64Array:
        """eps_z = det(Q*) tau_21 (px^2, shape (N,))."""
    @property
    def image_error(self) -> _F64Array:
        """largest distance of a visible point from its reference pixel (px, shape (N,))."""
    @property
    def translation_error(self) -> _F64Array:
        """distance of the camera centre from the reference pose (m, shape (N,))."""
    @property
    def rotation_error(self) -> _F64Array:
        """rotation angle from the reference pose (rad, shape (N,))."""
    @property
    def reference_pixels(self) -> _F64Array:
        """reference pixels (with their noise, if any); one row per point, not per iteration (px, shape (n, 2))."""
    @property
    def detection_error(self) -> _F64Array | None:
        """distance of each tracked centroid from the true projection of its dot's centre (NaN where not found) (px, shape (N, n); None without [vision])."""
    @property
    def joint_velocities(self) -> _F64Array | None:
        """an arm's joint velocities after saturation (NaN on the last row) (m/s, rad/s, shape (N, n_joints); None for robots other than an arm)."""
    @property
    def joint_limits(self) -> dict[str, Any] | None:
        """An arm's joint `names` and limits `lower`, `upper` (rad or m) and `velocity` (per second); None for the
        other robots."""

def load_scenario(source: _ScenarioLike, allow_outside_files: bool = False) -> Scenario:
    """Loads a scenario from a built-in name, a TOML file path or a dictionary. Scenario angles
    are degrees and their keys say so (`rotation_deg`, `skew_deg`, `max_angular_speed_deg`; the
    older `rotation` is read as degrees); the Python API itself is SI (radians). The files a
    scenario names (`calibration`, `robot.urdf`) must be inside its folder (the working
    directory for a dictionary) unless `allow_outside_files`."""
def list_scenarios() -> list[tuple[str, str]]:
    """The built-in scenarios as (name, description) pairs."""
def run_batch(
    scenarios: Iterable[_ScenarioLike],
    threads: int | None = None,
    allow_outside_files: bool = False,
    progress: Callable[[int, int], object] | None = None,
) -> dict[str, npt.NDArray[Any]]:
    """Runs many scenarios (Scenario objects, dicts, JSON texts, built-in names or TOML paths)
    in parallel with the GIL released (recording off) and returns the table as a dict of NumPy
    arrays, one row per scenario: status (str), iterations, the summary fields final_translation_error,
    final_rotation_error, final_image_error, final_invariant_error, max_line_deviation,
    observed_max_eps, pixel_sigma, translation_uncertainty, rotation_uncertainty (SI, NaN where
    not measured), prop1, prop2, within_tolerance, message (str). A scenario whose configuration
    is invalid raises before anything runs; a run that fails on the way has status "error" and
    its message.

    `progress`: None, or a callable `progress(done, total)` called from the calling thread as
    runs finish (`done` increasing to `total`); `vsinv.sim.run_batch` draws a tqdm bar instead
    for None, True or False. Ctrl-C or an exception of `progress` stops the batch and is raised.
    Works in a process forked after earlier batches (the pools are rebuilt)."""
def run_sweep_runs(
    base: dict[str, Any],
    keys: list[str],
    values: list[list[Any]],
    seeds: list[int] | None = None,
    threads: int | None = None,
    allow_outside_files: bool = False,
    progress: Callable[[int, int], object] | None = None,
) -> dict[str, npt.NDArray[Any]]:
    """Runs a sweep's runs (the scenarios `sweep_scenarios` gives for the same arguments) with the
    GIL released and returns `run_batch`'s table, one row per run. Each run's scenario is
    parsed once, on the worker that runs it; a run whose scenario is invalid raises, its index
    in the key (`[17].estimate.fku`), and the runs not started are skipped. `threads`,
    `allow_outside_files` and `progress` as for `run_batch`."""
def run_scenario(
    scenario: _ScenarioLike,
    record: bool = True,
    progress: Callable[[int, int], object] | None = None,
    allow_outside_files: bool = False,
) -> RunResult:
    """Runs a scenario (a `Scenario`, dict, built-in name or TOML path) with the GIL released.
    `progress(done, total)` is called every 64 iterations if given; Ctrl-C stops the run."""

def sweep_scenarios(
    base: dict[str, Any],
    keys: list[str],
    values: list[list[Any]],
    seeds: list[int] | None = None,
) -> list[dict[str, Any]]:
    """The scenarios of a sweep's runs as dictionaries: the scenario dictionary `base` with, for
    run i, `values[k][i]` set for each key `keys[k]` (dotted scenario keys as given, then the
    derived keys in the order of `SWEEP_DERIVED_KEYS`) and `noise.seed = seeds[i]` unless
    `seeds` is None. `InvalidInput` names the key at fault ("vary key 'control.gian': ...")."""

@final
class PlaneParallax:
    """The plane + parallax parameters of eq. (9) (gamma_3 = 1)."""

    @property
    def gamma(self) -> _F64Array:
        """Gamma / gamma_3, (3,)."""
    @property
    def epipole(self) -> _F64Array:
        """The epipole e* (unit norm), (3,)."""
    @property
    def mu_e(self) -> _F64Array:
        """mu_k* e* for each non-basis point, (n-3, 3)."""
    @property
    def gamma_k(self) -> _F64Array:
        """gamma_k / gamma_3 for each non-basis point, (n-3,)."""
    @property
    def residual(self) -> float:
        """RMS distance between the current invariant points and those eq. (9) predicts."""
    @property
    def candidates(self) -> int:
        """Number of det F = 0 candidates of the minimal method (1 for the linear method)."""

def estimate_plane_parallax(
    current_pixels: _ArrayLike, reference_pixels: _ArrayLike, basis: _Basis = (0, 1, 2)
) -> PlaneParallax:
    """Eq. (9) from a current and a reference image (n >= 7 points; linear method for n >= 8,
    minimal 7-point method otherwise)."""

@final
class InvariantPath:
    """The path of eq. (10) from the current image (t = 0) to the reference image (t = T)."""

    def __new__(
        cls, current_pixels: _ArrayLike, reference_pixels: _ArrayLike, duration: float, basis: _Basis = (0, 1, 2)
    ) -> InvariantPath: ...
    @property
    def duration(self) -> float:
        """T, seconds."""
    @property
    def plane_parallax(self) -> PlaneParallax:
        """The plane + parallax estimate the path was built from."""
    def sample(self, t: float) -> tuple[_F64Array, _F64Array]:
        """(q_k*(t), dq_k*/dt) for the non-basis points, two (n-3, 3) arrays; pass them to
        `InvariantController.set_reference`."""

def reference_depths(object_points: _ArrayLike, reference_pixels: _ArrayLike, K: _IntrinsicsLike | None = None) -> _F64Array:
    """The reference depths zeta* (n,) of a photo taken with any camera: `object_points` (n, 3),
    the object's model in any frame (metres), seen at `reference_pixels` (n, 2) in the photo
    (undistorted pixels). At least 6 points not on one plane need no intrinsics (a DLT
    resection); points on one plane (at least 4) need `K`, the photo's camera matrix (3x3 or
    Intrinsics)."""

def depths_from_translation(
    first_pixels: _ArrayLike, second_pixels: _ArrayLike, pixel_noise: float | None = None
) -> tuple[_F64Array, _F64Array, float]:
    """Eq. (26): depths of the first image of a pure-translation pair (any camera), up to one
    positive scale (mean 1). Returns (depths (n,), epipole (3,), residual). Without
    `pixel_noise` the pixels must be exact (the epipole is a least-squares fit of every
    point's motion). With `pixel_noise` (pixels, standard deviation per coordinate of the
    tracking error; about 0.1-0.15 for keypoints tracked by the features target) the
    estimate is robust: a consensus on the epipole, then a depth only for the points whose
    residual is below 4 sqrt(2) pixel_noise and whose parallax fixes the depth to 10 % (three
    standard deviations); the other depths are NaN (`np.isfinite(depths)` is the mask of the
    usable points, which ResectionDepths accepts as is), the mean over the usable ones is 1
    and the residual is their RMS distance from the epipolar lines (pixels)."""


@final
class ResectionDepths:
    """Appendix A on line: the current depths up to kappa(t) > 0 by resecting the current camera
    against the reconstruction from the translation pair. A NaN in `first_depths` marks a
    point without a usable depth (depths_from_translation with pixel_noise): the reference
    camera is resected from the others and that point placed on its ray of the first image
    where the reference image sees it."""

    def __new__(
        cls,
        first_pixels: _ArrayLike,
        first_depths: _ArrayLike,
        reference_pixels: _ArrayLike,
        reference_mean_depth: float = 1.0,
    ) -> ResectionDepths: ...
    def estimate(self, pixels: _ArrayLike, visible: npt.ArrayLike | None = None) -> _F64Array:
        """Depths (n,) of the current image up to kappa(t) > 0, from the pixels of the visible
        points (all by default; at least 6, not coplanar)."""

# An image: returned, a (height, width) uint8 grey array; as an argument, any uint8 array read
# by the bindings' one image reader: grey (height, width) or (height, width, 1), colour
# (height, width, 3) BGR or (height, width, 4) BGRA (OpenCV's order; alpha ignored) converted
# to grey by Rec. 601 luma (OpenCV's COLOR_BGR2GRAY to the bit), in C, Fortran or strided order.
# Anything else raises InvalidInput naming the argument, its dtype and shape.
_U8Image = npt.NDArray[np.uint8]

def render(
    scenario: _ScenarioLike,
    pose: npt.ArrayLike | None = None,
    time: float = 0.0,
    reference: bool = False,
) -> _U8Image:
    """The image a scenario's camera sees: the servo camera K(time) at `pose` (a 4x4 camera
    frame in F*; default the start pose), or the reference camera K* (default at F*) when
    `reference` is true; rendered with the scenario's `[vision]` settings."""

def render_view(
    scenario: _ScenarioLike,
    pose: npt.ArrayLike | None = None,
    time: float = 0.0,
    reference: bool = False,
) -> tuple[_U8Image, _F64Array, npt.NDArray[np.bool_]]:
    """`render` with what it shows: `(image, pixels (n, 2), visible (n,))`, the true
    projections of the dots' centres and which dots are in the image."""

def render_faces(
    faces: Sequence[tuple[_ArrayLike, _ArrayLike, _U8Image]],
    pose: _ArrayLike,
    K: _IntrinsicsLike,
    width: int,
    height: int,
    blur_sigma: float = 0.8,
    noise_sigma: float = 2.0,
    background: int = 30,
    seed: int = 0,
    frame: int = 0,
) -> _U8Image:
    """The image a camera sees of textured faces: `faces` a sequence of `(vertices (n, 3),
    texture_coords (n, 2), texture)`, each a convex planar polygon of F* (metres, n >= 3, front
    side the one its vertices turn counter-clockwise around) whose vertex `k` shows texture pixel
    `texture_coords[k]` (`(u, v)`, the texel `(i, j)` centred on `(i, j)`, a texture of w x h
    texels spanning `[-0.5, w - 0.5] x [-0.5, h - 0.5]`; a projective map from the face: affine
    for a triangle, the homography of the first four otherwise), `texture` a grey or colour uint8
    image (as `to_grey` reads it). The camera frame `pose` (4x4, in F*), its intrinsics `K`
    (`Intrinsics` or 3x3; a pinhole, no distortion), an image of `width` x `height` pixels. A
    pixel shows the area average over its footprint of the texture read bilinearly between texel
    centres (OpenGL's linear filter; the nearest face per sample; faces seen from behind are not
    drawn), on a background of grey level `background`, then the Gaussian PSF
    of `blur_sigma` pixels and the noise of `noise_sigma` grey levels (draw `frame` of `seed`), as
    `render`. More faces than the limit (`MAX_FACES` of the crate's renderer) are refused.
    Returns the `(height, width)` uint8 image."""

def degrade(
    image: _U8Image,
    blur_sigma: float = 0.8,
    noise_sigma: float = 2.0,
    seed: int = 0,
    frame: int = 0,
) -> _U8Image:
    """`image` (a grey or colour array, see `to_grey`) through the renderer's optics and sensor, as
    a scenario's `[vision]` table describes them: blurred by a Gaussian PSF of `blur_sigma`
    pixels in [0, 20] (near the border the kernel renormalised to the image), plus sensor noise
    of `noise_sigma` grey levels in [0, 100] (the draws `render` takes for frame `frame` from
    `seed`), rounded and clamped to 8 bits; what a MuJoCo run does to each render."""

@final
class Dots:
    """Dots found in an image, sorted by row then column of their centroids."""

    @property
    def centroids(self) -> _F64Array:
        """Subpixel centroids `(u, v)`, `(m, 2)` float64."""
    @property
    def areas(self) -> _F64Array:
        """Pixels above the threshold, `(m,)` float64."""
    @property
    def bboxes(self) -> npt.NDArray[np.int64]:
        """Bounding boxes `[u_min, v_min, u_max, v_max]` (inclusive), `(m, 4)` int64."""
    def __len__(self) -> int: ...

def match_features(
    reference_image: _U8Image, image: _U8Image, threshold: float = 1.5
) -> tuple[_F64Array, _F64Array]:
    """The SIFT matches of `reference_image` in `image` (two cameras, any intrinsics): mutual
    nearest descriptors passing Lowe's ratio (0.8), then those within `threshold` pixels of the
    epipolar lines of one fundamental matrix (RANSAC, seeded), agreeing with their neighbours (a
    locally affine view), each refined to a fraction of a pixel by aligning the reference's
    patch warped into `image` (a match whose patch does not align is dropped). Returns `(reference_pixels (m, 2),
    pixels (m, 2))`; fewer than 12 matches (too little texture, another scene) raises
    `InvalidImage` naming the image."""

def track_points(
    previous_image: _U8Image, next_image: _U8Image, points: _ArrayLike, max_error: float = 0.5
) -> tuple[_F64Array, npt.NDArray[np.bool_]]:
    """Where `points` (n, 2) of `previous_image` are in `next_image` (same size): pyramidal
    Lucas-Kanade (21 x 21 windows, 3 levels above the image) forward, then backward; a point
    is found when both ways converge and it comes back within `max_error` pixels of where it
    started. Returns `(pixels (n, 2), found (n,) bool)`, NaN where not found."""

def detect_dots(
    image: _U8Image,
    threshold: int | None = None,
    min_area: int = 8,
    max_area: int | None = None,
    polarity: Literal["light", "dark", "auto"] = "light",
    min_fill: float = 0.95,
    min_contrast: int = 20,
    max_ring_residual: float = 0.15,
) -> Dots:
    """Bright dots on a dark background (`polarity="light"`), dark dots on a bright one
    (`"dark"`: the bright dots of `255 - image`, threshold `t` standing for `255 - t`) or as the
    image shows (`"auto"`): a local threshold (a pixel is a dot pixel when it stands out of the
    background of its neighbourhood by half the contrast of the dots nearby and at least
    `min_contrast`; `threshold=` sets one level for the whole image instead), 8-connected
    components with `min_area <= area <= max_area` (pixels) and a fill ratio (area over that
    of the ellipse of its second moments) of at least `min_fill` (less `0.2 / sqrt(area)`,
    the digitised outline's share), a mean contrast over the background plane around it of at
    least `min_contrast` grey levels and a ring around it that fits that plane (RMS residual at
    most `max_ring_residual` times the contrast), intensity-weighted subpixel centroids over
    that plane. A uniform image raises `InvalidInput`.

    `threshold`: None (default) for the local threshold (per 32 px tile: half way between the
    background of the neighbourhood and the brightest dot nearby, at least `min_contrast` above
    the background), or one grey level for the whole image. A dot has `min_area <= area <=
    max_area` pixels (default 8 and no limit), a fill ratio (area over that of the ellipse of
    its second moments: 1 for a filled ellipse, 0.955 for a square) of at least `min_fill` in
    [0, 1] (default 0.95, less `0.2 / sqrt(area)`: the digitised outline's share of a small
    dot), a mean contrast over the background plane around it of at least `min_contrast` grey
    levels in [0, 255] (default 20), and a plain ring around it: the RMS residual of that plane
    on its bounding box's ring (grown by 2 px) at most `max_ring_residual` >= 0 times its
    contrast (default 0.15; inf: no check)."""

@final
class DotTracker:
    """Tracks dots through images: `DotTracker(image, initial_pixels (n, 2), search_radius=20.0,
    max_search_radius=80.0, min_area=4, polarity="light", max_area_ratio=1.5)` finds each dot
    near its click in the first image (a dot larger than the window too; `"dark"`: dark dots,
    `"auto"`: decided on the first image); `track(image)` returns `(pixels (n, 2), found (n,)
    bool)`. The window follows each dot's size and motion; a dot whose area or shape changed
    too much (merged with another region, say) is not found and keeps its last position with
    `found` false; two dots are never swapped. Too much: a component whose area differs from
    the dot's last area by more than `max_area_ratio` (beyond the boundary pixels), or whose
    principal spreads differ by more than its square root, is not that dot.

    Works from several threads: their calls take turns (each waits with the GIL released)."""

    def __new__(
        cls,
        image: _U8Image,
        initial_pixels: npt.ArrayLike,
        search_radius: float = 20.0,
        max_search_radius: float = 80.0,
        min_area: int = 4,
        polarity: Literal["light", "dark", "auto"] = "light",
        max_area_ratio: float = 1.5,
    ) -> DotTracker: ...
    def track(self, image: _U8Image) -> tuple[_F64Array, npt.NDArray[np.bool_]]:
        """Finds the dots in the next image: `(pixels (n, 2), found (n,) bool)`."""
    @property
    def positions(self) -> _F64Array:
        """The last known position of every dot, `(n, 2)`."""
    def __len__(self) -> int: ...

@final
class TagTracker:
    """AprilTags of `family` through a sequence of frames: after a frame, each tag is followed from its last corners
    (its edges measured again near them, its bits read there, accepted only as the same id: no quad search), else
    searched in a crop around its last corners (a margin of a quarter of its side plus twice its last motion), and
    the whole frame is read when one is not found there, when the size changes, and every `refresh` frames (0: only
    then) to pick up tags coming into view. A tracked frame gives the corners `detect_tags` gives on it (within
    0.02 px), for the tags tracked; `reads` says how each was read. `follow=False` skips the following (the quad
    search in each crop every frame). `decimation` (1..=8, None: the detector's default) is `detect_tags`'s.

    Works from several threads: their calls take turns (each waits with the GIL released)."""

    def __new__(
        cls,
        family: _TagFamily = "tag36h11",
        decimation: int | None = None,
        refresh: int = 15,
        follow: bool = True,
    ) -> TagTracker: ...
    def track(self, image: npt.NDArray[np.uint8]) -> Tags:
        """The tags in the next frame (an image: grey, or BGR/BGRA converted), sorted by id; their `stopped_early` says
        whether a quad search of this frame (whole or in a crop) stopped early, as `detect_tags`'s."""
    def reset(self) -> None:
        """Forgets the last frame: the next one is read whole."""
    @property
    def read_whole(self) -> bool:
        """Whether the last frame was read whole (not tracked in crops)."""
    @property
    def reads(self) -> list[str]:
        """How each tag of the last frame was read, in the order of its ids: "edges" (followed from its last corners,
        its edges measured again and its bits read there, no quad search), "crop" (the quad search in a crop around
        them) or "whole" (the quad search in the whole frame)."""

@final
class Tags:
    """AprilTags found in an image, sorted by id."""

    @property
    def ids(self) -> npt.NDArray[np.int64]:
        """Tag ids, `(m,)` int64."""
    @property
    def corners(self) -> _F64Array:
        """Corners (u, v) of each tag's black square, (m, 4, 2): top-left, top-right, bottom-right, bottom-left as
        OpenCV's aruco module orders them (clockwise in the image), pixel (u, v) centred at integer coordinates
        (OpenCV's convention)."""
    @property
    def family(self) -> str:
        """The family searched for (`"tag36h11"`, ...)."""
    @property
    def stopped_early(self) -> bool:
        """Whether the search stopped early: the frame was too cluttered to be searched whole
        within the detector's bound on its work (some levels not searched, or some decoded
        candidates not measured); the tags found are still right, others may be missing."""
    def __len__(self) -> int: ...

def detect_tags(
    image: _U8Image,
    family: _TagFamily = "tag36h11",
    decimation: int | None = None,
) -> Tags:
    """The AprilTags of `family` in an image (grey, or BGR/BGRA converted to grey), sorted by id, with the corners of
    each black square in OpenCV's aruco order and pixel convention (the same numbers as cv2.aruco.ArucoDetector with
    DICT_APRILTAG_36h11, within noise), measured on the square's outer edges; a tag whose edges do not support its
    corners is left out. An empty image raises `InvalidInput`; an image without tags gives an empty result. Quads
    are searched in the image shrunk by `decimation` (1..=8: larger is faster, smaller finds smaller tags; `None`:
    chosen per image, 1 below 960 pixels on the shorter side, 2 at 1920 x 1080) and on the image halved again and
    again, so large tags are found too; corners are measured at full size. Bounds: an image of at most 2^28 pixels
    (65536 a side, as every image argument), a decimation that leaves at most about 2^22 pixels to search
    (`InvalidInput` naming `decimation` and the one that fits otherwise; `None` always fits: the detector takes
    some 70 bytes a searched pixel). The work per frame is bounded too: a level of the search holding more regions
    (black or white, of the detector's threshold) than is left of the frame's budget of 4,096 is not searched, and
    at most 512 decoded candidates have their corners measured (best first, one per id); the result's
    `stopped_early` says when that happened (a cluttered frame: thousands of small squares or tags), never on
    ordinary frames."""

def load_image(path: str | os.PathLike[str]) -> _U8Image:
    """Reads an image file (PNG, PGM/PPM, JPEG, or GIF's first frame) as a `(height, width)`
    uint8 array; colour images are converted to grey with the Rec. 601 luma weights (0.299,
    0.587, 0.114, as OpenCV), 16-bit images are refused. At most 64 MiB of file, 2^28 pixels
    (65536 a side) and 512 MiB to decode; a PNG file's colour profile (iCCP) and text chunks are
    skipped unread."""

def save_image(image: _U8Image, path: str | os.PathLike[str]) -> None:
    """Writes an image as a grey PNG file (a colour array, BGR or BGRA, is written as its grey)."""

def decode_image(data: bytes | bytearray | memoryview | array.array[int] | npt.NDArray[np.uint8],
                 format: Literal["png", "jpeg"] | None = None) -> _U8Image:
    """The (height, width) uint8 grey image of PNG or JPEG bytes (a ROS sensor_msgs/CompressedImage's data), in Rust
    with the GIL released: the declared size is checked against the pixel limit (2^28, 65536 a side) before
    decoding, at most 64 MiB of data and 512 MiB to decode; colour by Rec. 601 luma. `format` "png" or "jpeg"
    refuses the other one (None: either). Empty, unknown, corrupt or truncated data, or 16-bit samples, raise
    InvalidInput; another `format` InvalidInput naming it."""

def to_grey(image: npt.NDArray[np.uint8], order: Literal["rgb", "bgr"] | None = None) -> _U8Image:
    """The (height, width) uint8 grey image of a (height, width, 3) uint8 colour image, or a (height, width, 4) one
    with alpha last (ignored), whose colour channels are in `order` (None: `"rgb"`), by Rec. 601 luma in integer
    arithmetic (OpenCV's COLOR_RGB2GRAY, COLOR_BGR2GRAY, COLOR_RGBA2GRAY, COLOR_BGRA2GRAY to the bit), vectorised
    (AVX2 when the processor has it), in Rust with the GIL released; a non-contiguous array is copied once, a grey
    (height, width) or (height, width, 1) array is returned as a copy. Another shape or dtype raises InvalidInput,
    another order InvalidInput naming `order`. (Every function that takes an image reads colour itself, in OpenCV's
    BGR order.)"""

@final
class Distortion:
    """Lens distortion: OpenCV's coefficients and the model, "plumb_bob" (k1, k2, p1, p2[, k3]),
    "rational_polynomial" (k1, k2, p1, p2, k3, k4, k5, k6) or "equidistant", OpenCV's fisheye
    (cv2.fisheye, Kannala-Brandt: k1, k2, k3, k4). Without a model, 4 or 5 coefficients are
    plumb_bob and 8 rational_polynomial: a fisheye needs model="equidistant"."""

    def __new__(
        cls,
        coefficients: _ArrayLike,
        model: Literal["plumb_bob", "rational_polynomial", "equidistant"] | None = None,
    ) -> Distortion: ...
    @property
    def model(self) -> Literal["plumb_bob", "rational_polynomial", "equidistant"]:
        """"plumb_bob", "rational_polynomial" or "equidistant"."""
    @property
    def coefficients(self) -> _F64Array:
        """The coefficients in OpenCV's order, a new (5,), (8,) or (4,) (equidistant) array."""
    @property
    def max_angle(self) -> float:
        """The largest angle from the optical axis (radians) the model images one-to-one, not
        included: for equidistant its fold (where d theta_d / d theta reaches 0) or pi,
        whichever comes first; pi / 2 for the others (the half-space in front of the camera)."""
    def __eq__(self, other: object, /) -> bool: ...

_DistortionLike = Union[Distortion, _ArrayLike]

def distort_points(pixels: _ArrayLike, K: _IntrinsicsLike, distortion: _DistortionLike) -> _F64Array:
    """Distorts pixels (n, 2) of the ideal pinhole image: `K d(K^-1 p)`; K may have skew. Raises for a point at or
    beyond an equidistant lens's fold."""

def undistort_points(
    pixels: _ArrayLike, K: _IntrinsicsLike, distortion: _DistortionLike, tol: float = 1e-10, max_iter: int = 50
) -> _F64Array:
    """Undistorts pixels (n, 2) by Newton's method, the inverse of `distort_points`, to `tol` pixels within `max_iter`
    iterations (for equidistant, Newton's method on the angle theta). Raises for a pixel beyond the image of the fold,
    and for an equidistant pixel whose ray is 90 degrees or more from the axis (no pinhole pixel: see `undistort_rays`)."""

def distort_rays(rays: _ArrayLike, K: _IntrinsicsLike, distortion: _DistortionLike) -> _F64Array:
    """Distorts rays (n, 3) of the camera frame into pixels (n, 2): for equidistant `K m_d` with
    `m_d = theta_d (X, Y) / sqrt(X^2 + Y^2)`, `theta` the ray's angle from the axis, which images rays beyond 90
    degrees while `theta < max_angle`; for the others `K d(X/Z, Y/Z)`, which needs `Z > 0`."""

def undistort_rays(
    pixels: _ArrayLike, K: _IntrinsicsLike, distortion: _DistortionLike, tol: float = 1e-10, max_iter: int = 50
) -> _F64Array:
    """The unit rays (n, 3) of distorted pixels (n, 2), the inverse of `distort_rays`: for equidistant Newton's method
    on theta (rays beyond 90 degrees have Z < 0); for the others `undistort_points`' normalised point, normalised."""

@final
class Calibration:
    """A camera calibration read from a file: intrinsics, distortion and image size."""

    @property
    def intrinsics(self) -> Intrinsics:
        """The camera matrix as `Intrinsics` (no skew)."""
    @property
    def distortion(self) -> Distortion:
        """The lens distortion."""
    @property
    def image_size(self) -> tuple[int, int] | None:
        """(width, height) in pixels, or None when the file does not give it."""

def load_calibration(path: str | os.PathLike[str]) -> Calibration:
    """Reads a calibration file: ROS camera_info YAML, OpenCV FileStorage YAML or XML (a regular
    file of at most 1 MiB; no YAML aliases)."""

def exp_twist(twist: _ArrayLike, dt: float = 1.0) -> _F64Array:
    """The 4x4 rigid motion of holding the camera twist `(vx, vy, vz, wx, wy, wz)` (camera frame)
    for `dt` seconds: the next pose is `pose @ exp_twist(twist, dt)`."""

def pose_from_position_thetau(position: _ArrayLike, thetau: _ArrayLike) -> _F64Array:
    """The 4x4 pose with camera centre `position` (metres, F*) and theta-u rotation `thetau`
    (radians, F*)."""

def thetau_from_pose(pose: _ArrayLike) -> tuple[_F64Array, _F64Array]:
    """`(position (3,), thetau (3,))` of a 4x4 pose: the camera centre and the theta-u rotation
    vector (radians, theta in [0, pi])."""

def thetau_from_rotations(rotations: _ArrayLike) -> _F64Array:
    """The theta-u vectors (rad, theta in [0, pi]) of rotation matrices `(n, 3, 3)`, shape `(n, 3)` (OpenCV's Rodrigues
    vectors); `InvalidInput` naming the matrix for one with a non-finite entry or that is not a rotation
    (orthonormal, det +1, within 1e-6)."""

def twist_adjoint(pose: _ArrayLike) -> _F64Array:
    """The 6x6 twist transform (adjoint) of a pose `(R, t)` (4x4): a twist `(v, w)` in the pose's
    frame to the same motion's twist in the parent frame, `(R v + t x R w, R w)`; for the
    camera's pose in the end effector's frame, the camera twist as the end effector's. The
    rotation block and translation are used as given; the last row is not read."""

@final
class IkSolution:
    """A solution of [`ik`]: the joints (radians; metres for prismatic joints) and how far their
    pose is from the target."""

    @property
    def joints(self) -> _F64Array:
        """Joint positions (rad; m for prismatic joints), base to end-effector."""
    @property
    def position_residual(self) -> float:
        """Distance between the reached and the target positions, metres."""
    @property
    def rotation_residual(self) -> float:
        """Angle between the reached and the target orientations, radians."""
    @property
    def iterations(self) -> int:
        """Iterations of the seed that converged."""
    @property
    def seed(self) -> int:
        """The seed that converged: 0 for the given one (or the middle of the limits), then the
        spread seeds in order."""

def fk(arm: str, joints: _ArrayLike) -> _F64Array:
    """The 4x4 pose of the end-effector of the built-in `arm` ('ur5', 'ur5e': `tool0`, 'panda': `panda_hand_tcp`) in the arm's
    base frame (its URDF root link: `base_link`, `panda_link0`) at `joints` (rad), one value per joint within the
    joint limits (InvalidInput naming the first joint outside)."""

def damped_least_squares(
    jacobian: _ArrayLike, twist: _ArrayLike, damping: float = ..., null_space: _ArrayLike | None = None
) -> _F64Array:
    """Joint velocities (n,) that give `twist` (6,: vx, vy, vz, wx, wy, wz) where the arm's Jacobian
    is `jacobian` (6, n: rows in the twist's frame, a column per joint), by the kinematic arm's
    damped least squares: the damping grows as the smallest singular value of the Jacobian falls
    below `damping`; with more than six joints `null_space` (n,) is added projected on the
    Jacobian's null space. For a Jacobian from elsewhere (MuJoCo's `mj_jacSite`)."""

def ik(arm: str, pose: _ArrayLike, seed: _ArrayLike | None = None) -> IkSolution:
    """Joints within the limits of the built-in `arm` ('ur5', 'ur5e', 'panda') that put its end-effector at `pose`: a 4x4
    float64 rigid motion of the end-effector frame ('ur5', 'ur5e': `tool0`, 'panda': `panda_hand_tcp`) in the arm's base
    frame (the URDF root link), as :func:`fk` returns. Damped least squares (Levenberg-Marquardt, Sugihara 2011)
    projected on the joint limits, from `seed` (one value per joint; default the middle of the limits), then from up
    to 63 spread seeds until one converges to 1e-10 m and 1e-10 rad. A redundant arm (the Panda) returns one of its
    solutions. Raises InvalidInput (kind 'unreachable', argument 'pose', `residual` the best position residual) when
    no seed reaches the pose."""

_HandEyeMethod = Literal["tsai", "park", "daniilidis"]
_HandEyeSetup = Literal["eye_in_hand", "eye_to_hand"]

@final
class HandEyeCalibration:
    """A hand-eye calibration: the camera-to-gripper (eye_in_hand) or camera-to-base (eye_to_hand)
    transform and its diagnostics.

    For stations i < j the gripper motion A = G_j^-1 G_i and the camera motion B = C_j C_i^-1
    satisfy A X = X B (eye_to_hand: A = G_j G_i^-1); every pair is a motion (as in OpenCV)."""

    @property
    def matrix(self) -> _F64Array:
        """The 4x4 transform X: camera-to-gripper (eye_in_hand) or camera-to-base (eye_to_hand),
        the camera frame in the gripper frame or in the base frame."""
    @property
    def setup(self) -> _HandEyeSetup:
        """Where the camera is: 'eye_in_hand' (on the flange; `matrix` is camera-to-gripper) or
        'eye_to_hand' (fixed in the base frame; `matrix` is camera-to-base)."""
    @property
    def method(self) -> _HandEyeMethod:
        """The method: 'tsai', 'park' or 'daniilidis'."""
    @property
    def residuals(self) -> _F64Array:
        """(m, 2): the residual of A X = X B for every pair of stations i < j (order of `pairs`):
        rotation in degrees, translation in metres (eye_to_hand: A = G_j G_i^-1, in the base frame)."""
    @property
    def pairs(self) -> npt.NDArray[np.int64]:
        """(m, 2): the stations (i, j), i < j, of each residual row."""
    @property
    def axis_spread_deg(self) -> float:
        """The spread of the rotation axes of the gripper motions, degrees: 2 atan(sqrt(l2/l1)) of the eigenvalues of
        the mean u u^T of their unit axes (the angle between the axes for two motions; 0 when all are parallel, 90
        for axes spread evenly)."""
    @property
    def axis_eigenvalues(self) -> _F64Array:
        """(3,): the eigenvalues of the mean u u^T of the motions' unit axes, descending, sum 1."""
    @property
    def rotating_motions(self) -> int:
        """The number of gripper motions that rotate by 0.1 degree or more."""
    @property
    def motions_used(self) -> int:
        """The number of motions the method used (Tsai-Lenz leaves out those rotating outside 17.3-116.4 degrees, as
        OpenCV does)."""
    @property
    def rms_rotation_deg(self) -> float:
        """The RMS of the rotation residuals, degrees."""
    @property
    def rms_translation_m(self) -> float:
        """The RMS of the translation residuals, metres."""
    @property
    def max_rotation_deg(self) -> float:
        """The largest rotation residual, degrees."""
    @property
    def max_translation_m(self) -> float:
        """The largest translation residual, metres."""

@final
class HandEyeAgreement:
    """Every method's calibration on the same poses, and how far apart they are."""

    @property
    def calibrations(self) -> dict[str, HandEyeCalibration]:
        """{method: calibration} of the methods that succeeded ('tsai', 'park', 'daniilidis')."""
    @property
    def failures(self) -> dict[str, str]:
        """{method: reason} of the methods that refused the poses."""
    @property
    def setup(self) -> _HandEyeSetup:
        """Where the camera is: 'eye_in_hand' or 'eye_to_hand' (what every calibration's `matrix` is)."""
    @property
    def max_rotation_deg(self) -> float:
        """The largest rotation between two methods' transforms, degrees."""
    @property
    def max_translation_m(self) -> float:
        """The largest distance between two methods' translations, metres."""

def calibrate_hand_eye(
    gripper_poses: _ArrayLike,
    target_poses: _ArrayLike,
    method: _HandEyeMethod | str = "tsai",
    setup: _HandEyeSetup | str = "eye_in_hand",
) -> HandEyeCalibration:
    """The camera-to-gripper (setup='eye_in_hand': camera on the flange, target fixed) or
    camera-to-base (setup='eye_to_hand': camera fixed, target on the flange) transform from
    (n, 4, 4) gripper-to-base `gripper_poses` and target-to-camera `target_poses` (OpenCV's
    calibrateHandEye convention), by `method` ('tsai', 'park' or 'daniilidis').

    `gripper_poses`: (n, 4, 4) gripper-to-base poses reported by the robot; `target_poses`:
    (n, 4, 4) target-to-camera poses (e.g. from solvePnP); `method`: 'tsai' (default), 'park' or
    'daniilidis'; `setup`: 'eye_in_hand' (default) or 'eye_to_hand' (the gripper poses are
    inverted, base-to-gripper, and the same method runs). Raises InvalidInput for a pose that is
    not a rigid transform (naming the argument and the pose), an unknown method or setup, and
    DegenerateGeometry (kind 'degenerate_motion') for fewer than 3 poses, no rotation, or
    rotations about (nearly) parallel axes only."""

def compare_hand_eye_methods(
    gripper_poses: _ArrayLike, target_poses: _ArrayLike, setup: _HandEyeSetup | str = "eye_in_hand"
) -> HandEyeAgreement:
    """Runs every method on the same poses, for `setup` 'eye_in_hand' or 'eye_to_hand': their
    calibrations and how far apart they are."""
