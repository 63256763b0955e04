"""The simulated half of tests/test_ros_compressed.py's fault test, in its own process: the
fault rig of tests/ros_fault_sim.py publishing sensor_msgs/CompressedImage (PNG of the rendered
mono8 image, image_transport's format string) on /camera/image_raw/compressed, and each
unusable compressed message sent while running, timed from its publication to the zero twist.
Writes JSON to --out."""

from __future__ import annotations

from typing import Any, Callable

import cv2
import numpy as np
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile
from sensor_msgs.msg import CompressedImage

from ros_fault_sim import FRAME, Rig, fault, spin_until, spun_rig

PNG_FORMAT = "mono8; png compressed mono8"


def crc32(data: bytes) -> int:
    import zlib

    return zlib.crc32(data) & 0xFFFFFFFF


def png_declaring(width: int, height: int) -> bytes:
    """A valid PNG of one pixel whose header (IHDR, its CRC recomputed) declares ``width`` x
    ``height``: a bomb's header, with no data behind it."""
    ok, data = cv2.imencode(".png", np.zeros((1, 1), np.uint8))
    assert ok
    b = bytearray(data.tobytes())
    b[16:20], b[20:24] = width.to_bytes(4, "big"), height.to_bytes(4, "big")
    b[29:33] = crc32(bytes(b[12:29])).to_bytes(4, "big")
    return bytes(b)


class CompressedRig(Rig):
    def __init__(self, grey: np.ndarray, K: list[float]) -> None:
        super().__init__(grey, K)
        self.image_pub = self.create_publisher(CompressedImage, "/camera/image_raw/compressed", QoSProfile(depth=1))
        ok, data = cv2.imencode(".png", grey)
        assert ok
        self.png = data.tobytes()

    def image(self, **change: Any) -> CompressedImage:  # type: ignore[override]
        msg = CompressedImage(format=PNG_FORMAT, data=self.png)
        msg.header.frame_id = FRAME
        msg.header.stamp = self.get_clock().now().to_msg()
        for k, v in change.items():
            setattr(msg, k, v)
        return msg


def faults(ex: SingleThreadedExecutor, rig: CompressedRig) -> dict[str, Any]:
    ok, jpeg = cv2.imencode(".jpg", rig.grey)
    ok16, deep = cv2.imencode(".png", rig.grey.astype(np.uint16) * 257)
    ok_small, small = cv2.imencode(".png", np.zeros((480, 640), np.uint8))
    assert ok and ok16 and ok_small
    cases: dict[str, Callable[[], Any]] = {
        "truncated png": lambda: rig.image(data=rig.png[: len(rig.png) // 2]),
        "truncated jpeg": lambda: rig.image(format="bgr8; jpeg compressed bgr8", data=jpeg.tobytes()[: len(jpeg) // 2]),
        "not an image": lambda: rig.image(data=b"GIF89a and then nothing useful"),
        "empty data": lambda: rig.image(data=b""),
        "format png, data jpeg": lambda: rig.image(data=jpeg.tobytes()),
        "format compressedDepth": lambda: rig.image(format="16UC1; compressedDepth png"),
        "format tiff": lambda: rig.image(format="tiff"),
        "header 40000x40000": lambda: rig.image(data=png_declaring(40000, 40000)),
        "16-bit png": lambda: rig.image(data=deep.tobytes()),
        "size 640x480": lambda: rig.image(data=small.tobytes()),
        "duplicate": lambda: rig.last,
    }
    return {name: fault(ex, rig, lambda make=make: rig.image_pub.publish(make())) for name, make in cases.items()}


def run(config: dict[str, Any]) -> dict[str, Any]:
    with spun_rig(CompressedRig, config) as (ex, rig):
        spin_until(ex, lambda: rig.statuses > 0, 30.0)
        rig.info_pub.publish(rig.info)
        spin_until(ex, lambda: rig.status.get("K_hat") is not None, 10.0)
        return {"faults": faults(ex, rig)}


if __name__ == "__main__":
    from ros_sim_main import main

    main(run)
