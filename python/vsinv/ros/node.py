"""The ROS 2 node ``vsinv_ros``: sensor_msgs/Image and sensor_msgs/CameraInfo in,
geometry_msgs/TwistStamped (for MoveIt Servo), the status (std_msgs/String holding JSON) and
the annotated image out, std_srvs/Trigger services ``~/start``, ``~/stop`` and ``~/reset``,
and a watchdog timer. This module imports rclpy: import it only with a ROS 2 installation
(``vsinv.ros`` itself does not).

The status is JSON in a std_msgs/String: a package installed with pip cannot ship compiled
message types, and diagnostic_msgs/DiagnosticArray holds only string key-values, which would
flatten the per-point arrays and the uncertainty; JSON keeps them typed, `ros2 topic echo`
shows it, and every client library parses it.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import rclpy
from geometry_msgs.msg import TwistStamped
from rclpy.node import Node
from rclpy.qos import QoSProfile, qos_profile_sensor_data
from sensor_msgs.msg import CameraInfo, Image
from std_msgs.msg import String
from std_srvs.srv import Trigger

from .._core import InvalidInput
from .annotate import annotate
from .conversions import image_to_grey, lens_from_camera_info
from .params import parse_parameters
from .session import BridgeSession, Output, validate_pipeline

__all__ = ["BridgeNode"]


class BridgeNode(Node):
    """The bridge. Its parameters are read at construction (every parameter given is declared
    from the overrides, so a misspelt one is refused by name) and a bad one raises
    :class:`vsinv.InvalidInput` there; afterwards nothing raises out of a callback for a bad
    frame: it is said in the status and the robot is stopped."""

    def __init__(self, name: str = "vsinv_ros", **kwargs: Any) -> None:
        super().__init__(name, automatically_declare_parameters_from_overrides=True, **kwargs)
        values = {k: p.value for k, p in self.get_parameters_by_prefix("").items()}
        self.config = parse_parameters(values)
        validate_pipeline(self.config)
        self.session = BridgeSession(self.config)
        self.frame_id = self.config.end_effector_frame if self.config.output_frame == "end_effector" else self.config.camera_frame
        topics = self.config.topics
        self.twist_pub = self.create_publisher(TwistStamped, topics["twist"], QoSProfile(depth=10))
        self.status_pub = self.create_publisher(String, topics["status"], QoSProfile(depth=10))
        self.annotated_pub = self.create_publisher(Image, topics["annotated"], QoSProfile(depth=1))
        self.create_subscription(Image, topics["image"], self._on_image, qos_profile_sensor_data)
        self.create_subscription(CameraInfo, topics["camera_info"], self._on_camera_info, qos_profile_sensor_data)
        self.create_service(Trigger, "~/start", self._on_start)
        self.create_service(Trigger, "~/stop", self._on_stop)
        self.create_service(Trigger, "~/reset", self._on_reset)
        period = min(self.config.watchdog_timeout / 4.0, 0.05)
        self.create_timer(period, self._on_watchdog)
        self.latency: float | None = None
        self.get_logger().info(
            f"vsinv_ros: {self.config.target} target, twist to {self.twist_pub.topic_name} in the "
            f"{self.config.output_frame} frame; {'servoing at the first image' if self.config.autostart else 'call ~/start to servo'}"
        )

    # ---- callbacks ------------------------------------------------------------------------
    def _on_camera_info(self, msg: CameraInfo) -> None:
        try:
            self.session.camera_info(lens_from_camera_info(msg, self.config.image_rectified))
        except InvalidInput as e:
            self.session.refuse_frame(e)
            self._publish_status()

    def _on_image(self, msg: Image) -> None:
        try:
            self._servo_on(msg)
        except Exception as e:  # a fault of the bridge itself: the robot stops, the node stays up
            self.get_logger().error(f"vsinv_ros: internal error on an image: {e!r}")
            self._send(self.session.stop(f"internal error: {e!r}"))

    def _servo_on(self, msg: Image) -> None:
        """One image: converted, stepped while running, the twist, status and annotated image sent."""
        received = time.monotonic()
        if not self.config.camera_frame and msg.header.frame_id and self.config.output_frame == "camera":
            self.frame_id = msg.header.frame_id
        try:
            grey = image_to_grey(msg)
        except InvalidInput as e:
            self.session.refuse_frame(e)
            self._publish_status()
            return
        out = self.session.frame(grey, received)
        if out.twist is not None:
            self._publish_twist(out.twist)
            stamp = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
            self.latency = self._now() - stamp if stamp > 0 else None
        self._publish_status()
        if out.frame_used and self.config.publish_annotated and self.annotated_pub.get_subscription_count() > 0:
            step = out.step
            marks = (step.pixels, step.found) if step is not None else (np.zeros((0, 2)), np.zeros(0, bool))
            self._publish_annotated(msg, annotate(grey, *marks))

    def _on_watchdog(self) -> None:
        out = self.session.watchdog(time.monotonic())
        if out.twist is not None:
            self._publish_twist(out.twist)
            self._publish_status()

    def _on_start(self, _request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        response.success, response.message = self.session.start(time.monotonic())
        self._publish_status()
        return response

    def _on_stop(self, _request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        self._send(self.session.stop("stopped by request"))
        response.success, response.message = True, "stopped"
        return response

    def _on_reset(self, _request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        self._send(self.session.reset())
        response.success, response.message = True, "reset: the next start begins a new session"
        return response

    # ---- publishing -----------------------------------------------------------------------
    def _now(self) -> float:
        sec, nanosec = self.get_clock().now().seconds_nanoseconds()
        return sec + 1e-9 * nanosec

    def _send(self, out: Output) -> None:
        if out.twist is not None:
            self._publish_twist(out.twist)
        self._publish_status()

    def _publish_twist(self, twist: np.ndarray) -> None:
        msg = TwistStamped()
        msg.header.stamp = self.get_clock().now().to_msg()
        msg.header.frame_id = self.frame_id
        (msg.twist.linear.x, msg.twist.linear.y, msg.twist.linear.z,
         msg.twist.angular.x, msg.twist.angular.y, msg.twist.angular.z) = (float(x) for x in twist)
        self.twist_pub.publish(msg)

    def _publish_status(self) -> None:
        text = self.session.status_json(frame_id=self.frame_id, latency=self.latency)
        self.status_pub.publish(String(data=text))

    def _publish_annotated(self, source: Image, rgb: np.ndarray) -> None:
        msg = Image()
        msg.header = source.header
        msg.height, msg.width = rgb.shape[:2]
        msg.encoding, msg.is_bigendian, msg.step = "rgb8", 0, 3 * rgb.shape[1]
        msg.data = rgb.tobytes()
        self.annotated_pub.publish(msg)

    def halt(self) -> None:
        """At shutdown: a last zero twist, whatever the state."""
        if rclpy.ok(context=self.context):
            self._send(self.session.stop("node shut down"))
