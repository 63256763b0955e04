"""The bindings only bind (issue 29, item 4): scenario dictionaries cross the boundary as
values walked in Rust (no JSON text), the figures and the progress bar are the Python
package's, and the pose helpers the package uses are Rust's, checked here against
independent computations (OpenCV's Rodrigues, finite differences)."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import vsinv
from vsinv import _core

ROOT = Path(__file__).resolve().parents[1]


def _scenario() -> dict[str, Any]:
    return vsinv.load_scenario("lens-12-6").to_dict()


# --- no Python package imported from Rust ----------------------------------------------------


def test_the_rust_sources_import_nothing_of_the_python_package() -> None:
    offenders = [
        f"{p.relative_to(ROOT)}:{i}"
        for p in (ROOT / "src").rglob("*.rs")
        for i, line in enumerate(p.read_text().splitlines(), 1)
        if re.search(r'import\("(vsinv|json)\b', line)
    ]
    assert offenders == []


def test_run_result_plot_is_the_packages_figure() -> None:
    pytest.importorskip("matplotlib")
    import vsinv.plots

    result = vsinv.run_scenario("lens-12-6")
    assert vsinv.RunResult.plot is vsinv.plots._run_result_plot
    import matplotlib.pyplot as plt

    fig = result.plot("errors")
    assert fig.axes
    plt.close(fig)
    with pytest.raises(vsinv.InvalidInput, match="kind: expected one of"):
        result.plot("nope")


def test_the_core_batch_reports_to_a_callable_only() -> None:
    calls: list[tuple[int, int]] = []
    _core.run_batch(["lens-12-6"] * 2, threads=1, progress=lambda d, t: calls.append((d, t)))
    assert calls[-1] == (2, 2)
    with pytest.raises(TypeError, match="progress: expected a callable"):
        _core.run_batch(["lens-12-6"], progress=True)  # type: ignore[arg-type]


# --- dictionaries without JSON text ------------------------------------------------------------


EXTREMES = [5e-324, 2.2250738585072014e-308, 0.1 + 0.2, 1.0 / 3.0, -0.0, 123456.789e-10, 2.0**70, 1e-300]


def test_floats_cross_exactly_both_ways() -> None:
    d = _scenario()
    points = d["object"]["points"]
    for i, x in enumerate(EXTREMES):
        points[i][1] = x
    back = vsinv.sim.Scenario.from_dict(d).to_dict()["object"]["points"]
    for i, x in enumerate(EXTREMES):
        got = back[i][1]
        assert type(got) is float and got == x and math.copysign(1.0, got) == math.copysign(1.0, x), (x, got)
    # A scenario's own dictionary comes back equal, key order included.
    once = vsinv.sim.Scenario.from_dict(d).to_dict()
    twice = vsinv.sim.Scenario.from_dict(once).to_dict()
    assert twice == once and list(twice) == list(once) and list(once)[:2] == ["name", "description"]
    assert list(once["control"]) == list(vsinv.sim.Scenario.from_dict(once).to_dict()["control"])


def test_integers_cross_as_integers_and_big_ones_as_the_nearest_float() -> None:
    d = _scenario()
    d["stop"]["max_iterations"] = np.int64(7)
    assert vsinv.sim.Scenario.from_dict(d).to_dict()["stop"]["max_iterations"] == 7
    d["control"]["gain"] = 2**70 + 1  # beyond 64 bits: the nearest f64, as JSON text read it
    assert vsinv.sim.Scenario.from_dict(d).to_dict()["control"]["gain"] == float(2**70)
    d["control"]["gain"] = 10**400
    with pytest.raises(vsinv.InvalidInput, match="control.gain: number out of range") as e:
        vsinv.sim.Scenario.from_dict(d)
    assert e.value.key == "control.gain"


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf, np.float32("nan"), np.float64("-inf")])
def test_non_finite_numbers_are_refused_naming_the_key(bad: Any) -> None:
    d = _scenario()
    d["object"]["points"][2][1] = bad
    with pytest.raises(vsinv.InvalidInput, match=r"scenario: object\.points\[2\]\[1\]: expected a finite number") as e:
        vsinv.load_scenario(d)
    assert e.value.key == "object.points[2][1]" and e.value.kind == "scenario"
    # In a batch, the key is named as the batch's validation names it (the item's index first).
    with pytest.raises(vsinv.InvalidInput, match=r"scenario: \[1\]\.object\.points\[2\]\[1\]: expected a finite") as e:
        vsinv.sim.run_batch([_scenario(), d], progress=False)
    assert e.value.key == "[1].object.points[2][1]"


def test_values_python_cannot_describe_are_refused_naming_the_key() -> None:
    d = _scenario()
    d["control"]["gain"] = object()
    with pytest.raises(vsinv.InvalidInput, match="control.gain: Object of type object is not JSON serializable") as e:
        vsinv.load_scenario(d)
    assert e.value.key == "control.gain"
    d["control"]["gain"] = 0.5
    d["control"][(1, 2)] = 1.0
    with pytest.raises(vsinv.InvalidInput, match="control: keys must be str, int, float, bool or None, not tuple"):
        vsinv.load_scenario(d)
    del d["control"][(1, 2)]
    d["control"][3] = 1.0  # an int key is written as JSON writes it, then refused as unknown
    with pytest.raises(vsinv.InvalidInput, match="control: unknown field `3`"):
        vsinv.load_scenario(d)


def test_nested_values_are_bounded() -> None:
    d = _scenario()
    deep: Any = 1.0
    for _ in range(200):
        deep = [deep]
    d["control"]["gain"] = deep
    with pytest.raises(vsinv.InvalidInput, match="nested more than 128 levels deep"):
        vsinv.load_scenario(d)
    loop: dict[str, Any] = {}
    loop["a"] = loop
    d["control"]["gain"] = loop
    with pytest.raises(vsinv.InvalidInput, match="nested more than 128 levels deep"):
        vsinv.load_scenario(d)


def test_numpy_values_and_tuples_cross_as_lists_and_numbers() -> None:
    d = _scenario()
    d["start"]["position"] = np.array([0.2, -0.15, -0.15], dtype=np.float32)
    d["noise"]["on_reference"] = np.bool_(False)
    d["object"]["points"] = tuple(tuple(p) for p in d["object"]["points"])
    s = vsinv.sim.Scenario.from_dict(d).to_dict()
    assert s["start"]["position"] == [float(np.float32(0.2)), float(np.float32(-0.15)), float(np.float32(-0.15))]
    assert s["noise"]["on_reference"] is False and isinstance(s["object"]["points"][0], list)


# --- the pose helpers the package uses are Rust's ---------------------------------------------


def test_thetau_from_rotations_is_opencvs_rodrigues() -> None:
    cv2 = pytest.importorskip("cv2")
    rng = np.random.default_rng(3)
    axes = rng.normal(size=(40, 3))
    angles = np.concatenate([np.linspace(0.0, np.pi - 1e-6, 38), [1e-9, 2.9]])
    vectors = axes / np.linalg.norm(axes, axis=1, keepdims=True) * angles[:, None]
    rotations = np.array([cv2.Rodrigues(v)[0] for v in vectors])
    np.testing.assert_allclose(vsinv.geometry.thetau_from_rotations(rotations), vectors, atol=1e-9)
    # Rodrigues back: the rotation of a theta-u vector is pose_from_position_thetau's block.
    for v, r in zip(vectors, rotations):
        np.testing.assert_allclose(vsinv.geometry.pose_from_position_thetau(np.zeros(3), v)[:3, :3], r, atol=1e-12)


def test_thetau_from_rotations_refusals_name_the_matrix() -> None:
    r = np.stack([np.eye(3), np.eye(3)])
    r[1, 0, 2] = np.nan
    with pytest.raises(vsinv.InvalidInput, match=r"rotations\[1\]: non-finite value at row 0, column 2") as e:
        vsinv.geometry.thetau_from_rotations(r)
    assert (e.value.index, e.value.row, e.value.column) == (1, 0, 2)
    with pytest.raises(vsinv.InvalidInput, match=r"rotations\[1\]: not a rotation matrix") as e:
        vsinv.geometry.thetau_from_rotations(np.stack([np.eye(3), 2.0 * np.eye(3)]))
    assert e.value.index == 1
    with pytest.raises(vsinv.InvalidInput, match="rotations: expected shape"):
        vsinv.geometry.thetau_from_rotations(np.eye(3))
    assert vsinv.geometry.thetau_from_rotations(np.empty((0, 3, 3))).shape == (0, 3)


def test_plots_theta_u_leaves_unrecorded_poses_nan() -> None:
    import vsinv.plots

    r = np.stack([np.eye(3), np.full((3, 3), np.nan)])
    out = vsinv.plots.theta_u(r)
    assert out.shape == (2, 3) and (out[0] == 0).all() and np.isnan(out[1]).all()


def test_twist_adjoint_moves_points_as_finite_differences_say() -> None:
    """A frame with pose (R, t) in its parent moves with twist xi (its own frame); a point p
    fixed in it moves in the parent as d/ds [X exp(s xi) p] at s = 0, which the parent-frame
    twist Ad xi must give: v + w x q for q = X p."""
    rng = np.random.default_rng(5)
    for _ in range(10):
        x = vsinv.geometry.pose_from_position_thetau(rng.normal(size=3), rng.normal(size=3))
        xi = rng.normal(size=6)
        ad = vsinv.geometry.twist_adjoint(x)
        assert ad.shape == (6, 6)
        v, w = (ad @ xi)[:3], (ad @ xi)[3:]
        p = np.append(rng.normal(size=3), 1.0)
        h = 1e-6
        fd = ((x @ vsinv.geometry.exp_twist(xi, h) @ p) - (x @ vsinv.geometry.exp_twist(xi, -h) @ p))[:3] / (2 * h)
        q = (x @ p)[:3]
        np.testing.assert_allclose(v + np.cross(w, q), fd, atol=1e-8)
    with pytest.raises(vsinv.InvalidInput, match="pose: non-finite value at row 0, column 0"):
        vsinv.geometry.twist_adjoint(np.full((4, 4), np.nan))
    with pytest.raises(vsinv.InvalidInput, match="pose"):
        vsinv.geometry.twist_adjoint(np.full((4, 4), 1e300))  # t x R overflows
