"""`Views`: the images of a recorded MuJoCo run rendered again from its poses (the figures and
the GIF of `vsinv run --out` for `[world] engine = "mujoco"`), as `vsinv.vision.render` does for
the kinematic simulator."""

from __future__ import annotations

from typing import Any

import numpy as np

from ._session import _intrinsics
from ._world import World


class Views:
    """A scenario's MuJoCo world kept open to render views: `render(pose=..., time=...)` with
    `[camera]`'s K at `time` (a zoom followed), `render(reference=True)` at F* with
    `[reference_camera]`'s K (with an arm, the arm hidden: `World.render_view`). Close it (or use it as a context manager) to free the renderer."""

    def __init__(self, scenario: Any) -> None:
        self.world = World.from_scenario(scenario)
        assert self.world.scenario is not None
        self._d: dict[str, Any] = self.world.scenario

    def render(self, pose: Any = None, time: float = 0.0, reference: bool = False) -> np.ndarray:
        """The grey image (height, width) uint8 MuJoCo renders of the view."""
        if reference:
            self.world.set_K(_intrinsics(self._d, "reference_camera"))
            return self.world.render_view(np.eye(4))
        self.world.set_K(_intrinsics(self._d, "camera", float(time)))
        return self.world.render_view(np.eye(4) if pose is None else pose)

    def close(self) -> None:
        self.world.close()

    def __enter__(self) -> Views:
        return self

    def __exit__(self, *_: object) -> None:
        self.close()
