"""The DotTracker checks a dot's shape when it starts, as detect_dots does: a notched disc (ViSP's
circle/circle.pgm, and drawn ones) is refused, a whole disc is taken."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

import vsinv

CIRCLE = Path("/usr/share/visp-images-data/ViSP-images/circle/circle.pgm")


def _disc(notch: int) -> np.ndarray:
    """A disc of radius 30 at (80, 60) on 30, less a notch `notch` px deep, 16 px high, on
    its right (0: whole)."""
    v, u = np.mgrid[0:120, 0:160]
    disc = np.hypot(u - 80, v - 60) < 30
    cut = (u > 110 - notch) & (np.abs(v - 60) < 8)
    return np.where(disc & ~cut, 220, 30).astype(np.uint8)


def test_a_whole_disc_starts_a_notched_one_does_not() -> None:
    tracker = vsinv.vision.DotTracker(_disc(0), [[82.0, 58.0]])
    np.testing.assert_allclose(tracker.positions[0], [80.0, 60.0], atol=0.05)
    for notch in [20, 30]:
        assert len(vsinv.vision.detect_dots(_disc(notch))) == 0
        with pytest.raises(vsinv.InvalidInput, match="not a dot"):
            vsinv.vision.DotTracker(_disc(notch), [[82.0, 58.0]])


@pytest.mark.skipif(not CIRCLE.exists(), reason="Debian's visp-images-data is not installed")
def test_the_notched_disc_of_visp_is_refused_by_both() -> None:
    image = cv2.imread(str(CIRCLE), cv2.IMREAD_GRAYSCALE)
    assert len(vsinv.vision.detect_dots(image)) == 0
    with pytest.raises(vsinv.InvalidInput, match="point 0 .*not a dot"):
        vsinv.vision.DotTracker(image, [[155.0, 111.0]])
    with pytest.raises(vsinv.InvalidInput, match="not a dot"):
        vsinv.vision.DotTracker(image, [[155.0, 111.0]], search_radius=80.0, max_search_radius=160.0)
