"""Calibration: hand-eye (the camera's mount on the gripper), camera calibration files, and the
reference depths (from the object's model, from a known translation, or the plane + parallax
estimate of appendix A)."""

from ._core import (
    Calibration,
    HandEyeAgreement,
    HandEyeCalibration,
    PlaneParallax,
    ResectionDepths,
    calibrate_hand_eye,
    compare_hand_eye_methods,
    depths_from_translation,
    estimate_plane_parallax,
    load_calibration,
    reference_depths,
)

__all__ = [
    "Calibration",
    "HandEyeAgreement",
    "HandEyeCalibration",
    "PlaneParallax",
    "ResectionDepths",
    "calibrate_hand_eye",
    "compare_hand_eye_methods",
    "depths_from_translation",
    "estimate_plane_parallax",
    "load_calibration",
    "reference_depths",
]
