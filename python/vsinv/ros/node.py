"""The ROS 2 node ``vsinv_ros``: sensor_msgs/Image and sensor_msgs/CameraInfo in,
geometry_msgs/TwistStamped (for MoveIt Servo), the status (std_msgs/String holding JSON,
latched), ``/diagnostics`` (diagnostic_msgs/DiagnosticArray) and the annotated image out,
std_srvs/Trigger services ``~/start``, ``~/stop`` and ``~/reset``, a watchdog timer and a
status heartbeat. This module imports rclpy: import it only with a ROS 2 installation
(``vsinv.ros`` itself does not).

The status is JSON in a std_msgs/String (typed per-point arrays and the uncertainty, which
DiagnosticArray's string key-values would flatten); ``/diagnostics`` carries its summary for
rqt_robot_monitor and the diagnostic aggregator.

Time: the twist's ``header.stamp`` is the node's clock (ROS time: the simulation's clock with
``use_sim_time``) when the twist is sent, which MoveIt Servo compares with its own clock for
its command timeout; the stamp of the image it came from is in the status (``image_stamp``),
and the latency is the node's clock at sending minus that stamp.
"""

from __future__ import annotations

import time
from typing import Any, Optional

import numpy as np
import rclpy
from geometry_msgs.msg import TwistStamped
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, SetParametersResult
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.publisher import Publisher
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.service import Service
from rclpy.subscription import Subscription
from rclpy.timer import Timer
from sensor_msgs.msg import CameraInfo, CompressedImage, Image
from std_msgs.msg import String
from std_srvs.srv import Trigger

from .._core import InvalidInput, VsinvError
from .annotate import annotate
from .conversions import compressed_to_grey, image_to_grey, lens_from_camera_info
from .gate import ImageGate, stamp_seconds
from .live import apply_change
from .params import PARAMETERS, parse_parameters
from .session import BridgeSession, Output, validate_pipeline

try:  # diagnostic_msgs is in every ROS 2 installation; the PyPI wheels install it apart
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
except ImportError:  # pragma: no cover
    DiagnosticArray = None

__all__ = ["BridgeNode", "LifecycleBridgeNode"]

_TYPES = {"str": Parameter.Type.STRING, "bool": Parameter.Type.BOOL, "int": Parameter.Type.INTEGER,
          "float": Parameter.Type.DOUBLE, "floats": Parameter.Type.DOUBLE_ARRAY, "ints": Parameter.Type.INTEGER_ARRAY}
#: Ranges shown by `ros2 param describe` and enforced by ROS on a set.
_FLOAT_RANGES = {"watchdog_timeout": (0.01, 10.0), "max_linear_speed": (0.0, 10.0), "max_angular_speed": (0.0, 20.0),
                 "gain": (0.0, 100.0), "gain_rz": (0.0, 100.0), "status_period": (0.01, 60.0)}
_INT_RANGES = {"image_qos.depth": (1, 100), "decimation": (1, 8)}


def _descriptor(name: str) -> ParameterDescriptor:
    """The ROS descriptor of one of the bridge's parameters: type, description, choices, range."""
    p = next(q for q in PARAMETERS if q.name == name)
    d = ParameterDescriptor(name=name, type=_TYPES[p.kind].value, description=p.doc)
    if p.choices:
        d.additional_constraints = f"one of: {', '.join(p.choices)}"
    if name in _FLOAT_RANGES:
        d.floating_point_range = [FloatingPointRange(from_value=_FLOAT_RANGES[name][0], to_value=_FLOAT_RANGES[name][1])]
    if name in _INT_RANGES:
        d.integer_range = [IntegerRange(from_value=_INT_RANGES[name][0], to_value=_INT_RANGES[name][1], step=1)]
    return d


class _Bridge(Node):
    """The bridge's ROS side, shared by :class:`BridgeNode` (set up at construction) and
    :class:`LifecycleBridgeNode` (set up at configure): parameters, publishers, subscriptions,
    services and timers, and the callbacks. Nothing raises out of a callback: a bad frame is
    said in the status and the robot is stopped with a zero twist."""

    #: Whether images are stepped on and twists sent (a lifecycle node: only while active).
    _live = True
    #: The ~/start, ~/stop and ~/reset services (a lifecycle node's transitions replace them).
    _offer_services = True

    def _setup(self, values: dict[str, Any], declare: bool) -> None:
        """Reads the parameters (``values``; a bad one raises :class:`vsinv.InvalidInput`
        naming it), declares them when ``declare``, and creates everything the bridge uses
        (kept in ``_entities`` for a lifecycle cleanup)."""
        self.config = parse_parameters(values)
        validate_pipeline(self.config)
        if declare:
            self._declare(values)
        self.session = BridgeSession(self.config)
        c = self.config
        self.frame_id = c.end_effector_frame if c.output_frame == "end_effector" else c.camera_frame
        self.gate = ImageGate(c.camera_frame)
        topics = c.topics
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE)
        self.twist_pub = self.create_publisher(TwistStamped, topics["twist"], QoSProfile(depth=10))
        self.status_pub = self.create_publisher(String, topics["status"], latched)
        self.diag_pub = self.create_publisher(DiagnosticArray, "/diagnostics", QoSProfile(depth=10)) if DiagnosticArray else None
        self.annotated_pub = self.create_publisher(Image, topics["annotated"], QoSProfile(depth=1))
        self._entities: list[Any] = [self.twist_pub, self.status_pub, self.annotated_pub] + ([self.diag_pub] if self.diag_pub else [])
        reliability = ReliabilityPolicy.RELIABLE if c.image_reliability == "reliable" else ReliabilityPolicy.BEST_EFFORT
        images = QoSProfile(depth=c.image_depth, history=HistoryPolicy.KEEP_LAST, reliability=reliability)
        if c.image_transport == "compressed":  # image_transport's naming: the raw topic + /compressed
            self._entities.append(self.create_subscription(
                CompressedImage, f"{topics['image'].rstrip('/')}/compressed", self._on_image, images,
                event_callbacks=self._qos_events("image")))
        else:
            self._entities.append(self.create_subscription(Image, topics["image"], self._on_image, images,
                                                           event_callbacks=self._qos_events("image")))
        self._entities.append(self.create_subscription(CameraInfo, topics["camera_info"], self._on_camera_info,
                                                       QoSProfile(depth=1, reliability=reliability),
                                                       event_callbacks=self._qos_events("camera_info")))
        if self._offer_services:
            self._entities += [self.create_service(Trigger, "~/start", self._on_start),
                               self.create_service(Trigger, "~/stop", self._on_stop),
                               self.create_service(Trigger, "~/reset", self._on_reset)]
        self._entities += [self.create_timer(0.01, self._on_watchdog),  # 10 ms: a stop at most that late after the timeout
                           self.create_timer(c.status_period, self._publish_status)]
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self.latency: Optional[float] = None
        self.image_stamp: Optional[float] = None
        self.qos_message: Optional[str] = None
        self._publish_status()
        start = "activate to servo" if not self._offer_services else "servoing at the first image" if c.autostart else "call ~/start to servo"
        self.get_logger().info(
            f"vsinv_ros: {c.target} target, twist to {self.twist_pub.topic_name} in frame {self.frame_id!r}; "
            f"images {c.image_transport}, {c.image_reliability}, keep last {c.image_depth}; {start}"
        )

    def _teardown(self) -> None:
        """Destroys what :meth:`_setup` created (a lifecycle cleanup)."""
        self.remove_on_set_parameters_callback(self._on_set_parameters)
        destroy = {Publisher: self.destroy_publisher, Subscription: self.destroy_subscription,
                   Service: self.destroy_service, Timer: self.destroy_timer}
        for entity in self._entities:
            next(f for kind, f in destroy.items() if isinstance(entity, kind))(entity)
        self._entities = []

    def _declare(self, overrides: dict[str, Any]) -> None:
        """Every parameter declared with its descriptor (`ros2 param describe`), at its value."""
        for p in PARAMETERS:
            value = overrides.get(p.name, p.default)
            descriptor = _descriptor(p.name)
            if value is None:
                descriptor.dynamic_typing = False
                self.declare_parameter(p.name, _TYPES[p.kind], descriptor)
            else:
                try:
                    self.declare_parameter(p.name, value, descriptor)
                except Exception as e:  # a value out of the declared range
                    raise InvalidInput(f"parameter {p.name}: {e}") from None

    def _qos_events(self, what: str) -> Any:
        from rclpy.event_handler import SubscriptionEventCallbacks

        def incompatible(_event: Any) -> None:
            self.qos_message = (f"{what}: a publisher's QoS is incompatible with image_qos.reliability "
                                f"{self.config.image_reliability!r} (a best_effort camera needs best_effort)")
            self.get_logger().warning(f"vsinv_ros: {self.qos_message}")
            self._publish_status()

        return SubscriptionEventCallbacks(incompatible_qos=incompatible)

    # ---- callbacks ------------------------------------------------------------------------
    def _on_camera_info(self, msg: CameraInfo) -> None:
        refused = self.gate.camera_info(msg)
        if refused is not None:
            self._send(self.session.refuse_frame(refused))
            return
        try:
            lens = lens_from_camera_info(msg, self.config.image_rectified)
        except InvalidInput as e:
            self._send(self.session.refuse_frame(e))
            return
        first = self.session.lens is None
        self.session.camera_info(lens)
        if first:
            self._publish_status()

    def _on_image(self, msg: Image | CompressedImage) -> None:
        if not self._live:
            return
        try:
            self._servo_on(msg)
        except Exception as e:  # a fault of the bridge itself: the robot stops, the node stays up
            self.get_logger().error(f"vsinv_ros: internal error on an image: {e!r}")
            self._send(self.session.stop(f"internal error: {e!r}"))

    def _servo_on(self, msg: Image | CompressedImage) -> None:
        """One image: checked (a refusal publishes a zero twist at once), converted (a
        compressed one decoded), stepped while running; the twist, status and annotated image
        sent."""
        received = time.monotonic()
        size: Optional[tuple[int, int]] = None
        try:
            if isinstance(msg, CompressedImage):
                grey = compressed_to_grey(msg)
                size = (grey.shape[1], grey.shape[0])
            else:
                grey = image_to_grey(msg)
            refused = self.gate.check(msg, size)
        except InvalidInput as e:
            refused = str(e)
        if refused is not None:
            self._send(self.session.refuse_frame(refused))
            return
        if self.session.state != "running" and not (self.config.autostart and self.session.pipeline is None):
            return
        out = self.session.frame(grey, received)
        if out.frame_used:
            self.gate.used(msg, size)
            self.image_stamp = stamp_seconds(msg.header.stamp)
        if out.twist is not None:
            self._publish_twist(out.twist)
            self.latency = self._now() - self.image_stamp if self.image_stamp else None
        self._publish_status()
        if out.frame_used and self.config.publish_annotated and self.annotated_pub.get_subscription_count() > 0:
            step = out.step
            marks = (step.pixels, step.found) if step is not None else (np.zeros((0, 2)), np.zeros(0, bool))
            self._publish_annotated(msg, annotate(grey, *marks))

    def _on_watchdog(self) -> None:
        out = self.session.watchdog(time.monotonic())
        if out.twist is not None:
            self._send(out)

    def _on_set_parameters(self, params: list[Parameter]) -> SetParametersResult:
        """`ros2 param set`: the speed limits and the watchdog at once, the gains from the next
        session, the rest refused with the reason (all or nothing)."""
        reasons = []
        for p in params:
            ok, reason = apply_change(self.session, p.name, p.value)
            if not ok:
                return SetParametersResult(successful=False, reason=reason)
            reasons.append(reason)
        self.session.message = "; ".join(reasons)
        self._publish_status()
        return SetParametersResult(successful=True, reason="; ".join(reasons))

    def _on_start(self, _request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        if self.session.pipeline is None or self.session.finished:
            self.gate.reset()  # a new session: a new frame, stamps and size
        response.success, response.message = self.session.start(time.monotonic())
        self._publish_status()
        return response

    def _on_stop(self, _request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        self._send(self.session.stop("stopped by request"))
        response.success, response.message = True, "stopped"
        return response

    def _on_reset(self, _request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        self._send(self.session.reset())
        self.gate.reset()
        response.success, response.message = True, "reset: the next start begins a new session"
        return response

    # ---- publishing -----------------------------------------------------------------------
    def _now(self) -> float:
        sec, nanosec = self.get_clock().now().seconds_nanoseconds()
        return sec + 1e-9 * nanosec

    def _send(self, out: Output) -> None:
        if out.twist is not None and self._live:
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
        extra = {"frame_id": self.frame_id, "latency": self.latency, "image_stamp": self.image_stamp,
                 "qos": self.qos_message, "watchdog_timeout": self.config.watchdog_timeout,
                 "image_size": self.gate.size(), "image_frame": self.gate.frame}
        text = self.session.status_json(**extra)
        self.status_pub.publish(String(data=text))
        if self.diag_pub is not None:
            self.diag_pub.publish(self._diagnostics())

    def _diagnostics(self) -> Any:
        """The status as one DiagnosticStatus: OK idle or running, WARN stopped by request or
        a final verdict, ERROR stopped by a refused image, the watchdog or an internal error."""
        s = self.session
        reason = s.reason or ""
        faulty = reason.startswith(("refused", "watchdog", "internal", "frame refused"))
        level = DiagnosticStatus.ERROR if s.state == "stopped" and faulty else (
            DiagnosticStatus.WARN if s.state == "stopped" or self.qos_message else DiagnosticStatus.OK)
        status = DiagnosticStatus(level=level, name=f"{self.get_name()}: visual servo", hardware_id=self.frame_id)
        status.message = f"{s.state}" + (f": {reason}" if reason else "")
        step = s.last_step
        values = {"state": s.state, "reason": reason, "message": s.message or "", "iterations": s.pipeline.iterations if s.pipeline else 0,
                  "verdict": step.verdict if step is not None else "", "latency_s": self.latency, "qos": self.qos_message or "",
                  "watchdog_timeout_s": self.config.watchdog_timeout}
        status.values = [KeyValue(key=k, value="" if v is None else str(v)) for k, v in values.items()]
        array = DiagnosticArray(status=[status])
        array.header.stamp = self.get_clock().now().to_msg()
        return array

    def _publish_annotated(self, source: Image | CompressedImage, rgb: np.ndarray) -> None:
        msg = Image()
        msg.header = source.header
        msg.height, msg.width = rgb.shape[:2]
        msg.encoding, msg.is_bigendian, msg.step = "rgb8", 0, 3 * rgb.shape[1]
        msg.data = rgb.tobytes()
        self.annotated_pub.publish(msg)

    def halt(self) -> None:
        """At shutdown: a last zero twist, whatever the state."""
        if rclpy.ok(context=self.context) and getattr(self, "session", None) is not None:
            self._send(self.session.stop("node shut down"))


class BridgeNode(_Bridge):
    """The bridge as a plain node. Its parameters are read at construction (a misspelt one is
    refused by name) and a bad one raises :class:`vsinv.InvalidInput` there; servoing starts
    by the ~/start service (or ``autostart``)."""

    def __init__(self, name: str = "vsinv_ros", **kwargs: Any) -> None:
        super().__init__(name, **kwargs)
        self._setup({k: p.value for k, p in self._parameter_overrides.items()}, declare=True)


class LifecycleBridgeNode(_Bridge, LifecycleNode):
    """The bridge as a managed (lifecycle) node, for a system that brings its nodes up in
    order (``vsinv-ros --lifecycle``; ``ros2 lifecycle set /vsinv_ros configure`` ...):

    - configure: reads the parameters (a bad one fails the transition, named in the log) and
      creates the publishers, subscriptions and timers; the status is latched from then on;
    - activate: starts servoing (a new session after a final verdict), as ~/start; it fails
      without a lens (no CameraInfo yet and no K_hat);
    - deactivate: one zero twist, then silent: images are not read and no twist is sent
      until the next activate (the status and /diagnostics go on);
    - cleanup: destroys what configure created (the parameters stay declared: a new
      configure reads their current values); shutdown: a last zero twist if active.

    The ~/start, ~/stop and ~/reset services are not offered: the transitions replace them."""

    _live = False
    _offer_services = False

    def __init__(self, name: str = "vsinv_ros", **kwargs: Any) -> None:
        super().__init__(name, **kwargs)
        self.session: Optional[BridgeSession] = None  # type: ignore[assignment]

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        declared = self.has_parameter("reference_image")
        if declared:  # a configure after a cleanup: the current values that are not the defaults
            current = {p.name: (self.get_parameter_or(p.name, Parameter(p.name)).value, p.default) for p in PARAMETERS}
            values = {k: v for k, (v, default) in current.items() if v is not None and v != default}
        else:
            values = {k: p.value for k, p in self._parameter_overrides.items()}
        try:
            self._setup(values, declare=not declared)
        except VsinvError as e:
            self.get_logger().error(f"vsinv_ros: refused to configure: {e}")
            return TransitionCallbackReturn.FAILURE
        return TransitionCallbackReturn.SUCCESS

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        assert self.session is not None
        if self.session.pipeline is None or self.session.finished:
            self.gate.reset()  # a new session: a new frame, stamps and size
        ok, message = self.session.start(time.monotonic())
        self._publish_status()
        if not ok:
            self.get_logger().error(f"vsinv_ros: cannot activate: {message}")
            return TransitionCallbackReturn.FAILURE
        self._live = True
        return super().on_activate(state)

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        self._stop_once("deactivated")
        return super().on_deactivate(state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        self._teardown()
        self.session = None
        return TransitionCallbackReturn.SUCCESS

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        self._stop_once("node shut down")
        if self.session is not None:
            self._teardown()
        return TransitionCallbackReturn.SUCCESS

    def on_error(self, state: LifecycleState) -> TransitionCallbackReturn:
        self._stop_once("lifecycle error")
        return TransitionCallbackReturn.SUCCESS

    def _stop_once(self, reason: str) -> None:
        """While active: the session stopped with one zero twist, then nothing more is sent."""
        if self.session is not None and self._live:
            self._send(self.session.stop(reason))
        self._live = False
        if self.session is not None:
            self._publish_status()
