"""OpenCV's own keypoint matching: the independent pipeline the keypoint target is checked against
(tests/test_features.py) and timed beside (benches/features_matching.py)."""

from __future__ import annotations

import numpy as np


def opencv_matches(a: np.ndarray, b: np.ndarray, nfeatures: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """OpenCV's SIFT (`nfeatures` keypoints at most, 0: all), Lowe's ratio 0.8 and its MAGSAC
    fundamental matrix: (pixels in a, pixels in b, F) of the kept pairs."""
    import cv2

    sift = cv2.SIFT_create(nfeatures=nfeatures)
    ka, da = sift.detectAndCompute(a, None)
    kb, db = sift.detectAndCompute(b, None)
    pairs = cv2.BFMatcher(cv2.NORM_L2).knnMatch(da, db, k=2)
    good = [m for m, n in pairs if m.distance < 0.8 * n.distance]
    pa = np.array([ka[m.queryIdx].pt for m in good])
    pb = np.array([kb[m.trainIdx].pt for m in good])
    F, mask = cv2.findFundamentalMat(pa, pb, cv2.USAC_MAGSAC, 1.0, 0.999, 10000)
    keep = mask.ravel() == 1
    return pa[keep], pb[keep], F
