"""The bridge with ``image_transport: compressed`` over real ROS 2 topics (loopback, a domain
id of its own, each process bounded in time; skipped without rclpy, as tests/test_ros_loop.py):
the lens change loop closed through sensor_msgs/CompressedImage (PNG of mono8, JPEG of bgr8),
and each unusable compressed message stopping the robot at once with a zero twist and its
cause in the status. The decoding itself against OpenCV is tests/test_decode_image.py."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import vsinv
from test_ros_loop import HAND_EYE, K_6MM, SCENARIO, bridge_parameters, ros_ready, run_bridge_with  # noqa: F401
from vsinv.ros import hand_eye_matrix

START = vsinv.geometry.pose_from_position_thetau([0.2, -0.15, -0.15], np.radians([-19.33, -4.86, 77.28]))


@pytest.mark.parametrize("how", ["png", "jpeg"])
def test_the_loop_converges_on_compressed_images(tmp_path: Path, how: str) -> None:
    parameters = bridge_parameters(tmp_path)
    parameters.update(image_transport="compressed", dt=1.0 / 30.0)
    config = {"scenario": SCENARIO, "K": K_6MM, "start_pose": START.tolist(), "dt": 1.0 / 30.0, "frame": "tool0",
              "hand_eye": hand_eye_matrix("hand_eye", HAND_EYE).tolist(), "timeout": 240.0, "encoding": how,
              "converge_only": True}
    r, err = run_bridge_with(tmp_path, parameters, "ros_loop_sim.py", config, timeout=300)
    assert r["start"][0], (r["start"], err[-3000:])
    s = r["status"]
    print(f"\ncompressed {how}: {s['verdict']} after {s['iterations']} iterations, {r['error_mm']:.3f} mm, "
          f"{r['error_deg']:.4f} deg; {r['rate_hz']:.1f} twists/s lock-step; latency median {r['latency_median_ms']:.2f} ms, "
          f"p99 {r['latency_p99_ms']:.2f} ms")
    assert r["K_hat"] == K_6MM
    assert s["verdict"] == "converged", (s, err[-2000:])
    assert r["error_mm"] < 1.0 and r["error_deg"] < 0.1
    assert r["last_twist"] == [0.0] * 6 and r["frames"] == ["tool0"]
    assert s["image_size"] == [832, 624], s


#: Each compressed fault and the words the status's reason must hold.
FAULTS = {
    "truncated png": "not a valid", "truncated jpeg": "truncated", "not an image": "neither PNG nor JPEG",
    "empty data": "no data", "format png, data jpeg": "the format says png but the data is jpeg",
    "format compressedDepth": "compressedDepth", "format tiff": "format 'tiff' is not read",
    "header 40000x40000": "too large", "16-bit png": "only 8-bit images are read",
    "size 640x480": "image size 640x480 is not the CameraInfo's 832x624", "duplicate": "a duplicate",
}


def test_every_compressed_fault_stops_the_robot_at_once(tmp_path: Path) -> None:
    """Each unusable CompressedImage sent while servoing: the next twist is a zero twist, the
    state stopped, the cause in the status; the zero twist arrives within three frames at 30 Hz
    (about one frame on a quiet machine: 4-28 ms; up to 94 ms measured on this shared 2-core
    machine under a load of 15)."""
    parameters = bridge_parameters(tmp_path)
    parameters.update(image_transport="compressed", output_frame="camera", camera_frame="camera_optical_frame",
                      stop={"max_iterations": 100000, "stall": False})
    for key in ("hand_eye", "end_effector_frame"):
        parameters.pop(key)
    config = {"scenario": SCENARIO, "K": K_6MM, "start_pose": START.tolist()}
    r, err = run_bridge_with(tmp_path, parameters, "ros_compressed_sim.py", config, timeout=240)
    print("\ncompressed fault -> zero twist (ms):")
    for name, words in FAULTS.items():
        f = r["faults"][name]
        print(f"  {name:<24} {f['ms']:.2f}" if f["ms"] is not None else f"  {name:<24} none", f["reason"])
        assert f["was_running"], (name, f, err[-2000:])
        assert f["twist"] == [0.0] * 6, (name, f)
        assert f["ms"] < 3000.0 / 30.0, (name, f)
        assert f["state"] == "stopped" and words in f["reason"], (name, f)
