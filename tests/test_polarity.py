"""Dot polarity: bright dots on dark (`"light"`, the default), dark dots on bright (`"dark"`,
the bright dots of the negative image, bit for bit) and `"auto"`, in `detect_dots`,
`DotTracker` and the scenario's `[vision]` table."""

from __future__ import annotations

import numpy as np
import pytest

import vsinv


def _scene() -> np.ndarray:
    return vsinv.vision.render("vision-12-12")


def test_dark_detection_is_light_detection_of_the_negative() -> None:
    image = _scene()  # light dots
    negative = 255 - image  # dark dots
    for args in ({}, {"min_area": 30, "max_area": 2000}):
        dark = vsinv.vision.detect_dots(negative, polarity="dark", **args)
        light = vsinv.vision.detect_dots(255 - negative, polarity="light", **args)
        assert len(dark) == len(light) > 0
        assert np.array_equal(dark.centroids, light.centroids)
        assert np.array_equal(dark.areas, light.areas) and np.array_equal(dark.bboxes, light.bboxes)
    # A threshold t for dark dots is 255 - t for the negative.
    assert np.array_equal(
        vsinv.vision.detect_dots(negative, threshold=100, polarity="dark").centroids,
        vsinv.vision.detect_dots(image, threshold=155).centroids,
    )


def test_default_is_light_and_auto_follows_the_image() -> None:
    image = _scene()
    default = vsinv.vision.detect_dots(image)
    assert len(default) == 12
    assert np.array_equal(vsinv.vision.detect_dots(image, polarity="light").centroids, default.centroids)
    assert np.array_equal(vsinv.vision.detect_dots(image, polarity="auto").centroids, default.centroids)
    assert np.array_equal(vsinv.vision.detect_dots(255 - image, polarity="auto").centroids, default.centroids)
    assert len(vsinv.vision.detect_dots(255 - image)) != 12  # light dots of a dark-dot image: not the dots


def test_tracker_polarity() -> None:
    image = _scene()
    clicks = vsinv.vision.detect_dots(image).centroids + 1.0
    for polarity in ("dark", "auto"):
        light = vsinv.vision.DotTracker(image, clicks)  # the same step as the dark tracker (each learns its threshold)
        tracker = vsinv.vision.DotTracker(255 - image, clicks, polarity=polarity)
        assert np.array_equal(tracker.positions, light.positions)
        pixels, found = tracker.track(255 - image)
        assert found.all() and np.array_equal(pixels, light.track(image)[0])
    with pytest.raises(vsinv.InvalidInput):
        vsinv.vision.DotTracker(255 - image, clicks)  # light dots wanted: none near the clicks


@pytest.mark.parametrize("bad", ["bright", "", "Dark"])
def test_unknown_polarity_is_refused_by_name(bad: str) -> None:
    image = _scene()
    with pytest.raises(vsinv.InvalidInput, match='polarity: expected one of "light", "dark", "auto"'):
        vsinv.vision.detect_dots(image, polarity=bad)
    with pytest.raises(vsinv.InvalidInput, match='polarity: expected one of "light", "dark", "auto"'):
        vsinv.vision.DotTracker(image, [[10.0, 10.0]], polarity=bad)
    with pytest.raises(TypeError, match="polarity"):
        vsinv.vision.detect_dots(image, polarity=1)  # type: ignore[arg-type]


def test_scenario_dark_images_give_the_same_run() -> None:
    light = vsinv.run_scenario("vision-12-12")
    d = vsinv.load_scenario("vision-12-12").to_dict()
    assert d["vision"]["polarity"] == "light"
    d["vision"]["polarity"] = "dark"
    dark = vsinv.run_scenario(d)
    assert np.array_equal(dark.pixels, light.pixels) and np.array_equal(dark.pose, light.pose)
    image = vsinv.vision.render(d)
    assert np.array_equal(image, 255 - vsinv.vision.render("vision-12-12"))
    d["vision"]["polarity"] = "sideways"
    with pytest.raises(vsinv.InvalidInput, match=r"scenario: vision\.polarity: unknown variant `sideways`, expected one of `light`, `dark`, `auto`"):
        vsinv.load_scenario(d)
