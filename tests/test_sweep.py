"""Parameter sweeps (vsinv.sweep): grids, random draws, derived keys, seeds, executors
(in-process, ProcessPoolExecutor, dask), the result table, the stability map and the CLI."""

import concurrent.futures
import csv
import multiprocessing
import sys

import numpy as np
import pytest

import vsinv
from conftest import rotation
from vsinv.cli import main
from vsinv.sweep import Choice, LogUniform, SweepResult, Uniform, build_scenarios, run_sweep

BASE = "lens-12-6"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def lens_12_6() -> dict:
    return vsinv.load_scenario(BASE).to_dict()


def assert_same_results(a: SweepResult, b: SweepResult) -> None:
    assert list(a.columns) == list(b.columns)
    for name in a.columns:
        x, y = a[name], b[name]
        if x.dtype.kind == "f":
            np.testing.assert_array_equal(x, y, err_msg=name)  # deterministic: bit-identical
        else:
            assert x.tolist() == y.tolist(), name


# ---------------------------------------------------------------------------------------------
# grids, columns, repeats


def test_grid_is_the_cartesian_product_with_one_column_per_key():
    gains = [0.5, 1.0, 2.0]
    sigmas = [0.0, 0.3]
    res = run_sweep(BASE, {"control.gain": gains, "noise.pixel_sigma": sigmas}, repeats=2, progress=False)
    assert len(res) == 3 * 2 * 2
    assert res.grid_keys == ("control.gain", "noise.pixel_sigma") and res.random_keys == ()
    # Last key fastest, repeats innermost.
    assert res["control.gain"].tolist() == [g for g in gains for _ in range(4)]
    assert res["noise.pixel_sigma"].tolist() == [s for _ in gains for s in sigmas for _ in range(2)]
    assert res["repeat"].tolist() == [0, 1] * 6
    for col in ("status", "iterations", "final_translation_error", "prop1", "prop2", "seed", "message"):
        assert len(res[col]) == len(res)
    # The scenarios really carry the values of their row.
    scenarios = build_scenarios(BASE, {"control.gain": gains, "noise.pixel_sigma": sigmas}, repeats=2)
    assert len(scenarios) == len(res)
    for i, d in enumerate(scenarios):
        assert d["control"]["gain"] == res["control.gain"][i]
        assert d["noise"]["pixel_sigma"] == res["noise.pixel_sigma"][i]
        assert d["noise"]["seed"] == res["seed"][i]
    # Without noise the invariant stop rule is met; with 0.3 px noise and window = 1 it is not.
    clean = res["noise.pixel_sigma"] == 0.0
    assert set(res["status"][clean]) == {"converged"}
    assert set(res["status"][~clean]) <= {"converged", "max_iterations"}


def test_list_index_keys_and_scalar_axes():
    scenarios = build_scenarios(BASE, {"start.position.2": [-0.2, -0.1], "stop.max_iterations": 50})
    assert [d["start"]["position"] for d in scenarios] == [[0.2, -0.15, -0.2], [0.2, -0.15, -0.1]]
    assert all(d["stop"]["max_iterations"] == 50 for d in scenarios)
    assert lens_12_6()["start"]["position"] == [0.2, -0.15, -0.15]  # the base is not modified


def test_repeats_have_distinct_seeds_and_different_noise():
    res = run_sweep("noise-12-6", {"control.gain": [1.0, 1.5]}, repeats=4, seed=3, progress=False)
    seeds = res["seed"].tolist()
    assert len(set(seeds)) == len(seeds) == 8
    assert all(0 <= s < 2**63 for s in seeds)
    # With 0.5 px noise, the repetitions of a point end differently.
    first = res["final_invariant_error"][res["control.gain"] == 1.0]
    assert len(set(first.tolist())) == 4
    again = run_sweep("noise-12-6", {"control.gain": [1.0, 1.5]}, repeats=4, seed=3, progress=False)
    assert_same_results(res, again)
    other = build_scenarios("noise-12-6", {"control.gain": [1.0, 1.5]}, repeats=4, seed=4)
    assert not set(seeds) & {d["noise"]["seed"] for d in other}


def test_varying_noise_seed_itself_is_used_verbatim():
    res = run_sweep("noise-12-6", {"noise.seed": [5, 6]}, progress=False)
    assert res["seed"].tolist() == [5, 6]
    assert res["final_invariant_error"][0] != res["final_invariant_error"][1]


# ---------------------------------------------------------------------------------------------
# derived keys


def test_focal_error_sets_k_hat_relative_to_the_servo_camera():
    d = lens_12_6()
    (s,) = build_scenarios(d, {"focal_error": [-0.5]})
    cam = d["camera"]
    assert s["estimate"]["fku"] == pytest.approx(0.5 * cam["fku"])
    assert s["estimate"]["fkv"] == pytest.approx(0.5 * cam["fkv"])
    assert (s["estimate"]["u0"], s["estimate"]["v0"]) == (d["estimate"]["u0"], d["estimate"]["v0"])  # kept
    assert s["camera"] == cam and s["reference_camera"] == d["reference_camera"]
    # Without an estimate in the base, K_hat's other fields come from the camera.
    del d["estimate"]
    (s,) = build_scenarios(d, {"focal_error": [0.25]})
    assert s["estimate"] == {"fku": 750.0, "fkv": 750.0, "u0": cam["u0"], "v0": cam["v0"], "skew_deg": 90.0}
    # On a zooming camera: relative to the focal length at t = 0.
    (z,) = build_scenarios("zoom-servo", {"focal_error": [0.1]})
    assert z["estimate"]["fku"] == pytest.approx(1.1 * z["camera"]["zoom"]["fku"][0])


def test_principal_point_error_shifts_u0_and_v0():
    d = lens_12_6()
    a, b = build_scenarios(d, {"principal_point_error": [0.0, 40.0]})
    assert (a["estimate"]["u0"], a["estimate"]["v0"]) == (d["estimate"]["u0"], d["estimate"]["v0"])
    assert b["estimate"]["u0"] == d["estimate"]["u0"] + 40 and b["estimate"]["v0"] == d["estimate"]["v0"] + 40
    assert b["estimate"]["fku"] == d["estimate"]["fku"]
    # Combined with focal_error: both apply.
    (c,) = build_scenarios(d, {"focal_error": [0.0], "principal_point_error": [-10.0]})
    assert c["estimate"]["fku"] == d["camera"]["fku"] and c["estimate"]["u0"] == d["estimate"]["u0"] - 10


def test_lens_ratio_changes_the_servo_lens_and_k_hat_follows():
    d = lens_12_6()  # reference 1200 px, camera 600 px, K_hat 648 x 570
    (s,) = build_scenarios(d, {"lens_ratio": [0.25]})
    assert s["camera"]["fku"] == pytest.approx(300.0) and s["camera"]["fkv"] == pytest.approx(300.0)
    assert s["estimate"]["fku"] == pytest.approx(324.0)  # 648 * 300/600: same relative error
    assert s["estimate"]["fkv"] == pytest.approx(285.0)
    assert s["estimate"]["u0"] == d["estimate"]["u0"]
    (same,) = build_scenarios(d, {"lens_ratio": [0.5]})
    assert same["camera"] == d["camera"] and same["estimate"] == pytest.approx(d["estimate"])
    # Without an estimate K_hat keeps following the camera (no estimate section is created).
    del d["estimate"]
    (s,) = build_scenarios(d, {"lens_ratio": [2.0]})
    assert s["camera"]["fku"] == 2400.0 and s.get("estimate") is None
    # A zoom schedule is scaled with the lens.
    (z,) = build_scenarios("zoom-servo", {"lens_ratio": [0.5]})
    assert z["camera"]["zoom"]["fku"] == pytest.approx([600.0, 350.0])
    res = run_sweep(BASE, {"lens_ratio": [0.5, 1.0]}, progress=False)
    assert res["status"].tolist() == ["converged", "converged"]


def roll_rotation(scenario: dict) -> np.ndarray:
    return rotation(np.radians(scenario["start"]["rotation_deg"]))


def rz(deg: float) -> np.ndarray:
    a = np.radians(deg)
    return np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])


@pytest.mark.parametrize("roll", [0.0, 30.0, 90.0, 135.0, 180.0, -170.0, 270.0, 400.0])
def test_roll_composes_about_the_optical_axis(roll):
    d = lens_12_6()
    r0 = roll_rotation(d)
    (s,) = build_scenarios(d, {"roll_deg": [roll]})
    np.testing.assert_allclose(roll_rotation(s), r0 @ rz(roll), atol=1e-9)
    assert np.linalg.norm(s["start"]["rotation_deg"]) <= 180.0 + 1e-9
    assert s["start"]["position"] == d["start"]["position"]


def test_roll_there_and_back():
    d = lens_12_6()
    (there,) = build_scenarios(d, {"roll_deg": [90.0]})
    (back,) = build_scenarios(there, {"roll_deg": [-90.0]})
    np.testing.assert_allclose(back["start"]["rotation_deg"], d["start"]["rotation_deg"], atol=1e-9)
    # 180 degrees from a rotation of 180 degrees about z: the identity.
    d["start"]["rotation_deg"] = [0.0, 0.0, 180.0]
    (ident,) = build_scenarios(d, {"roll_deg": [180.0]})
    np.testing.assert_allclose(ident["start"]["rotation_deg"], [0.0, 0.0, 0.0], atol=1e-9)
    (near,) = build_scenarios(d, {"roll_deg": [-1e-7]})  # just below pi: stays accurate
    np.testing.assert_allclose(roll_rotation(near), rz(180.0 - 1e-7), atol=1e-12)


# ---------------------------------------------------------------------------------------------
# random draws


def test_random_draws_are_reproducible_and_combined_with_every_grid_point():
    vary = {"focal_error": [0.0, 0.5], "roll_deg": Uniform(-20, 20), "control.gain": LogUniform(0.5, 2.0)}
    a = run_sweep(BASE, vary, draws=3, seed=11, progress=False)
    b = run_sweep(BASE, vary, draws=3, seed=11, progress=False)
    c = run_sweep(BASE, vary, draws=3, seed=12, progress=False)
    assert len(a) == 6 and a.grid_keys == ("focal_error",) and a.random_keys == ("roll_deg", "control.gain")
    assert_same_results(a, b)
    assert not np.array_equal(a["roll_deg"], c["roll_deg"])
    assert not np.array_equal(a["seed"], c["seed"])
    rolls = a["roll_deg"]
    np.testing.assert_array_equal(rolls[:3], rolls[3:])  # same draws for each grid point
    assert len(set(rolls[:3].tolist())) == 3 and np.all(np.abs(rolls) <= 20)
    assert np.all((a["control.gain"] >= 0.5) & (a["control.gain"] <= 2.0))
    assert a["focal_error"].tolist() == [0.0] * 3 + [0.5] * 3


def test_choice_draws_from_the_given_values():
    res = build_scenarios(BASE, {"control.law": Choice(["invariant", "ibvs"])}, draws=40, seed=1)
    laws = [d["control"]["law"] for d in res]
    assert set(laws) == {"invariant", "ibvs"}


def test_draws_must_match_random_keys():
    with pytest.raises(vsinv.InvalidInput, match=r"draws: random keys \(roll_deg\) need draws=N"):
        run_sweep(BASE, {"roll_deg": Uniform(0, 1)}, progress=False)
    with pytest.raises(vsinv.InvalidInput, match=r"draws: given without any random key \(Uniform, LogUniform, Choice\)"):
        run_sweep(BASE, {"roll_deg": [0.0]}, draws=5, progress=False)
    with pytest.raises(vsinv.InvalidInput, match="LogUniform: needs 0 < lo <= hi"):
        LogUniform(0.0, 1.0)
    with pytest.raises(ValueError):
        Uniform(2.0, 1.0)


# ---------------------------------------------------------------------------------------------
# errors before anything runs


@pytest.mark.parametrize(
    "key, values, match",
    [
        ("focl_error", [0.0], "focl_error"),
        ("control.gian", [1.0], "gian"),
        ("nosie.pixel_sigma", [0.0], "nosie"),
        ("start.position.7", [0.1], "start.position.7"),
        ("noise.pixel_sigma.x", [0.1], "noise.pixel_sigma.x"),
        ("control..gain", [1.0], "control..gain"),
        ("focal_error", [0.0, -1.5], "focal_error"),  # K_hat's focal terms would be negative
        ("roll_deg", ["a"], "roll_deg"),
        ("control.gain", "12", "control.gain"),
        ("control.gain", Uniform(-1.0, 1.0), "control.gain"),  # a bound is checked
    ],
)
def test_bad_keys_and_values_raise_before_running(monkeypatch, key, values, match):
    module = sys.modules["vsinv.sweep.execute"]  # where the chunks run

    def no_run(*args, **kwargs):
        raise AssertionError("ran before validating")

    monkeypatch.setattr(module, "run_batch", no_run)
    monkeypatch.setattr(module, "run_sweep_runs", no_run)
    draws = 2 if not isinstance(values, (list, str)) else None
    with pytest.raises(vsinv.InvalidInput, match=match.replace(".", r"\.")):
        run_sweep(BASE, {key: values}, draws=draws, progress=False)
    assert issubclass(vsinv.InvalidInput, ValueError)


#: A representative key of every table, with a base scenario that has it (or an optional table
#: the base lacks, created by the sweep) and a valid value.
TABLE_KEYS = [
    ("lens-12-6", "name", "renamed"),
    ("lens-12-6", "description", "varied"),
    ("lens-12-6", "object.points.0.2", 0.61),
    ("occlusion", "object.bodies.0.position.0", 0.001),
    ("lens-12-6", "reference_camera.fku", 1150.0),
    ("lens-12-6", "camera.u0", 410.0),
    ("lens-12-6", "estimate.skew_deg", 89.5),
    ("zoom-servo", "camera.zoom.fku.1", 750.0),
    ("lens-12-6", "start.rotation_deg.2", 70.0),
    ("lens-12-6", "control.max_linear_speed", 0.2),
    ("ibvs-12-6", "control.interaction", "mean"),
    ("vision-12-6", "control.rz_task", "angle"),
    ("lens-12-6", "control.law", "ibvs"),
    ("cartesian-12-6", "robot.joint_velocity.0", 0.2),
    ("arm-ur5-12-6", "robot.damping", 0.03),
    ("arm-panda-12-6", "robot.min_manipulability", 1e-5),
    ("noise-12-6", "noise.pixel_sigma", 0.3),
    ("lens-12-6", "stop.window", 3),
    ("path-500", "path.samples", 400),
    ("lens-12-6", "path.samples", 400),  # [path] the base lacks
    ("path-500", "depth_estimation.reference_mean_depth", 0.8),
    ("vision-12-6", "vision.blur_sigma", 1.0),
    ("lens-12-6", "vision.blur_sigma", 1.0),  # [vision] the base lacks
]


@pytest.mark.parametrize("base, key, value", TABLE_KEYS)
def test_a_key_of_every_table_is_accepted(base, key, value):
    (d,) = build_scenarios(base, {key: [value]})
    node = d
    for seg in key.split("."):
        node = node[int(seg)] if seg.isdigit() else node[seg]
    assert node == value
    vsinv.load_scenario(d)


@pytest.mark.parametrize(
    "base, key, match",
    [
        ("vision-12-6", "vision.blur", "blur"),
        ("lens-12-6", "visoin.blur_sigma", "visoin"),
        ("path-500", "path.sample", "sample"),
        ("arm-ur5-12-6", "robot.wheels", "wheels"),
        ("lens-12-6", "directory", "directory"),  # not a key of the files, though a field in Rust
        ("lens-12-6", "control.interaction", r"control\.interaction: belongs to the ibvs law"),
        ("lens-12-6", "0.gain", "0.gain"),
    ],
)
def test_unknown_keys_are_refused_by_name(base, key, match):
    with pytest.raises(vsinv.InvalidInput, match=match) as info:
        build_scenarios(base, {key: ["current"]})
    assert f"vary key {key!r}" in str(info.value)


def test_roll_uses_the_package_rotations():
    (d,) = build_scenarios(BASE, {"roll_deg": [30.0]})
    before = vsinv.load_scenario(BASE).to_dict()["start"]["rotation_deg"]
    r0 = vsinv.sweep.rotation_from_thetau(np.radians(before))
    r1 = vsinv.sweep.rotation_from_thetau(np.radians(d["start"]["rotation_deg"]))
    np.testing.assert_allclose(r1, r0 @ rotation([0.0, 0.0, np.radians(30.0)]), atol=1e-12)
    tu = np.array([0.3, -0.4, 2.9])
    np.testing.assert_allclose(vsinv.sweep.thetau_from_rotation(vsinv.sweep.rotation_from_thetau(tu)), tu, atol=1e-12)
    with pytest.raises(vsinv.InvalidInput, match="rot: not a rotation"):
        vsinv.sweep.thetau_from_rotation(2.0 * np.eye(3))


# ---------------------------------------------------------------------------------------------
# Props. 1 and 2


def test_prop2_fails_for_large_principal_point_errors_and_is_conservative():
    values = [0.0, 400.0, 1000.0, 1500.0]
    res = run_sweep(BASE, {"principal_point_error": values}, progress=False)
    assert res["prop1"].tolist() == [True] * 4  # K_hat's focal terms stay positive
    assert res["prop2"].tolist() == [True, True, False, False]
    # The columns agree with check_stability on the scenarios' K and K_hat.
    for d, p1, p2 in zip(build_scenarios(BASE, {"principal_point_error": values}), res["prop1"], res["prop2"]):
        k = vsinv.Intrinsics(*(d["camera"][f] for f in ("fku", "fkv", "u0", "v0")))
        k_hat = vsinv.Intrinsics(*(d["estimate"][f] for f in ("fku", "fkv", "u0", "v0")))
        report = vsinv.laws.check_stability(k, k_hat)
        assert (report.prop1, report.prop2) == (p1, p2)
    # Prop. 2 is only sufficient: 1000 px off, it fails but the servo still converges.
    assert res["status"][2] == "converged"


def test_focal_errors_keep_prop2_a_large_skew_error_breaks_it():
    res = run_sweep(BASE, {"focal_error": [-0.8, 0.0, 3.0]}, progress=False)
    assert res["prop2"].all() and res["prop1"].all()
    res = run_sweep(BASE, {"estimate.fku": [300.0, 2400.0], "estimate.fkv": [300.0, 2400.0]}, progress=False)
    assert res["prop2"].all()  # anisotropic too: K_hat^-1 K stays close to a positive diagonal
    res = run_sweep(BASE, {"estimate.skew_deg": [90.0, 10.0]}, progress=False)
    assert res["prop1"].tolist() == [True, True] and res["prop2"].tolist() == [True, False]
    d = build_scenarios(BASE, {"estimate.skew_deg": [10.0]})[0]
    k = vsinv.Intrinsics(*(d["camera"][f] for f in ("fku", "fkv", "u0", "v0")))
    e = d["estimate"]
    k_hat = vsinv.Intrinsics(e["fku"], e["fkv"], e["u0"], e["v0"], np.radians(e["skew_deg"]))
    assert not vsinv.laws.check_stability(k, k_hat).prop2


# ---------------------------------------------------------------------------------------------
# executors


def _pool_context() -> multiprocessing.context.BaseContext:
    methods = multiprocessing.get_all_start_methods()
    return multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")


VARY = {"focal_error": [-0.3, 0.4, 1.2], "roll_deg": [0.0, -30.0], "noise.pixel_sigma": [0.3]}


def test_process_pool_gives_the_same_results_as_in_process():
    here = run_sweep(BASE, VARY, repeats=2, chunk_size=5, progress=False)
    with concurrent.futures.ProcessPoolExecutor(max_workers=2, mp_context=_pool_context()) as ex:
        there = run_sweep(BASE, VARY, repeats=2, chunk_size=5, executor=ex, threads=1, progress=False)
    assert len(here) == 12
    assert_same_results(here, there)


def test_dask_executor_gives_the_same_table():
    distributed = pytest.importorskip("dask.distributed")
    here = run_sweep(BASE, VARY, repeats=2, chunk_size=4, progress=False)
    with distributed.LocalCluster(
        n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        there = run_sweep(BASE, VARY, repeats=2, chunk_size=4, executor=client.get_executor(), threads=1, progress=False)
    assert_same_results(here, there)
    a, b = here.summary_by(), there.summary_by()
    assert a.keys() == b.keys()
    for k in a:
        np.testing.assert_array_equal(a[k], b[k])


def test_chunk_sizes_do_not_change_results():
    a = run_sweep(BASE, {"focal_error": np.linspace(-0.5, 1.0, 7)}, chunk_size=1, progress=False)
    b = run_sweep(BASE, {"focal_error": np.linspace(-0.5, 1.0, 7)}, progress=False)
    assert_same_results(a, b)


# ---------------------------------------------------------------------------------------------
# the result table


def test_summary_by_and_pandas():
    res = run_sweep("noise-12-6", {"focal_error": [0.0, 0.5], "control.gain": [1.0, 2.0]}, repeats=3, progress=False)
    s = res.summary_by("focal_error")
    assert s["focal_error"].tolist() == [0.0, 0.5]
    assert s["runs"].tolist() == [6, 6]
    assert np.all((0 <= s["convergence_rate"]) & (s["convergence_rate"] <= 1))
    conv = res["status"][res["focal_error"] == 0.0] == "converged"
    assert s["convergence_rate"][0] == pytest.approx(conv.mean())
    err = res["final_translation_error"][res["focal_error"] == 0.5]
    assert s["median_translation_error"][1] == pytest.approx(np.median(err))
    assert "median_translation_error_mm" not in s and "final_translation_error_mm" not in res.columns  # no older names
    assert len(res.summary_by()["runs"]) == 4  # default: the grid keys
    assert res.summary_by(())["runs"].tolist() == [12]
    pd = pytest.importorskip("pandas")
    df = res.to_pandas()
    assert isinstance(df, pd.DataFrame) and df.shape == (12, len(res.columns))
    assert df["focal_error"].tolist() == res["focal_error"].tolist()


def test_write_parquet_and_csv_fallback(tmp_path, monkeypatch):
    res = run_sweep(BASE, {"focal_error": [0.0, 0.5], "start.position": [[0.2, -0.15, -0.15]]}, progress=False)
    pq = pytest.importorskip("pyarrow.parquet")
    path = res.write(tmp_path / "runs.parquet")
    assert path == tmp_path / "runs.parquet"
    table = pq.read_table(path)
    assert table.num_rows == 2 and table.column("focal_error").to_pylist() == [0.0, 0.5]
    assert table.schema.metadata[b"vsinv.base"] == b"lens-12-6"
    # No pyarrow: CSV next to the requested name.
    monkeypatch.setitem(sys.modules, "pyarrow", None)
    monkeypatch.setitem(sys.modules, "pyarrow.parquet", None)
    path = res.write(tmp_path / "runs.parquet")
    assert path == tmp_path / "runs.csv"
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 2 and list(rows[0]) == list(res.columns)
    assert [float(r["focal_error"]) for r in rows] == [0.0, 0.5]
    assert rows[0]["status"] == res["status"][0]
    assert float(rows[1]["final_translation_error"]) == res["final_translation_error"][1]


def test_stability_maps(tmp_path):
    pytest.importorskip("matplotlib")
    from vsinv.sweep.plots import plot_stability_map

    one = run_sweep(BASE, {"principal_point_error": [0.0, 500.0, 1000.0]}, progress=False)
    two = run_sweep(BASE, {"focal_error": [0.0, 1.0], "principal_point_error": [0.0, 1000.0]}, progress=False)
    rnd = run_sweep(BASE, {"roll_deg": Uniform(-30, 30)}, draws=70, progress=False)  # binned
    for name, res in (("one", one), ("two", two), ("rnd", rnd)):
        path = plot_stability_map(res, tmp_path / f"{name}.png")
        assert path.read_bytes()[:8] == PNG_MAGIC
    with pytest.raises(ValueError, match=r"plot_stability_map: 3 varied keys \(focal_error, roll_deg, control\.gain\); pass keys= with one or two of them"):
        plot_stability_map(run_sweep(BASE, {"focal_error": [0.0], "roll_deg": [0.0], "control.gain": [1.0]},
                                 progress=False), tmp_path / "x.png")


def test_exports():
    import types

    import vsinv.sweep.plots

    assert vsinv.sim.run_sweep is run_sweep and vsinv.sim.SweepResult is SweepResult
    assert vsinv.sim.Uniform is Uniform and vsinv.sim.LogUniform is LogUniform and vsinv.sim.Choice is Choice
    # `vsinv.sweep` is the package, not hidden by a function of the same name.
    assert isinstance(vsinv.sweep, types.ModuleType) and vsinv.sweep.Uniform is Uniform
    assert vsinv.sweep.run_sweep is run_sweep and callable(vsinv.sweep.plots.plot_stability_map)
    for name in ("run_sweep", "Uniform", "LogUniform", "Choice", "SweepResult"):
        assert name in vsinv.sim.__all__ and name not in vsinv.__all__


def test_readme_sweep_example_type_checks(tmp_path):
    """The sweep guide's use (docs/guides/sweeps.md) of `vsinv.sweep.Uniform` and `vsinv.sim.run_sweep` passes mypy."""
    api = pytest.importorskip("mypy.api")
    snippet = tmp_path / "snippet.py"
    snippet.write_text(
        "import numpy as np\nimport vsinv\n"
        "res = vsinv.sim.run_sweep('lens-12-6', {'focal_error': np.linspace(-0.5, 1.0, 3),\n"
        "                                    'roll_deg': vsinv.sweep.Uniform(-120, 120)}, draws=2, seed=1)\n"
        "table = res.summary_by('focal_error')\n"
    )
    out, err, status = api.run([str(snippet), "--no-incremental", "--cache-dir", str(tmp_path / ".mypy")])
    assert status == 0, out + err


# ---------------------------------------------------------------------------------------------
# the command line


def test_cli_sweep_prints_the_table_and_writes_files(capsys, tmp_path):
    pytest.importorskip("matplotlib")
    out_dir = tmp_path / "out"
    code = main(["sweep", BASE, "--vary", "focal_error=-0.5:1:4", "--out", str(out_dir), "--no-progress"])
    out, err = capsys.readouterr()
    assert code == 0, err
    lines = out.splitlines()
    assert lines[0].startswith("sweep lens-12-6: 4 runs")
    head = lines[1].split()
    assert head[0] == "focal_error" and "runs" in head and "converged" in head
    for v in ("-0.5", "0", "0.5", "1"):
        assert any(line.split()[0] == v and "100%" in line for line in lines[2:6])
    data = out_dir / ("sweep.parquet" if _has("pyarrow") else "sweep.csv")
    assert data.exists() and str(data) in out
    png = out_dir / "stability_map.png"
    assert png.read_bytes()[:8] == PNG_MAGIC


def test_cli_sweep_random_with_workers(capsys):
    code = main(
        ["sweep", BASE, "--random", "roll_deg=-20:20", "--draws", "4", "--vary", "control.law=invariant",
         "--workers", "2", "--repeats", "2", "--no-progress"]
    )
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "8 runs" in out.splitlines()[0]


def test_cli_sweep_varies_a_key_of_an_optional_table(capsys):
    # Issue 17: vision.blur_sigma was refused as "unknown key 'vision'"; a few short runs.
    code = main(
        ["sweep", "vision-12-6", "--vary", "vision.blur_sigma=0.5,1.0", "--vary", "stop.window=1",
         "--vary", "stop.max_iterations=3", "--no-progress"]
    )
    out, err = capsys.readouterr()
    assert code == 0, err
    lines = out.splitlines()
    assert lines[0].startswith("sweep vision-12-6: 2 runs"), out
    assert lines[1].split()[0] == "vision.blur_sigma"
    assert [line.split()[0] for line in lines[2:4]] == ["0.5", "1"]


def test_cli_sweep_unknown_key_exits_2(capsys):
    code = main(["sweep", "vision-12-6", "--vary", "vision.blur_sigmaa=0.5", "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2 and "vision.blur_sigmaa" in err and "blur_sigmaa" in err


def _has(module: str) -> bool:
    try:
        __import__(module)
    except ImportError:
        return False
    return True


@pytest.mark.parametrize(
    "args, match",
    [
        (["--vary", "focal_error=-0.5:1"], "START:STOP:COUNT"),
        (["--vary", "focal_error"], "START:STOP:COUNT"),
        (["--vary", "focal_error=a:1:3"], "not a number"),
        (["--vary", "focal_error=0:1:x"], "COUNT"),
        (["--vary", "focal_error=0:1:0"], "COUNT"),
        (["--vary", "nope=0:1:3"], "nope"),
        (["--vary", "control.gian=0:1:3"], "gian"),
        (["--vary", "focal_error=-2:1:3"], "focal_error"),
        (["--random", "roll_deg=1"], "LO:HI"),
        (["--random", "roll_deg=-1:1", "--draws", "0"], "draws"),
        (["--vary", "roll_deg=0:1:2", "--draws", "3"], "draws"),
        ([], "--vary"),
    ],
)
def test_cli_sweep_bad_arguments_exit_2(capsys, args, match):
    code = main(["sweep", BASE, "--no-progress", *args])
    out, err = capsys.readouterr()
    assert code == 2
    assert match in err and err.startswith("vsinv: error:")


def test_the_rust_sweep_runner_names_bad_arguments():
    from vsinv import _core

    base = vsinv.load_scenario(BASE).to_dict()
    with pytest.raises(vsinv.InvalidInput, match="seeds: 1 seeds for 2 runs"):
        _core.run_sweep_runs(base, ["focal_error"], [[0.1, 0.2]], seeds=[1])
    with pytest.raises(vsinv.InvalidInput, match="seeds: expected a non-negative integer at index 0"):
        _core.sweep_scenarios(base, ["focal_error"], [[0.1]], seeds=[-1])
    with pytest.raises(vsinv.InvalidInput, match="values: expected 2 lists, one per key"):
        _core.sweep_scenarios(base, ["focal_error", "roll_deg"], [[0.1]])
    with pytest.raises(vsinv.InvalidInput, match="values: list 1 has 1 values, expected 2"):
        _core.sweep_scenarios(base, ["focal_error", "roll_deg"], [[0.1, 0.2], [3.0]])
    with pytest.raises(vsinv.InvalidInput, match=r"\[1\]\.estimate"):  # the run at fault, by index
        _core.run_sweep_runs(base, ["focal_error"], [[0.1, -1.5]], threads=1)
    assert _core.SWEEP_DERIVED_KEYS == vsinv.sweep.DERIVED_KEYS == ("lens_ratio", "focal_error", "principal_point_error", "roll_deg")
