"""Figures of images: the camera views of a run with ``[vision]`` (reference view, first and
last views with the tracked centroids, an animated GIF of the servo) and the paper's Fig. 3
for dots tracked through image files. A tag rig's views also show each tag's outline (its
four detected corners) and id.

The views are rendered again from the recorded poses (``vsinv.vision.render`` is deterministic: the
same pose, time and seed give the simulator's image; a ``[world] engine = "mujoco"`` run's views
are MuJoCo's renders, ``vsinv.mujoco.Views``).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, Union

import numpy as np
import numpy.typing as npt

from ._core import render
from .plots import AxesArg, _panels, _save, draw_point_errors

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ._core import RunResult
    from .images import InvarianceResult

__all__ = ["VIEW_FIGURES", "plot_invariance", "plot_view", "save_servo_gif", "save_view_figures"]

_PathLike = Union[str, "os.PathLike[str]"]

#: File names written by :func:`save_view_figures`, in order.
VIEW_FIGURES = ("view_reference.png", "view_first.png", "view_last.png", "camera.gif")

#: Frames of the GIF at most (iterations are subsampled evenly).
GIF_FRAMES = 80


def _tag_ids(scenario: object) -> list[int]:
    """The ids of a scenario's tag rig, in order (empty for dots)."""
    to_dict = getattr(scenario, "to_dict", None)
    d = to_dict() if callable(to_dict) else scenario
    tags = ((d or {}).get("object") or {}).get("tags") or [] if isinstance(d, dict) else []
    return [int(t["id"]) for t in tags]


def _tag_outlines(pixels: npt.NDArray[np.float64], ids: list[int]) -> list[tuple[int, npt.NDArray[np.float64]]]:
    """Per tag whose four corners (points 4 k .. 4 k + 3) are all finite: its id and corners."""
    out = []
    for k, tag_id in enumerate(ids):
        corners = pixels[4 * k : 4 * k + 4]
        if len(corners) == 4 and np.isfinite(corners).all():
            out.append((tag_id, corners))
    return out


def plot_view(
    image: npt.NDArray[np.uint8],
    tracked: npt.NDArray[np.float64],
    reference: npt.NDArray[np.float64],
    title: str,
    ax: AxesArg = None,
    tag_ids: list[int] | None = None,
) -> Figure:
    """A camera view with the tracked centroids (red +) and the reference positions (green o),
    drawn into ``ax`` or a new figure; with ``tag_ids`` (a tag rig: four points a tag), each
    tag's outline through its tracked corners and its id."""
    h, w = image.shape
    fig, (ax,), own = _panels(ax, 1, figsize=(8, 8 * h / w + 0.6))
    ax.imshow(image, cmap="gray", vmin=0, vmax=255, interpolation="nearest")
    for tag_id, corners in _tag_outlines(tracked, tag_ids or []):
        closed = np.vstack([corners, corners[:1]])
        ax.plot(closed[:, 0], closed[:, 1], "-", color="tab:cyan", lw=1.2)
        ax.plot(corners[0, 0], corners[0, 1], "s", mfc="none", mec="tab:cyan", ms=7)
        u, v = corners.mean(axis=0)
        ax.text(u, v, f"id {tag_id}", color="tab:cyan", fontsize=10, ha="center", va="center", weight="bold")
    ax.plot(reference[:, 0], reference[:, 1], "o", mfc="none", mec="tab:green", ms=10, label="reference image p* (K*)")
    ax.plot(tracked[:, 0], tracked[:, 1], "+", color="tab:red", ms=10, mew=1.5, label="tracked centroid")
    for i, (u, v) in enumerate(tracked):
        if np.isfinite(u):
            ax.annotate(str(i), (u, v), xytext=(6, -6), textcoords="offset points", color="yellow", fontsize=8)
    ax.set_xlim(-0.5, w - 0.5)
    ax.set_ylim(h - 0.5, -0.5)
    ax.set_title(title, fontsize=10)
    ax.legend(loc="lower right", fontsize=8)
    return fig


def _frame_indices(rows: int) -> npt.NDArray[np.int64]:
    return np.unique(np.linspace(0, rows - 1, min(rows, GIF_FRAMES)).round().astype(np.int64))


def _mark(frame: npt.NDArray[np.uint8], pixels: npt.NDArray[np.float64], colour: int, size: int) -> None:
    """Draws a small cross of palette index ``colour`` at each finite pixel."""
    h, w = frame.shape
    for u, v in pixels:
        if not (np.isfinite(u) and np.isfinite(v)):
            continue
        iu, iv = int(round(u)), int(round(v))
        if 0 <= iv < h:
            frame[iv, max(iu - size, 0) : min(iu + size + 1, w)] = colour
        if 0 <= iu < w:
            frame[max(iv - size, 0) : min(iv + size + 1, h), iu] = colour


def _half(image: npt.NDArray[np.uint8]) -> npt.NDArray[np.uint8]:
    """2 x 2 block means (odd edges dropped)."""
    h, w = image.shape[0] // 2 * 2, image.shape[1] // 2 * 2
    blocks = image[:h, :w].reshape(h // 2, 2, w // 2, 2).astype(np.uint16)
    return (blocks.sum(axis=(1, 3)) // 4).astype(np.uint8)


#: Grey levels of the GIF: few enough that the sensor noise does not fill the file
#: (80 frames of vision-12-6 took 5.2 MB with 32 adaptive colours, 0.4 MB with these).
GIF_GREYS = 16
_GREEN, _RED, _CYAN, _WHITE, _BLACK = range(GIF_GREYS, GIF_GREYS + 5)


def _gif_palette() -> list[int]:
    greys = [round(255 * k / (GIF_GREYS - 1)) for k in range(GIF_GREYS)]
    rgb = [c for g in greys for c in (g, g, g)]
    rgb += [40, 200, 40, 230, 40, 40, 40, 200, 230, 255, 255, 255, 0, 0, 0]
    return rgb + [0] * (768 - len(rgb))


def _gif_frame(grey: npt.NDArray[np.uint8], tracked: npt.NDArray[np.float64], reference: npt.NDArray[np.float64],
               ids: list[int], stamp: str) -> Any:
    """One GIF frame (palette image): the view in :data:`GIF_GREYS` levels, reference positions
    (green), tracked centroids (red), a tag rig's outlines and ids (cyan) and the time stamp."""
    from PIL import Image, ImageDraw

    index = np.rint(grey.astype(np.float64) * ((GIF_GREYS - 1) / 255.0)).astype(np.uint8)
    _mark(index, reference, _GREEN, 3)
    _mark(index, tracked, _RED, 4)
    frame = Image.fromarray(index, mode="P")
    frame.putpalette(_gif_palette())
    draw = ImageDraw.Draw(frame)
    for tag_id, corners in _tag_outlines(tracked, ids):
        points = [(float(u), float(v)) for u, v in corners]
        draw.line([*points, points[0]], fill=_CYAN, width=1)
        u, v = corners.mean(axis=0)
        draw.text((float(u) - 8, float(v) - 5), str(tag_id), fill=_CYAN)
    box = draw.textbbox((4, 3), stamp)
    draw.rectangle((box[0] - 2, box[1] - 2, box[2] + 2, box[3] + 2), fill=_BLACK)
    draw.text((4, 3), stamp, fill=_WHITE)
    return frame


class _Renderer:
    """The views of a run's scenario: vsinv's renderer, or MuJoCo's for ``[world] engine =
    "mujoco"`` (the images that run saw), one world kept open while the figures are drawn."""

    def __init__(self, scenario: Any) -> None:
        self.scenario, self.views = scenario, None
        if getattr(scenario, "engine", "kinematic") == "mujoco":
            from .mujoco import Views

            self.views = Views(scenario)

    def __call__(self, pose: Any = None, time: float = 0.0, reference: bool = False) -> npt.NDArray[np.uint8]:
        if self.views is not None:
            return self.views.render(pose=pose, time=time, reference=reference)
        if reference:
            return render(self.scenario, reference=True)
        return render(self.scenario, pose=pose, time=time)

    def __enter__(self) -> _Renderer:
        return self

    def __exit__(self, *_: object) -> None:
        if self.views is not None:
            self.views.close()


def save_servo_gif(result: RunResult, path: _PathLike, frame_ms: int = 80) -> Path:
    """An animated GIF of the camera view during the servo: up to :data:`GIF_FRAMES` frames
    evenly spaced over the run at half resolution, each stamped with its time and iteration,
    tracked centroids in red, reference positions in green (a tag rig's outlines and ids in
    cyan); :data:`GIF_GREYS` grey levels, so that the sensor noise does not swell the file
    (under 1 MB for the built-ins)."""
    scenario, poses, times = result.scenario, result.pose, result.time
    ids = _tag_ids(scenario)
    last = len(times) - 1
    frames = []
    with _Renderer(scenario) as view:
        greys = [(k, _half(view(pose=poses[k], time=float(times[k])))) for k in _frame_indices(len(times))]
    for k, grey in greys:
        stamp = f"t = {float(times[k]):.2f} s  iteration {k}/{last}"
        frames.append(_gif_frame(grey, result.pixels[k] / 2, result.reference_pixels / 2, ids, stamp))
    out = Path(path)
    frames[0].save(out, save_all=True, append_images=frames[1:], duration=frame_ms, loop=0, optimize=False)
    return out


def save_view_figures(result: RunResult, out_dir: _PathLike) -> list[Path]:
    """The reference view, the first and last camera views with the tracked centroids, and
    the servo GIF of a recorded ``[vision]`` run (:data:`VIEW_FIGURES`)."""
    out = Path(out_dir)
    sc, last = result.scenario, len(result.time) - 1
    ref = result.reference_pixels
    with _Renderer(sc) as view:
        views = [
            (view(reference=True), ref, "reference view (K* at F*), detected centroids"),
            (view(pose=result.pose[0], time=float(result.time[0])), result.pixels[0], "first camera view"),
            (view(pose=result.pose[last], time=float(result.time[last])), result.pixels[last], "last camera view"),
        ]
    paths = []
    ids = _tag_ids(sc)
    for (image, tracked, what), name in zip(views, VIEW_FIGURES):
        title = f"{sc.name}: {what}" + (f", iteration {last}" if "last" in what else ", iteration 0" if "first" in what else "")
        paths.append(_save(plot_view(image, tracked, ref, title, tag_ids=ids), out, name))
    paths.append(save_servo_gif(result, out / VIEW_FIGURES[3]))
    return paths


def plot_invariance(result: InvarianceResult, ax: AxesArg = None) -> Figure:
    """The paper's Fig. 3: per image, the image error ||p - p*|| and the invariant error
    ||q - q*|| of every point (one style per point, the same in both panels, a legend naming
    the points), drawn into ``ax`` (divided in two, or two Axes) or a new figure."""
    x = np.arange(1, len(result.names) + 1, dtype=float)
    fig, (a, b), own = _panels(ax, 1, 2, figsize=(13, 4.8))
    draw_point_errors(fig, (a, b), x, result.image_error, result.invariant_error, result.basis, "image", own)
    if len(x) <= 12:  # few images: name them under their ticks
        for c in (a, b):
            c.set_xticks(x, [name if len(name) <= 14 else name[:13] + "…" for name in result.names],
                         rotation=30, ha="right", fontsize=8)
    if own:
        fig.suptitle(f"image and invariant error per point (Fig. 3): {len(x)} images, basis {list(result.basis)}",
                     fontsize=11)
    return fig
