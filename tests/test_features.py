"""The keypoint target's pieces on real frames nobody here drew (issue 32, items 1 and 2): ViSP's
`mbt/cube` sequence (a camera moving around a cube on a desk, 640 x 480), read from Debian's
visp-images-data at run time. OpenCV is the independent computation: its pyramidal Lucas-Kanade
(`cv2.calcOpticalFlowPyrLK`, the same two passes) for the tracks, and its own SIFT, ratio test and
MAGSAC fundamental matrix (`cv2.findFundamentalMat(USAC_MAGSAC)`) for the matches.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import vsinv
from opencv_matching import opencv_matches

cv2 = pytest.importorskip("cv2", reason="OpenCV is the oracle: pip install opencv-python-headless")

CUBE = Path("/usr/share/visp-images-data/ViSP-images/mbt/cube")
if not CUBE.is_dir():
    pytest.skip(f"ViSP's images are not installed ({CUBE}): apt install visp-images-data", allow_module_level=True)

LK = {"winSize": (21, 21), "maxLevel": 3, "criteria": (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 30, 0.01)}


def frame(k: int) -> np.ndarray:
    return cv2.imread(str(CUBE / f"image{k:04d}.pgm"), cv2.IMREAD_GRAYSCALE)


def opencv_tracks(a: np.ndarray, b: np.ndarray, points: np.ndarray, max_error: float) -> tuple[np.ndarray, np.ndarray]:
    p0 = points.astype(np.float32).reshape(-1, 1, 2)
    p1, st1, _ = cv2.calcOpticalFlowPyrLK(a, b, p0, None, **LK)
    back, st2, _ = cv2.calcOpticalFlowPyrLK(b, a, p1, None, **LK)
    ok = (st1.ravel() == 1) & (st2.ravel() == 1) & (np.linalg.norm(back - p0, axis=2).ravel() <= max_error)
    return p1.reshape(-1, 2).astype(float), ok


@pytest.mark.parametrize("step", [1, 4])
def test_tracks_agree_with_opencvs_lucas_kanade(step: int) -> None:
    """The tracks of OpenCV's corners from frame k to frame k + step are OpenCV's own (both run
    forward then backward, 21 x 21 windows, 3 levels), and the points each keeps are nearly the
    same. Within 10 px of the image's border the two sample outside the image differently
    (kornia clamps, OpenCV pads its pyramid): there the tracks differ by tenths of a pixel."""
    inner, border, agree, total = [], [], 0, 0
    for k in (0, 20, 40):
        a, b = frame(k), frame(k + step)
        points = cv2.goodFeaturesToTrack(a, 150, 0.01, 10).reshape(-1, 2).astype(float)
        mine, found = vsinv.vision.track_points(a, b, points, max_error=0.5)
        theirs, ok = opencv_tracks(a, b, points, 0.5)
        assert found.shape == (len(points),) and mine.shape == (len(points), 2)
        assert np.isnan(mine[~found]).all() and np.isfinite(mine[found]).all()
        both = found & ok
        h, w = a.shape
        near_border = (points.min(axis=1) < 10) | (points[:, 0] > w - 11) | (points[:, 1] > h - 11)
        d = np.linalg.norm(mine - theirs, axis=1)
        inner.extend(d[both & ~near_border])
        border.extend(d[both & near_border])
        agree += int((found == ok).sum())
        total += len(points)
    inner, border = np.asarray(inner), np.asarray(border)
    print(f"step {step}: {len(inner)} inner tracks kept by both, median {np.median(inner):.5f} px, max {inner.max():.4f} px; "
          f"{len(border)} near the border, max {border.max(initial=0):.3f} px; kept or dropped alike {agree}/{total}")
    assert len(inner) + len(border) > 0.85 * total
    assert np.median(inner) < 0.005 and inner.max() < 0.05
    assert border.max(initial=0) < 1.0
    assert agree > 0.95 * total


def test_a_point_that_cannot_be_tracked_is_not_found() -> None:
    """A point on a flat patch (the frame's blank sky is not there: a flat square painted on
    both frames) and a point tracked into an unrelated image come back not found, never wrong."""
    a = frame(0).copy()
    a[200:260, 300:360] = 128
    b = a.copy()
    points = np.array([[330.0, 230.0]])
    _, found = vsinv.vision.track_points(a, b, points)
    assert not found[0]
    rng = np.random.default_rng(5)
    noise = rng.integers(0, 256, a.shape, dtype=np.uint8)
    corners = cv2.goodFeaturesToTrack(frame(0), 100, 0.01, 10).reshape(-1, 2).astype(float)
    _, found = vsinv.vision.track_points(frame(0), noise, corners)
    assert found.sum() <= 3, found.sum()


def sampson(F: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The first-order distance (pixels) of the pairs (a, b) to F's epipolar geometry."""
    x1 = np.column_stack([a, np.ones(len(a))])
    x2 = np.column_stack([b, np.ones(len(b))])
    Fx1, Ftx2 = x1 @ F.T, x2 @ F
    num = np.einsum("ij,ij->i", x2, Fx1)
    return np.abs(num) / np.sqrt(Fx1[:, 0] ** 2 + Fx1[:, 1] ** 2 + Ftx2[:, 0] ** 2 + Ftx2[:, 1] ** 2)


@pytest.mark.parametrize("k", [15, 40])
def test_matches_agree_with_an_independent_opencv_pipeline(k: int) -> None:
    """The matches between frame 0 and frame k (the camera moved around the cube, a
    non-planar scene) lie on the epipolar geometry OpenCV finds on its own matches, and are as
    many as OpenCV keeps; a frame half the size (another "lens") is matched as well."""
    a, b = frame(0), frame(k)
    mine_a, mine_b = vsinv.vision.match_features(a, b)
    cv_a, cv_b, F = opencv_matches(a, b, nfeatures=4000)
    d = sampson(F, mine_a, mine_b)
    print(f"frame {k}: vsinv {len(mine_a)} matches, OpenCV {len(cv_a)}; Sampson distance to OpenCV's F: "
          f"median {np.median(d):.3f} px, {int((d > 3).sum())} beyond 3 px")
    assert len(mine_a) >= 0.7 * len(cv_a) and len(mine_a) >= 40
    assert np.median(d) < 0.5
    assert (d > 3.0).mean() < 0.02
    # Another lens: frame k at half the resolution (focal length halved). The matches scaled back
    # lie on the same geometry.
    small = cv2.resize(b, (b.shape[1] // 2, b.shape[0] // 2), interpolation=cv2.INTER_AREA)
    sa, sb = vsinv.vision.match_features(a, small)
    d_small = sampson(F, sa, 2.0 * sb + 0.5)
    print(f"frame {k} at half size: {len(sa)} matches, median {np.median(d_small):.3f} px")
    assert len(sa) >= 20 and np.median(d_small) < 1.0 and (d_small > 4.0).mean() < 0.03


def test_unrelated_images_are_refused_with_the_reason() -> None:
    """No fundamental matrix agrees with matches of two unrelated images: the call raises,
    naming the image, rather than returning chance matches."""
    rng = np.random.default_rng(3)
    noise = cv2.GaussianBlur(rng.integers(0, 256, (480, 640), dtype=np.uint8), (5, 5), 1.5)
    with pytest.raises(vsinv.InvalidInput, match="^image: "):
        vsinv.vision.match_features(frame(0), noise)
    with pytest.raises(vsinv.InvalidInput, match="reference_image"):
        vsinv.vision.match_features(np.full((480, 640), 128, np.uint8), frame(0))
