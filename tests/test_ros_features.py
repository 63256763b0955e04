"""The ROS 2 bridge with the keypoint target (``target: features``, issue 32) over ROS 2 topics:
MuJoCo's textured box (tests/feature_world.py: photographs on three faces, no marker), the
reference image taken with one lens (f = 1200 px), the frames published by a servo camera with
another (f = 600 px, its CameraInfo giving K_hat) from tests/ros_features_sim.py (its own
process), the bridge (``python -m vsinv.ros``) in another. Loopback only, a domain id of its own
(tests/test_ros_loop.py's), each process bounded in time; skipped, saying why, without rclpy or
the textured box.

The bridge's steps are compared with :class:`vsinv.ImageServo` stepped in this process on the
very frames the bridge stepped on (by their stamps): the same verdicts and twists. Bad feature
parameters stop the node at start, named as parameters."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import feature_world as fw

_WHY_NOT = fw.available()
if _WHY_NOT is not None:
    pytest.skip(_WHY_NOT, allow_module_level=True)

import mujoco_world as mw  # noqa: E402
import test_features_mujoco as t  # noqa: E402
import vsinv  # noqa: E402
from vsinv.ros.annotate import annotate  # noqa: E402
import test_ros_loop as loop  # noqa: E402
from test_ros_loop import HERE, ros_env, stop, write_params  # noqa: E402

ros_ready = loop.ros_ready  # its autouse fixture: skipped, saying why, where rclpy does not start

K_SERVO = list(mw.intrinsics(t.FOVY_SERVO, t.WIDTH, t.HEIGHT))  # the servo camera's CameraInfo
OPTIONS = {"max_points": 80, "min_tracked": 20}
DT = 0.04
SERVO = {"law": "invariant", "gain": 2.0, "dt": DT,
         "stop": {"max_iterations": 200}}  # the stall rule ends the run (settled)


@pytest.fixture(scope="module")
def scene(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The reference image (f = 1200) as a file, the keypoints' reference depths (the scene's,
    in the target's point order) and a start pose."""
    folder = tmp_path_factory.mktemp("features")
    world = fw.TexturedBox(t.WIDTH, t.HEIGHT)
    try:
        reference = world.render(t.REFERENCE_POSE, t.FOVY_REFERENCE)
        probe = vsinv.ImageServo(reference, "features", vsinv.Intrinsics(*K_SERVO), depths="per_step", **OPTIONS)
        points = world.surface_point(t.REFERENCE_POSE, t.FOVY_REFERENCE, probe.reference_pixels)
        _, z = mw.project(t.REFERENCE_POSE, world.intrinsics(t.FOVY_REFERENCE), points)
        start = t.start_poses(world, 1)[0]
    finally:
        world.close()
    vsinv.vision.save_image(reference, folder / "reference.png")
    return {"reference": folder / "reference.png", "depths": [float(x) for x in z], "start": start}


def parameters(scene: dict[str, Any], **change: Any) -> dict[str, Any]:
    p = {
        "reference_image": str(scene["reference"]), "target": "features", **OPTIONS, **SERVO,
        "reference_depths": scene["depths"], "output_frame": "camera", "camera_frame": "camera_optical_frame",
        "watchdog_timeout": 5.0, "image_topic": "/camera/image_raw", "camera_info_topic": "/camera/camera_info",
        "twist_topic": "/servo_node/delta_twist_cmds",
    }
    p.update(change)
    return p


def in_process(scene: dict[str, Any], frames: list[np.ndarray]) -> list[vsinv.ImageStep]:
    """ImageServo with the bridge's options and the CameraInfo's K, stepped on `frames`."""
    servo = vsinv.ImageServo(vsinv.vision.load_image(scene["reference"]), "features", vsinv.Intrinsics(*K_SERVO),
                             reference_depths=scene["depths"], **OPTIONS, **SERVO)
    return [servo.step(f) for f in frames]


@pytest.mark.slow
def test_the_keypoint_loop_through_ros_messages_steps_as_image_servo(scene: dict[str, Any], tmp_path: Path) -> None:
    env = ros_env()
    params = write_params(tmp_path / "bridge.yaml", parameters(scene))
    config = {"K": K_SERVO, "start_pose": scene["start"].tolist(), "dt": DT, "fovy": t.FOVY_SERVO, "width": t.WIDTH,
              "height": t.HEIGHT, "timeout": 240.0, "frames": str(tmp_path / "frames.npz")}
    (tmp_path / "sim.json").write_text(json.dumps(config))
    bridge = subprocess.Popen([sys.executable, "-m", "vsinv.ros", "--ros-args", "--params-file", str(params)],
                              env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        sim = subprocess.run([sys.executable, str(HERE / "ros_features_sim.py"), "--config", str(tmp_path / "sim.json"),
                              "--out", str(tmp_path / "out.json")], env=env, capture_output=True, text=True, timeout=300)
    finally:
        _, err = stop(bridge)
    assert sim.returncode == 0, sim.stderr[-3000:]
    r = json.loads((tmp_path / "out.json").read_text())
    assert r["start"][0], (r["start"], err[-3000:])
    assert r["K_hat"] == K_SERVO  # from CameraInfo
    s, twists = r["status"], r["twists"]
    error_mm, error_deg = mw.pose_error(np.asarray(r["camera_pose"]), t.REFERENCE_POSE)
    print(f"\nROS keypoint loop: {s['verdict']} ({s['reason']}) after {s['iterations']} iterations, {len(twists)} twists; "
          f"camera {error_mm:.2f} mm, {error_deg:.3f} deg from the reference pose; "
          f"{s['points']['found']}/{s['points']['total']} keypoints found at the end")
    assert s["state"] == "stopped" and s["verdict"] is not None, s
    with np.load(tmp_path / "frames.npz") as saved:
        frames = list(saved["frames"])
        annotated = {float(k.split()[1]): saved[k] for k in saved.files if k.startswith("annotated ")}
    # lock-step: the k-th twist is the bridge's step on the k-th frame; the last one the verdict's zero twist
    assert len(twists) == len(frames) == len(r["stamps"]), (len(twists), len(frames))
    direct = in_process(scene, frames)
    for k, (twist, step) in enumerate(zip(twists, direct), 1):
        if k < len(frames):
            assert step.running, (k, step.verdict, step.reason)
            np.testing.assert_allclose(twist, step.twist, rtol=1e-12, atol=1e-15, err_msg=f"step {k}")
    last = direct[-1]
    assert (last.verdict, last.reason) == (s["verdict"], s["reason"].split(": ", 1)[1]), (last.verdict, last.reason, s)
    assert twists[-1] == [0.0] * 6 and r["frame_ids"] == ["camera_optical_frame"]
    assert s["points"]["found"] == int(np.asarray(last.found).sum())
    # the annotated images (the keypoints found in green, those lost in red) as drawn from the direct steps
    index = {stamp: i for i, stamp in enumerate(r["stamps"])}
    assert annotated and set(annotated) <= set(index), (sorted(annotated), len(frames))
    for stamp, rgb in annotated.items():
        step = direct[index[stamp]]
        np.testing.assert_array_equal(rgb, annotate(frames[index[stamp]], step.pixels, step.found))


@pytest.mark.slow
def test_bad_feature_parameters_stop_the_node_at_start(scene: dict[str, Any], tmp_path: Path) -> None:
    env = ros_env()
    for change, words in (
        ({"max_points": 5}, "parameter"), ({"max_points": 2.5}, "parameter max_points: expected an integer"),
        ({"min_tracked": 5000}, "min_tracked"), ({"point_ids": [0.5]}, "parameter point_ids: expected an array of integers"),
        ({"family": "tag16h5"}, "parameter family: not a parameter of target 'features'"),
        ({"reference_points": [1.0, 2.0]}, "parameter reference_points: not a parameter of target 'features'"),
    ):
        params = write_params(tmp_path / "bad.yaml", parameters(scene, **change))
        done = subprocess.run([sys.executable, "-m", "vsinv.ros", "--ros-args", "--params-file", str(params)],
                              env=env, capture_output=True, text=True, timeout=120)
        assert done.returncode == 2, (change, done.stderr[-2000:])
        assert "refused to start: parameter" in done.stderr and words in done.stderr, (change, done.stderr[-2000:])
        name = next(iter(change))
        assert name in done.stderr, (change, done.stderr[-2000:])
