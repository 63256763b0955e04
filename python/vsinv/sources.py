"""Frame sources for the image pipeline: NumPy arrays, a folder of image files, or a video file.

Every source yields ``(name, image)`` pairs, the image a ``(height, width)`` uint8 array:

- an array ``(n, height, width)`` (or one ``(height, width)`` image), or any iterable of such
  arrays: names ``frame-0000``, ``frame-0001``, ...;
- a folder: its image files (PNG, PGM/PPM/PNM/PAM, JPEG) in the order of their names, read with
  :func:`vsinv.load_image` (colour converted to grey);
- a video file: its frames read with OpenCV's ``VideoCapture`` (the optional extra
  ``pip install "vsinv[video]"``), converted to grey with OpenCV's Rec. 601 weights.
"""

from __future__ import annotations

from pathlib import Path
from itertools import islice
from typing import Any, Iterable, Iterator, Optional, Union

import numpy as np
import numpy.typing as npt

from ._core import InvalidInput, load_image

__all__ = ["IMAGE_SUFFIXES", "frames"]

#: The file name endings read from a folder (lower case).
IMAGE_SUFFIXES = (".png", ".pgm", ".ppm", ".pnm", ".pam", ".jpg", ".jpeg")

Frame = tuple[str, npt.NDArray[np.uint8]]


def frames(source: Union[str, Path, npt.ArrayLike, Iterable[Any]], max_frames: Optional[int] = None) -> Iterator[Frame]:
    """The frames of ``source`` as ``(name, image)`` pairs (see the module documentation), at
    most ``max_frames`` of them (None: all; a video or an iterable may be endless). A source
    that is none of these raises ``InvalidInput`` naming ``source``."""
    if max_frames is None:
        return _frames(source)
    if isinstance(max_frames, bool) or not isinstance(max_frames, int) or max_frames < 1:
        raise InvalidInput(f"max_frames: expected an integer >= 1 or None, got {max_frames!r}")
    return islice(_frames(source), max_frames)


def _frames(source: Union[str, Path, npt.ArrayLike, Iterable[Any]]) -> Iterator[Frame]:
    if isinstance(source, (str, Path)):
        path = Path(source)
        if path.is_dir():
            return _folder(path)
        if path.is_file():
            return _video(path)
        raise InvalidInput(f"source: {path} is neither a folder of images nor a video file")
    if isinstance(source, np.ndarray):
        if source.ndim == 2:
            return _arrays([source])
        if source.ndim == 3:
            return _arrays(source)
        raise InvalidInput(f"source: expected (n, height, width) or (height, width) images, got shape {source.shape}")
    try:
        items = iter(source)  # type: ignore[arg-type]
    except TypeError:
        raise InvalidInput(f"source: expected arrays, a folder or a video file, got {type(source).__name__}") from None
    return _arrays(items)


def _arrays(items: Iterable[Any]) -> Iterator[Frame]:
    for k, image in enumerate(items):
        yield f"frame-{k:04d}", image


def _folder(folder: Path) -> Iterator[Frame]:
    paths = sorted(p for p in folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES and p.is_file())
    if not paths:
        raise InvalidInput(f"source: no image files ({', '.join(IMAGE_SUFFIXES)}) in {folder}")
    return ((p.name, load_image(p)) for p in paths)


def _video(path: Path) -> Iterator[Frame]:
    try:
        import cv2
    except ImportError:
        raise InvalidInput(
            f"source: {path.name} is not a folder; reading a video file needs OpenCV: pip install \"vsinv[video]\""
        ) from None
    capture = cv2.VideoCapture(str(path))
    if not capture.isOpened():
        raise InvalidInput(f"source: {path} could not be opened as a video file")
    return _video_frames(capture, cv2)


def _video_frames(capture: Any, cv2: Any) -> Iterator[Frame]:
    try:
        k = 0
        while True:
            ok, frame = capture.read()
            if not ok:
                return
            grey = frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
            yield f"frame-{k:05d}", np.ascontiguousarray(grey, dtype=np.uint8)
            k += 1
    finally:
        capture.release()
