"""Images from Python: rendering, dot detection and tracking, checked against OpenCV."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import vsinv


def opencv_discs(radius: float, seed: int, blur: float = 0.8, noise: float = 2.0):
    """Anti-aliased discs drawn by OpenCV at known subpixel centres (8 fractional bits), on a
    dark background, blurred, with sensor noise: (image, centres (m, 2))."""
    rng = np.random.default_rng(seed)
    step = int(4 * radius + 12)
    image = np.full((4 * step, 5 * step), 30, np.uint8)
    centres = []
    for j in range(4):
        for i in range(5):
            c = np.array([step * (i + 0.5), step * (j + 0.5)]) + rng.uniform(-0.5, 0.5, 2)
            fixed = np.round(c * 256).astype(int)
            cv2.circle(image, tuple(int(x) for x in fixed), int(round(radius * 256)), 220, -1, cv2.LINE_AA, 8)
            centres.append(fixed / 256)
    blurred = cv2.GaussianBlur(image, (0, 0), blur) if blur > 0 else image
    noisy = blurred + rng.normal(0.0, noise, image.shape)
    return np.clip(np.round(noisy), 0, 255).astype(np.uint8), np.array(centres)


def nearest_errors(found: np.ndarray, truth: np.ndarray) -> np.ndarray:
    d = np.linalg.norm(found[None, :, :] - truth[:, None, :], axis=2)
    return d.min(axis=1)


@pytest.mark.parametrize("radius", [3.0, 4.0, 6.0, 10.0])
def test_detect_dots_finds_opencv_discs_within_005_px_median(radius: float) -> None:
    errors = []
    for seed in range(5):
        image, centres = opencv_discs(radius, seed)
        dots = vsinv.vision.detect_dots(image)
        assert len(dots) == len(centres)
        errors.append(nearest_errors(dots.centroids, centres))
    e = np.concatenate(errors)
    assert np.median(e) < 0.05, (radius, np.median(e))
    assert e.max() < 0.2, (radius, e.max())


def weighted_moments_centroid(image: np.ndarray, dots: vsinv.vision.Dots, k: int, labels: np.ndarray) -> np.ndarray:
    """cv2.moments of the pixels detect_dots documents for dot k: its bounding box grown by
    2 px, grey levels above the least-squares plane fitted to that box's border ring (NumPy's
    lstsq), other components masked, and the box's pixels off the dot counted only above two
    RMS of the ring's residuals."""
    u0, v0, u1, v1 = dots.bboxes[k]
    h, w = image.shape
    u0, v0, u1, v1 = max(u0 - 2, 0), max(v0 - 2, 0), min(u1 + 2, w - 1), min(v1 + 2, h - 1)
    box = image[v0 : v1 + 1, u0 : u1 + 1].astype(np.float64)
    box_labels = labels[v0 : v1 + 1, u0 : u1 + 1]
    ring = np.zeros(box.shape, bool)
    ring[0, :] = ring[-1, :] = ring[:, 0] = ring[:, -1] = True
    ring &= box_labels == 0
    vv, uu = np.mgrid[0 : box.shape[0], 0 : box.shape[1]]
    design = np.c_[np.ones(ring.sum()), uu[ring], vv[ring]]
    plane = np.linalg.lstsq(design, box[ring], rcond=None)[0]
    above = box - (plane[0] + plane[1] * uu + plane[2] * vv)
    ring_rms = np.sqrt(np.mean(above[ring] ** 2))
    weights = np.clip(above, 0, None)
    own = box_labels[box_labels > 0]
    own_label = np.bincount(own).argmax()
    weights[(box_labels != 0) & (box_labels != own_label)] = 0
    weights[(box_labels == 0) & (above <= 2.0 * ring_rms)] = 0
    m = cv2.moments(weights.astype(np.float32))
    return np.array([m["m10"] / m["m00"] + u0, m["m01"] / m["m00"] + v0])


@pytest.mark.parametrize("name", ["vision-12-12", "vision-12-6"])
def test_centroids_agree_with_opencv_moments_on_rendered_images(name: str) -> None:
    for reference in (True, False):
        image = vsinv.vision.render(name, reference=reference)
        dots = vsinv.vision.detect_dots(image)
        assert len(dots) == 12
        threshold = int(np.ceil(np.max([image[int(round(v)), int(round(u))] for u, v in dots.centroids]))) // 2
        _, labels = cv2.connectedComponents((image > threshold).astype(np.uint8), connectivity=8)
        for k in range(len(dots)):
            expected = weighted_moments_centroid(image, dots, k, labels)
            assert np.linalg.norm(dots.centroids[k] - expected) < 0.01


def test_rendered_views_show_the_dots_where_they_project() -> None:
    image, pixels, visible = vsinv.vision.render_view("vision-12-6")
    assert image.dtype == np.uint8 and image.shape == (624, 832)
    assert image.flags.c_contiguous and image.base is not None  # moved from Rust, not copied
    assert visible.all()
    dots = vsinv.vision.detect_dots(image)
    assert nearest_errors(dots.centroids, pixels).max() < 0.2
    assert np.array_equal(vsinv.vision.render("vision-12-6"), image)  # same seed, same image
    at_goal = vsinv.vision.render("vision-12-6", pose=np.eye(4))
    assert not np.array_equal(at_goal, image)


def test_tracker_follows_a_run_and_reports_lost_dots() -> None:
    run = vsinv.run_scenario("vision-12-12")
    poses, times = run.pose, run.time
    first = vsinv.vision.render("vision-12-12", pose=poses[0], time=times[0])
    tracker = vsinv.vision.DotTracker(first, run.pixels[0] + 1.5, search_radius=15)
    assert len(tracker) == 12
    for i in range(1, 60, 3):
        image = vsinv.vision.render("vision-12-12", pose=poses[i], time=times[i])
        pixels, found = tracker.track(image)
        assert found.all()
        _, truth, _ = vsinv.vision.render_view("vision-12-12", pose=poses[i], time=times[i])
        assert np.abs(pixels - truth).max() < 0.3
    pixels, found = tracker.track(np.full((624, 832), 30, np.uint8))
    assert not found.any()
    assert np.array_equal(pixels, tracker.positions)


def test_run_reports_detection_errors() -> None:
    run = vsinv.run_scenario("vision-12-6")
    s = run.summary
    assert s["status"] == "converged"
    assert run.detection_error is not None and run.detection_error.shape == run.pixels.shape[:2]
    finite = run.detection_error[np.isfinite(run.detection_error)]
    assert np.isclose(np.median(finite), s["detection_error_median"])
    assert np.isclose(finite.max(), s["detection_error_max"])
    assert vsinv.run_scenario("lens-12-6").detection_error is None


@pytest.mark.parametrize(
    "image, fragment",
    [
        (np.zeros((10, 10), np.float64), r"image: expected a uint8 NumPy array: grey \(height, width\) .* got dtype float64 with shape \(10, 10\)"),
        (np.zeros((10, 10, 2), np.uint8), r"image: expected a uint8 NumPy array: grey \(height, width\) .* got dtype uint8 with shape \(10, 10, 2\)"),
        (np.zeros((10, 10, 3), np.uint8), r"image: uniform image \(every pixel is 0\): no dot can stand out"),  # colour: read as grey
        (np.zeros((0, 10), np.uint8), r"image: empty image \(0 x 10\)"),
        (np.zeros((20, 20), np.uint8), r"image: uniform image \(every pixel is 0\): no dot can stand out"),
        ([[0, 1], [2, 3]], r"image: expected a uint8 NumPy array: grey \(height, width\) .* got list"),
    ],
)
def test_bad_images_raise_invalid_input(image: object, fragment: str) -> None:
    with pytest.raises(vsinv.InvalidInput, match=fragment):
        vsinv.vision.detect_dots(image)  # type: ignore[arg-type]


def test_tracker_refuses_clicks_without_a_dot() -> None:
    image = vsinv.vision.render("vision-12-12", reference=True)
    with pytest.raises(vsinv.InvalidInput, match=r"initial_pixels: point 0 at \(5\.0, 5\.0\): no dot around it \(no whole dot under it\)"):
        vsinv.vision.DotTracker(image, [[5.0, 5.0]])
    with pytest.raises(vsinv.InvalidInput, match="initial_pixels: non-finite value at row 0, column 0"):
        vsinv.vision.DotTracker(image, [[np.nan, 5.0]])
    with pytest.raises(vsinv.InvalidInput, match=r"initial_pixels: expected shape \(n, 2\)"):
        vsinv.vision.DotTracker(image, np.zeros((3, 3)))
    tracker = vsinv.vision.DotTracker(image, vsinv.vision.render_view("vision-12-12", reference=True)[1])
    with pytest.raises(vsinv.InvalidInput, match="tracker was started"):
        tracker.track(np.zeros((10, 10), np.uint8))


def test_non_contiguous_images_are_read() -> None:
    image = vsinv.vision.render("vision-12-12", reference=True)
    wide = np.zeros((624, 832 * 2), np.uint8)
    wide[:, ::2] = image
    view = wide[:, ::2]
    assert not view.flags.c_contiguous
    a, b = vsinv.vision.detect_dots(view), vsinv.vision.detect_dots(image)
    assert np.array_equal(a.centroids, b.centroids)
