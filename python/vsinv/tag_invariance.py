"""The image and invariant errors of AprilTag corners through image files (``vsinv invariance
--target tags``): the corners of the tags decoded in the reference image, matched by identity
(corner c of tag t is point 4 t + c, as :class:`vsinv.ImageServo` numbers them) in every image,
so no clicks are needed, whichever cameras took the images."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Optional, Sequence, Union

import numpy as np

from ._core import InvalidInput, choose_basis, detect_tags, invariant_points, load_image
from .images import InvarianceResult, _errors

__all__ = ["track_tag_invariance"]

_PathLike = Union[str, Path]


def _corners(image: Any, options: dict[str, Any]) -> dict[int, np.ndarray]:
    """Point identity (4 t + c) -> pixel, for every corner of every tag decoded in ``image``."""
    tags = detect_tags(image, **options)
    return {4 * int(t) + c: tags.corners[k, c] for k, t in enumerate(tags.ids) for c in range(4)}


def track_tag_invariance(
    reference: _PathLike,
    images: Sequence[_PathLike],
    basis: Optional[Sequence[int]] = None,
    *,
    family: str = "tag36h11",
    tag_ids: Optional[Sequence[int]] = None,
    decimation: Optional[int] = None,
) -> InvarianceResult:
    """Decodes the tags of ``family`` in ``reference`` (those of ``tag_ids``, each of which
    must be there; None: all), then in each image, and measures per corner the image and
    invariant errors of eq. (7); a corner whose tag is not decoded in an image is not found
    there (its last pixel is kept). ``decimation`` is :func:`vsinv.vision.detect_tags`'s (None: its
    default). The points are the corners in identity order; ``basis`` indexes them."""
    options: dict[str, Any] = {"family": family}
    if decimation is not None:
        options["decimation"] = decimation
    found_ref = _corners(load_image(reference), options)
    if tag_ids is not None:
        if len(tag_ids) == 0:
            raise InvalidInput("tag_ids: empty (None: every tag in the reference image)")
        missing = [t for t in tag_ids if 4 * int(t) not in found_ref]
        if missing:
            raise InvalidInput(f"tag_ids: tag {missing[0]} is not decoded in the reference image")
        found_ref = {i: p for i, p in found_ref.items() if i // 4 in {int(t) for t in tag_ids}}
    if len(found_ref) < 3:
        raise InvalidInput(f"{reference}: no tag of family {family} decoded in the reference image")
    ids = sorted(found_ref)
    p_star = np.array([found_ref[i] for i in ids], dtype=float)
    b = tuple(int(i) for i in basis) if basis is not None else choose_basis(p_star)
    q_star = invariant_points(p_star, b)
    rows, last = [], p_star.copy()
    for path in images:
        seen = _corners(load_image(path), options)
        found = np.array([i in seen for i in ids], dtype=bool)
        last = np.array([seen.get(i, last[k]) for k, i in enumerate(ids)], dtype=float)
        rows.append(_errors(last, found, p_star, q_star, b))
    n = len(ids)
    return InvarianceResult(
        names=[Path(p).name for p in images],
        reference_pixels=p_star,
        basis=(b[0], b[1], b[2]),
        pixels=np.array([r[0] for r in rows]).reshape(len(rows), n, 2),
        found=np.array([r[1] for r in rows], dtype=bool).reshape(len(rows), n),
        image_error=np.array([r[2] for r in rows]).reshape(len(rows), n),
        invariant_error=np.array([r[3] for r in rows]).reshape(len(rows), n),
    )
