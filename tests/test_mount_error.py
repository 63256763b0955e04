"""The hand-eye error of an arm scenario (issue 20, item 3): ``robot.mount_error`` makes the
controller map camera twists to joint velocities through ``camera_mount * mount_error`` while
the camera moves with ``camera_mount``. The loop is closed on the images, so a moderate error
changes the path, not where it ends; ``benches/mount_error.py`` measures how far each law
tolerates it."""

from __future__ import annotations

import math

import pytest

import vsinv


def arm(law: str = "invariant", mount_error: dict | None = None) -> dict:
    """arm-ur5-12-6 with the reference image taken by the servo lens (so that IBVS can reach it)."""
    d = vsinv.load_scenario("arm-ur5-12-6").to_dict()
    d["reference_camera"] = dict(d["camera"])
    d["control"]["law"] = law
    if mount_error is not None:
        d["robot"]["mount_error"] = mount_error
    return d


def test_zero_mount_error_is_the_true_mount() -> None:
    plain = vsinv.run_scenario(arm()).summary
    zero = vsinv.run_scenario(arm(mount_error={"position": [0.0, 0.0, 0.0], "rotation_deg": [0.0, 0.0, 0.0]})).summary
    for key in ("status", "iterations", "final_translation_error", "final_rotation_error", "max_line_deviation"):
        assert zero[key] == plain[key], key


@pytest.mark.parametrize("law", ["invariant", "ibvs"])
def test_moderate_mount_error_changes_the_path_not_the_goal(law: str) -> None:
    plain = vsinv.run_scenario(arm(law)).summary
    error = {"position": [0.01, -0.01, 0.01], "rotation_deg": [3.0, 3.0, 3.0]}
    wrong = vsinv.run_scenario(arm(law, error)).summary
    assert plain["status"] == wrong["status"] == "converged"
    assert wrong["final_translation_error"] < 1e-3 and math.degrees(wrong["final_rotation_error"]) < 0.1
    assert wrong["iterations"] != plain["iterations"] or wrong["max_line_deviation"] != plain["max_line_deviation"]


def test_mount_error_is_checked_and_for_arms_only() -> None:
    bad = arm(mount_error={"position": [0.0, float("nan"), 0.0], "rotation_deg": [0.0, 0.0, 0.0]})
    with pytest.raises(vsinv.InvalidInput, match=r"robot\.mount_error\.position"):
        vsinv.run_scenario(bad)
    free = vsinv.load_scenario("lens-12-6").to_dict()
    free["robot"] = {"mount_error": {"position": [0.0, 0.0, 0.0], "rotation_deg": [0.0, 0.0, 0.0]}}
    with pytest.raises(vsinv.InvalidInput, match=r'scenario: robot\.mount_error: applies to kind = "urdf" only'):
        vsinv.run_scenario(free)
