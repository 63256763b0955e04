"""The ROS 2 bridge end to end over ROS 2 topics (skipped when rclpy is not importable: CI
installs the PyPI wheels ros-rclpy and the message packages, the extra vsinv[ros-test]): the
bridge (``python -m vsinv.ros``, its own process) and a simulated camera and robot
(tests/ros_loop_sim.py, another process) close the paper's lens change loop: reference image
from the 12 mm lens, frames from the 6 mm lens whose CameraInfo gives K_hat, the twist in the
end effector frame through a hand-eye transform. Loopback only, a domain id of its own, each
process bounded in time and stopped at the end.

Measured and printed: iterations, final errors, the message rate and the latency from an
image's publication to the twist's arrival (median, 99th percentile)."""

from __future__ import annotations

import importlib.util
import json
import os
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import vsinv
from vsinv.images import write_scenario_images
from vsinv.ros import hand_eye_matrix

INSTALL_HINT = "source a ROS 2 installation, or pip install the PyPI wheels of the extra ros-test"
PROBE = (
    "import rclpy\nfrom sensor_msgs.msg import Image, CameraInfo\nfrom geometry_msgs.msg import TwistStamped\n"
    "from std_msgs.msg import String\nfrom std_srvs.srv import Trigger\nrclpy.init()\nrclpy.shutdown()\n"
)


@pytest.fixture(scope="module", autouse=True)
def ros_ready() -> None:
    """Skips, saying why, unless rclpy and the messages import and rclpy starts (in a process
    of its own: a broken install must not take pytest down)."""
    if importlib.util.find_spec("rclpy") is None:
        pytest.skip(f"rclpy is not importable ({INSTALL_HINT})")
    try:
        probe = subprocess.run([sys.executable, "-c", PROBE], env=ros_env(), capture_output=True, text=True, timeout=120)
    except subprocess.TimeoutExpired:
        pytest.skip(f"rclpy did not start within 120 s ({INSTALL_HINT})")
    if probe.returncode != 0:
        last = (probe.stderr.strip().splitlines() or ["no message"])[-1]
        pytest.skip(f"rclpy does not start: {last} ({INSTALL_HINT})")


HERE = Path(__file__).resolve().parent
SCENARIO = "vision-12-6"
OBJECT_Z = [0.60, 0.66, 0.56, 0.63, 0.54, 0.65, 0.62, 0.57, 0.64, 0.55, 0.61, 0.66]
K_6MM = [600.0, 600.0, 416.0, 312.0]  # the scenario's servo camera, as its CameraInfo says
# The camera 40 mm ahead and 90 mm along x of the flange, turned 30 degrees about z.
HAND_EYE = [0.09, 0.0, 0.04, 0.0, 0.0, float(np.sin(np.radians(15.0))), float(np.cos(np.radians(15.0)))]
DT = 0.01  # the scenario's camera period: the robot holds each twist for 10 ms


def ros_env() -> dict[str, str]:
    """Loopback discovery and a domain id of this test run's own: pytest-xdist's workers (gw0,
    gw1, ...) each get their own band of ids, so two tests of one run never share a domain."""
    env = dict(os.environ)
    worker = int(os.environ.get("PYTEST_XDIST_WORKER", "gw0").removeprefix("gw") or 0)
    domain = 10 + (worker % 4) * 20 + os.getpid() % 20
    env.update(ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST", ROS_LOCALHOST_ONLY="1", ROS_DOMAIN_ID=str(domain))
    env.pop("ROS_STATIC_PEERS", None)
    return env


def bridge_parameters(tmp_path: Path) -> dict[str, Any]:
    scenario = vsinv.load_scenario(SCENARIO)
    write_scenario_images(scenario, tmp_path)
    ref_px = vsinv.images.read_points(tmp_path / "reference.csv")
    start_px = vsinv.images.read_points(tmp_path / "start.csv")
    return {
        "reference_image": str(tmp_path / "reference.png"),
        "target": "dots",
        "reference_points": [float(x) for x in (ref_px + 2.0).ravel()],
        "first_points": [float(x) for x in (start_px - 2.0).ravel()],
        "reference_depths": OBJECT_Z,
        "law": "invariant",
        "rz_task": "tau21",
        "max_linear_speed": 0.25,
        "max_angular_speed": float(np.radians(60.0)),
        "dt": DT,
        "stop": {"max_iterations": 3000, "invariant_error": 1e-3, "tau21": 5e-4, "window": 50},
        "output_frame": "end_effector",
        "end_effector_frame": "tool0",
        "hand_eye": HAND_EYE,
        "watchdog_timeout": 1.0,
        "image_topic": "/camera/image_raw",
        "camera_info_topic": "/camera/camera_info",
        "twist_topic": "/servo_node/delta_twist_cmds",
    }


def write_params(path: Path, parameters: dict[str, Any]) -> Path:
    """A ROS 2 parameters file (JSON is YAML's flow style) for every node."""
    path.write_text(json.dumps({"/**": {"ros__parameters": parameters}}))
    return path


def stop(process: subprocess.Popen[str]) -> tuple[str, str]:
    """Stops a process by SIGINT (the bridge's last zero twist), killing it after 10 s."""
    if process.poll() is None:
        process.send_signal(signal.SIGINT)
    try:
        return process.communicate(timeout=10)
    except subprocess.TimeoutExpired:
        process.kill()
        return process.communicate()


def in_process_loop(parameters: dict[str, Any], start: np.ndarray) -> tuple[int, float, float]:
    """The same pipeline stepped in this process on the same renderings (K_hat the CameraInfo's,
    the twist integrated in the camera frame): iterations, final errors (mm, degrees)."""
    scenario = vsinv.load_scenario(SCENARIO)
    options = {k: v for k, v in parameters.items() if k in ("reference_depths", "law", "rz_task", "max_linear_speed",
                                                            "max_angular_speed", "dt", "stop")}
    pipeline = vsinv.ImageServo(
        vsinv.vision.load_image(parameters["reference_image"]), "dots", vsinv.Intrinsics(*K_6MM),
        reference_points=np.reshape(parameters["reference_points"], (-1, 2)),
        first_points=np.reshape(parameters["first_points"], (-1, 2)), **options,
    )
    pose = start
    for _ in range(parameters["stop"]["max_iterations"] + 1):
        step = pipeline.step(vsinv.vision.render(scenario, pose=pose))
        if not step.running:
            break
        pose = pose @ vsinv.geometry.exp_twist(step.twist, DT)
    position, thetau = vsinv.geometry.thetau_from_pose(pose)
    return pipeline.iterations, 1e3 * float(np.linalg.norm(position)), float(np.degrees(np.linalg.norm(thetau)))


def test_the_loop_converges_through_ros_messages(tmp_path: Path) -> None:
    env = ros_env()
    parameters = bridge_parameters(tmp_path)
    params = write_params(tmp_path / "bridge.yaml", parameters)
    start = vsinv.geometry.pose_from_position_thetau([0.2, -0.15, -0.15], np.radians([-19.33, -4.86, 77.28]))
    config = {"scenario": SCENARIO, "K": K_6MM, "start_pose": start.tolist(), "dt": DT, "frame": "tool0",
              "hand_eye": hand_eye_matrix("hand_eye", HAND_EYE).tolist(), "timeout": 240.0}
    (tmp_path / "sim.json").write_text(json.dumps(config))
    bridge = subprocess.Popen(
        [sys.executable, "-m", "vsinv.ros", "--ros-args", "--params-file", str(params)],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        sim = subprocess.run(
            [sys.executable, str(HERE / "ros_loop_sim.py"), "--config", str(tmp_path / "sim.json"), "--out", str(tmp_path / "out.json")],
            env=env, capture_output=True, text=True, timeout=300,
        )
    finally:
        out, err = stop(bridge)
    assert sim.returncode == 0, sim.stderr[-3000:]
    assert bridge.returncode == 0, err[-3000:]
    r = json.loads((tmp_path / "out.json").read_text())
    assert r["start"][0], (r["start"], err[-3000:])
    assert r["K_hat"] == K_6MM  # from CameraInfo
    s = r["status"]
    print(
        f"\nROS loop: {s['verdict']} after {s['iterations']} iterations: {r['error_mm']:.3f} mm, {r['error_deg']:.4f} deg; "
        f"{r['twists']} twists in {r['seconds']:.2f} s ({r['rate_hz']:.1f} Hz); image->twist latency median "
        f"{r['latency_median_ms']:.2f} ms, p99 {r['latency_p99_ms']:.2f} ms; {r['images']} images"
    )
    assert s["verdict"] == "converged", s
    assert r["error_mm"] < 1.0 and r["error_deg"] < 0.1
    # as the same pipeline in this process: the messages and the mount change nothing
    iterations, error_mm, error_deg = in_process_loop(parameters, start)
    print(f"in process: {iterations} iterations, {error_mm:.3f} mm, {error_deg:.4f} deg")
    assert abs(s["iterations"] - iterations) <= 5, (s["iterations"], iterations)
    assert abs(r["error_mm"] - error_mm) < 0.05 and abs(r["error_deg"] - error_deg) < 0.005, (error_mm, error_deg)
    assert r["frames"] == ["tool0"]
    assert r["last_twist"] == [0.0] * 6  # the stop is a zero twist
    assert s["points"]["found"] == 12 and s["uncertainty"] is not None
    # the annotated image, and an image of another encoding said in the status
    assert r["annotated"] and r["annotated"][0] == ["rgb8", 832, 624, 832 * 624 * 3], r["annotated_status"]
    assert "encoding 'yuv422' is not read" in r["refused_message"], r["refused_message"]
    # the watchdog: started again with no images, the bridge stops itself with a zero twist
    assert r["restart"][0], r["restart"]
    w = r["watchdog_status"]
    assert w["state"] == "stopped" and w["reason"].startswith("watchdog"), w
    assert r["watchdog_twists"] and all(t == [0.0] * 6 for t in r["watchdog_twists"])


def test_bad_parameters_stop_the_node_at_start(tmp_path: Path) -> None:
    env = ros_env()
    good = bridge_parameters(tmp_path)
    for change, name in (({"gain": -1.0}, "gain"), ({"gian": 1.0}, "gian"), ({"hand_eye": [1.0, 2.0]}, "hand_eye"),
                         ({"reference_image": str(tmp_path / "missing.png")}, "reference_image")):
        params = write_params(tmp_path / "bad.yaml", {**good, **change})
        done = subprocess.run([sys.executable, "-m", "vsinv.ros", "--ros-args", "--params-file", str(params)],
                              env=env, capture_output=True, text=True, timeout=60)
        assert done.returncode == 2, (change, done.stderr)
        assert "refused to start: parameter" in done.stderr and name in done.stderr, (change, done.stderr)


def run_bridge_with(tmp_path: Path, parameters: dict[str, Any], script: str, config: dict[str, Any], timeout: float,
                    options: tuple[str, ...] = ()) -> tuple[dict[str, Any], str]:
    """The bridge with ``parameters`` (and command line ``options``, e.g. --lifecycle) and a
    simulation script with ``config``: its JSON output and the bridge's stderr."""
    env = ros_env()
    params = write_params(tmp_path / "bridge.yaml", parameters)
    (tmp_path / "sim.json").write_text(json.dumps(config))
    bridge = subprocess.Popen([sys.executable, "-m", "vsinv.ros", *options, "--ros-args", "--params-file", str(params)],
                              env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        sim = subprocess.run([sys.executable, str(HERE / script), "--config", str(tmp_path / "sim.json"), "--out", str(tmp_path / "out.json")],
                             env=env, capture_output=True, text=True, timeout=timeout)
    finally:
        _, err = stop(bridge)
    assert sim.returncode == 0, f"{sim.stderr[-3000:]}\nthe bridge (exit {bridge.returncode}) said:\n{err[-3000:]}"
    return json.loads((tmp_path / "out.json").read_text()), err


#: Each fault and the words the status's reason must hold.
FAULTS = {
    "encoding bayer_rggb8": "encoding 'bayer_rggb8' is not read", "encoding 8UC1": "encoding '8UC1' is not read",
    "encoding empty": "encoding '' is not read", "step < width": "rows of 831 bytes", "short data": "does not fit",
    "0x0 image": "0x0", "size 640x480": "image size 640x480 is not the CameraInfo's 832x624",
    "frame_id other": "frame_id 'other' is not the camera's 'camera_optical_frame'", "frame_id empty": "frame_id '' is not",
    "duplicate": "a duplicate", "out of order": "out of order", "camera_info 640x480": "camera_info size 640x480 is not the images' 832x624",
}


def test_every_fault_stops_the_robot_at_once(tmp_path: Path) -> None:
    """Each unusable image (and a CameraInfo of another size) sent while servoing: the next
    twist is a zero twist, within one frame (33 ms), with the cause in the status; twists carry
    the camera_frame parameter and a stamp; the status is latched before any image; parameter
    sets apply or are refused with a reason; /diagnostics says the fault."""
    parameters = bridge_parameters(tmp_path)
    parameters.update(output_frame="camera", camera_frame="camera_optical_frame", watchdog_timeout=1.0,
                      stop={"max_iterations": 100000, "stall": False}, max_linear_speed=0.25)
    for key in ("hand_eye", "end_effector_frame"):
        parameters.pop(key)
    start = vsinv.geometry.pose_from_position_thetau([0.2, -0.15, -0.15], np.radians([-19.33, -4.86, 77.28]))
    config = {"scenario": SCENARIO, "K": K_6MM, "start_pose": start.tolist()}
    r, err = run_bridge_with(tmp_path, parameters, "ros_fault_sim.py", config, timeout=240)
    assert r["status_before_images"].get("state") == "idle", r["status_before_images"]  # latched, from the start
    print("\nfault -> zero twist (ms):")
    for name, words in FAULTS.items():
        f = r["faults"][name]
        print(f"  {name:<22} {f['ms']:.2f}" if f["ms"] is not None else f"  {name:<22} none", f["reason"])
        assert f["was_running"], (name, f, err[-2000:])
        assert f["twist"] == [0.0] * 6, (name, f)  # the very next twist is the stop
        assert f["ms"] < 1000.0 / 30.0, (name, f)  # within one frame at 30 Hz
        assert f["state"] == "stopped" and words in f["reason"], (name, f)
    p = r["parameters"]
    assert p["speed_before"] > 0.01 and p["set_speed"][0] and p["speed_after"] <= 0.01 + 1e-9, p
    assert not p["set_target"][0] and "read at start only" in p["set_target"][1], p
    assert p["set_watchdog"][0] and 150.0 < p["watchdog_ms"] < 400.0 and p["watchdog_reason"].startswith("watchdog"), p
    watchdog, reliability = p["describe"]
    assert watchdog["range"] == [[0.01, 10.0]] and "MoveIt Servo" in watchdog["description"], watchdog
    assert "reliable, best_effort" in reliability["constraints"], reliability
    assert r["frames"] == ["camera_optical_frame"] and r["stamps_set"]
    assert "incompatible with image_qos.reliability 'reliable'" in str(r["qos"]), r["qos"]
    assert any(level == 2 and "vsinv_ros" in name and "refused" in message for level, name, message in r["diagnostics"])


@pytest.mark.parametrize("width, height, encoding", [(1280, 720, "mono8"), (1280, 720, "bgr8"), (1920, 1080, "mono8"), (1920, 1080, "bgr8")])
def test_large_images_converge(tmp_path: Path, width: int, height: int, encoding: str) -> None:
    """The lens change loop with the 6 mm lens on a 1280x720 or 1920x1080 sensor (the principal
    point at the centre), mono8 and bgr8, a 30 Hz camera period: images of up to 6.2 MB arrive
    over the default QoS (reliable, keep last 1) and the loop converges."""
    parameters = bridge_parameters(tmp_path)
    dx, dy = width / 2.0 - K_6MM[2], height / 2.0 - K_6MM[3]
    parameters["first_points"] = [x + (dx if i % 2 == 0 else dy) for i, x in enumerate(parameters["first_points"])]
    parameters.update(dt=1.0 / 30.0)
    k = [K_6MM[0], K_6MM[1], width / 2.0, height / 2.0]
    start = vsinv.geometry.pose_from_position_thetau([0.2, -0.15, -0.15], np.radians([-19.33, -4.86, 77.28]))
    config = {"scenario": SCENARIO, "K": k, "start_pose": start.tolist(), "dt": 1.0 / 30.0, "frame": "tool0",
              "hand_eye": hand_eye_matrix("hand_eye", HAND_EYE).tolist(), "timeout": 240.0, "size": [width, height],
              "encoding": encoding, "converge_only": True}
    r, err = run_bridge_with(tmp_path, parameters, "ros_loop_sim.py", config, timeout=300)
    s = r["status"]
    print(f"\n{width}x{height} {encoding}: {s['verdict']} after {s['iterations']} iterations, {r['error_mm']:.3f} mm, "
          f"{r['error_deg']:.4f} deg; {r['rate_hz']:.1f} twists/s lock-step; latency median {r['latency_median_ms']:.2f} ms, "
          f"p99 {r['latency_p99_ms']:.2f} ms")
    assert r["K_hat"] == k, (r, err[-2000:])
    assert s["verdict"] == "converged", (s, err[-2000:])
    assert r["error_mm"] < 1.0 and r["error_deg"] < 0.1
