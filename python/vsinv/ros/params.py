"""The bridge's ROS parameters: their table (name, type, default, meaning) and their parsing
into a :class:`BridgeConfig`, refusing an unknown name, a wrong type or a bad value at start
with :class:`vsinv.InvalidInput` naming the parameter. Pure Python: no ROS needed.

The names of the image pipeline's options are :class:`vsinv.ImageServo`'s keyword arguments
(``gain``, ``reference_points``, ``stop.max_iterations``, ...), so that its refusals name the
ROS parameter too. ROS parameters have no 2-d arrays: point lists are flat ``[u0, v0, u1, v1,
...]`` or a CSV file (``u, v`` columns; ``z`` for depths).
"""

from __future__ import annotations

import array
import difflib
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping, Optional, Sequence, cast

import numpy as np
import numpy.typing as npt

from .._core import LAW_OPTIONS, TARGETS, TRACKER_SETTINGS, Distortion, Intrinsics, InvalidInput, check_law_option, load_calibration
from .conversions import hand_eye_matrix, intrinsics_from_numbers

if TYPE_CHECKING:
    from .._core import _TargetName

__all__ = ["PARAMETERS", "Parameter", "BridgeConfig", "parse_parameters", "parameter_help"]


@dataclass(frozen=True)
class Parameter:
    """One ROS parameter: its name, type (str, float, int, bool, floats, ints), default (None:
    unset) and meaning."""

    name: str
    kind: str
    default: Any
    doc: str
    choices: tuple[str, ...] = ()


#: The ROS type of each kind of law option.
_ROS_KINDS = {"number": "float", "flag": "bool", "choice": "str", "adaptive_gain": "floats"}


def _law_parameters() -> tuple[Parameter, ...]:
    """The laws' options (``vsinv.laws.LAW_OPTIONS``, declared once in the servo layer) as
    parameters of the same names; unset: the law's default."""
    out = []
    for o in LAW_OPTIONS:
        unit = f", {o['unit']}" if o["unit"] else ""
        form = " as [lambda_0, lambda_inf, lambda'_0]" if o["kind"] == "adaptive_gain" else ""
        default = "" if o["default"] is None else f"; unset: {o['default']!r}"
        doc = f"({', '.join(o['laws'])}) {o['doc']}{form}{unit}{default}"
        out.append(Parameter(o["name"], _ROS_KINDS[o["kind"]], None, doc, tuple(o["choices"])))
    return tuple(out)


#: The ROS type of each kind of target argument (points: a flat list, or ``NAME_file``).
_ROS_TARGET_KINDS = {"points": "floats", "choice": "str", "ids": "ints", "count": "int"}

#: The ROS type of each kind of tracker setting.
_ROS_SETTING_KINDS = {"number": "float", "count": "int", "choice": "str"}


def _tracker_parameters(name: str, scope: str) -> tuple[Parameter, ...]:
    """The dot tracker's settings (``vsinv.vision.TRACKER_SETTINGS``, declared once in the vision
    layer), one parameter ``NAME.KEY`` each; unset: the tracker's default. The values are
    checked by ImageServo (its messages), not here: the choices are in the text only."""
    out = []
    for s in TRACKER_SETTINGS:
        unit = f", {s['unit']}" if s["unit"] else ""
        choices = f" ({', '.join(s['choices'])})" if s["choices"] else ""
        doc = f"{scope}the tracker's {s['doc']}{choices}{unit}; unset: {s['default']!r}"
        out.append(Parameter(f"{name}.{s['name']}", _ROS_SETTING_KINDS[s["kind"]], None, doc))
    return tuple(out)


def _arg_parameters(target: str, a: dict[str, Any]) -> tuple[Parameter, ...]:
    """The parameters of one target argument of ``vsinv.TARGETS`` (same name; ``NAME_file`` too
    for points; ``NAME.KEY`` per setting of the tracker)."""
    scope, name, kind = f"{target}: ", a["name"], a["kind"]
    if kind == "tracker":
        return _tracker_parameters(name, scope)
    doc = scope + a["doc"]
    if kind == "count":
        doc += f", {a['min']}..={a['max']}"
    if kind == "points":
        flat = Parameter(name, "floats", None, doc + ", flat [u0, v0, u1, v1, ...]")
        return flat, Parameter(f"{name}_file", "str", None, f"{scope}the same as a CSV file with u, v columns")
    return (Parameter(name, _ROS_TARGET_KINDS[kind], a["default"], doc),)


def _target_parameters() -> tuple[Parameter, ...]:
    """The target (``vsinv.TARGETS``, declared once in the vision layer) and each target's
    arguments as parameters of the same names."""
    names = tuple(t["name"] for t in TARGETS)
    what = "; ".join(f"{t['name']}: {t['doc']}" for t in TARGETS)
    out = [Parameter("target", "str", "tags", f"what to servo on ({what})", names)]
    for t in TARGETS:
        for a in t["args"]:
            out.extend(_arg_parameters(t["name"], a))
    return tuple(out)


def _target_of(parameter: str) -> Optional[dict[str, Any]]:
    """The argument of a target a parameter gives (None: not a target's)."""
    for t in TARGETS:
        for a in t["args"]:
            if parameter == a["name"] or parameter == f"{a['name']}_file" or parameter.startswith(f"{a['name']}."):
                return {"target": t["name"], **a}
    return None


_P = Parameter
#: Every parameter the node reads, in the order ``vsinv-ros --help`` lists them.
PARAMETERS: tuple[Parameter, ...] = (
    # the reference and the target
    _P("reference_image", "str", None, "the reference image file (PNG, PGM/PPM, JPEG), taken by any camera; required"),
    _P("reference_calibration", "str", None, "the reference camera's calibration file (ROS/OpenCV YAML), to undistort its points"),
    _P("reference_K", "floats", None, "the reference camera's intrinsics [fx, fy, u0, v0] or 3x3 row-major (instead of reference_calibration)"),
    _P("reference_distortion", "floats", None, "the reference camera's distortion (OpenCV order k1, k2, p1, p2[, k3...]); needs reference_K"),
    *_target_parameters(),
    # the servo camera
    _P("K_hat", "floats", None, "the servo camera's intrinsics [fx, fy, u0, v0] or 3x3 row-major (unset: from CameraInfo)"),
    _P("distortion", "floats", None, "the servo camera's distortion with K_hat (OpenCV order); unset: none"),
    _P("calibration", "str", None, "the servo camera's calibration file (ROS camera_info or OpenCV YAML) instead of CameraInfo"),
    _P("image_rectified", "bool", False, "the images are rectified: K_hat from CameraInfo's P, no distortion"),
    # the control law (vsinv.Servo's options)
    _P("law", "str", "invariant", "the control law", ("invariant", "ibvs", "none")),
    _P("reference_depths", "floats", None, "the points' depths at the reference pose, metres, in the points' order"),
    _P("reference_depths_file", "str", None, "the same as a CSV file with a z column"),
    _P("depth", "float", None, "one depth for every point, metres (IBVS)"),
    _P("depths", "str", None, "the depth source: reference or per_step", ("reference", "per_step")),
    _P("basis", "ints", None, "the three points of the invariant basis (unset: chosen)"),
    *_law_parameters(),
    _P("stop.max_iterations", "int", None, "stop after this many images"),
    _P("stop.window", "int", None, "images averaged by the stop rules"),
    _P("stop.pixel_error", "float", None, "converged below this image error, pixels (pixel rule)"),
    _P("stop.invariant_error", "float", None, "converged below this invariant error (invariant rule)"),
    _P("stop.tau21", "float", None, "and below this rz error"),
    _P("stop.max_translation_uncertainty", "float", None, "converged only if the images certify this translation, metres"),
    _P("stop.max_rotation_uncertainty_deg", "float", None, "and this rotation, degrees"),
    _P("stop.reference_pixel_sigma", "float", None, "the reference image's pixel noise, pixels"),
    _P("stop.stall", "bool", None, "the stall rule: end when the error stopped decreasing and the camera is still (unset: on)"),
    _P("stop.stall_window", "int", None, "images the stall rule looks back over"),
    _P("stop.stall_motion", "float", None, "the stall rule's motion over the window, as a fraction of the pose tolerance"),
    _P("stop_rule", "str", None, "the image rule that decides convergence", ("pixel", "invariant")),
    _P("path_samples", "int", None, "path following: images along the path"),
    _P("basis_hold", "int", None, "images a missing basis point is ridden out, the last twist repeated (unset: 3; 0: "
       "change the basis at once)"),
    _P("dt", "float", 1.0 / 30.0, "the camera period, seconds (the path's time step)"),
    # the output
    _P("output_frame", "str", "camera", "the twist's frame: the camera's optical frame, or the end effector's through hand_eye", ("camera", "end_effector")),
    _P("camera_frame", "str", "", "the camera optical frame's name: the twist's frame_id with output_frame camera (required "
       "then), and the frame_id images must carry (empty: the first image's, with output_frame end_effector)"),
    _P("end_effector_frame", "str", "", "the end effector frame's name (output_frame end_effector)"),
    _P("hand_eye", "floats", None, "the camera pose in the end effector frame: 4x4 row-major, or [x, y, z, qx, qy, qz, qw]"),
    _P("watchdog_timeout", "float", 0.1, "publish a zero twist and stop when no image came for this long, seconds "
       "(MoveIt Servo's incoming_command_timeout, 0.1 s); changed at once by a parameter set"),
    _P("autostart", "bool", False, "start servoing at the first image (otherwise call the start service)"),
    _P("publish_annotated", "bool", True, "publish the image with the points found"),
    _P("image_topic", "str", "image", "sensor_msgs/Image in (mono8, rgb8, bgr8, rgba8 or bgra8)"),
    _P("camera_info_topic", "str", "camera_info", "sensor_msgs/CameraInfo in"),
    _P("twist_topic", "str", "~/twist", "geometry_msgs/TwistStamped out (MoveIt Servo: /servo_node/delta_twist_cmds)"),
    _P("status_topic", "str", "~/status", "std_msgs/String out: the status as JSON"),
    _P("annotated_topic", "str", "~/annotated", "sensor_msgs/Image out: rgb8 with the points found"),
) + (
    # the ROS interface: QoS, status (issue 30); separate from the law options above
    _P("image_qos.reliability", "str", "reliable", "the image and CameraInfo subscriptions' reliability (best_effort "
       "loses large images between processes)", ("reliable", "best_effort")),
    _P("image_qos.depth", "int", 1, "the image subscription's history depth (keep last): 1 steps on the newest image"),
    _P("status_period", "float", 1.0, "the status and /diagnostics heartbeat, seconds"),
    _P("image_transport", "str", "raw", "raw: sensor_msgs/Image on image_topic; compressed: sensor_msgs/CompressedImage "
       "(JPEG or PNG, decoded in Rust) on image_topic/compressed", ("raw", "compressed")),
)

_BY_NAME = {p.name: p for p in PARAMETERS}

#: Parameters every ROS 2 node has, which are not the bridge's to parse.
_ROS_OWN = ("use_sim_time", "start_type_description_service")

#: ImageServo's keyword arguments given by a parameter of the same name, besides the laws'
#: options.
_SERVO_SCALARS = ("law", "depths", "stop_rule", "path_samples", "basis_hold", "dt")


@dataclass
class BridgeConfig:
    """The parsed parameters: the reference image, ImageServo's target and options, the lens
    override, the output frame and hand-eye transform, the topics and the watchdog."""

    reference_image: npt.NDArray[np.uint8]
    target: _TargetName
    servo_options: dict[str, Any]
    K_hat: Optional[Intrinsics] = None
    distortion: Optional[Distortion] = None
    image_rectified: bool = False
    output_frame: str = "camera"
    camera_frame: str = ""
    end_effector_frame: str = ""
    hand_eye: Optional[npt.NDArray[np.float64]] = None
    watchdog_timeout: float = 0.1
    image_reliability: str = "reliable"
    image_depth: int = 1
    status_period: float = 1.0
    image_transport: str = "raw"
    autostart: bool = False
    publish_annotated: bool = True
    topics: dict[str, str] = field(default_factory=dict)


def _refuse(name: str, reason: str) -> InvalidInput:
    return InvalidInput(f"parameter {name}: {reason}")


def _typed(p: Parameter, value: Any) -> Any:
    """The value as the parameter's type, or a refusal naming it."""
    number = (int, float, np.integer, np.floating)
    if p.kind == "str" and isinstance(value, str):
        if p.choices and value not in p.choices:
            raise _refuse(p.name, f"expected one of {', '.join(p.choices)}, got {value!r}")
        return value
    if p.kind == "bool" and isinstance(value, (bool, np.bool_)):
        return bool(value)
    if p.kind == "int" and isinstance(value, (int, np.integer)) and not isinstance(value, bool):
        return int(value)
    if p.kind == "float" and isinstance(value, number) and not isinstance(value, bool):
        if not math.isfinite(float(value)):
            raise _refuse(p.name, f"expected a finite number, got {value!r}")
        return float(value)
    if p.kind in ("floats", "ints") and isinstance(value, (list, tuple, array.array, np.ndarray)):
        kind = number if p.kind == "floats" else (int, np.integer)
        items = list(value)
        if all(isinstance(x, kind) and not isinstance(x, bool) for x in items):
            if p.kind == "floats" and not all(math.isfinite(float(x)) for x in items):
                raise _refuse(p.name, "expected finite numbers")
            return tuple(float(x) for x in items) if p.kind == "floats" else tuple(int(x) for x in items)
    expected = {"str": "a string", "bool": "true or false", "int": "an integer", "float": "a number",
                "floats": "an array of numbers", "ints": "an array of integers"}[p.kind]
    raise _refuse(p.name, f"expected {expected}, got {value!r} ({type(value).__name__})")


def _known(values: Mapping[str, Any]) -> dict[str, Any]:
    """The bridge's parameters among ``values``, typed; an unknown name is refused (with the
    closest known names)."""
    out: dict[str, Any] = {}
    for name, value in values.items():
        if name in _ROS_OWN or name.startswith("qos_overrides."):
            continue
        p = _BY_NAME.get(name)
        if p is None:
            close = difflib.get_close_matches(name, _BY_NAME, n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else "; `vsinv-ros --help` lists them"
            raise _refuse(name, f"unknown{hint}")
        if value is not None:
            out[name] = _typed(p, value)
    return out


def _one_of(given: dict[str, Any], *names: str) -> Optional[str]:
    """The one of ``names`` given, None; two given are refused."""
    present = [n for n in names if n in given]
    if len(present) > 1:
        raise _refuse(present[1], f"give either {present[0]} or {present[1]}, not both")
    return present[0] if present else None


def _pairs(name: str, flat: Sequence[float]) -> npt.NDArray[np.float64]:
    if not flat or len(flat) % 2:
        raise _refuse(name, f"expected a flat list of pixel pairs [u0, v0, u1, v1, ...], got {len(flat)} numbers")
    return np.asarray(flat, dtype=float).reshape(-1, 2)


def _file(name: str, text: str) -> Path:
    path = Path(text).expanduser()
    if not path.is_file():
        raise _refuse(name, f"no such file: {text!r}")
    return path


def _points(given: dict[str, Any], name: str) -> Optional[npt.NDArray[np.float64]]:
    """``name`` (flat pairs) or ``name_file`` (CSV), or None."""
    from ..images import read_points

    which = _one_of(given, name, f"{name}_file")
    if which == name:
        return _pairs(name, given[name])
    if which is not None:
        path = _file(which, given[which])
        try:
            return read_points(path)
        except (ValueError, OSError) as e:
            raise _refuse(which, str(e)) from None
    return None


def _lens(given: dict[str, Any], k_name: str, d_name: str, file_name: str) -> tuple[Optional[Intrinsics], Optional[Distortion]]:
    """A camera's intrinsics and distortion from numbers or a calibration file, or (None, None)."""
    which = _one_of(given, k_name, file_name)
    if which == file_name:
        if d_name in given:
            raise _refuse(d_name, f"the distortion comes from {file_name}")
        path = _file(file_name, given[file_name])
        try:
            c = load_calibration(path)
        except InvalidInput as e:
            raise _refuse(file_name, str(e)) from None
        return c.intrinsics, c.distortion
    if which is None:
        if d_name in given:
            raise _refuse(d_name, f"needs {k_name} (the intrinsics it goes with)")
        return None, None
    k = intrinsics_from_numbers(k_name, given[k_name])
    try:
        d = Distortion(list(given[d_name])) if d_name in given else None
    except InvalidInput as e:
        raise _refuse(d_name, str(e)) from None
    return k, d


def _target_options(given: dict[str, Any], explicit: dict[str, Any], target: str) -> dict[str, Any]:
    """ImageServo's arguments of the target (``vsinv.TARGETS``), each from its parameters by its
    kind (another target's, given explicitly, refused)."""
    for name in explicit:
        arg = _target_of(name)
        if arg is not None and arg["target"] != target:
            raise _refuse(name, f"not a parameter of target {target!r}")
    options: dict[str, Any] = {}
    spec = next(t for t in TARGETS if t["name"] == target)
    for a in spec["args"]:
        name, kind = a["name"], a["kind"]
        value: Any
        if kind == "points":
            value = _points(given, name)
        elif kind == "tracker":
            value = {k[len(name) + 1:]: v for k, v in given.items() if k.startswith(f"{name}.")} or None
        elif kind == "ids":
            value = list(given[name]) if name in given else None
        else:
            value = given.get(name)
        if value is None and a["required"]:
            raise _refuse(name, f"target {target!r} needs {a['doc']}")
        if value is not None:
            options[name] = value
    return options


def _law_options(given: dict[str, Any]) -> dict[str, Any]:
    """The laws' options given, each checked against the table (kind, range) by name."""
    options: dict[str, Any] = {}
    for o in LAW_OPTIONS:
        name = o["name"]
        if name not in given:
            continue
        value = given[name]
        if o["kind"] == "adaptive_gain":
            if len(value) != 3:
                raise _refuse(name, "expected [gain at zero, gain at infinity, slope at zero]")
            value = tuple(value)
        try:
            check_law_option(name, value)
        except InvalidInput as e:
            raise _refuse(name, getattr(e, "reason", None) or str(e)) from None
        options[name] = value
    return options


def _servo_options(given: dict[str, Any]) -> dict[str, Any]:
    """The Servo session's keyword arguments."""
    options: dict[str, Any] = {k: given[k] for k in _SERVO_SCALARS if k in given}
    which = _one_of(given, "reference_depths", "reference_depths_file", "depth")
    if which == "reference_depths":
        options["reference_depths"] = list(given[which])
    elif which == "reference_depths_file":
        from ..replaying import read_depths

        path = _file(which, given[which])
        try:
            options["reference_depths"] = read_depths(path)
        except (ValueError, OSError) as e:
            raise _refuse(which, str(e)) from None
    elif which == "depth":
        if "depths" in given:
            raise _refuse("depth", "give either depth (one depth for every point) or depths")
        options["depths"] = given["depth"]
    if "basis" in given:
        if len(given["basis"]) != 3:
            raise _refuse("basis", f"expected three point indices, got {list(given['basis'])}")
        options["basis"] = list(given["basis"])
    options.update(_law_options(given))
    stop = {k[len("stop."):]: v for k, v in given.items() if k.startswith("stop.")}
    if stop:
        options["stop"] = stop
    return options


def _output(given: dict[str, Any], config: BridgeConfig) -> None:
    """The output frame, the hand-eye transform, the watchdog and the topics, into ``config``."""
    config.output_frame = given["output_frame"]
    config.camera_frame = given["camera_frame"]
    config.end_effector_frame = given["end_effector_frame"]
    if config.output_frame == "end_effector":
        if "hand_eye" not in given:
            raise _refuse("hand_eye", "output_frame end_effector needs the camera pose in the end effector frame")
        if not config.end_effector_frame:
            raise _refuse("end_effector_frame", "output_frame end_effector needs the end effector frame's name")
        config.hand_eye = hand_eye_matrix("hand_eye", given["hand_eye"])
    elif "hand_eye" in given:
        raise _refuse("hand_eye", "only used with output_frame end_effector")
    elif not config.camera_frame:
        raise _refuse("camera_frame", "output_frame camera needs the camera optical frame's name (the twist's frame_id)")
    timeout = given["watchdog_timeout"]
    if not timeout > 0.0:
        raise _refuse("watchdog_timeout", f"expected a positive number of seconds, got {timeout}")
    config.watchdog_timeout = timeout
    _interface(given, config)
    for key in ("image", "camera_info", "twist", "status", "annotated"):
        name = f"{key}_topic"
        if not given[name].strip():
            raise _refuse(name, "empty topic name")
        config.topics[key] = given[name]


def _interface(given: dict[str, Any], config: BridgeConfig) -> None:
    """The QoS and the status period, into ``config``."""
    config.image_reliability = given["image_qos.reliability"]
    depth = given["image_qos.depth"]
    if not 1 <= depth <= 100:
        raise _refuse("image_qos.depth", f"expected 1..=100 images, got {depth}")
    config.image_depth = depth
    period = given["status_period"]
    if not 0.01 <= period <= 60.0:
        raise _refuse("status_period", f"expected 0.01..=60 seconds, got {period}")
    config.status_period = period
    config.image_transport = given["image_transport"]


def parse_parameters(values: Mapping[str, Any]) -> BridgeConfig:
    """The configuration from the node's parameter values (name to value; a value of None is
    unset). Raises :class:`vsinv.InvalidInput` naming the first bad parameter."""
    given = {p.name: p.default for p in PARAMETERS if p.default is not None}
    explicit = _known(values)
    given.update(explicit)
    if "reference_image" not in given:
        raise _refuse("reference_image", "required (the reference image file)")
    from .._core import load_image

    path = _file("reference_image", given["reference_image"])
    try:
        reference = load_image(path)
    except InvalidInput as e:
        raise _refuse("reference_image", str(e)) from None
    target = cast("_TargetName", given["target"])
    options = {**_target_options(given, explicit, target), **_servo_options(given)}
    ref_k, ref_d = _lens(given, "reference_K", "reference_distortion", "reference_calibration")
    if ref_k is not None:
        options["reference_K"] = ref_k
        if ref_d is not None:
            options["reference_distortion"] = ref_d
    k_hat, distortion = _lens(given, "K_hat", "distortion", "calibration")
    if k_hat is not None and given["image_rectified"]:
        raise _refuse("image_rectified", "only used with K_hat from CameraInfo (K_hat or calibration is given)")
    config = BridgeConfig(reference, target, options, k_hat, distortion, given["image_rectified"])
    config.autostart, config.publish_annotated = given["autostart"], given["publish_annotated"]
    _output(given, config)
    return config


def parameter_help() -> str:
    """The parameter table, one line a parameter, for ``vsinv-ros --help``."""
    lines = []
    for p in PARAMETERS:
        default = "" if p.default is None else f" (default {p.default!r})"
        choices = f" [{'|'.join(p.choices)}]" if p.choices else ""
        lines.append(f"  {p.name:<34} {p.kind:<6} {p.doc}{choices}{default}")
    return "\n".join(lines)
