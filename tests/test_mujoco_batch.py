"""Batches and sweeps of `[world] engine = "mujoco"` scenarios (issue 31, item 1): `vsinv.sim.run_batch`
runs them on worker processes (`vsinv._batch_mujoco`) and puts their rows in the Rust runner's
table; `vsinv.sim.run_sweep` goes through it.

Independent check: each row equals the summary of the same scenario run alone
(`vsinv.run_scenario`, in this process), and the kinematic rows of a mixed batch equal the Rust
runner's batch of them alone. MuJoCo's CPU renders are deterministic, so the equality is exact."""

from __future__ import annotations

import math
import os

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import vsinv  # noqa: E402
import vsinv.sim  # noqa: E402

vm = pytest.importorskip("vsinv.mujoco")
_WHY_NOT = vm.available()
pytestmark = pytest.mark.skipif(_WHY_NOT is not None, reason=_WHY_NOT or "")

from vsinv._batch_mujoco import COLUMNS  # noqa: E402


def _mujoco(gain: float = 1.0, iterations: int = 6) -> dict:
    d = vsinv.load_scenario("mujoco-lens-12-6").to_dict()
    d["stop"]["max_iterations"] = iterations
    d["control"]["gain"] = gain
    return d


def _same(row_value: object, summary_value: object) -> bool:
    if summary_value is None:
        return isinstance(row_value, float) and math.isnan(row_value)
    return row_value == summary_value


def _row(table: dict, i: int) -> dict:
    return {k: table[k][i].item() for k in COLUMNS}


def test_a_mixed_batch_on_two_processes_equals_the_single_runs() -> None:
    a, b = _mujoco(1.0), _mujoco(0.5, 4)
    calls: list[tuple[int, int]] = []
    table = vsinv.sim.run_batch(["lens-12-6", a, "vision-12-6", b], threads=2,
                                progress=lambda done, total: calls.append((done, total)))
    assert list(table) == list(COLUMNS) and all(len(v) == 4 for v in table.values())
    alone = vsinv.sim.run_batch(["lens-12-6", "vision-12-6"], progress=False)
    for k in COLUMNS:
        np.testing.assert_array_equal(table[k][[0, 2]], alone[k])
    for i, d in ((1, a), (3, b)):
        summary = vsinv.run_scenario(d, record=False).summary
        row = _row(table, i)
        assert all(_same(row[k], summary.get(k)) for k in COLUMNS), (row, summary)
    assert table["iterations"][1] == 6 and table["iterations"][3] == 4
    assert calls and calls[-1] == (4, 4) and [c[0] for c in calls] == sorted(c[0] for c in calls)


def test_a_sweep_of_a_mujoco_scenario_equals_the_single_runs() -> None:
    sweep = vsinv.sim.run_sweep(_mujoco(iterations=4), {"control.gain": [0.5, 1.5]}, threads=1, progress=False)
    for i, gain in enumerate(sweep.columns["control.gain"]):
        d = _mujoco(float(gain), 4)
        d["noise"] = {**(d.get("noise") or {}), "seed": int(sweep.columns["seed"][i])}
        summary = vsinv.run_scenario(d, record=False).summary
        for k in ("status", "iterations", "final_translation_error", "final_invariant_error"):
            assert _same(sweep.columns[k][i].item(), summary[k]), k


def test_a_mujoco_run_that_fails_on_the_way_is_an_error_row() -> None:
    d = _mujoco()
    d["camera"]["width"] = 900  # a valid scenario the MuJoCo world refuses (one sensor for both cameras)
    table = vsinv.sim.run_batch([d, _mujoco()], threads=1, progress=False)
    assert list(table["status"]) == ["error", "max_iterations"]
    assert "one sensor" in table["message"][0] and math.isnan(table["final_translation_error"][0])


def test_an_invalid_mujoco_scenario_is_refused_before_anything_runs() -> None:
    d = _mujoco()
    d["control"]["gain"] = -1.0
    with pytest.raises(vsinv.InvalidInput, match="scenario 1: .*gain"):
        vsinv.sim.run_batch([_mujoco(), d], progress=False)
    with pytest.raises(vsinv.InvalidInput, match="threads"):
        vsinv.sim.run_batch([_mujoco()], threads=0, progress=False)
