"""Dots several times larger than the threshold's 32-pixel tiles: ViSP's mire-2 and grid36
frames resized (``cv2.resize``, linear) to 1920 x 1080 and 3840 x 2160, where the dots are
up to 10 times their size in the camera's own frame (the middle dot of mire-2 is 600 x 380 px
at 3840 x 2160, grid36's 250 x 190 px each).

Independent computations (OpenCV): which dots there are, from ``SimpleBlobDetector`` tuned
for the dots (on the camera's frame, mapped to the resized one, and on the resized frame
itself), and where they are, from ``connectedComponentsWithStats`` centroids of each dot's
Otsu blob in a window around it. The images are GPL (Debian's ``visp-images-data``): read
from there, skipped when absent.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import vsinv

cv2 = pytest.importorskip("cv2")
from blob_reference import blob_detector  # noqa: E402

VISP = Path("/usr/share/visp-images-data/ViSP-images")
FRAMES = {"mire-2": ("mire-2/image.0001.pgm", False, 5), "grid36": ("calibration/grid36-01.pgm", True, 36)}
SIZES = [(1920, 1080), (3840, 2160)]

pytestmark = pytest.mark.skipif(not VISP.is_dir(), reason="ViSP's images (visp-images-data) are not installed")


def keypoints(image: np.ndarray, dark: bool, scale: float) -> tuple[np.ndarray, np.ndarray]:
    found = blob_detector(dark, scale).detect(image)
    return np.array([k.pt for k in found]).reshape(-1, 2), np.array([k.size for k in found])


def nearest(points: np.ndarray, to: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each of `to`: the distance to the nearest of `points` and its index."""
    d = np.hypot(*(points[None, :, :] - to[:, None, :]).transpose(2, 0, 1))
    return d.min(axis=1), d.argmin(axis=1)


def otsu_centroid(image: np.ndarray, dark: bool, centre: np.ndarray, half: np.ndarray) -> np.ndarray:
    """OpenCV's centroid of the Otsu blob under `centre` in the window of half-sides `half`."""
    h, w = image.shape
    u0, v0 = np.maximum(np.floor(centre - half).astype(int), 0)
    u1, v1 = np.minimum(np.ceil(centre + half).astype(int), [w - 1, h - 1])
    window = np.ascontiguousarray(image[v0 : v1 + 1, u0 : u1 + 1])
    mode = (cv2.THRESH_BINARY_INV if dark else cv2.THRESH_BINARY) | cv2.THRESH_OTSU
    _, binary = cv2.threshold(window, 0, 255, mode)
    _, labels, _, centroids = cv2.connectedComponentsWithStats(binary, connectivity=8)
    label = labels[int(round(centre[1])) - v0, int(round(centre[0])) - u0]
    assert label != 0, f"the Otsu blob does not cover the dot's centre {centre}"
    return centroids[label] + [u0, v0]


@pytest.fixture(scope="module", params=sorted(FRAMES))
def camera_frame(request):
    path, dark, count = FRAMES[request.param]
    image = cv2.imread(str(VISP / path), cv2.IMREAD_GRAYSCALE)
    truth, sizes = keypoints(image, dark, 1.0)
    # The reference itself: the blob detector finds the target's dots and nothing else.
    assert len(truth) == count, f"{request.param}: {len(truth)} blobs"
    return request.param, image, dark, truth, sizes


@pytest.mark.parametrize("size", SIZES, ids=lambda s: f"{s[0]}x{s[1]}")
def test_every_dot_of_the_resized_frame_is_found(camera_frame, size):
    name, native, dark, truth, _ = camera_frame
    (h0, w0), (w, h) = native.shape, size
    s = np.array([w / w0, h / h0])
    frame = cv2.resize(native, size, interpolation=cv2.INTER_LINEAR)
    ours = np.asarray(vsinv.vision.detect_dots(frame, polarity="dark" if dark else "light").centroids).reshape(-1, 2)
    assert len(ours) > 0, f"{name} at {size}: no dot"
    tolerance = 3.0 * s.max()
    # The camera's dots, mapped to the resized frame (cv2.resize's pixel-centre mapping).
    mapped = (truth + 0.5) * s - 0.5
    d, _ = nearest(ours, mapped)
    assert np.all(d < tolerance), f"{name} at {size}: true dots missed at {mapped[d >= tolerance].round(1).tolist()}"
    # Every dot the blob detector finds in the resized frame itself.
    blobs, _ = keypoints(frame, dark, s[0] * s[1])
    assert len(blobs) > 0
    d, _ = nearest(ours, blobs)
    assert np.all(d < tolerance), f"{name} at {size}: blobs missed at {blobs[d >= tolerance].round(1).tolist()}"
    if name == "grid36":
        # A plain sheet of paper: nothing but the 36 dots.
        assert len(ours) == 36, f"grid36 at {size}: {len(ours)} dots"


def centroid_errors(frame: np.ndarray, dark: bool, mapped: np.ndarray, windows: np.ndarray) -> np.ndarray:
    """The distance from each true dot's vsinv centroid to OpenCV's component centroid."""
    ours = np.asarray(vsinv.vision.detect_dots(frame, polarity="dark" if dark else "light").centroids).reshape(-1, 2)
    _, index = nearest(ours, mapped)
    return np.array([np.hypot(*(ours[i] - otsu_centroid(frame, dark, c, half))) for c, half, i in zip(mapped, windows, index)])


@pytest.mark.parametrize("size", SIZES, ids=lambda s: f"{s[0]}x{s[1]}")
def test_centroids_agree_with_opencv_components_as_at_the_cameras_size(camera_frame, size):
    # A binary centroid of a blurred blob (with the marks printed inside grid36's dots as
    # holes) against a grey-weighted one over a background plane: they differ by a tenth of a
    # pixel or two in the camera's own frame. In the resized frame, in the camera's pixels,
    # they differ by as much and no more: the large dots are measured as the small ones.
    name, native, dark, truth, sizes = camera_frame
    (h0, w0), (w, h) = native.shape, size
    s = np.array([w / w0, h / h0])
    at_native = centroid_errors(native, dark, truth, 0.8 * sizes[:, None] * [1.0, 1.0])
    frame = cv2.resize(native, size, interpolation=cv2.INTER_LINEAR)
    resized = centroid_errors(frame, dark, (truth + 0.5) * s - 0.5, 0.8 * sizes[:, None] * s) / s.max()
    assert np.median(resized) < np.median(at_native) + 0.05 and resized.max() < at_native.max() + 0.15, (
        f"{name} at {size}: median {np.median(resized):.3f}, max {resized.max():.3f} camera px; at the camera's size"
        f" median {np.median(at_native):.3f}, max {at_native.max():.3f} px"
    )
