"""K of a scenario's camera at a time of the run, read from the scenario's dict: what the
MuJoCo loops and the recordings need of `[camera] zoom` (the kinematic simulator reads the same
table in Rust, `sim::camera_model`)."""

from __future__ import annotations

from typing import Any

import numpy as np


def camera_k(d: dict[str, Any], key: str = "camera", t: float = 0.0) -> tuple[float, float, float, float]:
    """(fku, fkv, u0, v0) of `[key]` at time `t`: a `zoom` table (times, fku, fkv, optional u0,
    v0) interpolated piecewise linearly and held outside its times, as the simulator's. A
    missing `[estimate]` is the servo camera at t = 0 and a missing `[camera]` the reference
    camera, the scenario schema's defaults."""
    if key == "estimate" and d.get("estimate") is None:
        return camera_k(d, "camera", 0.0)
    if key == "camera" and d.get("camera") is None:
        key = "reference_camera"
    c = d[key]
    k = [float(c["fku"]), float(c["fkv"]), float(c["u0"]), float(c["v0"])]
    zoom = c.get("zoom")
    if zoom:
        for i, name in enumerate(("fku", "fkv", "u0", "v0")):
            if zoom.get(name) is not None:
                k[i] = float(np.interp(t, zoom["times"], zoom[name]))
    return k[0], k[1], k[2], k[3]
