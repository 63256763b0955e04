"""The tag target's settings as command options, shared by ``vsinv replay`` and ``vsinv
invariance`` (``--target tags``): each is a keyword argument of :class:`vsinv.ImageServo` and
:func:`vsinv.vision.detect_tags` of the same name (``tag_ids`` is ``--tag-ids``), stated once here.
Their values are checked by the library, whose errors name the argument; a command renames
it to the option (:data:`TAG_OPTION_NAMES` with :func:`vsinv.cli_tracker.named_as_options`)."""

from __future__ import annotations

import argparse
from typing import Any

from ._core import TAG_FAMILIES

__all__ = ["TAG_OPTION_NAMES", "add_tag_options", "tag_options"]

#: The keyword arguments an error may name, and the options that give them.
TAG_OPTION_NAMES = {"family": "--family", "tag_ids": "--tag-ids", "decimation": "--decimation"}


def add_tag_options(parser: Any, scope: str = "tags: ") -> None:
    """Adds the tag target's options to a command; ``scope`` starts each help text."""
    parser.add_argument("--family", default="tag36h11", help=f"{scope}the AprilTag family, one of {', '.join(TAG_FAMILIES)} (default tag36h11)")
    parser.add_argument("--tag-ids", metavar="I,J,...", help=f"{scope}the tags to follow (default: every tag decoded in REF)")
    parser.add_argument(
        "--decimation", metavar="D", type=int,
        help=f"{scope}the quad search's decimation, 1..=8 (default: the detector's): larger is faster and finds "
        "large tags, smaller finds small ones",
    )


def tag_options(args: argparse.Namespace) -> dict[str, Any]:
    """The keyword arguments of the options of :func:`add_tag_options` (those given)."""
    options: dict[str, Any] = {"family": args.family}
    if args.tag_ids is not None:
        try:
            options["tag_ids"] = [int(t) for t in args.tag_ids.split(",")]
        except ValueError:
            raise ValueError(f"--tag-ids: expected tag ids I,J,..., got {args.tag_ids!r}") from None
    if args.decimation is not None:
        options["decimation"] = args.decimation
    return options
