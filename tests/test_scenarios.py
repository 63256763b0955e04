"""The scenario runner from Python: loading, building in code, running, recorded arrays."""

import numpy as np
import pytest

import vsinv


def test_builtins_are_listed_and_load():
    names = [n for n, _ in vsinv.list_scenarios()]
    for required in ["zoom-stationary", "lens-12-12", "lens-12-6", "lens-25-12", "lens-6-12", "ibvs-12-6", "planar"]:
        assert required in names
    s = vsinv.load_scenario("lens-12-6")
    assert s.name == "lens-12-6" and "6 mm" in s.description


def test_run_returns_summary_and_zero_copy_arrays():
    r = vsinv.run_scenario("lens-12-6")
    s = r.summary
    assert s["status"] == "converged"
    assert s["final_translation_error_mm"] < 1.0 and s["final_rotation_error_deg"] < 0.1
    rows = s["iterations"] + 1
    assert r.pose.shape == (rows, 4, 4) and r.pixels.shape == (rows, 12, 2) and r.visible.dtype == np.bool_
    assert r.twist.shape == (rows, 6) and r.eps.shape == (rows, 5) and r.joints.shape == (rows, 6)
    # the arrays view the simulator's buffers: NumPy does not own their data
    for a in (r.pose, r.pixels, r.time, r.invariant_error):
        assert not a.flags.owndata and a.base is not None
    np.testing.assert_allclose(r.pose[-1], np.eye(4), atol=2e-3)
    np.testing.assert_allclose(r.translation_error, np.linalg.norm(r.pose[:, :3, 3], axis=1), rtol=1e-12)
    assert set(r.arrays) >= {"time", "pose", "twist", "pixels", "visible", "eps", "eps_z", "invariant_error"}


def test_build_scenarios_in_code():
    d = vsinv.load_scenario("lens-12-6").to_dict()
    d["name"] = "custom"
    d["camera"]["fku"] = d["camera"]["fkv"] = 800.0
    d["estimate"] = {"fku": 780.0, "fkv": 820.0, "u0": 416.0, "v0": 312.0}
    r = vsinv.run_scenario(d)
    assert r.summary["name"] == "custom" and r.summary["status"] == "converged"
    again = vsinv.Scenario.from_toml(vsinv.Scenario.from_dict(d).to_toml())
    assert again.to_dict() == vsinv.Scenario.from_dict(d).to_dict()


def test_scenario_file(tmp_path):
    path = tmp_path / "mine.toml"
    path.write_text(vsinv.load_scenario("lens-12-12").to_toml())
    assert vsinv.load_scenario(path).name == "lens-12-12"
    assert vsinv.run_scenario(str(path), record=False).summary["status"] == "converged"


@pytest.mark.parametrize(
    "edit, key",
    [
        (lambda d: d["control"].update(gain="fast"), "control.gain"),
        (lambda d: d["control"].update(speed=2.0), "control"),
        (lambda d: d["object"].update(points=d["object"]["points"][:5]), "object.points"),
        (lambda d: d["start"].update(position=[0.0, 0.0, 2.0]), "start"),
        (lambda d: d["camera"].update(fku=-1.0), "camera"),
        (lambda d: d.pop("reference_camera"), "reference_camera"),
        (lambda d: d["noise"].update(pixel_sigma=-1.0), "noise.pixel_sigma"),
    ],
)
def test_bad_scenarios_name_the_key(edit, key):
    d = vsinv.load_scenario("lens-12-6").to_dict()
    edit(d)
    with pytest.raises(vsinv.InvalidInput, match=key):
        vsinv.run_scenario(d)


def test_unknown_source():
    with pytest.raises(vsinv.InvalidInput, match="neither a scenario file nor a built-in"):
        vsinv.load_scenario("no-such-scenario")
    with pytest.raises(vsinv.InvalidInput):
        vsinv.load_scenario(42)


def test_statuses():
    assert vsinv.run_scenario("planar").summary["status"] == "degenerate"
    assert "planar" in vsinv.run_scenario("planar").summary["message"]
    ibvs = vsinv.run_scenario("ibvs-12-6").summary
    assert ibvs["final_translation_error_mm"] > 100.0


def test_progress_callback_and_its_errors():
    calls = []
    d = vsinv.load_scenario("lens-12-6").to_dict()
    vsinv.run_scenario(d, progress=lambda done, total: calls.append((done, total)))
    assert calls and calls[0] == (0, 1500)

    class Stop(Exception):
        pass

    def stop(done, total):
        if done >= 64:
            raise Stop

    with pytest.raises(Stop):
        vsinv.run_scenario(d, progress=stop)


@pytest.mark.parametrize("name", [n for n, _ in vsinv.list_scenarios()])
def test_every_builtin_runs_from_the_command_line(name, capsys):
    import json

    from vsinv import cli

    code = cli.main(["run", name, "--json", "--no-progress"])
    summary = json.loads(capsys.readouterr().out)
    assert summary["name"] == name
    statuses = {"converged", "max_iterations", "lost_features", "diverged", "degenerate", "rz_trap", "observed"}
    assert summary["status"] in statuses
    # 0 for converged, 1 for every other status.
    assert code == (0 if summary["status"] == "converged" else 1)
