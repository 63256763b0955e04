"""The keypoint target's settings as command options (``vsinv replay --target features``): each is
a keyword argument of :class:`vsinv.ImageServo` of the same name (``max_points`` is
``--max-points``), its meaning and default read from the target's entry of ``vsinv._core.TARGETS``
(declared once in the vision layer). Their values are checked by the library, whose errors name
the argument; a command renames it to the option (:data:`FEATURE_OPTION_NAMES` with
:func:`vsinv.cli_tracker.named_as_options`)."""

from __future__ import annotations

import argparse
from typing import Any

from ._core import TARGETS

__all__ = ["FEATURE_OPTION_NAMES", "add_feature_options", "feature_options"]

#: The keypoint target's keyword arguments, as ``TARGETS`` declares them.
_ARGS = {a["name"]: a for t in TARGETS if t["name"] == "features" for a in t["args"]}

#: The keyword arguments an error may name, and the options that give them.
FEATURE_OPTION_NAMES = {name: "--" + name.replace("_", "-") for name in _ARGS}


def _help(name: str, scope: str) -> str:
    arg = _ARGS[name]
    default = f" (default {arg['default']})" if arg.get("default") is not None else ""
    return f"{scope}{arg['doc']}{default}"


def add_feature_options(parser: Any, scope: str = "features: ") -> None:
    """Adds the keypoint target's options to a command; ``scope`` starts each help text."""
    parser.add_argument("--max-points", metavar="N", type=int, help=_help("max_points", scope))
    parser.add_argument("--min-tracked", metavar="N", type=int, help=_help("min_tracked", scope))
    parser.add_argument("--point-ids", metavar="I,J,...", help=_help("point_ids", scope))


def feature_options(args: argparse.Namespace) -> dict[str, Any]:
    """The keyword arguments of the options of :func:`add_feature_options` (those given)."""
    options: dict[str, Any] = {}
    for name in ("max_points", "min_tracked"):
        if getattr(args, name) is not None:
            options[name] = getattr(args, name)
    if args.point_ids is not None:
        try:
            options["point_ids"] = [int(i) for i in args.point_ids.split(",")]
        except ValueError:
            raise ValueError(f"--point-ids: expected point ids I,J,..., got {args.point_ids!r}") from None
    return options
