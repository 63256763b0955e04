"""Colour frames wherever a grey image is taken (issue 29, item 5): one image reader in the
bindings (src/python/image_arg.rs) reads grey (height, width) or (height, width, 1), BGR
(height, width, 3) and BGRA (height, width, 4) uint8 arrays in any memory order, converting
colour in Rust. Each image-taking function gives, on a BGR frame, exactly what it gives on
OpenCV's `cv2.cvtColor(frame, COLOR_BGR2GRAY)` of it (an independent conversion).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

import numpy as np
import pytest

import vsinv

cv2 = pytest.importorskip("cv2")


def _as_bgr(grey: np.ndarray) -> np.ndarray:
    """A colour frame with three different channels whose grey still shows the target."""
    g = grey.astype(np.int32)
    green = np.clip(g * 9 // 10 + 12, 0, 255)
    red = np.clip(g // 2 + 30, 0, 255)
    return np.stack([g, green, red], axis=-1).astype(np.uint8)


def _layouts(bgr: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Colour arrays in several layouts, each with OpenCV's grey of it."""
    bgra = np.concatenate([bgr, np.random.default_rng(1).integers(0, 256, bgr.shape[:2] + (1,), dtype=np.uint8)], axis=2)
    wide = np.zeros((bgr.shape[0], bgr.shape[1], 5), np.uint8)
    wide[..., :3] = bgr
    strided = wide[..., :3]  # pixels 5 bytes apart: not contiguous
    return {
        "bgr": (bgr, cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)),
        "bgra": (bgra, cv2.cvtColor(bgra, cv2.COLOR_BGRA2GRAY)),
        "fortran": (np.asfortranarray(bgr), cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)),
        "strided": (strided, cv2.cvtColor(np.ascontiguousarray(strided), cv2.COLOR_BGR2GRAY)),
    }


DOTS = vsinv.vision.render("vision-12-6", reference=True)
DOTS_FRAME, DOTS_PX, _ = vsinv.vision.render_view("vision-12-6", pose=np.eye(4))
TAGS = vsinv.vision.render("tags-12-6", reference=True)
TAGS_FRAME = vsinv.vision.render("tags-12-6")


def _same(a: Any, b: Any) -> None:
    if isinstance(a, tuple):
        for x, y in zip(a, b):
            _same(x, y)
    else:
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


def _dots(image: np.ndarray) -> Any:
    d = vsinv.vision.detect_dots(image)
    return d.centroids, d.areas, d.bboxes


def _tags(image: np.ndarray) -> Any:
    t = vsinv.vision.detect_tags(image)
    return np.asarray(t.ids), np.asarray(t.corners)


FUNCTIONS: dict[str, tuple[np.ndarray, Callable[[np.ndarray], Any]]] = {
    "detect_dots": (DOTS, _dots),
    "DotTracker": (DOTS, lambda im: vsinv.vision.DotTracker(im, vsinv.vision.detect_dots(DOTS).centroids).positions),
    "DotTracker.track": (DOTS_FRAME, lambda im: vsinv.vision.DotTracker(DOTS_FRAME, DOTS_PX).track(im)),
    "detect_tags": (TAGS, _tags),
    "TagTracker.track": (TAGS_FRAME, lambda im: (lambda t: (np.asarray(t.ids), np.asarray(t.corners)))(vsinv.vision.TagTracker().track(im))),
    "to_grey": (DOTS, lambda im: vsinv.vision.to_grey(im, "bgr") if im.ndim == 3 else vsinv.vision.to_grey(im)),
}


@pytest.mark.parametrize("name", sorted(FUNCTIONS))
@pytest.mark.parametrize("layout", ["bgr", "bgra", "fortran", "strided"])
def test_each_function_reads_colour_as_opencvs_grey(name: str, layout: str) -> None:
    grey, fn = FUNCTIONS[name]
    colour, cv_grey = _layouts(_as_bgr(grey))[layout]
    expected = fn(cv_grey)
    if name in ("detect_dots", "detect_tags", "TagTracker.track"):  # the target is still there
        assert len(expected[0]) >= 12 if name == "detect_dots" else len(expected[0]) == 3
    _same(fn(colour), expected)


def test_image_servo_steps_on_colour_as_on_opencvs_grey() -> None:
    K_hat = np.array([[600.0, 0.0, 416.0], [0.0, 600.0, 312.0], [0.0, 0.0, 1.0]])
    colour_ref, colour_frame = _as_bgr(TAGS), _as_bgr(TAGS_FRAME)
    grey_ref = cv2.cvtColor(colour_ref, cv2.COLOR_BGR2GRAY)
    grey_frame = cv2.cvtColor(colour_frame, cv2.COLOR_BGR2GRAY)
    z = np.full(12, 0.75)
    a = vsinv.ImageServo(colour_ref, "tags", K_hat, reference_depths=z)
    b = vsinv.ImageServo(grey_ref, "tags", K_hat, reference_depths=z)
    np.testing.assert_array_equal(a.reference_pixels, b.reference_pixels)
    sa, sb = a.step(np.asfortranarray(colour_frame)), b.step(grey_frame)
    assert sa.found.sum() == 12
    np.testing.assert_array_equal(sa.pixels, sb.pixels)
    np.testing.assert_array_equal(sa.twist, sb.twist)


def test_one_channel_and_grey_layouts_are_read_as_grey(tmp_path: Path) -> None:
    for image in (DOTS[:, :, None], np.asfortranarray(DOTS), np.repeat(DOTS, 2, axis=1)[:, ::2]):
        _same(_dots(image), _dots(DOTS))
    colour = _as_bgr(DOTS)
    vsinv.vision.save_image(colour, tmp_path / "colour.png")
    np.testing.assert_array_equal(vsinv.vision.load_image(tmp_path / "colour.png"), cv2.cvtColor(colour, cv2.COLOR_BGR2GRAY))


@pytest.mark.parametrize("bad", [np.zeros((10, 10, 2), np.uint8), np.zeros((10, 10, 5), np.uint8),
                                 np.zeros((10, 10, 3), np.float32), np.zeros((2, 10, 10, 3), np.uint8)])
def test_other_shapes_are_refused_naming_the_argument_and_the_shape(bad: np.ndarray) -> None:
    shape = rf"shape \({', '.join(str(s) for s in bad.shape)},?\)"
    with pytest.raises(vsinv.InvalidInput, match=rf"^image: expected a uint8 NumPy array: grey .* got dtype \w+ with {shape}"):
        vsinv.vision.detect_dots(bad)
    with pytest.raises(vsinv.InvalidInput, match=rf"^reference_image: expected a uint8 NumPy array.*{shape}"):
        vsinv.ImageServo(bad, "tags", np.diag([600.0, 600.0, 1.0]))
    with pytest.raises(vsinv.InvalidInput, match=rf"^image: .*{shape}") as e:
        vsinv.vision.TagTracker().track(bad)
    assert (e.value.kind, e.value.argument) == ("invalid_image", "image")
