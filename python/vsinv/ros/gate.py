"""Which images may be stepped on: the checks of a sensor_msgs/Image's header and size that
come before the pixels are read, and the CameraInfo size check. Pure Python, on the messages'
fields only (tested without ROS).

An image is refused (the bridge then publishes a zero twist at once and stops, naming the
cause) when its ``frame_id`` is not the camera's (the ``camera_frame`` parameter, or else the
first image used in the session), when its stamp is not after the last image used (a duplicate
or an image out of order: never stepped on), or when its size is not the one in use (the
CameraInfo's, or else the first image's). A CameraInfo whose size differs from the images' in
use is refused."""

from __future__ import annotations

from typing import Any, Optional

__all__ = ["ImageGate", "stamp_seconds"]


def stamp_seconds(stamp: Any) -> float:
    """A builtin_interfaces/Time as seconds."""
    return int(stamp.sec) + 1e-9 * int(stamp.nanosec)


class ImageGate:
    """The frame, last stamp and size in use; :meth:`check` says why an image cannot be used
    (None: it can), :meth:`used` records one that was."""

    def __init__(self, camera_frame: str = "") -> None:
        self.camera_frame = camera_frame
        self.frame: Optional[str] = camera_frame or None
        self.last_stamp: Optional[tuple[int, int]] = None
        self.info_size: Optional[tuple[int, int]] = None
        self.image_size: Optional[tuple[int, int]] = None

    def size(self) -> Optional[tuple[int, int]]:
        """The (width, height) images must have: the CameraInfo's, else the first image's."""
        return self.info_size or self.image_size

    def check(self, msg: Any, size: Optional[tuple[int, int]] = None) -> Optional[str]:
        """Why the image ``msg`` cannot be used now, or None; ``size`` (width, height) is the
        decoded size of a compressed image (which has no width and height fields)."""
        frame = str(msg.header.frame_id)
        if self.frame is not None and frame != self.frame:
            return f"image frame_id {frame!r} is not the camera's {self.frame!r}"
        stamp = (int(msg.header.stamp.sec), int(msg.header.stamp.nanosec))
        if self.last_stamp is not None and stamp <= self.last_stamp:
            what = "a duplicate" if stamp == self.last_stamp else "out of order"
            return (f"image stamp {stamp[0] + 1e-9 * stamp[1]:.9f} s is not after the last image used "
                    f"({self.last_stamp[0] + 1e-9 * self.last_stamp[1]:.9f} s): {what}")
        size, expected = size or (int(msg.width), int(msg.height)), self.size()
        if expected is not None and size != expected:
            source = "CameraInfo's" if self.info_size else "first image's"
            return f"image size {size[0]}x{size[1]} is not the {source} {expected[0]}x{expected[1]}"
        return None

    def used(self, msg: Any, size: Optional[tuple[int, int]] = None) -> None:
        """Records an image that was stepped on: its stamp, and its frame and size (``size``
        for a compressed image) if none yet."""
        self.last_stamp = (int(msg.header.stamp.sec), int(msg.header.stamp.nanosec))
        if self.frame is None:
            self.frame = str(msg.header.frame_id)
        if self.image_size is None:
            self.image_size = size or (int(msg.width), int(msg.height))

    def camera_info(self, msg: Any) -> Optional[str]:
        """Why the CameraInfo ``msg`` is refused (its size is not the images'), or None (its
        size is then the one images must have)."""
        size = (int(msg.width), int(msg.height))
        if size == (0, 0):
            return None  # no size given: only the lens is read
        if self.image_size is not None and size != self.image_size:
            return (f"camera_info size {size[0]}x{size[1]} is not the images' {self.image_size[0]}x"
                    f"{self.image_size[1]}: refused (the lens and size in use are kept)")
        self.info_size = size
        return None

    def reset(self) -> None:
        """A new session: the frame (unless a parameter), the last stamp and image size forgotten."""
        self.frame = self.camera_frame or None
        self.last_stamp, self.image_size = None, None
