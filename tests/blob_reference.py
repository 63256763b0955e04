"""OpenCV's SimpleBlobDetector tuned for calibration dots: the independent reference for which
dots a frame holds, shared by tests/test_dots_upscaled.py and benches/dots_vs_opencv.py."""

from __future__ import annotations

import cv2


def blob_detector(dark: bool, scale: float) -> cv2.SimpleBlobDetector:
    """OpenCV's blob detector tuned for the dots of a frame `scale` times the camera's (area)."""
    p = cv2.SimpleBlobDetector_Params()
    p.filterByColor, p.blobColor = True, 0 if dark else 255
    p.minThreshold, p.maxThreshold, p.thresholdStep, p.minRepeatability = 10, 250, 10, 2
    p.filterByArea, p.minArea, p.maxArea = True, 40 * scale, 1e9
    p.filterByCircularity, p.minCircularity = True, 0.8
    p.filterByConvexity, p.minConvexity = True, 0.95
    p.filterByInertia, p.minInertiaRatio = True, 0.4
    return cv2.SimpleBlobDetector_create(p)
