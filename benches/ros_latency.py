"""The ROS 2 bridge's latency and rate over real topics (loopback, a domain id of its own), and
colour conversion against OpenCV.

How to run (from the repository root, with rclpy: a ROS 2 installation or the extra
``vsinv[ros-test]``, and ``opencv-python-headless`` for the conversion table)::

    python benches/ros_latency.py              # about 2 minutes
    python benches/ros_latency.py --quick      # fewer images
    python benches/ros_latency.py --json out.json
    python benches/ros_latency.py --compressed  # also JPEG (image_transport: compressed)
    python benches/ros_latency.py --only 1920x1080:bgr8 --publisher-depth 10   # one run; the camera's queue

For each image size (640x480, 1280x720, 1920x1080) and encoding (mono8, bgr8) the bridge
(``python -m vsinv.ros``, its own process, default QoS: reliable, keep last 1) servos on the
lens-change scenario's dots seen by the 6 mm lens on a sensor of that size (principal point at
the centre), the image still (the robot does not move, so every image costs the same); this
process publishes the images, stamped at publication, and times each twist's arrival:

- 30 Hz: an image every 1/30 s from a timer; the latency of a twist is its arrival minus the
  publication of the newest image published before it; twists/s over the run;
- lock-step: the next image as soon as the twist of the previous one arrived (the bridge's
  largest rate); latency from publication to arrival.

With ``--compressed`` (needs OpenCV to encode) the bridge also runs with ``image_transport:
compressed`` at 640x480 and 1280x720: the same image as bgr8 JPEG (quality 95, encoded once,
image_transport's format string ``bgr8; jpeg compressed bgr8``) on
``/camera/image_raw/compressed``; the bridge decodes it in Rust for every image.

Then the time from each kind of unusable image to the zero twist is in tests/test_ros_loop.py
(``-s`` prints it). Colour to grey: ``vsinv.vision.to_grey`` and ``cv2.cvtColor(COLOR_BGR2GRAY)``,
the best of 7 rounds of 20 calls on the same random bgr8 image, and their ratio.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

import vsinv
from vsinv.images import write_scenario_images

SIZES = [(640, 480), (1280, 720), (1920, 1080)]
COMPRESSED_SIZES = [(640, 480), (1280, 720)]
SCENARIO = "vision-12-6"
K_6MM = [600.0, 600.0, 416.0, 312.0]


def grey_table(rounds: int = 7) -> list[dict[str, Any]]:
    """to_grey against OpenCV's cvtColor (ms, the best of rounds of 20 calls)."""
    try:
        import cv2
    except ImportError:
        return []
    rows = []
    for w, h in SIZES:
        bgr = np.random.default_rng(0).integers(0, 256, (h, w, 3), dtype=np.uint8)
        times = {}
        for name, f in (("vsinv", lambda: vsinv.vision.to_grey(bgr, order="bgr")), ("opencv", lambda: cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY))):
            f()
            samples = []
            for _ in range(rounds):
                t = time.perf_counter()
                for _ in range(20):
                    f()
                samples.append((time.perf_counter() - t) / 20)
            times[name] = 1e3 * float(np.min(samples))  # the least disturbed round: the machine is shared
        rows.append({"size": f"{w}x{h}", "vsinv_ms": times["vsinv"], "opencv_ms": times["opencv"], "ratio": times["vsinv"] / times["opencv"]})
    return rows


def bridge_parameters(folder: Path, width: int, height: int) -> dict[str, Any]:
    scenario = vsinv.load_scenario(SCENARIO)
    write_scenario_images(scenario, folder)
    ref_px = vsinv.images.read_points(folder / "reference.csv")
    start_px = vsinv.images.read_points(folder / "start.csv") + [width / 2 - K_6MM[2], height / 2 - K_6MM[3]]
    return {"reference_image": str(folder / "reference.png"), "target": "dots",
            "reference_points": [float(x) for x in ref_px.ravel()], "first_points": [float(x) for x in start_px.ravel()],
            "reference_depths": [0.60, 0.66, 0.56, 0.63, 0.54, 0.65, 0.62, 0.57, 0.64, 0.55, 0.61, 0.66],
            "rz_task": "tau21", "K_hat": [600.0, 600.0, width / 2.0, height / 2.0], "camera_frame": "camera_optical_frame",
            "autostart": True, "watchdog_timeout": 2.0, "stop": {"max_iterations": 1000000, "stall": False},
            "image_topic": "/camera/image_raw", "twist_topic": "/servo_node/delta_twist_cmds", "publish_annotated": False}


def image_of(width: int, height: int) -> np.ndarray:
    d = vsinv.load_scenario(SCENARIO).to_dict()
    d["camera"].update(width=float(width), height=float(height), u0=width / 2.0, v0=height / 2.0)
    return vsinv.vision.render(vsinv.sim.Scenario.from_dict(d))


def jpeg_of(grey: np.ndarray) -> bytes:
    """The image as bgr8 encoded in JPEG (quality 95), as image_transport's compressed plugin sends it."""
    import cv2

    ok, data = cv2.imencode(".jpg", np.repeat(grey[:, :, None], 3, 2), [cv2.IMWRITE_JPEG_QUALITY, 95])
    if not ok:
        raise RuntimeError("cv2.imencode failed")
    return bytes(data.tobytes())


def measure(grey: np.ndarray, encoding: str, images: int, publisher_depth: int = 1) -> dict[str, Any]:
    """Both modes against a running bridge (in this process: rclpy); encoding mono8, bgr8 or
    jpeg (a CompressedImage on the raw topic + /compressed); the image publisher is reliable,
    keep last ``publisher_depth``."""
    import rclpy
    from geometry_msgs.msg import TwistStamped
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import QoSProfile
    from sensor_msgs.msg import CompressedImage, Image

    node = rclpy.create_node("bench_camera")
    h, w = grey.shape
    if encoding == "jpeg":
        data = jpeg_of(grey)
        pub = node.create_publisher(CompressedImage, "/camera/image_raw/compressed", QoSProfile(depth=publisher_depth))
    else:
        data = grey.tobytes() if encoding == "mono8" else np.repeat(grey[:, :, None], 3, 2).tobytes()
        pub = node.create_publisher(Image, "/camera/image_raw", QoSProfile(depth=publisher_depth))
    arrivals: list[float] = []
    node.create_subscription(TwistStamped, "/servo_node/delta_twist_cmds", lambda m: arrivals.append(time.monotonic()), QoSProfile(depth=100))
    sent: list[float] = []
    ex = SingleThreadedExecutor()
    ex.add_node(node)

    def publish() -> None:
        if encoding == "jpeg":
            msg = CompressedImage(format="bgr8; jpeg compressed bgr8", data=data)
        else:
            msg = Image(height=h, width=w, encoding=encoding, step=w if encoding == "mono8" else 3 * w, data=data)
        msg.header.frame_id = "camera_optical_frame"
        msg.header.stamp = node.get_clock().now().to_msg()
        sent.append(time.monotonic())
        pub.publish(msg)

    def spin(seconds: float, until: Any = lambda: False) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end and not until():
            ex.spin_once(timeout_sec=0.001)

    deadline = time.monotonic() + 60.0
    while pub.get_subscription_count() == 0:  # discovery, bounded: a bridge that died never subscribes
        if time.monotonic() > deadline:
            raise RuntimeError("the bridge did not subscribe to the images within 60 s")
        spin(0.1)
    for _ in range(50):  # warm up: the bridge started servoing
        publish()
        n = len(arrivals)
        spin(2.0, lambda: len(arrivals) > n)
        if len(arrivals) > n:
            break
    out: dict[str, Any] = {}
    # 30 Hz
    sent.clear(), arrivals.clear()
    timer = node.create_timer(1.0 / 30.0, publish)
    t0 = time.monotonic()
    spin(images / 30.0)
    node.destroy_timer(timer)
    spin(0.2)
    lat = [a - max(s for s in sent if s <= a) for a in arrivals if any(s <= a for s in sent)]
    out["30Hz"] = summary(lat, len(arrivals), time.monotonic() - 0.2 - t0, len(sent))
    # lock-step
    sent.clear(), arrivals.clear()
    lat = []
    t0 = time.monotonic()
    for _ in range(images):
        n = len(arrivals)
        publish()
        spin(2.0, lambda: len(arrivals) > n)
        if len(arrivals) > n:
            lat.append(arrivals[n] - sent[-1])
    out["lock-step"] = summary(lat, len(arrivals), time.monotonic() - t0, len(sent))
    ex.shutdown()
    node.destroy_node()
    return out


def summary(latencies: list[float], twists: int, seconds: float, images: int) -> dict[str, Any]:
    lat = 1e3 * np.asarray(latencies)
    return {"median_ms": float(np.median(lat)) if lat.size else None, "p99_ms": float(np.percentile(lat, 99)) if lat.size else None,
            "twists_per_s": twists / seconds, "images": images, "twists": twists}


def ros_missing() -> str | None:
    """Why rclpy cannot run here (as tests/test_ros_loop.py probes it, in a process of its own),
    or None."""
    if importlib.util.find_spec("rclpy") is None:
        return "rclpy is not importable"
    probe = "import rclpy\nfrom geometry_msgs.msg import TwistStamped\nrclpy.init()\nrclpy.shutdown()\n"
    try:
        done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    except subprocess.TimeoutExpired:
        return "rclpy did not start within 120 s"
    if done.returncode != 0:
        return "rclpy does not start: " + (done.stderr.strip().splitlines() or ["no message"])[-1]
    return None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--json")
    parser.add_argument("--compressed", action="store_true", help="also JPEG (image_transport: compressed) at 640x480 and 1280x720")
    parser.add_argument("--only", nargs="+", metavar="WxH:ENCODING", help="only these runs, e.g. 1920x1080:bgr8 640x480:jpeg")
    parser.add_argument("--publisher-depth", type=int, default=1, help="the image publisher's history depth (keep last; default 1)")
    args = parser.parse_args()
    images = 60 if args.quick else 150
    why = ros_missing()
    if why:
        print(f"{why} (source a ROS 2 installation, or pip install the wheels of the extra ros-test): ROS 2 latency skipped")
        return
    import rclpy

    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST", ROS_LOCALHOST_ONLY="1", ROS_DOMAIN_ID=str(10 + os.getpid() % 90))
    os.environ.update({k: env[k] for k in ("ROS_AUTOMATIC_DISCOVERY_RANGE", "ROS_LOCALHOST_ONLY", "ROS_DOMAIN_ID")})
    rclpy.init()
    results: dict[str, Any] = {"to_grey": grey_table(), "ros": []}
    print("colour to grey (bgr8), ms: size, vsinv.vision.to_grey, cv2.cvtColor, ratio")
    for r in results["to_grey"]:
        print(f"  {r['size']:<10} {r['vsinv_ms']:7.3f} {r['opencv_ms']:7.3f} {r['ratio']:6.2f}")
    print("image -> twist over ROS 2 (ms): size encoding mode: median, p99, twists/s")
    try:
        with tempfile.TemporaryDirectory() as tmp:
            runs = [(w, h, e) for w, h in (SIZES[:1] if args.quick else SIZES) for e in ("mono8", "bgr8")]
            runs += [(w, h, "jpeg") for w, h in COMPRESSED_SIZES] if args.compressed else []
            if args.only:
                runs = [(int(w), int(h), e) for w, h, e in (s.replace("x", ":").split(":") for s in args.only)]
            for w, h, encoding in runs:
                grey = image_of(w, h)
                given = bridge_parameters(Path(tmp), w, h)
                given["image_transport"] = "compressed" if encoding == "jpeg" else "raw"
                params = Path(tmp) / "bridge.yaml"
                params.write_text(json.dumps({"/**": {"ros__parameters": given}}))
                bridge = subprocess.Popen([sys.executable, "-m", "vsinv.ros", "--ros-args", "--params-file", str(params)],
                                          env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
                try:
                    m = measure(grey, encoding, images, args.publisher_depth)
                finally:
                    bridge.send_signal(signal.SIGINT)
                    try:
                        bridge.communicate(timeout=10)
                    except subprocess.TimeoutExpired:
                        bridge.kill()
                for mode, r in m.items():
                    results["ros"].append({"size": f"{w}x{h}", "encoding": encoding, "mode": mode, **r})
                    print(f"  {w}x{h:<5} {encoding:<6} {mode:<9} {r['median_ms']:7.2f} {r['p99_ms']:7.2f} {r['twists_per_s']:7.1f}",
                          flush=True)
    finally:
        rclpy.try_shutdown()
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
