"""`DotTracker` on synthetic images (issue 18, item 1): a dot larger than the search window is
started and followed; a dot that doubles its area, grows past its window, or merges with a
region of its own polarity is reported lost and keeps its last position (never found elsewhere,
even with a look-alike dot in its window); a dot whose window holds another dot never takes it."""

from __future__ import annotations

import numpy as np

import vsinv


def discs(shape: tuple[int, int], dots: list[tuple[float, float, float]], background: int = 40, level: int = 220) -> np.ndarray:
    """Anti-aliased discs `(u, v, radius)` (8 x 8 supersampling: each pixel's grey level is
    proportional to the part of it the discs cover; pixel (u, v) covers [u - 0.5, u + 0.5])."""
    ss = 8
    h, w = shape
    v, u = np.mgrid[0 : h * ss, 0 : w * ss]
    u, v = (u + 0.5) / ss - 0.5, (v + 0.5) / ss - 0.5
    cover = np.zeros(u.shape, bool)
    for cu, cv, r in dots:
        cover |= (u - cu) ** 2 + (v - cv) ** 2 <= r * r
    fraction = cover.reshape(h, ss, w, ss).mean(axis=(1, 3))
    return np.round(background + (level - background) * fraction).astype(np.uint8)


def test_a_dot_larger_than_the_search_window_is_started_and_followed() -> None:
    # 57 px across with the default 20 px search radius (mire-2's large dot), clicked 3 px off,
    # moving 1.5 px and growing 0.3 px in radius per image.
    truth = [(100.3 + 1.5 * t, 90.7 + 1.0 * t, 28.5 + 0.3 * t) for t in range(12)]
    tracker = vsinv.vision.DotTracker(discs((200, 220), [truth[0]]), [[103.3, 88.7]])
    np.testing.assert_allclose(tracker.positions[0], truth[0][:2], atol=0.02)
    for t in range(1, 12):
        pixels, found = tracker.track(discs((200, 220), [truth[t]]))
        assert found[0], t
        np.testing.assert_allclose(pixels[0], truth[t][:2], atol=0.02)


def _lost_keeps_its_place(tracker: vsinv.vision.DotTracker, image: np.ndarray, dot: int) -> None:
    before = tracker.positions.copy()
    pixels, found = tracker.track(image)
    assert not found[dot]
    np.testing.assert_array_equal(pixels[dot], before[dot])
    np.testing.assert_array_equal(tracker.positions[dot], before[dot])


def test_a_dot_that_doubles_its_area_is_lost_then_found_again() -> None:
    shape = (120, 160)
    tracker = vsinv.vision.DotTracker(discs(shape, [(60.2, 60.6, 5.0), (120.0, 40.0, 5.0)]), [[61, 59], [119, 41]])
    _lost_keeps_its_place(tracker, discs(shape, [(60.2, 60.6, 5.0 * np.sqrt(2)), (120.0, 40.0, 5.0)]), 0)
    pixels, found = tracker.track(discs(shape, [(60.2, 60.6, 5.0), (120.0, 40.0, 5.0)]))
    assert found.all()
    np.testing.assert_allclose(pixels[0], [60.2, 60.6], atol=0.02)


def test_a_dot_that_outgrows_its_window_is_lost_not_found_elsewhere() -> None:
    # A look-alike dot 17 px away, inside the dot's window, is never taken for it.
    shape = (140, 160)
    look_alike = (77.0, 67.0, 5.0)
    tracker = vsinv.vision.DotTracker(discs(shape, [(60.0, 60.0, 5.0), look_alike]), [[60, 60]])
    _lost_keeps_its_place(tracker, discs(shape, [(60.0, 60.0, 30.0), look_alike]), 0)


def test_a_dot_that_merges_with_a_bright_region_is_lost_not_found_elsewhere() -> None:
    shape = (120, 160)
    look_alike = (72.0, 75.0, 6.0)
    first = discs(shape, [(60.0, 60.0, 6.0), look_alike])
    tracker = vsinv.vision.DotTracker(first, [[60, 60]])
    merged = first.copy()
    merged[56:65, 64:140] = 220  # a bright bar touching the dot
    _lost_keeps_its_place(tracker, merged, 0)


def test_a_dark_dot_that_merges_with_a_dark_region_is_lost() -> None:
    shape = (120, 160)
    first = discs(shape, [(60.0, 60.0, 6.0)], background=210, level=30)
    tracker = vsinv.vision.DotTracker(first, [[60, 60]], polarity="dark")
    merged = first.copy()
    merged[:, 64:70] = 30  # a dark band through the edge of the dot
    _lost_keeps_its_place(tracker, merged, 0)


def test_a_dot_never_takes_the_dot_in_its_window() -> None:
    # Dot 0 disappears; dot 1, 18 px away, is inside dot 0's window: dot 1 is found, dot 0 lost.
    shape = (120, 160)
    a, b = (50.0, 60.0, 4.0), (68.0, 60.0, 4.0)
    tracker = vsinv.vision.DotTracker(discs(shape, [a, b]), [[50, 60], [68, 60]])
    for _ in range(3):
        before = tracker.positions.copy()
        pixels, found = tracker.track(discs(shape, [b]))
        assert list(found) == [False, True]
        np.testing.assert_array_equal(pixels[0], before[0])
        np.testing.assert_allclose(pixels[1], b[:2], atol=0.02)
