"""Stability maps of a parameter sweep (:func:`vsinv.sim.run_sweep`).

>>> res = vsinv.sim.run_sweep("lens-12-6", {"principal_point_error": np.linspace(-2000, 2000, 41)})
>>> plot_stability_map(res, "stability_map.png")

One varied key: the convergence rate and the median final translation error against the
parameter, over coloured bands telling where Prop. 2 holds (sufficient condition, which
implies Prop. 1), where only Prop. 1 holds and where neither does. Runs that converge in the
"Prop. 1 only" band show how conservative Prop. 2 is. Two varied keys: a heatmap of the
convergence rate with the Prop. 1 / Prop. 2 boundaries as contours and the regions where they
fail hatched. A key with many distinct values (random draws) is binned.

matplotlib is imported inside the functions (Agg backend unless pyplot is already in use).
"""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

from ..plots import DPI, _use_agg
from ..safe_files import replace_file
from .columns import _binned

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from .result import SweepResult

__all__ = ["plot_stability_map", "stability_map_figure"]

_PathLike = Union[str, "os.PathLike[str]"]

#: Numeric keys with more distinct values than this are binned.
MAX_VALUES = 60
BINS_1D = 30
BINS_2D = 24

# Band colours: Prop. 2 holds / only Prop. 1 holds / neither.
_C_PROP2 = "#cfe8cf"
_C_PROP1 = "#fbe7b5"
_C_NONE = "#f4c7c3"

_LABELS = {
    "focal_error": "focal error of K_hat (relative, fku and fkv)",
    "principal_point_error": "principal point error of K_hat (px, u0 and v0)",
    "roll_deg": "extra roll about the optical axis at the start (deg)",
    "lens_ratio": "servo lens / reference lens focal ratio",
}


#: Run outcomes (the ``status`` column), colours of the stacked bars and markers of the map.
STATUSES = ("converged", "max_iterations", "lost_features", "diverged", "degenerate", "error")
_STATUS_COLOURS = {
    "converged": "tab:blue",
    "max_iterations": "0.55",
    "lost_features": "tab:purple",
    "diverged": "black",
    "degenerate": "tab:brown",
    "error": "magenta",
}
_STATUS_MARKERS = {"max_iterations": "+", "lost_features": "o", "diverged": "x", "degenerate": "s", "error": "*"}


def _status_fractions(result: SweepResult, labels: Sequence[npt.NDArray[Any]]) -> dict[tuple[Any, ...], dict[str, float]]:
    """Fraction of runs of each status per group (groups keyed like ``summary_by``'s rows)."""
    counts: dict[tuple[Any, ...], dict[str, int]] = {}
    for key, status in zip(zip(*[lab.tolist() for lab in labels]), result.columns["status"].tolist()):
        c = counts.setdefault(tuple(key), {})
        c[status] = c.get(status, 0) + 1
    return {k: {st: n / sum(c.values()) for st, n in c.items()} for k, c in counts.items()}


def _label(key: str) -> str:
    return _LABELS.get(key, key)


def _numeric(col: npt.NDArray[Any]) -> bool:
    return col.dtype.kind in "fiu"


def _axis_values(values: npt.NDArray[Any]) -> tuple[npt.NDArray[np.float64], Optional[list[str]]]:
    """Plot coordinates of the group values: the values themselves, or positions 0..n-1 and
    tick labels for non-numeric values."""
    if _numeric(values):
        return values.astype(float), None
    return np.arange(len(values), dtype=float), [str(v) for v in values]


def _edges(x: npt.NDArray[np.float64], log: bool) -> npt.NDArray[np.float64]:
    """Cell edges around sorted centres (midpoints; geometric midpoints on a log axis)."""
    t = np.log(x) if log else x
    if len(t) == 1:
        half = 0.5 if not log else 0.1
        e = np.array([t[0] - half, t[0] + half])
    else:
        mid = 0.5 * (t[1:] + t[:-1])
        e = np.concatenate([[t[0] - (mid[0] - t[0])], mid, [t[-1] + (t[-1] - mid[-1])]])
    return np.exp(e) if log else e


def _is_log(x: npt.NDArray[np.float64]) -> bool:
    """Geometrically spaced positive values spanning more than a decade."""
    if len(x) < 3 or not np.all(x > 0) or x[-1] / x[0] < 10:
        return False
    d = np.diff(np.log(x))
    return bool(np.allclose(d, d.mean(), rtol=0.05))


def _binning(result: SweepResult, key: str, bins: int) -> Optional[int]:
    col = result.columns[key]
    if _numeric(col) and len(np.unique(col)) > MAX_VALUES:
        return bins
    return None


def _title(result: SweepResult, keys: Sequence[str]) -> str:
    name = result.base_name or "sweep"
    runs = len(result)
    extra = f", {result.repeats} repeats per point" if result.repeats > 1 else ""
    return f"{name}: stability map over {' x '.join(keys)}\n({runs} runs{extra})"


def _bands(ax: Axes, edges: npt.NDArray[np.float64], p1: npt.NDArray[np.float64], p2: npt.NDArray[np.float64]) -> None:
    """Shade each cell by the Prop. verdict of the majority of its runs."""
    for i in range(len(p1)):
        colour = _C_PROP2 if p2[i] >= 0.5 else (_C_PROP1 if p1[i] >= 0.5 else _C_NONE)
        ax.axvspan(float(edges[i]), float(edges[i + 1]), color=colour, linewidth=0, zorder=0)


def _band_legend(fig: Figure, extra: list[Any], p1: npt.NDArray[np.float64], p2: npt.NDArray[np.float64]) -> None:
    from matplotlib.patches import Patch

    handles = list(extra)
    if (p2 >= 0.5).any():
        handles.append(Patch(color=_C_PROP2, label="background: Prop. 2 holds (sufficient condition)"))
    if ((p2 < 0.5) & (p1 >= 0.5)).any():
        handles.append(Patch(color=_C_PROP1, label="background: only Prop. 1 holds (Prop. 2 conservative where runs converge)"))
    if (p1 < 0.5).any():
        handles.append(Patch(color=_C_NONE, label="background: Prop. 1 fails"))
    fig.legend(handles=handles, loc="lower center", ncol=2, fontsize=8.5, frameon=False)


def _plot_1d(result: SweepResult, key: str) -> Figure:
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    s = result.summary_by([key], bins=_binning(result, key, BINS_1D))
    x, ticks = _axis_values(s[key])
    log = ticks is None and _is_log(x)
    edges = _edges(x, log) if ticks is None else np.arange(len(x) + 1, dtype=float) - 0.5
    rate = s["convergence_rate"].astype(float)
    err = 1e3 * s["median_translation_error"].astype(float)  # drawn in mm
    p1 = s["prop1_rate"].astype(float)
    p2 = s["prop2_rate"].astype(float)

    bins = _binning(result, key, BINS_1D)
    fractions = _status_fractions(result, [_binned(result.columns[key], bins)])
    groups = [(v,) for v in s[key].tolist()]

    fig, (a1, a2) = plt.subplots(2, 1, figsize=(10, 7.4), sharex=True)
    fig.subplots_adjust(left=0.09, right=0.85, top=0.9, bottom=0.15, hspace=0.14)
    for ax in (a1, a2):
        _bands(ax, edges, p1, p2)
        ax.grid(True, alpha=0.35, zorder=1)
        if log:
            ax.set_xscale("log")
    # Stacked bars: the outcome of the runs at each value, converged at the bottom.
    if log:
        shrink = (edges[1:] / edges[:-1]) ** 0.1
        left, right = edges[:-1] * shrink, edges[1:] / shrink
    else:
        gap = 0.1 * np.diff(edges)
        left, right = edges[:-1] + gap, edges[1:] - gap
    bottom = np.zeros(len(x))
    present = [st for st in STATUSES if any(fractions[g].get(st, 0.0) > 0 for g in groups)]
    present += sorted({st for g in groups for st in fractions[g]} - set(STATUSES))
    for st in present:
        h = np.array([100 * fractions[g].get(st, 0.0) for g in groups])
        a1.bar(left, h, width=right - left, bottom=bottom, align="edge", zorder=2, alpha=0.9,
               color=_STATUS_COLOURS.get(st, "0.3"), label=st.replace("_", " "))
        bottom += h
    a1.set_ylim(0, 104)
    a1.set_ylabel("runs (%)")
    a1.set_title("outcome of the runs (converged at the bottom: the convergence rate)", fontsize=10)
    a1.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8.5, frameon=False)

    pos = np.where(err > 0, err, np.nan)
    failed = rate < 0.5
    a2.plot(x, pos, "-", color="tab:purple", zorder=2)
    a2.plot(x[~failed], pos[~failed], "o", color="tab:purple", markersize=4, zorder=3)
    a2.plot(x[failed], pos[failed], "x", color="tab:red", markersize=7, mew=2, zorder=3)
    if np.isfinite(pos).any():
        a2.set_yscale("log")
    a2.set_ylabel("median final translation error (mm)")
    a2.set_title("median final translation error (all runs)", fontsize=10)
    a2.set_xlabel(_label(key) + (" (binned)" if _binning(result, key, BINS_1D) else ""))
    if ticks is not None:
        a2.set_xticks(x)
        a2.set_xticklabels(ticks)
    a2.set_xlim(float(edges[0]), float(edges[-1]))
    marker = Line2D([], [], marker="x", color="tab:red", linestyle="none", mew=2, label="most runs did not converge")
    _band_legend(fig, [marker], p1, p2)
    fig.suptitle(_title(result, [key]), fontsize=11)
    return fig


def _grid(
    s: dict[str, npt.NDArray[Any]], kx: str, ky: str
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], Optional[list[str]], Optional[list[str]], dict[str, Any]]:
    """Group summaries on the (x, y) grid of distinct values; missing cells masked."""
    ux = list(dict.fromkeys(s[kx].tolist()))  # numbers sorted, other values in the grid's order
    uy = list(dict.fromkeys(s[ky].tolist()))
    if _numeric(s[kx]):
        ux.sort()
    if _numeric(s[ky]):
        uy.sort()
    ix = {v: i for i, v in enumerate(ux)}
    iy = {v: i for i, v in enumerate(uy)}
    grids: dict[str, Any] = {}
    for name in ("convergence_rate", "prop1_rate", "prop2_rate", "runs"):
        g = np.full((len(uy), len(ux)), np.nan)
        for vx, vy, val in zip(s[kx].tolist(), s[ky].tolist(), s[name].tolist()):
            g[iy[vy], ix[vx]] = val
        grids[name] = np.ma.masked_invalid(g)
    x, tx = _axis_values(np.asarray(ux))
    y, ty = _axis_values(np.asarray(uy))
    return x, y, tx, ty, grids


def _plot_2d(result: SweepResult, kx: str, ky: str) -> Figure:
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    bx, by = _binning(result, kx, BINS_2D), _binning(result, ky, BINS_2D)
    if bx or by:  # bin each continuous key separately
        cols = dict(result.columns)
        cols[kx] = _binned(cols[kx], bx)
        cols[ky] = _binned(cols[ky], by)
        result = replace(result, columns=cols)
    s = result.summary_by([kx, ky])
    x, y, tx, ty, g = _grid(s, kx, ky)
    logx = tx is None and _is_log(x)
    logy = ty is None and _is_log(y)
    ex = _edges(x, logx) if tx is None else np.arange(len(x) + 1, dtype=float) - 0.5
    ey = _edges(y, logy) if ty is None else np.arange(len(y) + 1, dtype=float) - 0.5

    fig, ax = plt.subplots(figsize=(9, 7.2))
    fig.subplots_adjust(left=0.11, right=0.97, top=0.9, bottom=0.16)
    mesh = ax.pcolormesh(ex, ey, 100 * g["convergence_rate"], cmap="RdYlGn", vmin=0, vmax=100, shading="flat")
    cb = fig.colorbar(mesh, ax=ax, pad=0.02)
    cb.set_label("runs converged (%)")
    if logx:
        ax.set_xscale("log")
    if logy:
        ax.set_yscale("log")

    handles: list[Any] = []
    if len(x) >= 2 and len(y) >= 2:
        xx, yy = np.meshgrid(x, y)
        props: list[tuple[str, str, str, Any, str]] = [
            ("prop2_rate", "black", "//", "-", "Prop. 2"),
            ("prop1_rate", "navy", "xx", "--", "Prop. 1"),
        ]
        for name, colour, hatch, style, label in props:
            z = g[name]
            if z.count() == 0:
                continue
            zmin, zmax = float(z.min()), float(z.max())
            if zmin < 0.5 <= zmax:
                ax.contour(xx, yy, z, levels=[0.5], colors=colour, linewidths=2.2, linestyles=style)
                handles.append(Line2D([], [], color=colour, linestyle=style, linewidth=2.2, label=f"{label} boundary"))
            if zmin < 0.5:
                ax.contourf(xx, yy, z, levels=[-0.5, 0.5], colors="none", hatches=[hatch])
                handles.append(Patch(facecolor="none", edgecolor="0.2", hatch=hatch, label=f"{label} fails"))
            else:
                handles.append(Patch(facecolor="none", edgecolor="none", label=f"{label} holds in every cell"))
    else:  # one row or column: mark the cells where the propositions fail
        for i in range(len(y)):
            for j in range(len(x)):
                if g["prop2_rate"][i, j] is not np.ma.masked and g["prop2_rate"][i, j] < 0.5:
                    ax.add_patch(_cell(ex, ey, i, j, "//"))
        handles.append(Patch(facecolor="none", edgecolor="0.2", hatch="//", label="Prop. 2 fails"))

    # Cells where most runs failed: a marker for the most frequent outcome.
    fractions = _status_fractions(result, [result.columns[kx], result.columns[ky]])
    seen: set[str] = set()
    msize = max(3.0, min(9.0, 220.0 / max(len(x), len(y))))
    for (vx, vy), frac in fractions.items():
        if frac.get("converged", 0.0) >= 0.5:
            continue
        worst = max((st for st in frac if st != "converged"), key=lambda st: frac[st])
        xc, yc = x[_index(x, tx, vx)], y[_index(y, ty, vy)]  # at the value, inside its cell
        m = _STATUS_MARKERS.get(worst, "*")
        ax.plot(xc, yc, m, color="white", mfc="none", markersize=msize, mew=1.3, zorder=4)
        seen.add(worst)
    for st in STATUSES:
        if st in seen:
            handles.append(Line2D([], [], marker=_STATUS_MARKERS[st], color="0.2", mfc="none", linestyle="none",
                                  mew=1.3, label=f"mostly {st.replace('_', ' ')}"))
    if tx is not None:
        ax.set_xticks(x)
        ax.set_xticklabels(tx)
    if ty is not None:
        ax.set_yticks(y)
        ax.set_yticklabels(ty)
    ax.set_xlim(float(ex[0]), float(ex[-1]))
    ax.set_ylim(float(ey[0]), float(ey[-1]))
    ax.set_xlabel(_label(kx) + (" (binned)" if bx else ""))
    ax.set_ylabel(_label(ky) + (" (binned)" if by else ""))
    ax.set_title("convergence rate; Prop. 2 is sufficient, Prop. 1 necessary and sufficient for constant K", fontsize=9)
    fig.legend(handles=handles, loc="lower center", ncol=3, fontsize=9, frameon=False)
    fig.suptitle(_title(result, [kx, ky]), fontsize=11)
    return fig


def _index(centres: npt.NDArray[np.float64], ticks: Optional[list[str]], value: Any) -> int:
    if ticks is not None:
        return ticks.index(str(value))
    return int(np.argmin(np.abs(centres - float(value))))


def _cell(ex: npt.NDArray[np.float64], ey: npt.NDArray[np.float64], i: int, j: int, hatch: str) -> Any:
    from matplotlib.patches import Rectangle

    return Rectangle(
        (float(ex[j]), float(ey[i])), float(ex[j + 1] - ex[j]), float(ey[i + 1] - ey[i]),
        facecolor="none", edgecolor="0.2", hatch=hatch, linewidth=0,
    )


def stability_map_figure(result: SweepResult, keys: Union[str, Sequence[str], None] = None) -> Figure:
    """The stability map figure over one or two keys (default: the varied keys; other
    varied keys, repeats and draws are pooled per cell)."""
    _use_agg()
    if keys is None:
        keys = list(result.keys)
        if len(keys) > 2:
            raise ValueError(
                f"plot_stability_map: {len(keys)} varied keys ({', '.join(keys)}); pass keys= with one or two of them"
            )
    key_list = [keys] if isinstance(keys, str) else list(keys)
    if not 1 <= len(key_list) <= 2:
        raise ValueError("plot_stability_map: needs one or two keys")
    for k in key_list:
        if k not in result.columns:
            raise ValueError(f"plot_stability_map: no column {k!r}")
    if len(result) == 0:
        raise ValueError("plot_stability_map: no runs")
    if len(key_list) == 1:
        return _plot_1d(result, key_list[0])
    return _plot_2d(result, key_list[0], key_list[1])


def plot_stability_map(result: SweepResult, path: _PathLike, keys: Union[str, Sequence[str], None] = None) -> Path:
    """Write the stability map of a sweep to ``path`` (PNG); returns the path written."""
    _use_agg()
    import matplotlib.pyplot as plt

    fig = stability_map_figure(result, keys)
    out = Path(path)
    try:
        replace_file(out, lambda f: fig.savefig(f, dpi=DPI, format=out.suffix.lstrip(".") or "png"))
    finally:
        plt.close(fig)
    return out
