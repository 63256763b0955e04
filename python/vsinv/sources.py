"""Frame sources for the image pipeline: NumPy arrays, a folder of image files, a video file or a
live camera.

Every source yields ``(name, image)`` pairs, the image a ``(height, width)`` uint8 array:

- an array ``(n, height, width)`` (or one ``(height, width)`` image), or any iterable of such
  arrays: names ``frame-0000``, ``frame-0001``, ...;
- a folder: its image files (PNG, PGM/PPM/PNM/PAM, JPEG) in the order of their names, read with
  :func:`vsinv.vision.load_image` (colour converted to grey);
- a video file: its frames read with OpenCV's ``VideoCapture`` (the optional extra
  ``pip install "vsinv[video]"``), converted to grey with OpenCV's Rec. 601 weights;
- a live camera: a device index (``0``) or a device path (``"/dev/video0"``), read with OpenCV's
  ``VideoCapture`` (the same extra) until the caller stops, each read bounded by ``timeout``
  seconds; names ``camera-00000``, ...

The capture is released when the iteration ends, when the generator is closed (``close()``,
a ``with contextlib.closing(...)`` block, a ``break`` out of a loop over it once it is
collected) or when a read fails.
"""

from __future__ import annotations

import stat
import threading
from pathlib import Path
from itertools import islice
from typing import Any, Generator, Iterable, Iterator, Optional, Union

import numpy as np
import numpy.typing as npt

from ._core import InvalidInput, load_image

__all__ = ["IMAGE_SUFFIXES", "frames"]

#: The file name endings read from a folder (lower case).
IMAGE_SUFFIXES = (".png", ".pgm", ".ppm", ".pnm", ".pam", ".jpg", ".jpeg")

#: Seconds a live camera may take to give a frame (the first one included) by default.
CAMERA_TIMEOUT_S = 5.0

Frame = tuple[str, npt.NDArray[np.uint8]]
Source = Union[int, str, Path, npt.ArrayLike, Iterable[Any]]


def frames(source: Source, max_frames: Optional[int] = None, *, timeout: float = CAMERA_TIMEOUT_S) -> Iterator[Frame]:
    """The frames of ``source`` as ``(name, image)`` pairs (see the module documentation), at
    most ``max_frames`` of them (None: all; a camera, a video or an iterable may be endless).
    ``timeout``: the seconds a live camera may take to give each frame before ``InvalidInput``
    is raised. A source that is none of these, a camera that cannot be opened, or OpenCV
    missing for a video or camera raises ``InvalidInput`` naming ``source``."""
    if max_frames is not None and (isinstance(max_frames, bool) or not isinstance(max_frames, int) or max_frames < 1):
        raise InvalidInput(f"max_frames: expected an integer >= 1 or None, got {max_frames!r}")
    if isinstance(timeout, bool) or not isinstance(timeout, (int, float)) or not timeout > 0 or timeout == float("inf"):
        raise InvalidInput(f"timeout: expected a finite number of seconds > 0, got {timeout!r}")
    return _limited(_frames(source, float(timeout)), max_frames)


def _limited(items: Iterator[Frame], max_frames: Optional[int]) -> Generator[Frame, None, None]:
    """At most ``max_frames`` items, closing ``items`` (and so releasing a capture) at the end."""
    try:
        yield from (items if max_frames is None else islice(items, max_frames))
    finally:
        close = getattr(items, "close", None)
        if close is not None:
            close()


def _source_error(reason: str) -> InvalidInput:
    """``InvalidInput("source: {reason}")`` with the attributes of the core's argument errors."""
    err = InvalidInput(f"source: {reason}")
    err.kind, err.argument, err.reason = "invalid_argument", "source", reason
    return err


def _is_camera(source: object) -> bool:
    """A device index or the path of a character device (``/dev/video0``)."""
    if isinstance(source, int) and not isinstance(source, bool):
        return True
    if isinstance(source, (str, Path)):
        try:
            return stat.S_ISCHR(Path(source).stat().st_mode)
        except OSError:
            return str(source).startswith("/dev/video")
    return False


def _frames(source: Source, timeout: float) -> Iterator[Frame]:
    if _is_camera(source):
        return _camera(source, timeout)  # type: ignore[arg-type]
    if isinstance(source, (str, Path)):
        path = Path(source)
        if path.is_dir():
            return _folder(path)
        if path.is_file():
            return _video(path)
        raise _source_error(f"{path} is neither a folder of images, a video file nor a camera device")
    if isinstance(source, np.ndarray):
        if source.ndim == 2:
            return _arrays([source])
        if source.ndim == 3:
            return _arrays(source)
        raise _source_error(f"expected (n, height, width) or (height, width) images, got shape {source.shape}")
    try:
        items = iter(source)  # type: ignore[arg-type]
    except TypeError:
        raise _source_error(
            f"expected arrays, a folder, a video file or a camera (0, '/dev/video0'), got {type(source).__name__}"
        ) from None
    return _arrays(items)


def _arrays(items: Iterable[Any]) -> Iterator[Frame]:
    for k, image in enumerate(items):
        yield f"frame-{k:04d}", image


def _folder(folder: Path) -> Iterator[Frame]:
    paths = sorted(p for p in folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES and p.is_file())
    if not paths:
        raise _source_error(f"no image files ({', '.join(IMAGE_SUFFIXES)}) in {folder}")
    return ((p.name, load_image(p)) for p in paths)


def _opencv(what: str) -> Any:
    try:
        import cv2
    except ImportError:
        raise _source_error(f"{what} needs OpenCV: pip install \"vsinv[video]\" (or opencv-python-headless)") from None
    return cv2


def _video(path: Path) -> Iterator[Frame]:
    cv2 = _opencv(f"{path.name} is not a folder; reading a video file")
    capture = cv2.VideoCapture(str(path))
    if not capture.isOpened():
        capture.release()
        raise _source_error(f"{path} could not be opened as a video file")
    return _video_frames(capture, cv2)


def _grey(frame: Any, cv2: Any) -> npt.NDArray[np.uint8]:
    grey = frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    return np.ascontiguousarray(grey, dtype=np.uint8)


def _video_frames(capture: Any, cv2: Any) -> Iterator[Frame]:
    try:
        k = 0
        while True:
            ok, frame = capture.read()
            if not ok:
                return
            yield f"frame-{k:05d}", _grey(frame, cv2)
            k += 1
    finally:
        capture.release()


def _camera(device: Union[int, str, Path], timeout: float) -> Iterator[Frame]:
    label = f"camera {device}"
    cv2 = _opencv(f"reading {label}")
    capture = cv2.VideoCapture(device if isinstance(device, int) else str(device))
    if not capture.isOpened():
        capture.release()
        raise _source_error(f"{label} could not be opened (no such device, busy, or no permission)")
    return _camera_frames(capture, cv2, label, timeout)


def _camera_frames(capture: Any, cv2: Any, label: str, timeout: float) -> Iterator[Frame]:
    """Frames read each on a daemon thread and waited for at most ``timeout`` seconds: a read
    that does not return in time raises, and the capture is released once that read returns
    (releasing it under a running read is not safe; a daemon thread never holds up the
    interpreter's exit)."""
    read: Optional[_Read] = None
    try:
        k = 0
        while True:
            read = _Read(capture)
            if not read.done.wait(timeout):
                raise _source_error(f"{label} gave no frame within {timeout:g} s (timeout=)")
            ok, frame = read.result
            if read.error is not None or not ok or frame is None:
                raise _source_error(f"{label} gave no frame (read failed after {k} frames: {read.error or 'no image'})")
            yield f"camera-{k:05d}", _grey(frame, cv2)
            k += 1
    finally:
        if read is not None and not read.release_when_done():
            capture.release()


class _Read:
    """One ``capture.read()`` on its own daemon thread."""

    def __init__(self, capture: Any) -> None:
        self.capture = capture
        self.result: tuple[bool, Any] = (False, None)
        self.error: Optional[BaseException] = None
        self.done = threading.Event()
        self._lock = threading.Lock()
        self._release = False
        threading.Thread(target=self._run, name="vsinv-camera-read", daemon=True).start()

    def _run(self) -> None:
        try:
            self.result = self.capture.read()
        except Exception as e:  # reported to the reader, never lost on the thread
            self.error = e
        with self._lock:
            self.done.set()
            if self._release:
                self.capture.release()

    def release_when_done(self) -> bool:
        """Whether the capture will be released by this read's thread (it is still running)."""
        with self._lock:
            self._release = not self.done.is_set()
            return self._release
