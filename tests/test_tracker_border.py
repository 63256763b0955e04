"""A dot cut by the image's border (issue 27, item 4): the DotTracker and detect_dots declare it
not found while any of it is outside the image, never return it at the centroid of its visible
part (which is biased towards the image), and the tracker finds it again when it is whole.
Images drawn here in closed form (8 x 8 supersampled coverage, tests/test_tracker_lost.py)."""

from __future__ import annotations

import numpy as np
import pytest

import vsinv
from test_tracker_lost import discs

SHAPE = (120, 160)
RADIUS = 7.5
# The leaving dot's path: from well inside, across the right border (its centre 7 px outside at
# the farthest), and back; the second dot stays inside.
OUT = [135.0 + 1.5 * t for t in range(27)]
PATH = OUT + OUT[::-1]
STILL = (40.3, 70.6)


def _whole(u: float) -> bool:
    """Every part of the dot inside the image (pixel centres 0..159, borders at -0.5, 159.5)."""
    return u + RADIUS < SHAPE[1] - 0.5


def _frame(u: float) -> np.ndarray:
    return discs(SHAPE, [(u, 40.25, RADIUS), (*STILL, RADIUS)])


@pytest.mark.parametrize("polarity", ["light", "dark"])
def test_a_dot_leaving_the_image_is_lost_never_biased_and_found_again(polarity: str) -> None:
    flip = (lambda im: 255 - im) if polarity == "dark" else (lambda im: im)
    tracker = vsinv.vision.DotTracker(flip(_frame(PATH[0])), [[PATH[0] + 2, 42.0], [STILL[0] - 1, STILL[1] + 2]], polarity=polarity)
    seen = {"whole": 0, "cut": 0, "found_again": 0}
    was_lost = False
    for u in PATH[1:]:
        pixels, found = tracker.track(flip(_frame(u)))
        assert found[1] and np.hypot(*(pixels[1] - STILL)) < 0.02
        if _whole(u):
            assert found[0], u
            assert np.hypot(pixels[0, 0] - u, pixels[0, 1] - 40.25) < 0.02, (u, pixels[0])
            seen["whole"] += 1
            seen["found_again"] += int(was_lost)
            was_lost = False
        else:
            # Cut by the border: not found (its visible part's centroid would lie up to
            # several pixels inside the image).
            assert not found[0], (u, pixels[0])
            seen["cut"] += 1
            was_lost = True
    assert seen["cut"] >= 10 and seen["whole"] >= 10 and seen["found_again"] == 1, seen


def test_detect_dots_leaves_out_a_cut_dot() -> None:
    """detect_dots keeps a dot only when its box grown by the centroid's 2 px margin is in the
    image: found there within 0.02 px, and never while any of it is outside the image."""
    for u in PATH:
        dots = vsinv.vision.detect_dots(_frame(u))
        moving = dots.centroids[np.hypot(*(dots.centroids - STILL).T) > 1.0]
        assert np.min(np.hypot(*(dots.centroids - STILL).T)) < 0.02
        clear = u + RADIUS + 3.0 < SHAPE[1] - 0.5
        if clear:
            assert len(moving) == 1, (u, dots.centroids)
        if not _whole(u):
            assert len(moving) == 0, (u, moving)
        if len(moving):
            assert np.hypot(moving[0, 0] - u, moving[0, 1] - 40.25) < 0.02, (u, moving)
