"""Safe commands and the rz task from Python: speed limits, ViSP's adaptive gain, any roll."""

import math

import numpy as np
import pytest

import vsinv


def test_speed_limits_scale_the_whole_twist(scene):
    free = vsinv.laws.InvariantController(scene["ref"], scene["k"]).step(scene["cur"], scene["z_star"])
    vmax, wmax = 0.5 * np.linalg.norm(free[:3]), 0.4 * np.linalg.norm(free[3:])
    ctl = vsinv.laws.InvariantController(scene["ref"], scene["k"], max_linear_speed=vmax, max_angular_speed=wmax)
    limited = ctl.step(scene["cur"], scene["z_star"])
    scale = min(vmax / np.linalg.norm(free[:3]), wmax / np.linalg.norm(free[3:]))
    assert ctl.saturation == pytest.approx(scale)
    np.testing.assert_allclose(limited, free * scale, rtol=1e-10, atol=1e-14)
    only_linear = vsinv.laws.IbvsController(scene["ref"], scene["k"], max_linear_speed=1e-3)
    tw = only_linear.step(scene["cur"], scene["z"])
    assert np.linalg.norm(tw[:3]) == pytest.approx(1e-3)
    assert only_linear.saturation is not None and only_linear.saturation < 1.0


def test_adaptive_gain_follows_visps_formula(scene):
    l0, linf, slope = 4.0, 0.4, 30.0
    ctl = vsinv.laws.InvariantController(scene["ref"], scene["k"], adaptive_gain=(l0, linf, slope))
    twist = ctl.step(scene["cur"], scene["z_star"])
    x = ctl.invariant_error
    expected = (l0 - linf) * math.exp(-slope * x / (l0 - linf)) + linf
    assert ctl.last_gain == pytest.approx(expected, rel=1e-12)
    np.testing.assert_allclose(twist[:5], -expected * ctl.eps, rtol=1e-10, atol=1e-14)
    ibvs = vsinv.laws.IbvsController(scene["ref"], scene["k"], adaptive_gain=(2.0, 0.5, 0.01))
    assert ibvs.last_gain is None
    ibvs.step(scene["cur"], scene["z"])
    x = np.linalg.norm(scene["cur"] - scene["ref"])
    assert ibvs.last_gain == pytest.approx(1.5 * math.exp(-0.01 * x / 1.5) + 0.5, rel=1e-12)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"adaptive_gain": (1.0, 2.0, 1.0)}, r"invalid parameter `adaptive_gain\.at_infinity`: the gain for a large error \(2\) must not exceed"),
        ({"adaptive_gain": (1.0, 0.5, float("nan"))}, r"invalid parameter `adaptive_gain\.slope_at_zero`: must be finite and > 0, got NaN"),
        ({"max_linear_speed": 0.0}, "invalid parameter `max_linear_speed`: must be > 0, got 0"),
        ({"max_angular_speed": float("nan")}, "invalid parameter `max_angular_speed`: must be > 0, got NaN"),
        ({"rz_task": "sin"}, 'invalid parameter `rz_task`: expected "angle" or "tau21", got "sin"'),
    ],
)
def test_bad_command_options_are_invalid_input(scene, kwargs, name):
    with pytest.raises(vsinv.InvalidInput, match=name):
        vsinv.laws.InvariantController(scene["ref"], scene["k"], **kwargs)


def rolled(name: str, roll_deg: float, task: str) -> dict:
    d = vsinv.load_scenario(name).to_dict()
    rx, ry, _ = np.radians(d["start"]["rotation_deg"])
    r = vsinv.geometry.pose_from_position_thetau([0, 0, 0], [rx, ry, 0.0])[:3, :3]
    c, s = math.cos(math.radians(roll_deg)), math.sin(math.radians(roll_deg))
    rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    m = np.eye(4)
    m[:3, :3] = r @ rz
    _, thetau = vsinv.geometry.thetau_from_pose(m)
    d["start"]["rotation_deg"] = [float(a) for a in np.degrees(thetau)]
    d["control"]["rz_task"] = task
    return d


def test_any_roll_converges_and_the_papers_task_reports_the_trap():
    for roll in (-170.0, -100.0, 135.0, 175.0):
        s = vsinv.run_scenario(rolled("lens-12-6", roll, "angle"), record=False).summary
        assert s["status"] == "converged", (roll, s["message"])
        assert s["final_translation_error"] < 1e-3 and np.degrees(s["final_rotation_error"]) < 0.1
        assert np.degrees(s["peak_angular_speed"]) <= 60.0 + 1e-9 and s["peak_linear_speed"] <= 0.25 + 1e-12
    trapped = vsinv.run_scenario(rolled("lens-12-6", 150.0, "tau21"), record=False).summary
    assert trapped["status"] == "rz_trap"
    assert "180 degrees" in trapped["message"] and 'rz_task = "angle"' in trapped["message"]


def test_scenario_keys_for_commands_name_the_key():
    d = vsinv.load_scenario("lens-12-6").to_dict()
    d["control"]["max_angular_speed_deg"] = -5.0
    with pytest.raises(vsinv.InvalidInput, match="control.max_angular_speed_deg"):
        vsinv.run_scenario(d)
    d = vsinv.load_scenario("lens-12-6").to_dict()
    d["control"]["adaptive_gain"] = {"at_zero": 1.0, "at_infinity": 0.5}
    with pytest.raises(vsinv.InvalidInput, match=r"scenario: control\.adaptive_gain: missing field `slope_at_zero`"):
        vsinv.run_scenario(d)
