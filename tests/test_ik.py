"""Inverse kinematics in Python (issue 20, item 4): ``vsinv.kinematics.ik`` and ``vsinv.kinematics.fk`` of the
built-in arms, refusals naming the argument, arm scenarios placed by the camera pose and
sweeps over their start pose."""

import json
from pathlib import Path

import numpy as np
import pytest

import vsinv

FIXTURE = Path(__file__).parent / "fixtures" / "ik" / "ik_rtb.json"


def random_joints(arm: str, rng: np.random.Generator) -> np.ndarray:
    lo, hi = {"ur5": (np.full(6, -2 * np.pi), np.full(6, 2 * np.pi)),
              "panda": (np.array([-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973]),
                        np.array([2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973]))}[arm]
    return rng.uniform(lo, hi)


def pose_gap(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """Translation (m) and rotation angle (rad) between two poses."""
    d = np.linalg.inv(a) @ b
    return float(np.linalg.norm(d[:3, 3])), float(np.linalg.norm(vsinv.geometry.thetau_from_pose(d)[1]))


@pytest.mark.parametrize("arm", ["ur5", "panda"])
def test_round_trip(arm):
    rng = np.random.default_rng(4)
    for _ in range(20):
        q = random_joints(arm, rng)
        pose = vsinv.kinematics.fk(arm, q)
        s = vsinv.kinematics.ik(arm, pose)
        assert isinstance(s, vsinv.kinematics.IkSolution) and s.joints.shape == q.shape and s.joints.dtype == np.float64
        dt, dr = pose_gap(vsinv.kinematics.fk(arm, s.joints), pose)
        assert dt < 1e-9 and dr < 1e-9
        assert s.position_residual <= 1e-10 and s.rotation_residual <= 1e-10
        assert s.iterations >= 0 and s.seed >= 0 and "IkSolution(" in repr(s)


def test_seeded_from_the_neighbourhood_gives_the_same_joints_as_roboticstoolbox():
    cases = json.loads(FIXTURE.read_text())["arms"]["ur5"]
    for c in cases:
        s = vsinv.kinematics.ik("ur5", np.array(c["pose"]), seed=c["q_seed"])
        assert s.seed == 0
        np.testing.assert_allclose(s.joints, c["rtb_q"], atol=1e-7)
        np.testing.assert_allclose(vsinv.kinematics.fk("ur5", s.joints), c["pose"], atol=1e-9)


def test_unreachable_poses_are_refused_naming_the_pose_and_the_residual():
    far = np.eye(4)
    far[:3, 3] = [2.0, 0.0, 0.3]
    with pytest.raises(vsinv.InvalidInput, match=r"^pose: unreachable by ur5") as info:
        vsinv.kinematics.ik("ur5", far)
    err = info.value
    assert (err.kind, err.argument) == ("unreachable", "pose")
    assert err.residual > 1.0 and "m and" in str(err) and "rad away" in str(err)


def test_bad_arguments_are_named():
    pose = vsinv.kinematics.fk("panda", [0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8])
    with pytest.raises(vsinv.InvalidInput, match="unknown built-in arm `kuka`"):
        vsinv.kinematics.ik("kuka", pose)
    with pytest.raises(vsinv.InvalidInput, match="arm: expected a built-in arm name"):
        vsinv.kinematics.ik(None, pose)
    with pytest.raises(vsinv.InvalidInput, match="seed: expected 7 values"):
        vsinv.kinematics.ik("panda", pose, seed=np.zeros(6))
    with pytest.raises(vsinv.InvalidInput, match="seed: non-finite value at index 1"):
        vsinv.kinematics.ik("panda", pose, seed=[0.0, np.nan, 0, 0, 0, 0, 0])
    with pytest.raises(vsinv.InvalidInput, match=r"invalid parameter `pose`: not a rigid motion"):
        vsinv.kinematics.ik("panda", 2 * pose)
    with pytest.raises(vsinv.InvalidInput, match=r"joints: expected 6 values \(joints shoulder_pan_joint, .*\), got 7"):
        vsinv.kinematics.fk("ur5", np.zeros(7))


def placed_by_pose() -> dict:
    """arm-ur5-12-6 with its start given as the camera pose instead of the joints."""
    d = vsinv.load_scenario("arm-ur5-12-6").to_dict()
    r = vsinv.run_scenario(d)
    position, thetau = vsinv.geometry.thetau_from_pose(r.pose[0])
    d["start"] = {"position": position.tolist(), "rotation_deg": np.degrees(thetau).tolist()}
    d["robot"]["ik_seed"] = d["robot"].pop("joints")
    return d


def test_scenario_placed_by_pose_runs_as_the_one_placed_by_joints():
    by_joints = vsinv.run_scenario("arm-ur5-12-6")
    by_pose = vsinv.run_scenario(placed_by_pose())
    np.testing.assert_allclose(by_pose.joints[0], by_joints.joints[0], atol=1e-9)
    assert by_pose.summary["status"] == by_joints.summary["status"] == "converged"
    assert by_pose.summary["iterations"] == by_joints.summary["iterations"]


def test_giving_both_joints_and_pose_is_refused_naming_the_keys():
    d = placed_by_pose()
    d["robot"]["joints"] = d["robot"].pop("ik_seed")
    with pytest.raises(vsinv.InvalidInput, match=r"robot\.joints.*start\.position"):
        vsinv.run_scenario(d)


def test_sweeps_vary_the_start_of_an_arm_placed_by_pose():
    d = placed_by_pose()
    x0 = d["start"]["position"][0]
    result = vsinv.sim.run_sweep(d, {"start.position.0": [x0 - 0.05, x0, x0 + 0.05]})
    assert len(result) == 3 and list(result["status"]) == ["converged"] * 3
    rolled = vsinv.sim.run_sweep(d, {"roll_deg": [-10.0, 10.0]})
    assert list(rolled["status"]) == ["converged"] * 2
    # An arm placed by its joints has no start pose to vary: refused, naming both ways.
    with pytest.raises(vsinv.InvalidInput, match=r"start\.position\.0.*robot\.joints"):
        vsinv.sim.run_sweep("arm-ur5-12-6", {"start.position.0": [0.2]})
    with pytest.raises(vsinv.InvalidInput, match=r"vary key 'roll_deg': this arm is placed by robot\.joints, so its start pose is not a key to vary"):
        vsinv.sim.run_sweep("arm-ur5-12-6", {"roll_deg": [5.0]})
    # A start the arm cannot reach is refused before anything runs, naming the key.
    with pytest.raises(vsinv.InvalidInput, match=r"start\.position\.2.*unreachable by ur5"):
        vsinv.sim.run_sweep(d, {"start.position.2": [-3.0]})
