"""The simulated half of tests/test_ros_features.py, run in its own process: the loop of
tests/ros_loop_sim.py (camera, robot, supervisor over ROS 2 messages only) with MuJoCo's
textured box (tests/feature_world.py, no marker) in front of the servo camera instead of the
dots. Strict lock-step once started: the camera stops repeating its image, the idle bridge is
given time to drop what it received, then one image is published and every later one only when
a twist moved the robot; so the bridge's k-th twist is its step on the k-th image published
since the start. The frames go to an .npz file beside the output (with the last few annotated
images by stamp) so that the test steps :class:`vsinv.ImageServo` on the very same frames.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile
from sensor_msgs.msg import CameraInfo, Image

import feature_world as fw
from ros_loop_sim import SimCamera, SimRobot, Supervisor, call, spin_until, spinning
from vsinv.ros.gate import stamp_seconds


class FeatureCamera(SimCamera):
    """SimCamera rendering the textured box in MuJoCo (mono8, no distortion), keeping each
    published image by its stamp (seconds)."""

    def __init__(self, world: fw.TexturedBox, fovy: float, K: list[float], start_pose: np.ndarray) -> None:
        self.world, self.fovy = world, fovy
        self.repeat = True
        self.sent: list[tuple[float, np.ndarray]] = []  # (stamp, image) published since the start
        self.recording = False
        super().__init__(None, K, start_pose)  # type: ignore[arg-type]

    def render(self, pose: np.ndarray) -> None:
        self.grey = self.world.render(pose, self.fovy)
        h, w = self.grey.shape
        self.image = Image(height=h, width=w, encoding="mono8", step=w, data=self.grey.tobytes())
        self.image.header.frame_id = "camera_optical_frame"
        fx, fy, u0, v0 = self.K
        self.info = CameraInfo(height=h, width=w, distortion_model="plumb_bob")
        self.info.k = [fx, 0.0, u0, 0.0, fy, v0, 0.0, 0.0, 1.0]
        self.info.p = [fx, 0.0, u0, 0.0, 0.0, fy, v0, 0.0, 0.0, 0.0, 1.0, 0.0]
        self.info.d = [0.0] * 5
        self.publish()

    def publish(self) -> None:
        super().publish()
        if self.recording:
            self.sent.append((stamp_seconds(self.image.header.stamp), self.grey))

    def on_timer(self) -> None:
        if self.repeat:
            super().on_timer()


class Viewer(Supervisor):
    """The supervisor with a viewer of the annotated image keeping the last few by stamp."""

    def __init__(self) -> None:
        super().__init__()
        self.annotated: dict[float, np.ndarray] = {}
        self.create_subscription(Image, "/vsinv_ros/annotated", self.on_annotated, QoSProfile(depth=1))

    def on_annotated(self, msg: Image) -> None:
        rgb = np.frombuffer(bytes(msg.data), np.uint8).reshape(msg.height, msg.width, 3)
        self.annotated[stamp_seconds(msg.header.stamp)] = rgb
        while len(self.annotated) > 3:
            self.annotated.pop(next(iter(self.annotated)))


def lock_step(executor: SingleThreadedExecutor, camera: FeatureCamera, robot: SimRobot, sup: Viewer, deadline: float) -> dict[str, Any]:
    """Starts the bridge in lock-step and waits for its final verdict."""
    out: dict[str, Any] = {}
    spin_until(executor, lambda: sup.status.get("K_hat") is not None, time.monotonic() + 30.0)
    out["K_hat"] = sup.status.get("K_hat")
    camera.repeat = False
    spin_until(executor, lambda: False, time.monotonic() + 1.0)  # the idle bridge drops what it has
    out["start"] = call(executor, sup, "start", deadline)
    if not out["start"][0]:
        return out
    n0 = len(robot.received)
    camera.recording = True
    camera.publish()
    spin_until(executor, lambda: sup.status.get("state") == "stopped", deadline)
    # The verdict's zero twist may come after the status under load: wait (at most 10 s) until
    # there is a twist for every frame published, then half a second for the annotated image.
    spin_until(executor, lambda: len(robot.received) - n0 >= len(camera.sent), min(deadline, time.monotonic() + 10.0))
    spin_until(executor, lambda: False, time.monotonic() + 0.5)
    out.update(status=dict(sup.status), twists=[tw for _, tw, _ in robot.received[n0:]],
               frame_ids=sorted({f for _, _, f in robot.received}), camera_pose=robot.camera_pose().tolist(),
               stamps=[t for t, _ in camera.sent])
    return out


def run(config: dict[str, Any]) -> dict[str, Any]:
    """One servo session to its final verdict: the bridge's twists, the frames published since
    the start (to the .npz file `frames`) and the last annotated images."""
    deadline = time.monotonic() + config["timeout"]
    world = fw.TexturedBox(config["width"], config["height"])
    start = np.asarray(config["start_pose"], dtype=float)
    camera = FeatureCamera(world, config["fovy"], config["K"], start)
    robot = SimRobot(camera, start, np.eye(4), config["dt"], "camera_optical_frame")
    sup = Viewer()
    try:
        with spinning(camera, robot, sup) as executor:
            out = lock_step(executor, camera, robot, sup, deadline)
    finally:
        world.close()
    np.savez_compressed(Path(config["frames"]), frames=np.array([g for _, g in camera.sent]),
                        **{f"annotated {t!r}": rgb for t, rgb in sup.annotated.items()})
    return out


if __name__ == "__main__":
    from ros_sim_main import main

    main(run)
