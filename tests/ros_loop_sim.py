"""The simulated half of tests/test_ros_loop.py, run in its own process (bounded by the test's
timeout and by its own deadline): a camera node and a robot node closing the loop with the
``vsinv_ros`` bridge through ROS 2 messages only, and a supervisor that starts the bridge by
its service and watches its status.

- camera: renders the scenario's servo camera (the 6 mm lens) at the camera pose the robot
  publishes (geometry_msgs/PoseStamped), publishes sensor_msgs/Image (mono8) and CameraInfo
  (the lens's K, no distortion) with one stamp; it repeats its last image every 0.2 s when no
  pose came (discovery, a dropped message), unless paused.
- robot: holds the end effector pose, integrates each TwistStamped (end effector frame) over
  one camera period (simulated time) and publishes the camera pose (end effector pose times
  the mount). Lock-step: one image in flight, so the time from an image's publication to the
  twist's arrival is the loop's latency.
- supervisor: calls ~/start, waits for the status to say stopped; then pauses the camera,
  resets and starts again, and waits for the watchdog to stop the bridge.

Writes the measurements to the JSON file given as --out.
"""

from __future__ import annotations

import json
import math
import time
from contextlib import contextmanager
from typing import Any, Iterator

import numpy as np
from geometry_msgs.msg import PoseStamped, TwistStamped
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile
from sensor_msgs.msg import CameraInfo, CompressedImage, Image
from std_msgs.msg import String
from std_srvs.srv import Trigger

import vsinv


def pose_to_msg(pose: np.ndarray, msg: PoseStamped) -> None:
    """A 4x4 pose into a PoseStamped (the quaternion from vsinv's theta-u)."""
    position, thetau = vsinv.geometry.thetau_from_pose(pose)
    theta = float(np.linalg.norm(thetau))
    axis = thetau / theta if theta > 0 else np.zeros(3)
    q = np.append(axis * math.sin(theta / 2), math.cos(theta / 2))
    p, o = msg.pose.position, msg.pose.orientation
    p.x, p.y, p.z = (float(x) for x in position)
    o.x, o.y, o.z, o.w = (float(x) for x in q)


def pose_from_msg(msg: PoseStamped) -> np.ndarray:
    p, o = msg.pose.position, msg.pose.orientation
    xyz, w = np.array([o.x, o.y, o.z]), o.w
    s = float(np.linalg.norm(xyz))
    thetau = xyz / s * 2 * math.atan2(s, w) if s > 0 else np.zeros(3)
    return vsinv.geometry.pose_from_position_thetau([p.x, p.y, p.z], thetau)


def compress(grey: np.ndarray, how: str) -> CompressedImage:
    """image_transport's compressed message: PNG of the mono8 image, or JPEG (quality 95) of
    it as bgr8, with image_transport's format strings."""
    import cv2

    if how == "png":
        ok, data = cv2.imencode(".png", grey)
        fmt = "mono8; png compressed mono8"
    else:
        ok, data = cv2.imencode(".jpg", np.repeat(grey[:, :, None], 3, 2), [cv2.IMWRITE_JPEG_QUALITY, 95])
        fmt = "bgr8; jpeg compressed bgr8"
    assert ok
    return CompressedImage(format=fmt, data=data.tobytes())


class SimCamera(Node):
    def __init__(self, scenario: vsinv.sim.Scenario, K: list[float], start_pose: np.ndarray, encoding: str = "mono8") -> None:
        super().__init__("sim_camera")
        self.scenario, self.K, self.encoding = scenario, K, encoding
        if encoding in ("png", "jpeg"):  # image_transport's compressed topic
            self.image_pub = self.create_publisher(CompressedImage, "/camera/image_raw/compressed", QoSProfile(depth=1))
        else:
            self.image_pub = self.create_publisher(Image, "/camera/image_raw", QoSProfile(depth=1))
        self.info_pub = self.create_publisher(CameraInfo, "/camera/camera_info", QoSProfile(depth=1))
        self.create_subscription(PoseStamped, "/sim/camera_pose", self.on_pose, QoSProfile(depth=1))
        self.create_timer(0.2, self.on_timer)
        self.paused = False
        self.sent_at = time.monotonic()
        self.published = 0
        self.render(start_pose)

    def render(self, pose: np.ndarray) -> None:
        grey = vsinv.vision.render(self.scenario, pose=pose)
        h, w = grey.shape
        if self.encoding in ("png", "jpeg"):
            self.image = compress(grey, self.encoding)
        elif self.encoding == "mono8":
            self.image = Image(height=h, width=w, encoding="mono8", step=w, data=grey.tobytes())
        else:  # the grey scene in colour: every channel the same
            self.image = Image(height=h, width=w, encoding=self.encoding, step=3 * w, data=np.repeat(grey[:, :, None], 3, 2).tobytes())
        self.image.header.frame_id = "camera_optical_frame"
        fx, fy, u0, v0 = self.K
        self.info = CameraInfo(height=grey.shape[0], width=grey.shape[1], distortion_model="plumb_bob")
        self.info.k = [fx, 0.0, u0, 0.0, fy, v0, 0.0, 0.0, 1.0]
        self.info.p = [fx, 0.0, u0, 0.0, 0.0, fy, v0, 0.0, 0.0, 0.0, 1.0, 0.0]
        self.info.d = [0.0] * 5
        self.publish()

    def publish(self) -> None:
        if self.paused:
            return
        stamp = self.get_clock().now().to_msg()
        self.image.header.stamp = self.info.header.stamp = stamp
        self.info.header.frame_id = self.image.header.frame_id
        self.info_pub.publish(self.info)
        self.image_pub.publish(self.image)
        self.sent_at = time.monotonic()
        self.published += 1

    def on_pose(self, msg: PoseStamped) -> None:
        self.render(pose_from_msg(msg))

    def on_timer(self) -> None:
        if time.monotonic() - self.sent_at > 0.2:
            self.publish()


class SimRobot(Node):
    def __init__(self, camera: SimCamera, ee_pose: np.ndarray, hand_eye: np.ndarray, dt: float, frame: str) -> None:
        super().__init__("sim_robot")
        self.camera, self.ee, self.hand_eye, self.dt, self.frame = camera, ee_pose, hand_eye, dt, frame
        self.pose_pub = self.create_publisher(PoseStamped, "/sim/camera_pose", QoSProfile(depth=1))
        self.create_subscription(TwistStamped, "/servo_node/delta_twist_cmds", self.on_twist, QoSProfile(depth=10))
        self.latencies: list[float] = []
        self.received: list[tuple[float, list[float], str]] = []

    def camera_pose(self) -> np.ndarray:
        return self.ee @ self.hand_eye

    def on_twist(self, msg: TwistStamped) -> None:
        now = time.monotonic()
        t = msg.twist
        twist = [t.linear.x, t.linear.y, t.linear.z, t.angular.x, t.angular.y, t.angular.z]
        self.received.append((now, twist, msg.header.frame_id))
        if not any(twist):
            return  # a stop: nothing moves, no new image is asked for
        self.latencies.append(now - self.camera.sent_at)
        self.ee = self.ee @ vsinv.geometry.exp_twist(twist, self.dt)
        out = PoseStamped()
        out.header.stamp = msg.header.stamp
        out.header.frame_id = "world"
        pose_to_msg(self.camera_pose(), out)
        self.pose_pub.publish(out)


class Supervisor(Node):
    def __init__(self) -> None:
        super().__init__("sim_supervisor")
        self.clients_ = {n: self.create_client(Trigger, f"/vsinv_ros/{n}") for n in ("start", "stop", "reset")}
        self.create_subscription(String, "/vsinv_ros/status", self.on_status, QoSProfile(depth=50))
        self.status: dict[str, Any] = {}

    def on_status(self, msg: String) -> None:
        self.status = json.loads(msg.data)


def spin_until(executor: SingleThreadedExecutor, done: Any, deadline: float) -> bool:
    while time.monotonic() < deadline:
        if done():
            return True
        executor.spin_once(timeout_sec=0.05)
    return bool(done())


def call(executor: SingleThreadedExecutor, sup: Supervisor, name: str, deadline: float) -> tuple[bool, str]:
    """Calls a Trigger service of the bridge, waiting at most 30 s for it."""
    deadline = min(deadline, time.monotonic() + 30.0)
    client = sup.clients_[name]
    if not spin_until(executor, client.service_is_ready, deadline):
        return False, f"service {name} not available"
    future = client.call_async(Trigger.Request())
    if not spin_until(executor, future.done, deadline):
        return False, f"service {name} did not answer"
    result = future.result()
    return bool(result.success), str(result.message)


def converge(executor: SingleThreadedExecutor, camera: SimCamera, robot: SimRobot, sup: Supervisor, deadline: float) -> dict[str, Any]:
    """Starts the bridge once it has a CameraInfo and waits for its final verdict: the loop's
    measurements."""
    out: dict[str, Any] = {}
    spin_until(executor, lambda: sup.status.get("K_hat") is not None, time.monotonic() + 30.0)
    out["K_hat"] = sup.status.get("K_hat")
    out["start"] = call(executor, sup, "start", deadline)
    if not out["start"][0]:
        return out
    t0, n0 = time.monotonic(), len(robot.received)
    spin_until(executor, lambda: sup.status.get("state") == "stopped", deadline)
    elapsed = time.monotonic() - t0
    status = dict(sup.status)
    spin_until(executor, lambda: False, time.monotonic() + 0.3)  # the stop's zero twist
    position, thetau = vsinv.geometry.thetau_from_pose(robot.camera_pose())
    lat = np.array(robot.latencies)
    twists = len(robot.received) - n0
    out.update(
        status=status, seconds=elapsed, twists=twists, images=camera.published,
        rate_hz=twists / elapsed if elapsed > 0 else 0.0,
        latency_median_ms=1e3 * float(np.median(lat)) if lat.size else None,
        latency_p99_ms=1e3 * float(np.percentile(lat, 99)) if lat.size else None,
        error_mm=1e3 * float(np.linalg.norm(position)), error_deg=math.degrees(float(np.linalg.norm(thetau))),
        last_twist=robot.received[-1][1] if robot.received else None,
        frames=sorted({f for _, _, f in robot.received}),
    )
    return out


def annotated_and_refused(executor: SingleThreadedExecutor, camera: SimCamera, sup: Supervisor, deadline: float) -> dict[str, Any]:
    """A new session with a viewer of the annotated image; then an image of another encoding."""
    out: dict[str, Any] = {}
    annotated: list[Image] = []
    viewer = sup.create_subscription(Image, "/vsinv_ros/annotated", annotated.append, QoSProfile(depth=1))
    spin_until(executor, lambda: viewer.get_publisher_count() > 0, time.monotonic() + 10.0)
    spin_until(executor, lambda: False, time.monotonic() + 0.5)  # the bridge's side of the match
    out["reset"] = call(executor, sup, "reset", deadline)
    out["annotated_start"] = call(executor, sup, "start", deadline)
    spin_until(executor, lambda: bool(annotated), time.monotonic() + 10.0)
    out["annotated"] = [(m.encoding, m.width, m.height, len(m.data)) for m in annotated[:1]]
    out["annotated_status"] = dict(sup.status)
    out["stop"] = call(executor, sup, "stop", deadline)
    camera.image_pub.publish(Image(height=2, width=2, encoding="yuv422", step=4, data=bytes(8)))
    spin_until(executor, lambda: "yuv422" in str(sup.status.get("message")), time.monotonic() + 10.0)
    out["refused_message"] = sup.status.get("message")
    return out


def watchdog(executor: SingleThreadedExecutor, camera: SimCamera, robot: SimRobot, sup: Supervisor, deadline: float) -> dict[str, Any]:
    """Started again with the camera silent: the watchdog's stop and the twists sent."""
    camera.paused = True
    spin_until(executor, lambda: False, time.monotonic() + 0.3)
    n1 = len(robot.received)
    out: dict[str, Any] = {"restart": call(executor, sup, "start", deadline)}
    spin_until(executor, lambda: str(sup.status.get("reason")).startswith("watchdog"), time.monotonic() + 10.0)
    spin_until(executor, lambda: False, time.monotonic() + 0.3)
    out["watchdog_status"] = dict(sup.status)
    out["watchdog_twists"] = [tw for _, tw, _ in robot.received[n1:]]
    return out


def sized_scenario(name: str, size: list[int] | None) -> vsinv.sim.Scenario:
    """The scenario, its servo camera's image ``size`` (width, height) with the principal point
    at the centre (the same lens on a larger sensor), or as it is."""
    scenario = vsinv.load_scenario(name)
    if size is None:
        return scenario
    d = scenario.to_dict()
    d["camera"].update(width=float(size[0]), height=float(size[1]), u0=size[0] / 2.0, v0=size[1] / 2.0)
    return vsinv.sim.Scenario.from_dict(d)


@contextmanager
def spinning(*nodes: Node) -> Iterator[SingleThreadedExecutor]:
    """One executor holding `nodes`; on leaving, the executor shut down and the nodes destroyed."""
    executor = SingleThreadedExecutor()
    for node in nodes:
        executor.add_node(node)
    try:
        yield executor
    finally:
        executor.shutdown()
        for node in nodes:
            node.destroy_node()


def run(config: dict[str, Any]) -> dict[str, Any]:
    """The three phases, the nodes destroyed at the end."""
    deadline = time.monotonic() + config["timeout"]
    hand_eye = np.asarray(config["hand_eye"], dtype=float)
    start = np.asarray(config["start_pose"], dtype=float)
    camera = SimCamera(sized_scenario(config["scenario"], config.get("size")), config["K"], start, config.get("encoding", "mono8"))
    robot = SimRobot(camera, start @ np.linalg.inv(hand_eye), hand_eye, config["dt"], config["frame"])
    sup = Supervisor()
    with spinning(camera, robot, sup) as executor:
        out = converge(executor, camera, robot, sup, deadline)
        if out["start"][0] and not config.get("converge_only"):
            out.update(annotated_and_refused(executor, camera, sup, deadline))
            out.update(watchdog(executor, camera, robot, sup, deadline))
        return out


if __name__ == "__main__":
    from ros_sim_main import main

    main(run)
