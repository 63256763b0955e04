"""One result schema, in SI: the recorded columns and the summary's numbers are declared once
(Rust, `vsinv::sim::outcome`), and the Python results follow the declaration; the figures
compose (each draws into a given Axes) and read the scenario once per figure set."""

import json
import math

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import vsinv  # noqa: E402
from vsinv import plots  # noqa: E402


@pytest.fixture(scope="module")
def lens() -> vsinv.RunResult:
    return vsinv.run_scenario("lens-12-6")


@pytest.fixture(scope="module")
def arm() -> vsinv.RunResult:
    return vsinv.run_scenario("arm-panda-12-6")


def _expected_shape(column: dict, result: vsinv.RunResult) -> tuple[int, ...]:
    sizes = {"N": len(result.time), "n": len(result.reference_pixels), "n_joints": result.joints.shape[1]}
    return tuple(sizes[a] if isinstance(a, str) else a for a in column["shape"])


def _check_columns(result: vsinv.RunResult, present: set[str]) -> None:
    declared = {c["name"]: c for c in vsinv.sim.recorded_columns()}
    assert set(result.arrays) == present <= set(declared)  # nothing recorded is undeclared
    for name, c in declared.items():
        value = getattr(result, name)
        if name not in present:
            assert value is None and c["recorded"] != "always", name
            continue
        assert value is result.arrays[name] or np.shares_memory(value, result.arrays[name]), name
        assert value.shape == _expected_shape(c, result), name
        assert value.dtype == np.dtype(c["dtype"]), name


def test_declaration_is_complete_and_documented() -> None:
    columns = vsinv.sim.recorded_columns()
    names = [c["name"] for c in columns]
    assert len(names) == len(set(names))
    assert tuple(columns) == vsinv.RunResult.columns
    for c in columns:
        assert set(c) == {"name", "unit", "shape", "dtype", "recorded", "description"}
        assert c["unit"] and c["description"] and c["recorded"] in ("always", "vision", "arm")
        assert all(isinstance(a, int) or a in ("N", "n", "n_joints") for a in c["shape"])
        doc = getattr(vsinv.RunResult, c["name"]).__doc__
        assert c["unit"] in doc and c["description"] in doc
    assert {c["name"]: c["unit"] for c in columns}["translation_error"] == "m"
    assert {c["name"]: c["unit"] for c in columns}["rotation_error"] == "rad"


def test_every_declared_column_has_its_shape(lens: vsinv.RunResult, arm: vsinv.RunResult) -> None:
    always = {c["name"] for c in vsinv.sim.recorded_columns() if c["recorded"] == "always"}
    _check_columns(lens, always)
    _check_columns(arm, always | {"joint_velocities"})
    vision = vsinv.run_scenario("vision-12-12")
    _check_columns(vision, always | {"detection_error"})
    # Not recorded: the columns are there, with no rows.
    _check_columns(vsinv.run_scenario("lens-12-6", record=False), always)


# The older names the summary and the batch table gave some numbers (millimetres, degrees, a
# unit suffix) before 0.1.0 was published; removed (issue 29, item 3).
OLDER_NAMES = (
    "final_translation_error_mm", "final_rotation_error_deg", "final_image_error_px", "start_translation_error_mm",
    "start_rotation_error_deg", "max_line_deviation_mm", "peak_linear_speed_m_s", "peak_angular_speed_deg_s",
    "path_duration_s", "detection_error_median_px", "detection_error_max_px", "pixel_sigma_px",
    "reference_pixel_sigma_px", "translation_sigma_mm", "rotation_sigma_deg", "translation_uncertainty_mm",
    "rotation_uncertainty_deg",
)


def test_summary_is_si_with_one_name_per_number(lens: vsinv.RunResult) -> None:
    s = lens.summary
    fields = vsinv.sim.summary_fields()
    assert all(set(f) == {"name", "unit", "description"} for f in fields)
    declared = {f["name"] for f in fields}
    others = {"name", "status", "message", "iterations", "stop_rule", "prop1", "prop2", "within_tolerance", "basis", "basis_switches"}
    assert set(s) == declared | others and not set(OLDER_NAMES) & set(s)
    assert s["stop_rule"] in ("pixel", "invariant") and s["status"] == "converged"
    assert s["final_translation_error"] < 1e-3 and s["final_rotation_error"] < math.radians(0.1)


def test_batch_table_is_si_with_one_name_per_number(lens: vsinv.RunResult) -> None:
    table = vsinv.sim.run_batch(["lens-12-6"])
    s = lens.summary
    keys = ("final_translation_error", "final_rotation_error", "final_image_error", "final_invariant_error",
            "max_line_deviation", "observed_max_eps", "translation_uncertainty", "rotation_uncertainty", "pixel_sigma")
    for key in keys:
        expected = math.nan if s[key] is None else s[key]
        np.testing.assert_equal(table[key][0], expected, err_msg=key)
    others = {"status", "iterations", "prop1", "prop2", "within_tolerance", "message"}
    assert set(table) == set(keys) | others, sorted(set(table) ^ (set(keys) | others))


def test_npz_follows_the_declaration(lens: vsinv.RunResult, tmp_path) -> None:
    path = plots.save_npz(lens, tmp_path / "run.npz")
    with np.load(path) as npz:
        declared = json.loads(str(npz["columns_json"]))
        assert [c["name"] for c in declared] == list(lens.arrays)
        assert set(npz.files) == set(lens.arrays) | {"summary_json", "columns_json"}
        for c in declared:
            assert npz[c["name"]].shape == getattr(lens, c["name"]).shape


@pytest.mark.parametrize("kind", list(plots.PLOTS))
def test_each_kind_draws_into_a_given_axes(kind: str, lens: vsinv.RunResult, arm: vsinv.RunResult) -> None:
    result = arm if kind.startswith("joint") else lens
    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 5))
    try:
        drawn = result.plot(kind, ax=left)
        assert drawn is fig
        assert right in fig.axes  # the other Axes is left alone
        assert len(fig.axes) >= 2
        assert any(a.has_data() for a in fig.axes if a is not right)
        fig.canvas.draw()
    finally:
        plt.close(fig)


@pytest.mark.parametrize("kind", list(plots.PLOTS))
def test_run_result_plot_makes_a_figure_for_every_kind(kind: str, lens: vsinv.RunResult, arm) -> None:
    result = arm if kind.startswith("joint") else lens
    fig = result.plot(kind)
    try:
        assert fig.axes and fig.get_suptitle()
    finally:
        plt.close(fig)


def test_one_axes_per_panel(lens: vsinv.RunResult) -> None:
    fig, axes = plt.subplots(2, 1)
    try:
        assert lens.plot("errors", ax=axes) is fig and list(fig.axes) == list(axes)
        with pytest.raises(vsinv.InvalidInput, match="ax: expected one Axes or 4"):
            lens.plot("pose_errors", ax=[axes[0], axes[1], axes[0]])
    finally:
        plt.close(fig)


def test_plot_refuses_unknown_kinds(lens: vsinv.RunResult) -> None:
    with pytest.raises(vsinv.InvalidInput, match="kind: expected one of image_trajectories, errors, task_functions, velocities"):
        lens.plot("nonsense")  # type: ignore[arg-type]
    with pytest.raises(vsinv.InvalidInput, match=r"kind: .joints. is drawn for an arm only"):
        lens.plot("joints")


def test_scenario_is_converted_once_per_figure_set(arm: vsinv.RunResult, tmp_path, monkeypatch) -> None:
    calls = []
    convert = plots._scenario_dict
    monkeypatch.setattr(plots, "_scenario_dict", lambda r: calls.append(r) or convert(r))
    paths = plots.save_figures(arm, tmp_path)
    assert len(paths) == len(plots.FIGURES) + len(plots.ARM_FIGURES)
    assert len(calls) == 1


def test_view_figures_draw_into_a_given_axes() -> None:
    from vsinv.view_plots import plot_view

    image = np.zeros((48, 64), dtype=np.uint8)
    points = np.array([[10.0, 12.0], [30.0, 20.0]])
    fig, (left, right) = plt.subplots(1, 2)
    try:
        assert plot_view(image, points, points + 1.0, "a view", ax=right) is fig
        assert right.get_title() == "a view" and right.images and not left.has_data()
    finally:
        plt.close(fig)
