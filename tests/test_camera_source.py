"""A live camera as a frame source (issue 29, item 5): `vsinv.frames(0)` and
`vsinv.frames("/dev/video0")` read through OpenCV's `VideoCapture` (the `video` extra), each
read bounded by a timeout, the capture released when the iteration ends, is closed or fails.

A fake `cv2` module (no camera on a test machine) stands for OpenCV's capture; where OpenCV can
write a video file, a real `VideoCapture` reading that file stands for the device.
"""

from __future__ import annotations

import contextlib
import subprocess
import sys
import threading
import time
import types
from pathlib import Path
from typing import Any, Callable, Optional

import numpy as np
import pytest

import vsinv


def _colour(k: int) -> np.ndarray:
    """Frame k of the fake camera: a BGR frame whose three channels differ."""
    rng = np.random.default_rng(k)
    return rng.integers(0, 256, size=(24, 32, 3), dtype=np.uint8)


def _bgr_to_grey(frame: np.ndarray) -> np.ndarray:
    """Rec. 601 luma by floating point and rounding: an independent conversion (within one
    level of OpenCV's fixed point)."""
    b, g, r = (frame[..., i].astype(float) for i in range(3))
    return np.rint(0.299 * r + 0.587 * g + 0.114 * b).astype(np.uint8)


class FakeCapture:
    """OpenCV's VideoCapture as a camera: `read` returns the frames of `frames` (an iterator of
    (ok, frame)) or blocks while `block` is clear."""

    instances: list["FakeCapture"] = []

    def __init__(self, device: Any, opened: bool = True, frames: Optional[Callable[[int], tuple[bool, Any]]] = None,
                 block: Optional[threading.Event] = None) -> None:
        self.device, self.opened, self.released = device, opened, 0
        self.frames = frames or (lambda k: (True, _colour(k)))
        self.block, self.reads = block, 0
        FakeCapture.instances.append(self)

    def isOpened(self) -> bool:  # noqa: N802 (OpenCV's name)
        return self.opened

    def read(self) -> tuple[bool, Any]:
        if self.block is not None:
            self.block.wait()
        k, self.reads = self.reads, self.reads + 1
        return self.frames(k)

    def release(self) -> None:
        self.released += 1


def fake_cv2(monkeypatch: pytest.MonkeyPatch, **capture: Any) -> types.ModuleType:
    """Installs a fake `cv2` whose VideoCapture(device) is a FakeCapture(device, **capture)."""
    FakeCapture.instances = []
    cv2 = types.ModuleType("cv2")
    cv2.VideoCapture = lambda device: FakeCapture(device, **capture)  # type: ignore[attr-defined]
    cv2.COLOR_BGR2GRAY = 6  # type: ignore[attr-defined]
    cv2.cvtColor = lambda frame, code: vsinv.vision.to_grey(frame, "bgr")  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "cv2", cv2)
    return cv2


def test_a_device_index_or_path_is_read_as_a_camera(monkeypatch: pytest.MonkeyPatch) -> None:
    fake_cv2(monkeypatch)
    got = list(vsinv.frames(0, max_frames=3))
    assert [n for n, _ in got] == ["camera-00000", "camera-00001", "camera-00002"]
    for k, (_, image) in enumerate(got):
        assert image.shape == (24, 32) and image.dtype == np.uint8 and image.flags.c_contiguous
        assert np.abs(image.astype(int) - _bgr_to_grey(_colour(k))).max() <= 1
    (capture,) = FakeCapture.instances
    assert capture.device == 0 and capture.released == 1
    # A device path goes to OpenCV as a string (whether or not the device exists here).
    for source in ("/dev/video0", Path("/dev/video7")):
        assert len(list(vsinv.frames(source, max_frames=1))) == 1
    assert [c.device for c in FakeCapture.instances[1:]] == ["/dev/video0", "/dev/video7"]
    assert all(c.released == 1 for c in FakeCapture.instances)


def test_the_capture_is_released_when_the_caller_stops(monkeypatch: pytest.MonkeyPatch) -> None:
    fake_cv2(monkeypatch)
    source = vsinv.frames(0)
    next(source)
    next(source)
    (capture,) = FakeCapture.instances
    assert capture.released == 0
    source.close()  # type: ignore[attr-defined]
    assert capture.released == 1
    with contextlib.closing(vsinv.frames(1)) as camera:  # type: ignore[type-var]
        for name, _ in camera:
            if name == "camera-00004":
                break
    assert FakeCapture.instances[1].released == 1 and FakeCapture.instances[1].reads == 5


def test_a_camera_that_cannot_be_opened_or_read_raises_by_name(monkeypatch: pytest.MonkeyPatch) -> None:
    fake_cv2(monkeypatch, opened=False)
    with pytest.raises(vsinv.InvalidInput, match=r"^source: camera 3 could not be opened") as e:
        vsinv.frames(3)
    assert (e.value.kind, e.value.argument) == ("invalid_argument", "source")
    assert FakeCapture.instances[0].released == 1
    # A read that fails after two frames (the device unplugged) ends with an error, released.
    fake_cv2(monkeypatch, frames=lambda k: (k < 2, _colour(k) if k < 2 else None))
    source = vsinv.frames(0)
    assert [n for n, _ in itertools_take(source, 2)] == ["camera-00000", "camera-00001"]
    with pytest.raises(vsinv.InvalidInput, match=r"camera 0 gave no frame \(read failed after 2 frames"):
        next(source)
    assert FakeCapture.instances[0].released == 1


def itertools_take(source: Any, n: int) -> list[Any]:
    return [next(source) for _ in range(n)]


def test_a_silent_camera_times_out_and_is_released_after_its_read(monkeypatch: pytest.MonkeyPatch) -> None:
    block = threading.Event()
    fake_cv2(monkeypatch, block=block)
    t0 = time.monotonic()
    with pytest.raises(vsinv.InvalidInput, match=r"camera 0 gave no frame within 0.2 s \(timeout=\)"):
        next(vsinv.frames(0, timeout=0.2))
    assert time.monotonic() - t0 < 2.0
    (capture,) = FakeCapture.instances
    assert capture.released == 0  # never released under a running read
    block.set()
    for _ in range(200):
        if capture.released:
            break
        time.sleep(0.01)
    assert capture.released == 1


def test_a_hung_camera_does_not_hold_up_the_interpreters_exit(tmp_path: Path) -> None:
    script = tmp_path / "hung.py"
    script.write_text(
        "import sys, threading, types, vsinv\n"
        "cv2 = types.ModuleType('cv2')\n"
        "class C:\n"
        "    def isOpened(self): return True\n"
        "    def read(self): threading.Event().wait()\n"
        "    def release(self): pass\n"
        "cv2.VideoCapture = lambda d: C()\n"
        "sys.modules['cv2'] = cv2\n"
        "try:\n"
        "    next(vsinv.frames(0, timeout=0.1))\n"
        "except vsinv.InvalidInput as e:\n"
        "    print(e)\n"
    )
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0 and "gave no frame within 0.1 s" in done.stdout, done.stderr


def test_without_opencv_the_error_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "cv2", None)  # `import cv2` raises ImportError
    for source in (0, "/dev/video0"):
        with pytest.raises(vsinv.InvalidInput, match=r'reading camera .* needs OpenCV: pip install "vsinv\[video\]"'):
            vsinv.frames(source)


def test_bad_timeouts_and_sources_are_refused_by_name(monkeypatch: pytest.MonkeyPatch) -> None:
    fake_cv2(monkeypatch)
    for bad in (0, -1.0, float("nan"), float("inf"), "1", None, True):
        with pytest.raises(vsinv.InvalidInput, match=r"^timeout: expected a finite number of seconds > 0"):
            vsinv.frames(0, timeout=bad)  # type: ignore[arg-type]
    for bad in (True, 2.5, object()):
        with pytest.raises(vsinv.InvalidInput, match=r"^source: expected arrays, a folder, a video file or a camera"):
            vsinv.frames(bad)  # type: ignore[arg-type]
    assert not FakeCapture.instances


def test_a_real_videocapture_as_the_camera(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """OpenCV's own VideoCapture, reading a file it wrote, behind the camera path: frames through
    the bounded reads, grey as OpenCV converts them, the end of the file an error of the camera
    (a camera has no end), the capture released."""
    cv2 = pytest.importorskip("cv2")
    path = tmp_path / "clip.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 10.0, (64, 48), True)
    if not writer.isOpened():
        pytest.skip("this OpenCV cannot write MJPG video")
    rng = np.random.default_rng(5)
    for _ in range(4):
        writer.write(rng.integers(0, 256, size=(48, 64, 3), dtype=np.uint8))
    writer.release()
    expected = list(vsinv.frames(path))  # the same file as a video: OpenCV's decode, grey
    real = cv2.VideoCapture
    captures: list[Any] = []

    def device(index: Any) -> Any:
        assert index == 0
        captures.append(real(str(path)))
        return captures[-1]

    monkeypatch.setattr(cv2, "VideoCapture", device)
    source = vsinv.frames(0, timeout=10.0)
    got = itertools_take(source, 4)
    assert [n for n, _ in got] == [f"camera-{k:05d}" for k in range(4)]
    for (_, image), (_, want) in zip(got, expected):
        np.testing.assert_array_equal(image, want)
    with pytest.raises(vsinv.InvalidInput, match="read failed after 4 frames"):
        next(source)
    assert not captures[0].isOpened()  # released
