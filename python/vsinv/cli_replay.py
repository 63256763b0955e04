"""``vsinv replay REF FRAMES``: what the servo would command, frame by frame, on recorded
images (a folder or a video file), with the reference image taken by any camera."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from ._core import LAW_OPTIONS, TARGETS, Intrinsics, InvalidInput, VsinvError, check_law_option, load_calibration
from .cli_features import FEATURE_OPTION_NAMES, add_feature_options, feature_options
from .cli_tags import TAG_OPTION_NAMES, add_tag_options, tag_options
from .cli_tracker import add_tracker_options, named_as_options, tracker_options
from .images import read_points
from .replaying import read_depths, replay

__all__ = ["add_replay_command", "cmd_replay"]

#: The targets the command can follow (``vsinv.TARGETS``, declared once in the vision layer).
TARGET_NAMES = tuple(t["name"] for t in TARGETS)

#: The replay's own defaults of law options (the table's otherwise): a gentler gain for
#: frames that were recorded, not commanded.
_REPLAY_DEFAULTS = {"gain": 0.5}


def _flag(name: str) -> str:
    """A law option's command option: ``max_linear_speed`` is ``--max-linear-speed``."""
    return "--" + name.replace("_", "-")


#: ImageServo's keyword arguments that an error may name, and the options that give them.
_OPTION_NAMES = {
    "reference_points": "--points",
    "first_points": "--first-points",
    **TAG_OPTION_NAMES,
    **FEATURE_OPTION_NAMES,
    **{o["name"]: _flag(o["name"]) for o in LAW_OPTIONS},
}


def _triple(text: str) -> tuple[float, float, float]:
    try:
        a, b, c = (float(x) for x in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected three numbers L0,LINF,SLOPE, got {text!r}") from None
    return a, b, c


def _add_law_options(p: argparse.ArgumentParser) -> None:
    """A command option per law option of ``vsinv.laws.LAW_OPTIONS`` (declared once, in the servo
    layer); unset: the law's default."""
    group = p.add_argument_group("law options", "each read by the laws named (unset: the law's default)")
    for o in LAW_OPTIONS:
        name, kind = o["name"], o["kind"]
        default = _REPLAY_DEFAULTS.get(name)
        shown = default if default is not None else o["default"]
        unit = f", {o['unit']}" if o["unit"] else ""
        text = f"({', '.join(o['laws'])}) {o['doc']}{unit} ({'unset' if shown is None else shown})"
        kw: dict[str, Any] = {"dest": name, "default": default, "help": text.replace("%", "%%")}
        if kind == "number":
            kw.update(type=float, metavar="X")
        elif kind == "flag":
            kw.update(action=argparse.BooleanOptionalAction)
        elif kind == "choice":
            kw.update(choices=o["choices"])
        else:
            kw.update(type=_triple, metavar="L0,LINF,SLOPE")
        group.add_argument(_flag(name), **kw)


def add_replay_command(sub: Any) -> None:
    """Adds ``replay`` to the subcommand parsers."""
    p = sub.add_parser(
        "replay",
        help="print (and plot) what the servo would command on each recorded frame",
        description="Find the target in the reference image (any camera), then in every frame of FRAMES (a folder "
        "of images in name order, or a video file with the extra vsinv[video]), and print per frame the points "
        "found, the image and invariant errors, the verdict and the twist the servo session would command. "
        "Nothing moves: each frame is what the camera saw.",
    )
    p.add_argument("reference", metavar="REF", type=Path, help="the reference image (PNG, PGM/PPM or JPEG)")
    p.add_argument("frames", metavar="FRAMES", type=Path, help="a folder of images or a video file")
    what = "; ".join(f"{t['name']}: {t['doc']}" for t in TARGETS)
    p.add_argument("--target", choices=TARGET_NAMES, default="dots", help=f"what to follow ({what}) (dots)")
    p.add_argument("--points", metavar="CSV", type=Path, help="dots: approximate positions in REF (u, v columns)")
    p.add_argument("--first-points", metavar="CSV", type=Path, help="dots: approximate positions in the first frame (default: those found in REF)")
    add_tag_options(p)
    add_feature_options(p)
    camera = p.add_mutually_exclusive_group(required=True)
    camera.add_argument("--calibration", metavar="FILE", type=Path, help="the servo camera's calibration (K_hat and lens): ROS or OpenCV YAML/XML")
    camera.add_argument("--K-hat", metavar="FX,FY,U0,V0", help="the servo camera's intrinsics K_hat, pixels (no lens distortion)")
    p.add_argument("--reference-calibration", metavar="FILE", type=Path, help="the reference camera's calibration, to undistort REF's points")
    p.add_argument("--law", choices=("invariant", "ibvs", "none"), default="invariant", help="the control law (invariant)")
    p.add_argument("--reference-depths", metavar="CSV", type=Path, help="depths of the points at the reference pose, metres (z column)")
    p.add_argument("--depth", metavar="Z", type=float, help="one depth for every point, metres (IBVS; the invariant law needs --reference-depths)")
    _add_law_options(p)
    add_tracker_options(p, "dots: ")
    p.add_argument("--out", metavar="DIR", type=Path, help="write replay.csv and replay.png to DIR")
    p.add_argument("--max-frames", metavar="N", type=_positive_int, help="read at most N frames (default: all)")


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}")
    return value


def _intrinsics(text: str) -> Intrinsics:
    try:
        fx, fy, u0, v0 = (float(x) for x in text.split(","))
    except ValueError:
        raise ValueError(f"--K-hat: expected four numbers FX,FY,U0,V0, got {text!r}") from None
    return Intrinsics(fx, fy, u0, v0)


def _law_options(args: argparse.Namespace) -> dict[str, Any]:
    """The law options given, each checked (kind, range; the error names the command option);
    a replay default only for the laws that read it, an option given for another law is left
    for the session to refuse by name."""
    options: dict[str, Any] = {}
    for o in LAW_OPTIONS:
        name = o["name"]
        value = getattr(args, name)
        if value is None or (value == _REPLAY_DEFAULTS.get(name) and args.law not in o["laws"]):
            continue
        try:
            check_law_option(name, value)
        except InvalidInput as e:
            raise InvalidInput(f"{_flag(name)}: {getattr(e, 'reason', None) or e}") from None
        options[name] = value
    return options


def _options(args: argparse.Namespace) -> dict[str, Any]:
    """The ImageServo keyword arguments the command's options give."""
    options: dict[str, Any] = {"law": args.law, **_law_options(args)}
    if args.calibration is not None:
        calibration = load_calibration(args.calibration)
        options["distortion"] = calibration.distortion
    if args.reference_calibration is not None:
        ref = load_calibration(args.reference_calibration)
        options["reference_K"], options["reference_distortion"] = ref.intrinsics, ref.distortion
    depths = read_depths(args.reference_depths)
    if depths is not None:
        options["reference_depths"] = depths
    elif args.depth is not None:
        options["depths"] = args.depth
    if args.target == "dots":
        if args.points is None:
            raise ValueError("--points: --target dots needs the dots' approximate positions in REF")
        options["reference_points"] = read_points(args.points)
        if args.first_points is not None:
            options["first_points"] = read_points(args.first_points)
        options["tracker"] = tracker_options(args)
    elif args.target == "tags":
        options.update(tag_options(args))
    else:
        options.update(feature_options(args))
    return options


def _too_few_for_the_invariant_law(error: VsinvError) -> str:
    """What to do when the target has too few points for the invariant law (a 5-dot target such
    as ViSP's mire-2): the law needs 6 points not on one plane (sec. 4.1: each point beyond the
    three of the basis gives two independent rows, and five dof need five rows)."""
    needed, count = getattr(error, "needed", None) or 6, getattr(error, "count", None)
    given = f"the target gives {count}" if count is not None else str(error)
    return (
        f"--law invariant: needs at least {needed} points not on one plane (the paper's sec. 4.1: three "
        f"basis points and three more control five dof), {given}. Use --law ibvs with --depth Z (classic "
        "IBVS: 4 points or more, with the servo camera's calibration), or a target with 6 or more points "
        "in relief (for instance --target tags with tags on two or more faces of a box)."
    )


def cmd_replay(args: argparse.Namespace) -> int:
    k_hat = load_calibration(args.calibration).intrinsics if args.calibration is not None else _intrinsics(args.K_hat)
    try:
        result = replay(args.reference, args.frames, k_hat, args.target, args.max_frames, **_options(args))
    except VsinvError as e:
        if getattr(e, "kind", None) == "too_few_points" and args.law == "invariant":
            raise type(e)(_too_few_for_the_invariant_law(e)) from None
        raise named_as_options(e, _OPTION_NAMES) from None
    print(result.table())
    lost = int((~result.found).sum())
    print(f"{len(result.names)} frames, {result.found.shape[1]} points; {lost} point-frames not found")
    if args.out is not None:
        from .plots import _save

        args.out.mkdir(parents=True, exist_ok=True)
        paths = [result.write_csv(args.out / "replay.csv"), _save(result.plot(), args.out, "replay.png")]
        print(f"wrote {len(paths)} files to {args.out}:")
        for path in paths:
            print(f"  {path}")
    if lost:
        print("vsinv replay: some points were not found in some frames (not visible to the servo there)", file=sys.stderr)
        return 1
    return 0

