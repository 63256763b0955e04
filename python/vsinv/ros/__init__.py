"""vsinv's ROS 2 bridge (``vsinv-ros``, ``python -m vsinv.ros``): a node that runs
:class:`vsinv.ImageServo` on a camera's images and sends the twist to MoveIt Servo. rclpy comes
from the user's ROS 2 installation (the extra ``vsinv[ros]`` adds nothing): importing this
package does not import rclpy; :mod:`vsinv.ros.node` does."""

from .conversions import hand_eye_matrix, image_to_grey, lens_from_camera_info, twist_in_end_effector_frame
from .params import PARAMETERS, BridgeConfig, parse_parameters
from .session import BridgeSession, validate_pipeline

__all__ = [
    "PARAMETERS",
    "BridgeConfig",
    "BridgeSession",
    "hand_eye_matrix",
    "image_to_grey",
    "lens_from_camera_info",
    "parse_parameters",
    "twist_in_end_effector_frame",
    "validate_pipeline",
]
