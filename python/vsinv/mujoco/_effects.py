"""`camera_image`: MuJoCo's render through the scenario's `[vision]` blur and sensor noise
(`vsinv.vision.degrade`, the kernel and noise draws of vsinv's own renderer), so that `[vision]`
means the same in both worlds."""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import vision
from ._world import World


def camera_image(world: World, d: dict[str, Any], pose: Any, frame: int) -> np.ndarray:
    """`world.render(pose)` through `degraded` (frame `frame`)."""
    return degraded(d, world.render(pose), frame)


def degraded(d: dict[str, Any], image: np.ndarray, frame: int) -> np.ndarray:
    """`image` degraded by `[vision]`'s `blur_sigma`, `noise_sigma` and `seed` with the noise draw
    of frame `frame` (0 the reference image, k + 1 the k-th servo frame, as the kinematic image
    loop numbers them); `image` itself when the scenario has no `[vision]`."""
    options = d.get("vision")
    if not options:
        return image
    return vision.degrade(image, blur_sigma=float(options.get("blur_sigma", 0.8)),
                          noise_sigma=float(options.get("noise_sigma", 2.0)), seed=int(options.get("seed", 0)),
                          frame=int(frame))
