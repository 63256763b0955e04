"""The annotated image the bridge publishes: the grey frame in colour with a cross on every
point found (green) and on the last known pixel of every point lost (red)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

__all__ = ["annotate"]

_FOUND = np.array([0, 255, 0], np.uint8)
_LOST = np.array([255, 0, 0], np.uint8)


def annotate(
    grey: npt.NDArray[np.uint8], pixels: npt.NDArray[np.float64], found: npt.NDArray[np.bool_], arm: int = 6
) -> npt.NDArray[np.uint8]:
    """An rgb8 (height, width, 3) copy of ``grey`` with a cross of half-length ``arm`` pixels
    at each of ``pixels`` (n, 2): green where found, red where lost; crosses are clipped to the
    image."""
    rgb = np.repeat(grey[:, :, None], 3, axis=2)
    h, w = grey.shape
    for (u, v), ok in zip(np.asarray(pixels, dtype=float), np.asarray(found, dtype=bool)):
        if not (np.isfinite(u) and np.isfinite(v)):
            continue
        c, r = int(round(u)), int(round(v))
        colour = _FOUND if ok else _LOST
        if 0 <= r < h:
            rgb[r, max(c - arm, 0) : max(min(c + arm + 1, w), 0)] = colour
        if 0 <= c < w:
            rgb[max(r - arm, 0) : max(min(r + arm + 1, h), 0), c] = colour
    return rgb
