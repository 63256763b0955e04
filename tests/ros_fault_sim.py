"""The simulated half of tests/test_ros_loop.py's fault test, in its own process (bounded by
the test's timeout and its own deadline): a camera publishing one rendered image (a fresh stamp
each time, lock-step: the next image after the twist), a twist listener, /diagnostics and
status listeners and a supervisor calling the bridge's services and parameter services.

Phases: the latched status before any image; each fault (an unusable image, a CameraInfo of
another size) sent while running, timed from its publication to the zero twist; parameter
sets (applied, refused) and descriptions; the watchdog set shorter. Writes JSON to --out."""

from __future__ import annotations

import contextlib
import json
import time
from typing import Any, Callable, Iterator

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import TwistStamped
from rcl_interfaces.msg import Parameter as ParameterMsg
from rcl_interfaces.msg import ParameterType, ParameterValue
from rcl_interfaces.srv import DescribeParameters, SetParameters
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import CameraInfo, Image
from std_msgs.msg import String
from std_srvs.srv import Trigger

import vsinv

FRAME = "camera_optical_frame"


class Rig(Node):
    def __init__(self, grey: np.ndarray, K: list[float]) -> None:
        super().__init__("fault_rig")
        self.grey = grey
        self.image_pub = self.create_publisher(Image, "/camera/image_raw", QoSProfile(depth=1))
        self.info_pub = self.create_publisher(CameraInfo, "/camera/camera_info", QoSProfile(depth=1))
        self.twists: list[tuple[float, list[float], str, float]] = []
        self.create_subscription(TwistStamped, "/servo_node/delta_twist_cmds", self.on_twist, QoSProfile(depth=50))
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.status: dict[str, Any] = {}
        self.statuses = 0
        self.create_subscription(String, "/vsinv_ros/status", self.on_status, latched)
        self.diagnostics: list[DiagnosticArray] = []
        self.create_subscription(DiagnosticArray, "/diagnostics", self.diagnostics.append, QoSProfile(depth=50))
        self.clients_ = {n: self.create_client(Trigger, f"/vsinv_ros/{n}") for n in ("start", "stop", "reset")}
        self.set_client = self.create_client(SetParameters, "/vsinv_ros/set_parameters")
        self.describe_client = self.create_client(DescribeParameters, "/vsinv_ros/describe_parameters")
        h, w = grey.shape
        fx, fy, u0, v0 = K
        self.info = CameraInfo(height=h, width=w, distortion_model="plumb_bob", k=[fx, 0.0, u0, 0.0, fy, v0, 0.0, 0.0, 1.0])
        self.info.header.frame_id = FRAME
        self.last: Image | None = None

    def on_twist(self, msg: TwistStamped) -> None:
        t = msg.twist
        stamp = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
        self.twists.append((time.monotonic(), [t.linear.x, t.linear.y, t.linear.z, t.angular.x, t.angular.y, t.angular.z],
                            msg.header.frame_id, stamp))

    def on_status(self, msg: String) -> None:
        self.status = json.loads(msg.data)
        self.statuses += 1

    def image(self, **change: Any) -> Image:
        h, w = self.grey.shape
        msg = Image(height=h, width=w, encoding="mono8", step=w, data=self.grey.tobytes())
        msg.header.frame_id = FRAME
        msg.header.stamp = self.get_clock().now().to_msg()
        for k, v in change.items():
            setattr(msg, k, v)
        return msg


def spin_until(ex: SingleThreadedExecutor, done: Callable[[], bool], timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if done():
            return True
        ex.spin_once(timeout_sec=0.002)
    return bool(done())


def call(ex: SingleThreadedExecutor, client: Any, request: Any) -> Any:
    if not spin_until(ex, client.service_is_ready, 60.0):
        raise RuntimeError(f"service {client.srv_name} not available")
    future = client.call_async(request)
    spin_until(ex, future.done, 30.0)
    return future.result()


def running(ex: SingleThreadedExecutor, rig: Rig) -> bool:
    """Starts the bridge if needed and sends good images until a non-zero twist comes back."""
    if rig.status.get("state") != "running":
        call(ex, rig.clients_["start"], Trigger.Request())
    for _ in range(20):
        n = len(rig.twists)
        rig.last = rig.image()
        rig.image_pub.publish(rig.last)
        if spin_until(ex, lambda: len(rig.twists) > n, 2.0) and any(rig.twists[-1][1]):
            return True
    return False


def fault(ex: SingleThreadedExecutor, rig: Rig, send: Callable[[], None]) -> dict[str, Any]:
    """One fault while running: the time to the first twist after it, that twist, the status."""
    ok = running(ex, rig)
    n = len(rig.twists)
    t0 = time.monotonic()
    send()
    spin_until(ex, lambda: len(rig.twists) > n, 2.0)
    spin_until(ex, lambda: rig.status.get("state") == "stopped", 1.0)
    first = rig.twists[n] if len(rig.twists) > n else None
    return {"was_running": ok, "ms": 1e3 * (first[0] - t0) if first else None, "twist": first[1] if first else None,
            "state": rig.status.get("state"), "reason": rig.status.get("reason")}


def faults(ex: SingleThreadedExecutor, rig: Rig) -> dict[str, Any]:
    h, w = rig.grey.shape
    older = lambda: rig.image(header=rig.last.header.__class__(frame_id=FRAME, stamp=rig.last.header.stamp.__class__(
        sec=rig.last.header.stamp.sec - 1, nanosec=rig.last.header.stamp.nanosec)))
    small = np.zeros((480, 640), np.uint8)
    cases: dict[str, Callable[[], Any]] = {
        "encoding bayer_rggb8": lambda: rig.image(encoding="bayer_rggb8"),
        "encoding 8UC1": lambda: rig.image(encoding="8UC1"),
        "encoding empty": lambda: rig.image(encoding=""),
        "step < width": lambda: rig.image(step=w - 1),
        "short data": lambda: rig.image(data=rig.grey.tobytes()[: h * w // 2]),
        "0x0 image": lambda: rig.image(height=0, width=0, step=0, data=b""),
        "size 640x480": lambda: rig.image(height=480, width=640, step=640, data=small.tobytes()),
        "frame_id other": lambda: rig.image(header=rig.last.header.__class__(frame_id="other", stamp=rig.get_clock().now().to_msg())),
        "frame_id empty": lambda: rig.image(header=rig.last.header.__class__(frame_id="", stamp=rig.get_clock().now().to_msg())),
        "duplicate": lambda: rig.last,
        "out of order": older,
    }
    out = {}
    for name, make in cases.items():
        try:
            out[name] = fault(ex, rig, lambda make=make: rig.image_pub.publish(make()))
        except RuntimeError as e:
            raise RuntimeError(f"at the fault {name!r}, the status {rig.status}: {e}") from e
    info = CameraInfo(height=480, width=640, k=list(rig.info.k), distortion_model="plumb_bob")
    out["camera_info 640x480"] = fault(ex, rig, lambda: rig.info_pub.publish(info))
    return out


def set_parameter(ex: SingleThreadedExecutor, rig: Rig, name: str, value: Any) -> tuple[bool, str]:
    v = ParameterValue()
    if isinstance(value, float):
        v.type, v.double_value = ParameterType.PARAMETER_DOUBLE, value
    else:
        v.type, v.string_value = ParameterType.PARAMETER_STRING, value
    result = call(ex, rig.set_client, SetParameters.Request(parameters=[ParameterMsg(name=name, value=v)])).results[0]
    return bool(result.successful), str(result.reason)


def parameters(ex: SingleThreadedExecutor, rig: Rig) -> dict[str, Any]:
    out: dict[str, Any] = {}
    running(ex, rig)
    out["speed_before"] = float(np.linalg.norm(rig.twists[-1][1][:3]))
    out["set_speed"] = set_parameter(ex, rig, "max_linear_speed", 0.01)
    running(ex, rig)
    out["speed_after"] = float(np.linalg.norm(rig.twists[-1][1][:3]))
    out["set_target"] = set_parameter(ex, rig, "target", "tags")
    out["set_watchdog"] = set_parameter(ex, rig, "watchdog_timeout", 0.2)
    running(ex, rig)
    t0, n = rig.twists[-1][0], len(rig.twists)
    spin_until(ex, lambda: len(rig.twists) > n, 3.0)  # no image: the watchdog's zero twist
    out["watchdog_ms"] = 1e3 * (rig.twists[-1][0] - t0) if len(rig.twists) > n else None
    spin_until(ex, lambda: str(rig.status.get("reason")).startswith("watchdog"), 2.0)
    out["watchdog_reason"] = rig.status.get("reason")
    d = call(ex, rig.describe_client, DescribeParameters.Request(names=["watchdog_timeout", "image_qos.reliability"])).descriptors
    out["describe"] = [{"name": x.name, "description": x.description, "constraints": x.additional_constraints,
                        "range": [(r.from_value, r.to_value) for r in x.floating_point_range]} for x in d]
    return out


@contextlib.contextmanager
def spun_rig(make: Callable[..., Any], config: dict[str, Any]) -> Iterator[tuple[SingleThreadedExecutor, Any]]:
    """A rig (`make(first image, K)`, the config's scenario rendered at its start pose) spun by
    its own executor; both shut down after."""
    scenario = vsinv.load_scenario(config["scenario"])
    rig = make(vsinv.vision.render(scenario, pose=np.asarray(config["start_pose"], dtype=float)), config["K"])
    ex = SingleThreadedExecutor()
    ex.add_node(rig)
    try:
        yield ex, rig
    finally:
        ex.shutdown()
        rig.destroy_node()


def run(config: dict[str, Any]) -> dict[str, Any]:
    with spun_rig(Rig, config) as (ex, rig):
        spin_until(ex, lambda: rig.statuses > 0, 30.0)
        out: dict[str, Any] = {"status_before_images": dict(rig.status)}
        rig.info_pub.publish(rig.info)
        spin_until(ex, lambda: rig.status.get("K_hat") is not None, 10.0)
        out["faults"] = faults(ex, rig)
        out["parameters"] = parameters(ex, rig)
        # a best-effort camera against the default (reliable) subscription: said in the status
        rig.create_publisher(Image, "/camera/image_raw", QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT))
        spin_until(ex, lambda: rig.status.get("qos") is not None, 10.0)
        out["qos"] = rig.status.get("qos")
        out["frames"] = sorted({f for _, _, f, _ in rig.twists})
        out["stamps_set"] = all(s > 0 for _, _, _, s in rig.twists)
        out["diagnostics"] = [(s.level if isinstance(s.level, int) else int.from_bytes(s.level, "little"), s.name, s.message)
                              for a in rig.diagnostics for s in a.status]
        return out


if __name__ == "__main__":
    from ros_sim_main import main

    main(run)
