"""`run_scenario`: a scenario run in the world its `[world] engine` names (vsinv's kinematic
simulator, or MuJoCo through `vsinv.mujoco`), the result a `RunResult` either way."""

from __future__ import annotations

import os
from typing import Any, Callable, Union

import numpy as np

from . import _core
from ._core import InvalidInput, RunResult, Scenario, load_scenario


def run_scenario(
    scenario: Union[Scenario, dict[str, Any], str, "os.PathLike[str]"],
    record: bool = True,
    progress: Callable[[int, int], object] | None = None,
    allow_outside_files: bool = False,
) -> RunResult:
    """Runs a scenario (a `Scenario`, dict, built-in name or TOML path) in the world its
    `[world] engine` names: vsinv's kinematic simulator (the default, with the GIL released;
    `progress(done, total)` is called every 64 iterations if given; Ctrl-C stops the run) or
    MuJoCo (`vsinv.mujoco.run`, the mujoco extra; `progress` after each frame). Either way the
    result is a `RunResult` of the same schema."""
    flags_ok = all(isinstance(f, (bool, np.bool_)) for f in (record, allow_outside_files))
    if not flags_ok or (progress is not None and not callable(progress)):
        # The core refuses the arguments as it always did (a TypeError naming each), first.
        return _core.run_scenario(scenario, record=record, progress=progress, allow_outside_files=allow_outside_files)
    loaded = load_scenario(scenario, allow_outside_files=allow_outside_files)
    if loaded.engine != "mujoco":
        return _core.run_scenario(loaded, record=record, progress=progress)
    try:
        from . import mujoco
    except ImportError as e:  # pragma: no cover - depends on the machine
        raise InvalidInput(f"world.engine: \"mujoco\" needs the mujoco extra ({e}): pip install 'vsinv[mujoco]'") from e
    return mujoco.run(loaded, record=record, progress=progress)
