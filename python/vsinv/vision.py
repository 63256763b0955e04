"""Images: frame sources, the dot and AprilTag detectors and trackers, rendering of the
simulated camera, image files and grey conversion, lens distortion, and the pixel noise meter."""

from ._core import (
    TAG_FAMILIES,
    TARGETS,
    TRACKER_SETTINGS,
    Distortion,
    DotTracker,
    Dots,
    PixelNoiseMeter,
    Tags,
    TagTracker,
    decode_image,
    detect_dots,
    detect_tags,
    distort_points,
    load_image,
    render,
    render_view,
    save_image,
    to_grey,
    undistort_points,
)
from .sources import frames

__all__ = [
    "TAG_FAMILIES",
    "TARGETS",
    "TRACKER_SETTINGS",
    "Distortion",
    "DotTracker",
    "Dots",
    "PixelNoiseMeter",
    "Tags",
    "TagTracker",
    "decode_image",
    "detect_dots",
    "detect_tags",
    "distort_points",
    "frames",
    "load_image",
    "render",
    "render_view",
    "save_image",
    "to_grey",
    "undistort_points",
]
