"""Figures in the style of the paper's experiments (sec. 5), and an archive of a run.

matplotlib is imported inside the functions (with the non-interactive Agg backend) so that
``import vsinv`` does not need it.

>>> result = vsinv.run_scenario("lens-12-6")
>>> save_figures(result, "out")      # six PNGs (three for a camera that never moves)
>>> save_npz(result, "out/trajectory.npz")
>>> fig, axes = plt.subplots(1, 2); result.plot("errors", ax=axes[0]); result.plot("path3d", ax=axes[1])

Every figure function takes ``ax``: None for a figure of its own, or a matplotlib Axes whose
place is divided into the figure's panels (or a sequence of Axes, one per panel), so that
figures compose; and ``scenario``, the run's scenario as a dict, to convert it once for many
figures.
"""

from __future__ import annotations

import json
import math
import os
import sys
from pathlib import Path
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Callable, Optional, Union, cast

import numpy as np
import numpy.typing as npt

from ._core import (
    InvalidInput,
    RunResult as _RunResult,
    pose_from_position_thetau,
    recorded_columns,
    thetau_from_rotations,
)
from .safe_files import replace_file

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from ._core import RunResult

__all__ = [
    "ARM_FIGURES", "FIGURES", "PLOTS", "STATIONARY_FIGURES", "draw_point_errors", "is_stationary", "plot",
    "point_styles", "save_figures", "save_npz", "summary_json", "theta_u",
]

_PathLike = Union[str, "os.PathLike[str]"]
#: Where a figure is drawn: None (a figure of its own), an Axes, or one Axes per panel.
AxesArg = Union["Axes", Sequence["Axes"], None]
_Scenario = Optional[dict[str, Any]]

#: File names written by :func:`save_figures`, in order.
FIGURES = (
    "image_trajectories.png",
    "errors.png",
    "task_functions.png",
    "velocities.png",
    "pose_errors.png",
    "path3d.png",
)

#: File names written by :func:`save_figures` for a camera that never moves (sec. 5.1, the
#: stationary zoom): its path, velocity, task functions and pose error would be flat lines;
#: the image and invariant error per point (the paper's Fig. 3) are what the run shows.
STATIONARY_FIGURES = ("image_trajectories.png", "errors.png", "point_errors.png")

#: File names also written for an arm (``[robot] kind = "urdf"``), in order.
ARM_FIGURES = ("joints.png", "joint_velocities.png")

DPI = 120


def _json_safe(value: Any) -> Any:
    """Replace NaN and infinities by None and NumPy scalars/arrays by Python values."""
    if isinstance(value, dict):
        return {str(k): _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    if isinstance(value, np.ndarray):
        return _json_safe(value.tolist())
    if isinstance(value, np.generic):
        return _json_safe(value.item())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def summary_json(summary: dict[str, Any], indent: Optional[int] = None) -> str:
    """The summary as strict JSON (NaN and infinities written as null)."""
    return json.dumps(_json_safe(summary), indent=indent, allow_nan=False)


def save_npz(result: RunResult, path: _PathLike) -> Path:
    """Write every recorded column (:func:`vsinv.sim.recorded_columns`), the summary (entry
    ``summary_json``, a JSON string) and the columns' declaration (entry ``columns_json``:
    name, unit, shape, ...) to a compressed ``.npz`` archive; returns the path written."""
    out = Path(path)
    if out.suffix != ".npz":
        out = out.with_name(out.name + ".npz")  # what numpy would write anyway
    columns = [c for c in recorded_columns() if getattr(result, c["name"]) is not None]
    arrays: dict[str, Any] = {c["name"]: getattr(result, c["name"]) for c in columns}
    arrays["summary_json"] = np.array(summary_json(result.summary))
    arrays["columns_json"] = np.array(json.dumps(columns))
    return replace_file(out, lambda f: np.savez_compressed(f, **arrays))


# ---------------------------------------------------------------------------------------------
# helpers


def _use_agg() -> None:
    """Select the non-interactive Agg backend unless pyplot is already in use (say in a
    notebook, whose backend is left alone: every figure here is closed after saving)."""
    if "matplotlib.pyplot" in sys.modules:
        return
    import matplotlib

    matplotlib.use("Agg")


def _title(fig: Figure, result: RunResult, what: str, own: bool = True) -> None:
    """The figure's title, on a figure of its own only (a given Axes' figure is the caller's)."""
    if not own:
        return
    s = result.summary
    status = s.get("status", "?")
    iters = s.get("iterations", "?")
    fig.suptitle(f"{s.get('name', result.scenario.name)}: {what}\n({status} after {iters} iterations)", fontsize=11)


def _scenario_dict(result: RunResult) -> dict[str, Any]:
    """The run's scenario as a dict (one conversion; :func:`save_figures` shares it)."""
    return result.scenario.to_dict()


def _panels(
    ax: AxesArg,
    rows: int,
    cols: int = 1,
    *,
    figsize: tuple[float, float],
    sharex: bool = False,
    projection: Optional[str] = None,
) -> tuple[Figure, list[Axes], bool]:
    """The figure, its ``rows`` x ``cols`` panels (row-major) and whether the figure is ours:
    a new figure when ``ax`` is None; the given Axes when there is one per panel; else the
    place of the one given Axes divided into the panels."""
    _use_agg()
    import matplotlib.pyplot as plt

    n = rows * cols
    if ax is None:
        kw: dict[str, Any] = {"figsize": figsize, "sharex": sharex, "constrained_layout": True, "squeeze": False}
        if projection:
            kw["subplot_kw"] = {"projection": projection}
        fig, grid = plt.subplots(rows, cols, **kw)
        return fig, list(grid.ravel()), True
    from matplotlib.axes import Axes as _Axes

    given = list(np.ravel(np.asarray(ax, dtype=object))) if isinstance(ax, (Sequence, np.ndarray)) else [ax]
    if not given or not all(isinstance(a, _Axes) for a in given):
        raise TypeError(f"ax: expected a matplotlib Axes, a sequence of them, or None, got {type(ax).__name__}")
    if len(given) == n and (projection is None or all(getattr(a, "name", "") == projection for a in given)):
        return cast("Figure", given[0].figure), given, False
    if len(given) != 1:
        raise InvalidInput(f"ax: expected one Axes or {n} (one per panel), got {len(given)}")
    one = given[0]
    fig = one.figure
    spec = one.get_subplotspec()
    box = one.get_position().bounds
    one.remove()
    grid = spec.subgridspec(rows, cols) if spec is not None else None
    axes: list[Any] = []
    for k in range(n):
        i, j = divmod(k, cols)
        share = axes[0] if sharex and axes else None
        if grid is not None:
            axes.append(fig.add_subplot(grid[i, j], projection=projection, sharex=share))
        else:
            x0, y0, w, h = box
            rect = (x0 + j * w / cols, y0 + (rows - 1 - i) * h / rows, w / cols, h / rows)
            axes.append(fig.add_axes(rect, projection=projection, sharex=share))
    return cast("Figure", fig), axes, False


def _all_nan(a: npt.NDArray[Any]) -> bool:
    return a.size == 0 or not bool(np.isfinite(a).any())


def _no_data(ax: Axes, text: str) -> None:
    ax.text(0.5, 0.5, text, ha="center", va="center", transform=ax.transAxes, color="0.4")
    ax.set_yticks([])  # x ticks may be shared with another panel: leave them


def _image_size(camera: Any) -> Optional[tuple[float, float]]:
    if not isinstance(camera, dict):
        return None
    w, h = camera.get("width"), camera.get("height")
    if w is None or h is None:
        return None
    return float(w), float(h)


def _rotation(theta_u_deg: Any) -> npt.NDArray[np.float64]:
    """The rotation matrix of a theta-u vector in degrees (Rodrigues)."""
    thetau = np.radians(np.asarray(theta_u_deg, dtype=float))
    return np.ascontiguousarray(pose_from_position_thetau(np.zeros(3), thetau)[:3, :3])


def _object_points(scenario: dict[str, Any]) -> npt.NDArray[np.float64]:
    """The object's points in F*: ``object.points``, or the corners of its tags (four per tag,
    top-left, top-right, bottom-right, bottom-left, in the ``object.rig`` frame)."""
    obj = scenario.get("object") or {}
    tags = obj.get("tags") or []
    if not tags:
        return np.asarray(obj.get("points") or [], dtype=float).reshape(-1, 3)
    rig = obj.get("rig") or {}
    rig_r = _rotation(rig.get("rotation_deg", rig.get("rotation", [0.0, 0.0, 0.0])))
    rig_t = np.asarray(rig.get("position", [0.0, 0.0, 0.0]), dtype=float)
    corners = []
    for tag in tags:
        h = float(tag["size"]) / 2.0
        r = rig_r @ _rotation(tag.get("rotation_deg", tag.get("rotation", [0.0, 0.0, 0.0])))
        t = rig_r @ np.asarray(tag["position"], dtype=float) + rig_t
        corners += [r @ np.array([x, y, 0.0]) + t for x, y in ((-h, h), (h, h), (h, -h), (-h, -h))]
    return np.asarray(corners, dtype=float).reshape(-1, 3)


def _save(fig: Figure, out_dir: Path, name: str) -> Path:
    _use_agg()
    import matplotlib.pyplot as plt

    path = out_dir / name
    try:
        replace_file(path, lambda f: fig.savefig(f, dpi=DPI, format=path.suffix.lstrip(".") or "png"))
    finally:
        plt.close(fig)
    return path


def _finish_time_axis(ax: Axes, t: npt.NDArray[np.float64]) -> None:
    ax.grid(True, alpha=0.3)
    if t.size > 1:
        ax.set_xlim(float(t[0]), float(t[-1]))
    if t.size <= 2:  # too short for lines to show: mark the samples
        for line in ax.get_lines():
            x = np.asarray(line.get_xdata(), dtype=float)
            if x.shape == t.shape and np.array_equal(x, t, equal_nan=True):
                line.set_marker("o")


# ---------------------------------------------------------------------------------------------
# the figures


def plot_image_trajectories(result: RunResult, ax: AxesArg = None, *, scenario: _Scenario = None) -> Figure:
    """Image trajectories of the points (current camera), start and reference pixels."""
    fig, (ax,), own = _panels(ax, 1, figsize=(7.6, 6.6))
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    scen = scenario if scenario is not None else _scenario_dict(result)
    px = np.asarray(result.pixels, dtype=float)
    ref = np.asarray(result.reference_pixels, dtype=float)
    size = _image_size(scen.get("camera")) or _image_size(scen.get("reference_camera"))
    ref_size = _image_size(scen.get("reference_camera"))

    if size is not None:
        w, h = size
        ax.add_patch(
            Rectangle((0.0, 0.0), w, h, fill=False, edgecolor="0.3", linestyle="--", linewidth=1.0, label="image border")
        )
    if ref_size is not None and size is not None and ref_size != size:
        w, h = ref_size
        ax.add_patch(
            Rectangle((0.0, 0.0), w, h, fill=False, edgecolor="darkgoldenrod", linestyle=":", linewidth=1.2,
                          label="reference image border")
        )
    colors = plt.get_cmap("tab20")
    n = px.shape[1] if px.ndim == 3 else 0
    for i in range(n):
        ax.plot(px[:, i, 0], px[:, i, 1], "-", color=colors(i % 20), linewidth=1.2, zorder=2)
    if px.shape[0] > 0:
        start = px[0]
        ax.plot(start[:, 0], start[:, 1], "o", color="tab:green", markersize=7, markeredgecolor="darkgreen",
                linestyle="none", label="start", zorder=4)
        end = px[-1]
        ax.plot(end[:, 0], end[:, 1], "x", color="tab:red", markersize=7, markeredgewidth=1.6,
                linestyle="none", label="final", zorder=5)
    ax.plot(ref[:, 0], ref[:, 1], "s", color="gold", markeredgecolor="saddlebrown", markeredgewidth=1.3,
            markersize=8, linestyle="none", label="reference (p*)", zorder=3)
    for i, (u, v) in enumerate(ref):
        if np.isfinite(u) and np.isfinite(v):
            ax.annotate(str(i), (u, v), xytext=(5, 4), textcoords="offset points", fontsize=7, color="saddlebrown")

    # Limits: the image rectangle plus whatever the trajectories leave it by, with a margin.
    finite = np.concatenate([px.reshape(-1, 2), ref.reshape(-1, 2)])
    finite = finite[np.isfinite(finite).all(axis=1)]
    lo = finite.min(axis=0) if finite.size else np.zeros(2)
    hi = finite.max(axis=0) if finite.size else np.ones(2)
    for wh in (size, ref_size):
        if wh is not None:
            lo = np.minimum(lo, 0.0)
            hi = np.maximum(hi, wh)
    pad = 0.04 * max(float((hi - lo).max()), 1.0)
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(hi[1] + pad, lo[1] - pad)  # image v axis points down
    ax.set_aspect("equal")
    ax.xaxis.tick_top()
    ax.xaxis.set_label_position("top")
    ax.set_xlabel("u (px)")
    ax.set_ylabel("v (px)")
    ax.grid(True, alpha=0.25)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.02), ncol=5, fontsize=9, frameon=False)
    s = result.summary
    if own:
        fig.suptitle(f"{s.get('name', result.scenario.name)}: image trajectories ({s.get('status', '?')})", fontsize=11)
    return fig


def plot_errors(result: RunResult, ax: AxesArg = None, *, scenario: _Scenario = None) -> Figure:
    """The invariant-space error (and the path tracking error) and the image error."""
    scen = scenario if scenario is not None else _scenario_dict(result)
    stationary = is_stationary(result, scen)  # no servo, no stop rule: the images are numbered
    t = np.arange(1.0, len(result.time) + 1.0) if stationary else np.asarray(result.time, dtype=float)
    inv = np.asarray(result.invariant_error, dtype=float)
    img = np.asarray(result.image_error, dtype=float)
    s = result.summary
    stop = {} if stationary else scen.get("stop") or {}
    fig, (a1, a2), own = _panels(ax, 2, figsize=(8, 6.2), sharex=True)
    if _all_nan(inv):
        _no_data(a1, "no invariant error recorded")
    else:
        pos = np.where(inv > 0, inv, np.nan)
        a1.semilogy(t, pos, color="tab:blue", label="||s - s*||")
        if s.get("path_duration") is not None:
            track = np.asarray(result.tracking_error, dtype=float)
            a1.semilogy(t, np.where(track > 0, track, np.nan), color="tab:green", label="||s - s*(t)|| (path tracking)")
            a1.axvline(float(s["path_duration"]), color="0.5", linestyle="--", linewidth=1.0, label="end of the path")
            # The path starts exactly at the current image (error ~1e-15): keep the axis readable.
            top = float(np.nanmax(np.concatenate([pos, np.where(track > 0, track, np.nan)])))
            a1.set_ylim(bottom=top * 1e-5)
        tol = stop.get("invariant_error")
        if tol is not None and tol > 0 and s.get("stop_rule") == "invariant":
            a1.axhline(float(tol), color="tab:red", linestyle=":", linewidth=1.0, label=f"stop threshold {tol:g}")
        a1.legend(loc="best", fontsize=9)
        _finish_time_axis(a1, t)
    a1.set_ylabel("||s - s*|| (invariant space)")
    a1.set_title("invariant-space error", fontsize=10)
    if _all_nan(img):
        _no_data(a2, "no image error recorded")
    else:
        a2.plot(t, img, color="tab:orange", label="max_i ||p_i - p_i*||")
        tol = stop.get("pixel_error")
        if tol is not None and tol > 0 and s.get("stop_rule") == "pixel":
            a2.axhline(float(tol), color="tab:red", linestyle=":", linewidth=1.0, label=f"stop threshold {tol:g} px")
        a2.set_ylim(bottom=0.0)
        a2.legend(loc="best", fontsize=9)
        _finish_time_axis(a2, t)
    a2.set_ylabel("image error (px)")
    a2.set_title("largest distance to the reference pixel", fontsize=10)
    a2.set_xlabel("image" if stationary else "time (s)")
    if stationary and len(t) <= 40:
        a2.set_xticks(t)
    _title(fig, result, "errors", own)
    return fig


def plot_task_functions(result: RunResult, ax: AxesArg = None, *, scenario: _Scenario = None) -> Figure:
    """The task functions eps (eq. 14) and eps_z (sec. 4.2)."""
    t = np.asarray(result.time, dtype=float)
    eps = np.asarray(result.eps, dtype=float).reshape(len(t), -1)
    eps_z = np.asarray(result.eps_z, dtype=float)
    has_eps, has_z = not _all_nan(eps), not _all_nan(eps_z)
    if not has_eps and not has_z:
        fig, (one,), own = _panels(ax, 1, figsize=(8, 3.5))
        law = ((scenario if scenario is not None else _scenario_dict(result)).get("control") or {}).get("law", "?")
        _no_data(one, f"no task function for the '{law}' law")
        _title(fig, result, "task functions", own)
        return fig
    panels = int(has_eps) + int(has_z)
    fig, axes, own = _panels(ax, panels, figsize=(8, 3.1 * panels + 0.6), sharex=True)
    k = 0
    if has_eps:
        ax = axes[k]
        labels = ["ε₁ (v_x, m)", "ε₂ (v_y, m)", "ε₃ (v_z, m)", "ε₄ (ω_x, rad)", "ε₅ (ω_y, rad)"]
        for j in range(eps.shape[1]):
            ax.plot(t, eps[:, j], label=labels[j] if j < len(labels) else f"ε{j + 1}")
        ax.axhline(0.0, color="0.5", linewidth=0.8)
        ax.set_ylabel("ε (m | rad)")
        ax.set_title("task function ε = Ĵ⁺ (s − s*) (eq. 14)", fontsize=10)
        ax.legend(loc="best", ncol=2, fontsize=8.5)
        _finish_time_axis(ax, t)
        k += 1
    if has_z:
        ax = axes[k]
        ax.plot(t, eps_z, color="tab:purple", label="ε_z = det(Q*) τ₂₁")
        ax.axhline(0.0, color="0.5", linewidth=0.8)
        ax.set_ylabel("ε_z (px²)")
        ax.set_title("task function for the rotation about the optical axis (sec. 4.2)", fontsize=10)
        ax.legend(loc="best", fontsize=9)
        _finish_time_axis(ax, t)
    axes[-1].set_xlabel("time (s)")
    _title(fig, result, "task functions" + ("" if has_eps else " (ε not defined for this law)"), own)
    return fig


def plot_velocities(result: RunResult, ax: AxesArg = None, *, scenario: _Scenario = None) -> Figure:
    """The camera twist: translational (m/s) and rotational (deg/s) velocity."""
    t = np.asarray(result.time, dtype=float)
    tw = np.asarray(result.twist, dtype=float).reshape(len(t), 6)
    fig, (a1, a2), own = _panels(ax, 2, figsize=(8, 6.2), sharex=True)
    for j, name in enumerate(("v_x", "v_y", "v_z")):
        a1.plot(t, tw[:, j], label=f"${name}$")
    for j, name in enumerate(("\\omega_x", "\\omega_y", "\\omega_z")):
        a2.plot(t, np.degrees(tw[:, 3 + j]), label=f"${name}$")
    for ax in (a1, a2):
        ax.axhline(0.0, color="0.5", linewidth=0.8)
        ax.legend(loc="best", ncol=3, fontsize=9)
        _finish_time_axis(ax, t)
    a1.set_ylabel("translation (m/s)")
    a1.set_title("translational velocity (camera frame)", fontsize=10)
    a2.set_ylabel("rotation (deg/s)")
    a2.set_title("rotational velocity (camera frame)", fontsize=10)
    a2.set_xlabel("time (s)")
    _title(fig, result, "camera velocity", own)
    return fig


def theta_u(rotations: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """The theta-u vectors (rad) of rotation matrices (..., 3, 3): the axis u times the angle
    theta in [0, pi] (the rotation error components of the paper's Figs. 5, 7 and 9), by
    :func:`vsinv.geometry.thetau_from_rotations`; NaN for a matrix with a non-finite entry (a pose not
    recorded)."""
    r = np.asarray(rotations, dtype=float)
    if r.ndim < 2 or r.shape[-2:] != (3, 3):
        raise InvalidInput(f"rotations: expected shape (..., 3, 3), got {r.shape}")
    flat = r.reshape(-1, 3, 3)
    finite = np.isfinite(flat).all(axis=(1, 2))
    out = np.full((len(flat), 3), np.nan)
    out[finite] = thetau_from_rotations(flat[finite])
    return out.reshape(r.shape[:-2] + (3,))


def plot_pose_errors(result: RunResult, ax: AxesArg = None, *, scenario: _Scenario = None) -> Figure:
    """The pose error as in the paper's Figs. 5, 7 and 9: the translation of the camera from
    the goal per axis (mm, in F*) and its rotation per axis (theta-u components, deg), beside
    the distance and the angle (left). Four panels: norms on the left, components on the right."""
    t = np.asarray(result.time, dtype=float)
    te = np.asarray(result.translation_error, dtype=float) * 1e3
    re = np.degrees(np.asarray(result.rotation_error, dtype=float))
    pose = np.asarray(result.pose, dtype=float).reshape(-1, 4, 4)
    tr = pose[:, :3, 3] * 1e3
    tu = np.degrees(theta_u(pose[:, :3, :3]))  # NaN where the pose is not finite
    fig, (a1, b1, a2, b2), own = _panels(ax, 2, 2, figsize=(12, 6.4), sharex=True)
    a1.plot(t, te, color="tab:blue", label="||t||")
    a1.set_ylabel("translation error (mm)")
    a1.set_title("distance of the camera centre to the goal", fontsize=10)
    a2.plot(t, re, color="tab:red", label="|θ|")
    a2.set_ylabel("rotation error (deg)")
    a2.set_title("rotation angle to the goal orientation", fontsize=10)
    for j, name in enumerate("xyz"):
        b1.plot(t, tr[:, j], label=f"t_{name}")
        b2.plot(t, tu[:, j], label=f"θu_{name}")
    b1.set_ylabel("translation error (mm)")
    b1.set_title("translation per axis (camera centre in F*)", fontsize=10)
    b2.set_ylabel("rotation error θu (deg)")
    b2.set_title("rotation per axis (θu components)", fontsize=10)
    for a in (a1, a2):
        a.set_ylim(bottom=0.0)
    for a in (b1, b2):
        a.axhline(0.0, color="0.5", linewidth=0.8)
        a.legend(loc="best", ncol=3, fontsize=9)
    for a in (a1, a2, b1, b2):
        _finish_time_axis(a, t)
    a2.set_xlabel("time (s)")
    b2.set_xlabel("time (s)")
    s = result.summary
    ft, fr = _scaled(s.get("final_translation_error"), 1e3), _scaled(s.get("final_rotation_error"), 180 / math.pi)
    if ft is not None:
        a1.text(0.99, 0.9, f"final {ft:.3g} mm", ha="right", va="top", transform=a1.transAxes, fontsize=9)
    if fr is not None:
        a2.text(0.99, 0.9, f"final {fr:.3g} deg", ha="right", va="top", transform=a2.transAxes, fontsize=9)
    _title(fig, result, "pose errors", own)
    return fig


def _scaled(value: Any, factor: float) -> Optional[float]:
    """A finite summary number in display units (mm, deg), None otherwise."""
    if isinstance(value, (int, float)) and math.isfinite(value):
        return float(value) * factor
    return None


def _set_3d_limits(ax: Any, pts: npt.NDArray[np.float64], zoom: float, min_span: float = 10.0) -> None:
    """Equal-aspect limits around pts (x, y, z in F*, drawn as x, z, y with y down)."""
    from matplotlib.ticker import MaxNLocator

    pts = pts[np.isfinite(pts).all(axis=1)]
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = np.maximum(hi - lo, max(0.05 * float((hi - lo).max()), min_span))
    mid = 0.5 * (lo + hi)
    lo, hi = mid - 0.54 * span, mid + 0.54 * span
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[2], hi[2])
    ax.set_zlim(hi[1], lo[1])  # y down
    ax.set_box_aspect((float(hi[0] - lo[0]), float(hi[2] - lo[2]), float(hi[1] - lo[1])), zoom=zoom)
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_major_locator(MaxNLocator(nbins=4))
    ax.tick_params(labelsize=8, pad=1)
    ax.set_xlabel("x (mm)", labelpad=2)
    ax.set_ylabel("z (mm, optical axis)", labelpad=4)
    ax.set_zlabel("y (mm, down)", labelpad=4)


def plot_path3d(result: RunResult, ax: AxesArg = None, *, scenario: _Scenario = None) -> Figure:
    """The camera centre's path in F* (mm) against the straight line to the goal: the whole
    scene with the object (left) and a close-up of the path (right)."""
    _use_agg()
    import matplotlib.pyplot as plt

    scen = scenario if scenario is not None else _scenario_dict(result)
    pose = np.asarray(result.pose, dtype=float).reshape(-1, 4, 4)
    c = pose[:, :3, 3] * 1e3
    c = c[np.isfinite(c).all(axis=1)]
    obj = _object_points(scen) * 1e3
    own = ax is None
    if own:
        fig = plt.figure(figsize=(12.0, 6.2))
        left: Any = fig.add_axes((0.0, 0.1, 0.5, 0.76), projection="3d")
        right: Any = fig.add_axes((0.5, 0.1, 0.5, 0.76), projection="3d")
    else:
        fig, (left, right), _ = _panels(ax, 1, 2, figsize=(12.0, 6.2), projection="3d")
    origin = np.zeros((1, 3))

    # F* has x right, y down, z along the optical axis: draw z as depth and y downwards.
    for a3 in (left, right):
        if len(c):
            a3.plot(c[:, 0], c[:, 2], c[:, 1], color="tab:blue", linewidth=2.0, label="camera centre path")
            a3.plot([c[0, 0], 0.0], [c[0, 2], 0.0], [c[0, 1], 0.0], "--", color="0.35", linewidth=1.2,
                    label="straight line to the goal")
            a3.scatter(c[:1, 0], c[:1, 2], c[:1, 1], color="tab:green", edgecolors="darkgreen", s=55,
                       depthshade=False, label="start")
            if np.linalg.norm(c[-1]) > 1.0:
                a3.scatter(c[-1:, 0], c[-1:, 2], c[-1:, 1], color="tab:red", marker="x", s=50,
                           depthshade=False, label="final")
        a3.scatter([0.0], [0.0], [0.0], color="gold", edgecolors="saddlebrown", s=130, marker="*",
                   depthshade=False, label="goal (origin of F*)")
        a3.view_init(elev=22, azim=-58)
    if len(obj):
        left.scatter(obj[:, 0], obj[:, 2], obj[:, 1], color="k", s=14, depthshade=False, label="object points")
    _set_3d_limits(left, np.concatenate([origin, c, obj]), zoom=1.1)
    _set_3d_limits(right, np.concatenate([origin, c]), zoom=1.0)
    left.set_title("scene", fontsize=10)
    right.set_title("close-up of the path", fontsize=10)
    if own:
        fig.legend(*left.get_legend_handles_labels(), loc="lower center", ncol=6, fontsize=9, frameon=False)
    else:
        left.legend(loc="upper left", fontsize=7)
    dev = _scaled(result.summary.get("max_line_deviation"), 1e3)
    what = "camera path in F*"
    if dev is not None:
        what += f" (largest deviation from the line {dev:.1f} mm)"
    _title(fig, result, what, own)
    return fig


def point_styles(n: int) -> list[dict[str, Any]]:
    """Distinct line styles for ``n`` points: the 20 colours of tab20, then the same colours
    dashed, then dotted (so that 16 points never share a colour)."""
    import matplotlib.pyplot as plt

    cmap = plt.get_cmap("tab20")
    dashes = ("-", "--", ":", "-.")
    markers = ("o", "s", "^", "D")
    return [{"color": cmap(i % 20), "linestyle": dashes[(i // 20) % 4], "marker": markers[(i // 20) % 4]}
            for i in range(n)]


def draw_point_errors(
    fig: Figure,
    axes: tuple[Axes, Axes],
    x: npt.NDArray[np.float64],
    image_error: npt.NDArray[np.float64],
    invariant_error: npt.NDArray[np.float64],
    basis: Sequence[int],
    xlabel: str,
    own: bool,
) -> None:
    """The paper's Fig. 3 into two Axes: per point, the image error ||p_i - p_i*|| (px) and the
    invariant error ||q_i - q_i*|| against ``x``; one style per point (:func:`point_styles`),
    the same in both panels, one legend naming the points (the basis points marked)."""
    a, b = axes
    n = image_error.shape[1] if image_error.ndim == 2 else 0
    few = len(x) <= 40  # mark the samples of a short sequence (the six images of sec. 5.1)
    for i, style in enumerate(point_styles(n)):
        kw = dict(style, markersize=4 if few else 0, linewidth=1.2)
        label = f"point {i}" + (" (basis)" if i in basis else "")
        a.plot(x, image_error[:, i], label=label, **kw)
        b.plot(x, invariant_error[:, i], **kw)
    a.set_ylabel("image error ||p_i − p_i*|| (px)")
    a.set_title("image error per point", fontsize=10)
    b.set_ylabel("invariant error ||q_i − q_i*|| (dimensionless)")
    b.set_title(f"invariant error per point (basis {list(basis)}: zero by construction)", fontsize=10)
    for c in (a, b):
        c.set_ylim(bottom=0.0)
        c.set_xlabel(xlabel)
        c.grid(True, alpha=0.3)
        if few and len(x):
            c.set_xticks(x)
    if len(x) > 1:
        b.set_xlim(a.get_xlim())
    handles, labels = a.get_legend_handles_labels()
    if own:
        fig.legend(handles, labels, loc="outside right center", fontsize=8, title="points")
    elif handles:
        b.legend(handles, labels, loc="upper left", fontsize=6, ncol=2, title="points", title_fontsize=7)


def _point_errors(result: RunResult) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], tuple[int, int, int]]:
    """Per iteration and point: the image error ||p_i - p_i*|| (px), the invariant error
    ||q_i - q_i*|| (eq. 7, NaN where the point or a basis point is not visible), the basis."""
    from ._core import choose_basis, invariant_points

    px = np.asarray(result.pixels, dtype=float)
    ref = np.asarray(result.reference_pixels, dtype=float)
    image_error = np.linalg.norm(px - ref[None], axis=2)
    given = result.summary.get("basis")
    basis = tuple(int(i) for i in given) if given else tuple(choose_basis(ref))
    b3 = (basis[0], basis[1], basis[2])
    q_star = invariant_points(ref, b3)
    invariant_error = np.full(image_error.shape, np.nan)
    for k, row in enumerate(px):
        if np.isfinite(row[list(b3)]).all():
            filled = np.where(np.isfinite(row), row, ref)  # invariant_points wants finite pixels
            err = np.linalg.norm(invariant_points(filled, b3) - q_star, axis=1)
            invariant_error[k] = np.where(np.isfinite(row).all(axis=1), err, np.nan)
    return image_error, invariant_error, b3


def is_stationary(result: RunResult, scenario: _Scenario = None) -> bool:
    """Whether the camera never moves in the run (``law = "none"``, or several iterations all
    at the first pose): its path, velocity, task-function and pose-error figures mean nothing.
    A run that ended at its first iteration (lost, degenerate) is not stationary: its figures
    show where it stopped."""
    law = ((scenario if scenario is not None else _scenario_dict(result)).get("control") or {}).get("law")
    pose = np.asarray(result.pose, dtype=float).reshape(-1, 4, 4)
    return law == "none" or (len(pose) > 1 and bool(np.all(pose == pose[:1])))


def plot_point_errors(result: RunResult, ax: AxesArg = None, *, scenario: _Scenario = None) -> Figure:
    """The paper's Fig. 3 for a run: per point, the image error and the invariant error, against
    the image number for a stationary camera (sec. 5.1), against time otherwise."""
    image_error, invariant_error, basis = _point_errors(result)
    fig, (a, b), own = _panels(ax, 1, 2, figsize=(13, 4.8))
    if is_stationary(result, scenario):
        x, xlabel = np.arange(1, len(result.time) + 1, dtype=float), "image"
    else:
        x, xlabel = np.asarray(result.time, dtype=float), "time (s)"
    draw_point_errors(fig, (a, b), x, image_error, invariant_error, basis, xlabel, own)
    _title(fig, result, "image and invariant error per point (Fig. 3)", own)
    return fig


def _joint_panels(
    result: RunResult, values: npt.NDArray[np.float64], low: npt.NDArray[np.float64],
    high: npt.NDArray[np.float64], what: str, unit: str, ax: AxesArg,
) -> Figure:
    """One panel per joint: its value (display units) and its limits (red dashed lines, the
    region beyond them shaded). The axis spans the motion; a limit far off it is written in
    the panel instead of squashing the motion to a line."""
    t = np.asarray(result.time, dtype=float)
    names = list((result.joint_limits or {}).get("names", []))
    n = values.shape[1]
    fig, axes, own = _panels(ax, n, 1, figsize=(8, 1.45 * n + 1.0), sharex=True)
    for j, a in enumerate(axes):
        v = values[:, j]
        name = names[j] if j < len(names) else f"joint {j}"
        a.plot(t, v, color=f"C{j % 10}", label=name)
        lo, hi = float(low[j]), float(high[j])
        finite = v[np.isfinite(v)]
        vmin, vmax = (float(finite.min()), float(finite.max())) if finite.size else (lo, hi)
        span = max(vmax - vmin, 0.05 * (hi - lo), 1e-9)
        bottom, top = vmin - 0.25 * span, vmax + 0.25 * span
        if lo >= vmin - 1.5 * span:
            bottom = lo - 0.1 * span
        if hi <= vmax + 1.5 * span:
            top = hi + 0.1 * span
        for y in (lo, hi):
            a.axhline(y, color="tab:red", linestyle="--", linewidth=1.0)
        a.axhspan(hi, max(top, hi) + abs(hi - lo) + 1.0, color="tab:red", alpha=0.12, linewidth=0)
        a.axhspan(min(bottom, lo) - abs(hi - lo) - 1.0, lo, color="tab:red", alpha=0.12, linewidth=0)
        a.set_ylim(bottom, top)
        a.set_ylabel(f"{name}\n({unit})", fontsize=8)
        a.tick_params(labelsize=8)
        margin = min(hi - vmax, vmin - lo)
        a.set_title(f"limits [{lo:.4g}, {hi:.4g}] {unit}; closest approach {margin:.3g} {unit}", loc="right",
                    fontsize=7.5, color="tab:red", pad=2)
        _finish_time_axis(a, t)
    axes[-1].set_xlabel("time (s)")
    _title(fig, result, what, own)
    return fig


def plot_joints(result: RunResult, ax: AxesArg = None, *, scenario: _Scenario = None) -> Figure:
    """An arm's joint positions in degrees, one panel per joint with its limits drawn."""
    limits = result.joint_limits or {}
    q = np.degrees(np.asarray(result.joints, dtype=float))
    lower = np.degrees(np.asarray(limits.get("lower", []), dtype=float))
    upper = np.degrees(np.asarray(limits.get("upper", []), dtype=float))
    return _joint_panels(result, q, lower, upper, "joint positions and their limits", "deg", ax)


def plot_joint_velocities(result: RunResult, ax: AxesArg = None, *, scenario: _Scenario = None) -> Figure:
    """An arm's joint velocities in deg/s, one panel per joint with its speed limit ±v drawn."""
    limits = result.joint_limits or {}
    dq = np.degrees(np.asarray(result.joint_velocities, dtype=float))
    velocity = np.degrees(np.asarray(limits.get("velocity", []), dtype=float))
    return _joint_panels(result, dq, -velocity, velocity, "joint velocities and their speed limits", "deg/s", ax)


#: The figures of a run by kind (``RunResult.plot(kind)``; file name ``<kind>.png``): those of
#: :data:`FIGURES`, ``point_errors`` (Fig. 3, written for a stationary camera) and those of
#: :data:`ARM_FIGURES` (an arm only).
PLOTS: dict[str, Callable[..., Figure]] = {
    "image_trajectories": plot_image_trajectories,
    "errors": plot_errors,
    "task_functions": plot_task_functions,
    "velocities": plot_velocities,
    "pose_errors": plot_pose_errors,
    "path3d": plot_path3d,
    "point_errors": plot_point_errors,
    "joints": plot_joints,
    "joint_velocities": plot_joint_velocities,
}


def plot(result: RunResult, kind: str, ax: AxesArg = None, *, scenario: _Scenario = None) -> Figure:
    """The figure ``kind`` (a key of :data:`PLOTS`) of a recorded run, drawn into ``ax`` or a
    new figure; returns the figure (``RunResult.plot`` calls this)."""
    make = PLOTS.get(kind) if isinstance(kind, str) else None
    if make is None:
        raise InvalidInput(f"kind: expected one of {', '.join(PLOTS)}, got {kind!r}")
    if kind in ("joints", "joint_velocities") and result.joint_limits is None:
        raise InvalidInput(f"kind: {kind!r} is drawn for an arm only ([robot] kind = \"urdf\")")
    return make(result, ax, scenario=scenario)


def _run_result_plot(self: RunResult, kind: str, ax: AxesArg = None) -> Figure:
    """The figure ``kind`` (``vsinv.plots.PLOTS``) drawn into ``ax`` (a matplotlib Axes, or one
    per panel) or a new figure; returns the matplotlib Figure."""
    return plot(self, kind, ax)


# RunResult is a Rust class; its figures are drawn here (the Rust side imports no Python).
_RunResult.plot = _run_result_plot  # type: ignore[method-assign]


def save_figures(result: RunResult, out_dir: _PathLike) -> list[Path]:
    """Write the figures of a recorded run to ``out_dir`` (created if needed): :data:`FIGURES`,
    or :data:`STATIONARY_FIGURES` for a camera that never moves (:func:`is_stationary`), then
    :data:`ARM_FIGURES` for an arm; returns the paths written, in that order (each file is
    ``<kind>.png`` of :data:`PLOTS`). The scenario is converted to a dict once."""
    if len(result.time) == 0:
        raise ValueError("the run was not recorded (run_scenario(..., record=False)): nothing to plot")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    scenario = _scenario_dict(result)
    names: tuple[str, ...] = STATIONARY_FIGURES if is_stationary(result, scenario) else FIGURES
    if result.joint_limits is not None and result.joint_velocities is not None:
        names = names + ARM_FIGURES
    return [_save(PLOTS[Path(name).stem](result, scenario=scenario), out, name) for name in names]
