"""Eye-in-hand control of an arm from Python: the two built-ins, the summary, the recorded
joints and the figures `vsinv run --out` adds for an arm."""

import numpy as np
import pytest

import vsinv


@pytest.mark.parametrize("name,dof", [("arm-ur5-12-6", 6), ("arm-panda-12-6", 7)])
def test_arm_builtins_converge_within_limits(name, dof):
    r = vsinv.run_scenario(name)
    s = r.summary
    assert s["status"] == "converged", s["message"]
    assert s["final_translation_error"] < 1e-3 and np.degrees(s["final_rotation_error"]) < 0.1
    assert 0.0 < s["min_manipulability"] < 1.0
    assert s["peak_linear_speed"] <= 0.25 + 1e-12 and np.degrees(s["peak_angular_speed"]) <= 60.0 + 1e-9
    rows = s["iterations"] + 1
    assert r.joints.shape == (rows, dof) and r.joint_velocities.shape == (rows, dof)
    limits = r.joint_limits
    assert len(limits["names"]) == dof
    lower, upper, velocity = (np.asarray(limits[k]) for k in ("lower", "upper", "velocity"))
    assert np.all(r.joints >= lower) and np.all(r.joints <= upper)
    assert np.all(np.abs(r.joint_velocities[:-1]) <= velocity * (1 + 1e-12))
    assert np.isnan(r.joint_velocities[-1]).all()
    assert "joint_velocities" in r.arrays


def test_other_robots_have_no_arm_figures():
    r = vsinv.run_scenario("lens-12-6")
    assert r.summary["min_manipulability"] is None
    assert r.joint_velocities is None and r.joint_limits is None and r.joints.shape[1] == 6


def test_arm_figures(tmp_path):
    pytest.importorskip("matplotlib")
    from vsinv.plots import ARM_FIGURES, FIGURES, save_figures

    paths = save_figures(vsinv.run_scenario("arm-panda-12-6"), tmp_path)
    assert [p.name for p in paths] == list(FIGURES) + list(ARM_FIGURES)
    for p in paths:
        assert p.stat().st_size > 1000 and p.read_bytes().startswith(b"\x89PNG")


def test_arm_keys_are_checked():
    d = vsinv.load_scenario("arm-ur5-12-6").to_dict()
    assert "start" not in d
    d["robot"]["joints"] = d["robot"]["joints"][:5]
    with pytest.raises(vsinv.InvalidInput, match=r"robot\.joints: 5 values given, the arm ur5 has 6 joints"):
        vsinv.run_scenario(d)
