"""What the servo would command, frame by frame, on recorded images (``vsinv replay``): the
image pipeline (:class:`vsinv.ImageServo`) run on a reference image and a sequence of frames
(arrays, a folder or a video file: :func:`vsinv.frames`) without moving anything. The
result holds per frame the twist, the verdict, the errors and the points found, and plots
itself."""

from __future__ import annotations

import csv
import logging
import time
from dataclasses import dataclass
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any, Optional, Union

import numpy as np
import numpy.typing as npt

from ._core import ImageServo, InvalidInput, load_image
from .sources import frames as frame_source
from .safe_files import replace_text_file

if TYPE_CHECKING:
    from ._core import _TargetName

log = logging.getLogger("vsinv")

__all__ = ["ReplayResult", "replay"]

#: The CSV columns of :meth:`ReplayResult.write_csv`, one row per frame.
COLUMNS = ("frame", "verdict", "found", "image_error_px", "invariant_error", "vx", "vy", "vz", "wx", "wy", "wz")


@dataclass
class ReplayResult:
    """Per frame: its name, the verdict, the twist (m/s, rad/s, camera frame), the image error
    (largest distance of a point in use from its reference pixel, pixels), the invariant error
    ||s - s*||, and per point the pixel and whether it was found."""

    names: list[str]
    ids: npt.NDArray[np.uint32]
    reference_pixels: npt.NDArray[np.float64]
    verdicts: list[str]
    twists: npt.NDArray[np.float64]
    image_error: npt.NDArray[np.float64]
    invariant_error: npt.NDArray[np.float64]
    pixels: npt.NDArray[np.float64]
    found: npt.NDArray[np.bool_]

    def table(self) -> str:
        """One line per frame: points found, errors, verdict and twist."""
        lines = [f"{'frame':<20} {'found':>7} {'img err px':>10} {'inv err':>9}  {'verdict':<14} twist (vx vy vz m/s, wx wy wz rad/s)"]
        n = self.found.shape[1]
        for k, name in enumerate(self.names):
            twist = " ".join(f"{x:+.4f}" for x in self.twists[k])
            lines.append(
                f"{name[:20]:<20} {int(self.found[k].sum()):>3}/{n:<3} {self.image_error[k]:>10.2f} "
                f"{self.invariant_error[k]:>9.2e}  {self.verdicts[k]:<14} {twist}"
            )
        return "\n".join(lines)

    def write_csv(self, path: Path) -> Path:
        """One row per frame: the columns of :data:`COLUMNS`."""

        def write(f: IO[str]) -> None:
            w = csv.writer(f)
            w.writerow(COLUMNS)
            for k, name in enumerate(self.names):
                row = [name, self.verdicts[k], int(self.found[k].sum())]
                row += [f"{self.image_error[k]:.6g}", f"{self.invariant_error[k]:.6g}"]
                w.writerow(row + [f"{x:.9g}" for x in self.twists[k]])

        replace_text_file(path, write)
        return path

    def plot(self, ax: Any = None) -> Any:
        """The twist per frame (linear, m/s; angular, rad/s) and the image error, on ``ax`` (a
        sequence of three axes) or on a new figure; returns the figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
        else:
            fig = ax[0].figure
        k = np.arange(len(self.names))
        for i, label in enumerate(("vx", "vy", "vz")):
            ax[0].plot(k, self.twists[:, i], label=label)
        for i, label in enumerate(("wx", "wy", "wz")):
            ax[1].plot(k, self.twists[:, 3 + i], label=label)
        ax[2].plot(k, self.image_error, label="image error")
        lost = ~self.found.all(axis=1)
        if lost.any():
            ax[2].plot(k[lost], self.image_error[lost], "rx", label="a point lost")
        ax[0].set_ylabel("m/s")
        ax[1].set_ylabel("rad/s")
        ax[2].set_ylabel("pixels")
        ax[2].set_xlabel("frame")
        for a in ax:
            a.legend(loc="upper right", fontsize="small")
            a.grid(True, alpha=0.3)
        ax[0].set_title("what the servo would command, frame by frame")
        return fig


def replay(
    reference: Union[str, Path, npt.NDArray[np.uint8]],
    source: Any,
    K_hat: Any,
    target: _TargetName = "dots",
    max_frames: Optional[int] = None,
    **options: Any,
) -> ReplayResult:
    """Runs :class:`vsinv.ImageServo` (``target`` and ``options`` as its own) on every frame of
    ``source`` (see :func:`vsinv.frames`), at most ``max_frames`` of them, from the reference
    image (an array or a file); nothing moves, so each twist is what the servo would command
    on that frame."""
    t0 = time.perf_counter()
    log.info("replay: start (%s target)", target)
    ref = load_image(reference) if isinstance(reference, (str, Path)) else reference
    pipeline = ImageServo(ref, target, K_hat, **options)
    names: list[str] = []
    verdicts: list[str] = []
    twists, img, inv, pixels, found = [], [], [], [], []
    for name, image in frame_source(source, max_frames):
        step = pipeline.step(image)
        names.append(name)
        verdicts.append(step.verdict)
        twists.append(step.twist)
        t = step.telemetry
        img.append(t["image_error"])
        inv.append(t["invariant_error"])
        pixels.append(step.pixels)
        found.append(step.found)
        log.debug("replay: frame %s: %s, %d points found", name, step.verdict, int(np.count_nonzero(step.found)))
    if not names:
        raise InvalidInput("source: no frames")
    n = len(pipeline.ids)
    log.info("replay: %d frames in %.3f s", len(names), time.perf_counter() - t0)
    return ReplayResult(
        names=names,
        ids=pipeline.ids,
        reference_pixels=pipeline.reference_pixels,
        verdicts=verdicts,
        twists=np.array(twists).reshape(len(names), 6),
        image_error=np.array(img, dtype=float),
        invariant_error=np.array(inv, dtype=float),
        pixels=np.array(pixels).reshape(len(names), n, 2),
        found=np.array(found, dtype=bool).reshape(len(names), n),
    )


def read_depths(path: Optional[Path]) -> Optional[npt.NDArray[np.float64]]:
    """The ``z`` column of a points CSV (the reference depths, metres), or None."""
    if path is None:
        return None
    from .images import read_columns

    return read_columns(path, ("z",))[:, 0]
