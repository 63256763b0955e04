"""The dot tracker's settings as command options, shared by ``vsinv invariance`` and ``vsinv
replay``: each of :class:`vsinv.vision.DotTracker`'s keyword arguments is an option of the same name
(``search_radius`` is ``--search-radius``), with the default and the bound of its entry of
``vsinv.vision.TRACKER_SETTINGS`` (declared once in the vision layer), so that a bad value is
refused by argparse naming the option as the user typed it."""

from __future__ import annotations

import argparse
import math
from typing import Any, Callable, Mapping

from ._core import TRACKER_SETTINGS, VsinvError

__all__ = ["POLARITIES", "add_tracker_options", "named_as_options", "tracker_options"]

#: The tracker's settings by name (``vsinv.vision.TRACKER_SETTINGS``).
_SETTINGS = {s["name"]: s for s in TRACKER_SETTINGS}

#: The dots' polarities the tracker knows.
POLARITIES: tuple[str, ...] = tuple(_SETTINGS["polarity"]["choices"])

#: DotTracker's defaults (TrackerConfig::default, checked equal to the table in Rust).
_SEARCH_RADIUS: float = _SETTINGS["search_radius"]["default"]
_MAX_SEARCH_RADIUS: float = _SETTINGS["max_search_radius"]["default"]
_MIN_AREA: int = _SETTINGS["min_area"]["default"]
_MAX_AREA_RATIO: float = _SETTINGS["max_area_ratio"]["default"]


def _bounded(name: str) -> Callable[[str], float]:
    """The argparse type of the number setting ``name``: its table's bound."""
    s = _SETTINGS[name]
    return _finite_at_least(float(s["min"]), bool(s["min_open"]))


def _finite_at_least(low: float, strict: bool) -> Callable[[str], float]:
    """An argparse type: a finite number >= low (> low when strict)."""

    def parse(text: str) -> float:
        try:
            x = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
        if not math.isfinite(x) or x < low or (strict and x == low):
            bound = f"> {low:g}" if strict else f">= {low:g}"
            raise argparse.ArgumentTypeError(f"expected a finite number {bound}, got {text!r}")
        return x

    return parse


def _count(text: str) -> int:
    """An argparse type: a whole number >= 0."""
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number of pixels, got {text!r}") from None
    if n < 0:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 0, got {text!r}")
    return n


def add_tracker_options(parser: Any, scope: str = "") -> None:
    """Adds the tracker's options to a command; ``scope`` starts each help text (``"dots: "``
    where the command also follows other targets)."""
    parser.add_argument(
        "--search-radius", metavar="PX", type=_bounded("search_radius"), default=_SEARCH_RADIUS,
        help=f"{scope}tracker window half-side around each dot's prediction, >= 2 ({_SEARCH_RADIUS:g})",
    )
    parser.add_argument(
        "--max-search-radius", metavar="PX", type=_bounded("max_search_radius"), default=None,
        help=f"{scope}largest window while a dot is lost ({_MAX_SEARCH_RADIUS:g}, or --search-radius when larger)",
    )
    parser.add_argument(
        "--polarity", choices=POLARITIES, default=_SETTINGS["polarity"]["default"],
        help=f"{scope}light dots, dark dots, or decided by each image the dots are clicked in (light)",
    )
    parser.add_argument(
        "--min-area", metavar="PX", type=_count, default=_MIN_AREA,
        help=f"{scope}smallest dot, pixels above its threshold ({_MIN_AREA})",
    )
    parser.add_argument(
        "--max-area-ratio", metavar="R", type=_bounded("max_area_ratio"), default=_MAX_AREA_RATIO,
        help=f"{scope}largest change of a dot's area from image to image, > 1 ({_MAX_AREA_RATIO:g})",
    )


def tracker_options(args: argparse.Namespace) -> dict[str, Any]:
    """DotTracker's keyword arguments from the options of :func:`add_tracker_options`; an
    explicit --max-search-radius below --search-radius raises ``ValueError`` naming both."""
    search = args.search_radius
    largest = args.max_search_radius
    if largest is None:
        largest = max(_MAX_SEARCH_RADIUS, search)
    elif largest < search:
        raise ValueError(
            f"--max-search-radius: {largest:g} is below --search-radius {search:g} (the largest window must "
            "be at least the smallest)"
        )
    return {
        "search_radius": search,
        "max_search_radius": largest,
        "polarity": args.polarity,
        "min_area": args.min_area,
        "max_area_ratio": args.max_area_ratio,
    }


def named_as_options(error: VsinvError, options: Mapping[str, str]) -> VsinvError:
    """The same error with the keyword argument it starts by naming (``first_points: ...`` or
    ``invalid parameter `basis`: ...``) renamed to the command option the user typed
    (``--first-points: ...``, ``--basis: ...``)."""
    message = str(error)
    for argument, option in options.items():
        for prefix in (f"{argument}:", f"invalid parameter `{argument}`:"):
            if message.startswith(prefix):
                return type(error)(f"{option}:{message[len(prefix):]}")
    return error
