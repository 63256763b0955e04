"""detect_dots's shape, size and contrast filters and its local threshold, on drawn images whose
answer is known: a filled disc is kept, a ring, a cross, a faint disc and a speck in texture are
not; a lighting gradient neither hides dots nor pulls their centroids; bad values raise
InvalidInput naming the argument."""

from __future__ import annotations

import numpy as np
import pytest

import vsinv


def _scene() -> np.ndarray:
    """A disc (u = 20), a ring (60), a cross (100) and a faint disc (140) on a plain 30."""
    v, u = np.mgrid[0:64, 0:160].astype(float)
    disc = np.hypot(u - 20, v - 32) < 8
    ring = np.abs(np.hypot(u - 60, v - 32) - 8) < 1.5
    cross = ((u >= 80) & (u < 120) & (v >= 30) & (v < 34)) | ((u >= 96) & (u < 104) & (v >= 22) & (v < 42))
    faint = np.hypot(u - 140, v - 32) < 8
    image = np.full((64, 160), 30, np.uint8)
    image[disc | ring | cross] = 220
    image[faint] = 45
    return image


def _columns(dots: vsinv.vision.Dots) -> list[int]:
    return sorted(int(round(u)) for u in dots.centroids[:, 0])


def test_fill_ratio_and_contrast_reject_what_is_not_a_dot() -> None:
    image = _scene()
    assert _columns(vsinv.vision.detect_dots(image)) == [20]
    assert _columns(vsinv.vision.detect_dots(image, threshold=40)) == [20]
    assert _columns(vsinv.vision.detect_dots(image, threshold=40, min_fill=0.0)) == [20, 60, 100]
    assert _columns(vsinv.vision.detect_dots(image, threshold=40, min_contrast=5)) == [20, 140]
    # Dark dots: the same, on the negative.
    assert _columns(vsinv.vision.detect_dots(255 - image, polarity="dark")) == [20]


@pytest.mark.parametrize("reach", [9, 39])
def test_a_dot_in_texture_fails_the_ring_check(reach: int) -> None:
    """A speck in texture all round it (`reach` 39: the texture fills the image) fails the ring
    check; a dot in a small textured patch (`reach` 9) fails it near, and is measured against a
    ring farther out only when it is large enough to be a shaded sphere (100 px or more: this
    one has 113, so the patch must reach past twice its size to keep it out)."""
    rng = np.random.default_rng(3)
    v, u = np.mgrid[0:80, 0:80].astype(float)
    image = np.where(np.hypot(u - 40, v - 40) < 6, 200.0, 40.0)
    textured = image.copy()
    ring = (np.abs(u - 40) <= reach) & (np.abs(v - 40) <= reach) & (np.hypot(u - 40, v - 40) >= 7)
    textured[ring] += rng.choice([-30.0, 30.0], size=ring.sum())
    plain, busy = image.astype(np.uint8), textured.astype(np.uint8)
    assert len(vsinv.vision.detect_dots(plain)) == 1
    assert len(vsinv.vision.detect_dots(busy, threshold=120)) == (1 if reach < 12 else 0)
    assert len(vsinv.vision.detect_dots(busy, threshold=120, max_ring_residual=np.inf)) == 1


def test_a_small_speck_in_a_textured_patch_fails_the_ring_check() -> None:
    """Under 100 px a blob gets no grown ring: a speck in a patch of texture stays out."""
    rng = np.random.default_rng(4)
    v, u = np.mgrid[0:80, 0:80].astype(float)
    image = np.where(np.hypot(u - 40, v - 40) < 4, 200.0, 40.0)  # 49 px
    ring = (np.abs(u - 40) <= 7) & (np.abs(v - 40) <= 7) & (np.hypot(u - 40, v - 40) >= 5)
    image[ring] += rng.choice([-30.0, 30.0], size=ring.sum())
    assert len(vsinv.vision.detect_dots(image.astype(np.uint8), threshold=120)) == 0


def test_dots_under_a_strong_lighting_gradient_are_all_found_at_their_centres() -> None:
    # Background from 10 to 160 across the image, dots 60 levels above it: no global threshold
    # separates the dots on the left from the background on the right.
    v, u = np.mgrid[0:240, 0:640].astype(float)
    image = 10 + 150 * u / 640
    centres = [(40.0 + 80 * i + 0.3, 60.0 + 120 * j + 0.6) for i in range(8) for j in range(2)]
    sub = (np.arange(8) + 0.5) / 8 - 0.5
    for cu, cv in centres:
        cover = np.zeros_like(image)
        for du in sub:
            for dv in sub:
                cover += (np.hypot(u + du - cu, v + dv - cv) < 7) / 64
        image += 60 * cover
    image = np.round(image).astype(np.uint8)
    dots = vsinv.vision.detect_dots(image)
    assert len(dots) == len(centres)
    errors = [np.min(np.hypot(*(dots.centroids - c).T)) for c in centres]
    assert max(errors) < 0.05, errors


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"min_fill": -0.1}, "min_fill"),
        ({"min_fill": 1.5}, "min_fill"),
        ({"min_fill": float("nan")}, "min_fill"),
        ({"min_contrast": 256}, "min_contrast"),
        ({"min_contrast": -1}, "min_contrast"),
        ({"max_ring_residual": -1.0}, "max_ring_residual"),
        ({"max_ring_residual": float("nan")}, "max_ring_residual"),
    ],
)
def test_bad_filter_values_name_the_argument(kwargs: dict[str, float], name: str) -> None:
    with pytest.raises(vsinv.InvalidInput) as info:
        vsinv.vision.detect_dots(_scene(), **kwargs)
    assert name in str(info.value)
