"""The scenario runner from Python: loading, building in code, running, recorded arrays."""

import numpy as np
import pytest

import vsinv


def test_builtins_are_listed_and_load():
    names = [n for n, _ in vsinv.sim.list_scenarios()]
    for required in ["zoom-stationary", "lens-12-12", "lens-12-6", "lens-25-12", "lens-6-12", "ibvs-12-6", "planar"]:
        assert required in names
    s = vsinv.load_scenario("lens-12-6")
    assert s.name == "lens-12-6" and "6 mm" in s.description


def test_run_returns_summary_and_zero_copy_arrays():
    r = vsinv.run_scenario("lens-12-6")
    s = r.summary
    assert s["status"] == "converged"
    assert s["final_translation_error"] < 1e-3 and np.degrees(s["final_rotation_error"]) < 0.1
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
    again = vsinv.sim.Scenario.from_toml(vsinv.sim.Scenario.from_dict(d).to_toml())
    assert again.to_dict() == vsinv.sim.Scenario.from_dict(d).to_dict()


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
    assert ibvs["final_translation_error"] > 0.1


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


#: The CLI smoke test's sample, one built-in of each kind (points, IBVS, a stationary camera, a
#: failure mode, an arm, images); the other built-ins are marked slow (make test runs them all,
#: make test-fast the sample; tests/builtin_results.rs checks every built-in's result).
CLI_SAMPLE = ("lens-12-6", "ibvs-12-6", "zoom-stationary", "planar", "arm-ur5-12-6", "vision-12-6")


#: The built-ins of the kinematic simulator; the `mujoco-*` ones (`[world] engine = "mujoco"`)
#: need the mujoco extra and EGL: tests/test_mujoco_builtins.py runs them from the command line.
KINEMATIC = [n for n, _ in vsinv.sim.list_scenarios() if vsinv.load_scenario(n).engine == "kinematic"]


@pytest.mark.parametrize("name", [n if n in CLI_SAMPLE else pytest.param(n, marks=pytest.mark.slow) for n in KINEMATIC])
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


def test_the_cli_sample_names_built_ins():
    assert set(CLI_SAMPLE) <= {n for n, _ in vsinv.sim.list_scenarios()}


# ---------------------------------------------------------------------------------------------
# [control] read per law (issue 17)

#: The [control] keys each law reads besides law and dt (src/sim/scenario/law_keys.rs).
LAW_KEYS = {
    "invariant": ["gain", "gain_rz", "depths", "feedforward", "rz_task", "max_linear_speed",
                  "max_angular_speed_deg", "adaptive_gain"],
    "ibvs": ["gain", "depths", "interaction", "max_linear_speed", "max_angular_speed_deg", "adaptive_gain"],
    "none": [],
}
#: A valid value of each.
CONTROL_SAMPLES = {
    "gain": 0.8, "gain_rz": 0.9, "depths": "true", "feedforward": False, "interaction": "mean",
    "rz_task": "tau21", "max_linear_speed": 0.25, "max_angular_speed_deg": 60.0,
    "adaptive_gain": {"at_zero": 4.0, "at_infinity": 0.4, "slope_at_zero": 30.0},
}
OWN_KEYS = [(law, key) for law, keys in LAW_KEYS.items() for key in keys]
FOREIGN_KEYS = [(law, key) for law, keys in LAW_KEYS.items() for key in CONTROL_SAMPLES if key not in keys]


def with_control(law: str, **keys) -> dict:
    d = vsinv.load_scenario("lens-12-6").to_dict()
    d["control"] = {"law": law, "dt": 0.04, **keys}
    return d


@pytest.mark.parametrize("law, key", OWN_KEYS)
def test_each_law_reads_its_own_control_keys(law, key):
    s = vsinv.load_scenario(with_control(law, **{key: CONTROL_SAMPLES[key]}))
    assert s.to_dict()["control"][key] == CONTROL_SAMPLES[key]


@pytest.mark.parametrize("law, key", FOREIGN_KEYS)
def test_a_control_key_of_another_law_is_refused_by_name(law, key):
    with pytest.raises(vsinv.InvalidInput) as info:
        vsinv.load_scenario(with_control(law, **{key: CONTROL_SAMPLES[key]}))
    msg = str(info.value)
    assert f"control.{key}: belongs to the" in msg and f"this scenario's law (control.law) is {law}" in msg, msg
    for owner in (other for other, keys in LAW_KEYS.items() if key in keys):
        assert owner in msg.split("belongs to", 1)[1], msg


def test_control_keys_of_another_law_from_files_and_in_runs():
    assert len(FOREIGN_KEYS) == 1 + 3 + 9  # invariant: interaction; ibvs: gain_rz, feedforward, rz_task; none: all
    text = vsinv.load_scenario("vision-12-6").to_toml().replace('law = "invariant"', 'law = "ibvs"')
    with pytest.raises(vsinv.InvalidInput, match=r"control\.gain_rz: belongs to the invariant law"):
        vsinv.sim.Scenario.from_toml(text)
    with pytest.raises(vsinv.InvalidInput, match=r"control\.interaction: belongs to the ibvs law"):
        vsinv.run_scenario(with_control("invariant", interaction="current"))
    # lens-12-6 gives only keys both laws read: switching its law needs nothing else.
    d = vsinv.load_scenario("lens-12-6").to_dict()
    d["control"]["law"] = "ibvs"
    assert vsinv.load_scenario(d).to_dict()["control"]["law"] == "ibvs"


@pytest.mark.parametrize("name", [n for n, _ in vsinv.sim.list_scenarios()])
def test_every_builtin_parses_and_round_trips(name):
    s = vsinv.load_scenario(name)
    assert vsinv.sim.Scenario.from_dict(s.to_dict()).to_dict() == s.to_dict()
    assert vsinv.sim.Scenario.from_toml(s.to_toml()).to_dict() == s.to_dict()
