"""Images on disk: the views of a scenario written as PNG files with the CSV of their dots
(``vsinv render``), and the image and invariant errors of dots tracked through image files
(``vsinv invariance``, the paper's Fig. 3).

A points CSV has a header and one row per dot: ``point,u,v,visible`` as written here (the
true projection of the dot's centre, pixels, and 1 if the dot is in the image); a file
written by hand needs only the ``u`` and ``v`` columns, approximate (within the tracker's
search radius, 20 px by default), in the order that the dots should keep.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

from ._core import (
    DotTracker,
    InvalidInput,
    Scenario,
    choose_basis,
    invariant_points,
    load_image,
    load_scenario,
    render_view,
    save_image,
)
from .safe_files import MAX_CSV_BYTES, read_text, replace_text_file

__all__ = ["InvarianceResult", "read_columns", "read_points", "track_invariance", "write_points", "write_scenario_images"]

_PathLike = Union[str, Path]


def write_points(path: Path, pixels: npt.NDArray[np.float64], visible: npt.NDArray[np.bool_]) -> Path:
    """Writes the ``point,u,v,visible`` CSV of a view."""
    def write(f: IO[str]) -> None:
        w = csv.writer(f)
        w.writerow(["point", "u", "v", "visible"])
        for i, ((u, v), seen) in enumerate(zip(pixels, visible)):
            w.writerow([i, f"{u:.6f}", f"{v:.6f}", int(bool(seen))])

    replace_text_file(path, write)
    return path


def read_points(path: _PathLike) -> npt.NDArray[np.float64]:
    """The ``u`` and ``v`` columns of a points CSV as an (n, 2) array (see :func:`read_columns`)."""
    return read_columns(path, ("u", "v"))


def read_columns(path: _PathLike, columns: Sequence[str]) -> npt.NDArray[np.float64]:
    """Some columns of a CSV with a header as an (n, len(columns)) array; a missing column or a
    value that is not a finite number raises ``InvalidInput`` naming the file, row and column.
    The file must be a regular UTF-8 file of at most :data:`vsinv.safe_files.MAX_CSV_BYTES`;
    a value is quoted in an error only as a short excerpt."""
    text = read_text(path, MAX_CSV_BYTES)
    try:
        rows = list(csv.DictReader(io.StringIO(text, newline="")))
    except csv.Error as e:
        raise InvalidInput(f"{path}: not a points CSV ({e})") from None
    if not rows or any(c not in rows[0] for c in columns):
        raise InvalidInput(f"{path}: expected a header with columns {', '.join(columns)} and one row per point")
    out = np.empty((len(rows), len(columns)))
    for r, row in enumerate(rows):
        for c, key in enumerate(columns):
            try:
                out[r, c] = float(row[key])
            except (TypeError, ValueError):
                raise InvalidInput(f"{path}: row {r + 2}, column {key}: {_excerpt(row[key])} is not a number") from None
            if not np.isfinite(out[r, c]):
                raise InvalidInput(f"{path}: row {r + 2}, column {key}: {_excerpt(row[key])} is not finite")
    return out


def _write_view(out_dir: Path, stem: str, scenario: Scenario, **view: Any) -> list[Path]:
    image, pixels, visible = render_view(scenario, **view)
    png = out_dir / f"{stem}.png"
    save_image(image, png)
    return [png, write_points(out_dir / f"{stem}.csv", pixels, visible)]


def write_scenario_images(
    scenario: Union[Scenario, _PathLike], out_dir: _PathLike, *, allow_outside_files: bool = False
) -> list[Path]:
    """Writes ``reference.png`` (K* at F*) and ``start.png`` (K(0) at the start pose) with
    their points CSVs; a stationary camera (``law = "none"``) also gets ``image-K.png`` for
    each later image of its run (t = K dt, K = 1 .. max_iterations): the zoom sequence of
    sec. 5.1. Returns the paths written."""
    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario, allow_outside_files=allow_outside_files)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = _write_view(out, "reference", sc, reference=True)
    written += _write_view(out, "start", sc)
    d = sc.to_dict()
    control = d.get("control") or {}
    if control.get("law") == "none":
        dt = float(control.get("dt") or 0.04)
        count = int((d.get("stop") or {}).get("max_iterations") or 0)
        for k in range(1, count + 1):
            written += _write_view(out, f"image-{k}", sc, time=k * dt)
    return written


@dataclass
class InvarianceResult:
    """Dots tracked through image files: per image and point, the centroid, whether it was
    found, the image error ||p - p*|| (pixels) and the invariant error ||q - q*||."""

    names: list[str]
    reference_pixels: npt.NDArray[np.float64]
    basis: tuple[int, int, int]
    pixels: npt.NDArray[np.float64]
    found: npt.NDArray[np.bool_]
    image_error: npt.NDArray[np.float64]
    invariant_error: npt.NDArray[np.float64]


def _invariant_errors(pixels: npt.NDArray[np.float64], found: npt.NDArray[np.bool_], q_star: Any, basis: Any) -> Any:
    """||q - q*|| per point (NaN where a point, or any basis point, was not found)."""
    if not all(found[list(basis)]):
        return np.full(len(pixels), np.nan)
    q = invariant_points(pixels, basis)
    err = np.linalg.norm(q - q_star, axis=1)
    return np.where(found, err, np.nan)


def track_invariance(
    reference: _PathLike,
    images: Sequence[_PathLike],
    points: _PathLike,
    basis: Optional[Sequence[int]] = None,
    search_radius: float = 20.0,
    *,
    first_points: Optional[_PathLike] = None,
    labels: tuple[str, str] = ("points", "first_points"),
    **tracker: Any,
) -> InvarianceResult:
    """Detects the reference dots near the approximate positions of ``points`` (a CSV), tracks
    them through ``images`` in order and measures the image and invariant errors of eq. (7).
    ``first_points`` (a CSV, one row per reference dot, in the same order) gives the dots'
    approximate positions in the first image, as when the images come from another camera
    (a lens change moves every dot); without it the dots are searched near the reference
    positions. ``tracker`` holds the other keyword arguments of :class:`DotTracker`. An error
    about a CSV's points names it by ``labels`` (a command passes its options' names)."""
    options = dict(tracker, search_radius=search_radius)
    dots = _start_tracker(load_image(reference), read_points(points), labels[0], options)
    p_star = dots.positions
    b = tuple(int(i) for i in basis) if basis is not None else choose_basis(p_star)
    q_star = invariant_points(p_star, b)
    rows = []
    paths = list(images)
    if first_points is not None and paths:
        clicks = read_points(first_points)
        if len(clicks) != len(p_star):
            raise InvalidInput(f"{labels[1]}: expected {len(p_star)} points (one per reference dot), got {len(clicks)} points")
        dots = _start_tracker(load_image(paths[0]), clicks, labels[1], options)
        start = dots.positions
        found = np.ones(len(start), dtype=bool)
        rows.append(_errors(start, found, p_star, q_star, b))
        paths = paths[1:]
    rows += [_errors(*dots.track(load_image(path)), p_star, q_star, b) for path in paths]
    return InvarianceResult(
        names=[Path(p).name for p in images],
        reference_pixels=p_star,
        basis=(b[0], b[1], b[2]),
        pixels=np.array([r[0] for r in rows]).reshape(len(rows), len(p_star), 2),
        found=np.array([r[1] for r in rows], dtype=bool).reshape(len(rows), len(p_star)),
        image_error=np.array([r[2] for r in rows]).reshape(len(rows), len(p_star)),
        invariant_error=np.array([r[3] for r in rows]).reshape(len(rows), len(p_star)),
    )


def _start_tracker(image: Any, clicks: Any, label: str, options: dict[str, Any]) -> DotTracker:
    """A DotTracker started on ``clicks``; its complaint about them (a click without a dot)
    names them by ``label``."""
    try:
        return DotTracker(image, clicks, **options)
    except InvalidInput as e:
        message = str(e)
        if message.startswith("initial_pixels:"):
            raise InvalidInput(label + message[len("initial_pixels"):]) from None
        raise


def _errors(pixels: Any, found: Any, p_star: Any, q_star: Any, basis: Any) -> tuple[Any, Any, Any, Any]:
    """One image's row: pixels, found, image error and invariant error per dot."""
    image_error = np.where(found, np.linalg.norm(pixels - p_star, axis=1), np.nan)
    return pixels, found, image_error, _invariant_errors(pixels, found, q_star, basis)


def _excerpt(value: object) -> str:
    """At most 12 characters of a value, escaped (an error never quotes a file's contents)."""
    text = str(value)
    return repr(text) if len(text) <= 12 else f"{text[:12]!r}... ({len(text)} characters)"


def write_invariance_csv(result: InvarianceResult, path: Path) -> Path:
    """One row per image and point: image, point, u, v, found, image_error_px, invariant_error."""

    def write(f: IO[str]) -> None:
        w = csv.writer(f)
        w.writerow(["image", "point", "u", "v", "found", "image_error_px", "invariant_error"])
        for k, name in enumerate(result.names):
            for i in range(result.pixels.shape[1]):
                u, v = result.pixels[k, i]
                w.writerow(
                    [name, i, f"{u:.6f}", f"{v:.6f}", int(result.found[k, i]),
                     f"{result.image_error[k, i]:.6g}", f"{result.invariant_error[k, i]:.6g}"]
                )

    replace_text_file(path, write)
    return path
