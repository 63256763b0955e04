"""The image commands of ``vsinv``: ``render`` (a scenario's views as PNG files with their
dots' CSVs) and ``invariance`` (dots tracked, or tags decoded, through image files: the image
and invariant errors per image, the paper's Fig. 3)."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any, Callable, Optional, Sequence

import numpy as np

from ._core import TARGETS, VsinvError
from .cli_tags import TAG_OPTION_NAMES, add_tag_options, tag_options
from .cli_tracker import add_tracker_options, named_as_options, tracker_options
from .images import InvarianceResult, track_invariance, write_invariance_csv, write_scenario_images
from .tag_invariance import track_tag_invariance

#: The targets the command can follow (``vsinv._core.TARGETS``, declared once in the vision
#: layer), as ``vsinv replay`` reads them.
TARGET_NAMES = tuple(t["name"] for t in TARGETS)

__all__ = ["add_allow_outside_files", "add_image_commands", "cmd_invariance", "cmd_render", "complete", "measurement_summary"]


def add_allow_outside_files(parser: Any) -> None:
    """Adds ``--allow-outside-files`` to a command that reads a scenario."""
    parser.add_argument(
        "--allow-outside-files",
        action="store_true",
        help="let the scenario name files (calibration, robot.urdf) outside its folder: absolute paths, "
        "'..' or symbolic links leading out (refused by default: scenario files are shared)",
    )


def add_image_commands(sub: Any) -> None:
    """Adds ``render`` and ``invariance`` to the subcommand parsers."""
    r = sub.add_parser(
        "render",
        help="write a scenario's reference and start images (PNG) with their dots (CSV)",
        description="Render the reference view (K* at F*) and the start view (K(0) at the start pose) of a scenario "
        "as PNG files, with point CSVs (point,u,v,visible: the true projections of the dots' centres). A stationary "
        "camera (law = \"none\", e.g. vision-zoom) also gets image-K.png for every later image of its run.",
    )
    r.add_argument("scenario", metavar="NAME|FILE", help="a built-in scenario name (see `vsinv list`) or a TOML file")
    r.add_argument("--out", metavar="DIR", type=Path, required=True, help="output directory (created if needed)")
    add_allow_outside_files(r)

    inv = sub.add_parser(
        "invariance",
        help="track dots (or decode tags) through image files and print the image and invariant errors (Fig. 3)",
        description="Detect the reference dots near the approximate positions of --points, track them through the "
        "images in order, and print per image and point the image error ||p - p*|| (pixels) and the invariant "
        "error ||q - q*||. Images from another camera (a lens change) see every dot elsewhere: give the dots' "
        "approximate positions in the first image too (--first-points), in the order of --points, as one clicks "
        "both images in ViSP. With --target tags, the corners of the AprilTags decoded in REF are matched by "
        "identity in every image: no clicks.",
    )
    inv.add_argument("reference", metavar="REF", type=Path, help="the reference image (PNG, PGM/PPM or JPEG)")
    inv.add_argument("images", metavar="IMG", type=Path, nargs="+", help="the images, in tracking order (PNG, PGM/PPM or JPEG)")
    what = "; ".join(f"{t['name']}: {t['doc']}" for t in TARGETS)
    inv.add_argument("--target", choices=TARGET_NAMES, default="dots", help=f"what to follow ({what}) (dots)")
    inv.add_argument("--points", metavar="CSV", type=Path, help="dots: approximate dot positions in REF (u, v columns); required")
    inv.add_argument(
        "--first-points", metavar="CSV", type=Path,
        help="dots: approximate dot positions in the first IMG, in the order of --points (default: those found in REF)",
    )
    inv.add_argument("--basis", metavar="I,J,K", help="the three basis points (default: the widest triangle)")
    add_tag_options(inv)
    add_tracker_options(inv, "dots: ")
    inv.add_argument("--out", metavar="DIR", type=Path, help="write invariance.csv and invariance.png to DIR")


def cmd_render(args: argparse.Namespace) -> int:
    written = write_scenario_images(args.scenario, args.out, allow_outside_files=args.allow_outside_files)
    print(f"wrote {len(written)} files to {args.out}:")
    for path in written:
        print(f"  {path}")
    return 0


def _parse_basis(text: Optional[str]) -> Optional[Sequence[int]]:
    if text is None:
        return None
    try:
        basis = [int(x) for x in text.split(",")]
    except ValueError:
        basis = []
    if len(basis) != 3 or min(basis) < 0:
        raise ValueError(f"--basis: expected three point indices I,J,K, got {text!r}")
    return basis


def _fmt(x: float, spec: str) -> str:
    return "lost" if not math.isfinite(x) else format(x, spec)


def format_invariance(result: InvarianceResult) -> str:
    """A row per point, a column per image: image error (px) / invariant error."""
    n = result.pixels.shape[1]
    lines = [f"basis {list(result.basis)}; image error ||p - p*|| (px) / invariant error ||q - q*||"]
    lines.append("point".ljust(6) + "".join(f"{name[:18]:>20}" for name in result.names))
    for i in range(n):
        cells = [
            f"{_fmt(result.image_error[k, i], '.2f')} / {_fmt(result.invariant_error[k, i], '.1e')}"
            for k in range(len(result.names))
        ]
        lines.append(str(i).ljust(6) + "".join(f"{c:>20}" for c in cells))
    lines.append(measurement_summary(result))
    return "\n".join(lines)


def measurement_summary(result: InvarianceResult) -> str:
    """The largest errors over the measurements that were made, and what was not measured: a
    dot that was not found has no image error, and an image whose basis dots were not all found
    has no invariant error at all."""
    img, q = result.image_error, result.invariant_error
    made_img, made_q = np.isfinite(img), np.isfinite(q)
    lost = int((~result.found).sum())
    if not made_img.any():
        return f"no measurement: {lost} of {result.found.size} dots not found in any image"
    parts = [f"max image error {img[made_img].max():.2f} px over {int(made_img.sum())} of {img.size} dot images"]
    if made_q.any():
        parts.append(f"max invariant error {q[made_q].max():.2e} over {int(made_q.sum())} of {q.size}")
    else:
        parts.append("invariant error not measured (a basis dot was lost in every image)")
    return "; ".join(parts) + f"; {lost} of {result.found.size} dots not found"


def complete(result: InvarianceResult) -> bool:
    """Whether every dot was found in every image (so that every error was measured)."""
    return bool(result.found.all()) and bool(np.isfinite(result.invariant_error).all())


def _track_dots(args: argparse.Namespace, basis: Optional[Sequence[int]]) -> InvarianceResult:
    """Dots: tracked from the clicks of ``--points`` (and ``--first-points``)."""
    if args.points is None:
        raise ValueError("--points: --target dots needs the dots' approximate positions in REF")
    return track_invariance(
        args.reference, args.images, args.points, basis, first_points=args.first_points,
        labels=("--points", "--first-points"), **tracker_options(args),
    )


def _track_tags(args: argparse.Namespace, basis: Optional[Sequence[int]]) -> InvarianceResult:
    """Tags: corners matched by identity, no clicks."""
    for given, option in ((args.points, "--points"), (args.first_points, "--first-points")):
        if given is not None:
            raise ValueError(f"{option}: not an option of --target tags (tags match by identity, no clicks)")
    return track_tag_invariance(args.reference, args.images, basis, **tag_options(args))


def _track_features(args: argparse.Namespace, basis: Optional[Sequence[int]]) -> InvarianceResult:
    """Keypoints: not followed by this command yet (issue 32): refused with the reason."""
    raise ValueError("--target: features is not followed by `vsinv invariance` yet (issue 32); "
                     "`vsinv.vision.match_features` gives the matches of two images")


#: How the command follows each target of ``TARGET_NAMES`` through image files (a test checks
#: every target of the table has one: a new target cannot fall through to another's code).
TRACKERS: dict[str, Callable[[argparse.Namespace, Optional[Sequence[int]]], InvarianceResult]] = {
    "dots": _track_dots,
    "tags": _track_tags,
    "features": _track_features,
}


def _track(args: argparse.Namespace) -> InvarianceResult:
    """The errors of the target of ``--target`` through the images."""
    return TRACKERS[args.target](args, _parse_basis(args.basis))


def cmd_invariance(args: argparse.Namespace) -> int:
    try:
        result = _track(args)
    except VsinvError as e:
        raise named_as_options(e, {"basis": "--basis", **TAG_OPTION_NAMES}) from None
    print(format_invariance(result))
    if args.out is not None:
        from .plots import _save
        from .view_plots import plot_invariance

        args.out.mkdir(parents=True, exist_ok=True)
        paths = [write_invariance_csv(result, args.out / "invariance.csv")]
        paths.append(_save(plot_invariance(result), args.out, "invariance.png"))
        print(f"wrote {len(paths)} files to {args.out}:")
        for path in paths:
            print(f"  {path}")
    if not complete(result):
        print("vsinv invariance: not every dot was found in every image; the missing measurements are marked lost", file=sys.stderr)
        return 1
    return 0
