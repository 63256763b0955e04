"""Arms in MuJoCo scenarios (issue 31, item 2): a scenario with `[world] engine = "mujoco"` and a
built-in arm (`[robot] kind = "urdf"`, the kinematic simulator's keys) loads the arm with mass
into MuJoCo, the camera on its end effector, gravity on, 500 Hz physics under a 25 Hz law; the
twist becomes joint velocities through MuJoCo's Jacobian of the camera site and the kinematic
arm's damped least squares (`ScenarioArm.joint_velocities`, the Rust code).

The independent checks: MuJoCo's site Jacobian against central differences of the site's pose
(MuJoCo's own kinematics at q +- h) and of vsinv's `base * fk * mount`; the camera's pose in the
world against vsinv's forward kinematics; a commanded twist against the motion the physics
produces; a short servo run against the kinematic simulator's arm from the same start.
Skips (saying what to install) when mujoco or EGL is missing.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import vsinv  # noqa: E402
import vsinv.mujoco as vm  # noqa: E402
from vsinv.mujoco import _mounted  # noqa: E402

pytestmark = pytest.mark.sim

_WHY_NOT = vm.available()
needs_mujoco = pytest.mark.skipif(_WHY_NOT is not None, reason=_WHY_NOT or "")
mujoco = pytest.importorskip("mujoco", reason="pip install 'vsinv[mujoco]'")

UR5E = "scenarios/mujoco-arm-ur5e-12-6.toml"
PANDA = "scenarios/mujoco-arm-panda-zoom.toml"
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _scenario(path: str, **edits: dict) -> dict:
    d = vsinv.load_scenario(os.path.join(ROOT, path)).to_dict()
    for table, values in edits.items():
        d.setdefault(table, {}).update(values)
    return d


def _small(d: dict) -> dict:
    """The scenario at a quarter of its resolution (rendering is most of a frame's time)."""
    for key in ("reference_camera", "camera"):
        c = d[key]
        c.update(width=c["width"] // 4, height=c["height"] // 4, fku=c["fku"] / 4, fkv=c["fkv"] / 4,
                 u0=(c["u0"] + 0.5) / 4 - 0.5, v0=(c["v0"] + 0.5) / 4 - 0.5)
        if c.get("zoom"):
            c["zoom"] = {**c["zoom"], "fku": [f / 4 for f in c["zoom"]["fku"]], "fkv": [f / 4 for f in c["zoom"]["fkv"]]}
    e = d["estimate"]
    e.update(fku=e["fku"] / 4, fkv=e["fkv"] / 4, u0=(e["u0"] + 0.5) / 4 - 0.5, v0=(e["v0"] + 0.5) / 4 - 0.5)
    return d


def _site_pose(model, data, name: str) -> np.ndarray:
    s = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, name)
    pose = np.eye(4)
    pose[:3, :3] = data.site_xmat[s].reshape(3, 3)
    pose[:3, 3] = data.site_xpos[s]
    return pose


def _twist_of(minus: np.ndarray, plus: np.ndarray, h: float) -> np.ndarray:
    """The body twist (v, w) in the frame at the middle taking `minus` to `plus` over 2 h."""
    delta = np.linalg.inv(minus) @ plus
    _, thetau = vsinv.geometry.thetau_from_pose(delta)
    return np.concatenate([delta[:3, 3], thetau]) / (2 * h)


def test_the_arm_of_a_scenario_is_the_kinematic_simulators() -> None:
    """`Scenario.arm()` gives the arm the kinematic simulator runs: its start joints put the
    camera at `[start]` (solved by its inverse kinematics), its limits are the URDF's; no arm
    for a free camera."""
    d = _scenario(UR5E)
    arm = vsinv.load_scenario(d).arm()
    assert arm.model == "ur5e" and arm.end_effector == "tool0" and len(arm.joint_names) == 6
    start = vsinv.geometry.pose_from_position_thetau(d["start"]["position"], np.radians(d["start"]["rotation_deg"]))
    np.testing.assert_allclose(arm.camera_pose(arm.start), start, atol=1e-9)
    ee = np.linalg.inv(arm.base) @ start @ np.linalg.inv(arm.mount)
    np.testing.assert_allclose(vsinv.kinematics.fk("ur5e", arm.start), ee, atol=1e-9)
    np.testing.assert_allclose(arm.upper, 2 * np.pi)
    np.testing.assert_allclose(arm.velocity, np.pi, rtol=1e-5)  # 180 degrees/s (3.14159 in the URDF)
    assert vsinv.load_scenario("mujoco-lens-12-6").arm() is None


def test_what_the_mujoco_arm_does_not_model_is_refused_by_name(tmp_path) -> None:
    """A URDF file that is not there (a user's URDF arm runs: tests/test_mujoco_user_arm.py) and
    a Cartesian robot are refused naming their key; an end effector the built-in MJCF does not
    carry names robot.end_effector."""
    d = _scenario(UR5E)
    for robot, key in [({"urdf": "arm.urdf"}, "robot.urdf"), ({"kind": "cartesian"}, "robot.kind")]:
        bad = {**d, "robot": {**d["robot"], **robot}}
        if robot.get("kind") == "cartesian":
            bad["robot"] = {"kind": "cartesian"}
        with pytest.raises(vsinv.InvalidInput, match=key):
            vsinv.load_scenario(bad)
    with pytest.raises(vsinv.InvalidInput, match="robot.end_effector"):
        _mounted.end_effector("ur5e", "wrist_3_link")


@needs_mujoco
@pytest.mark.parametrize("path", [UR5E, PANDA])
def test_mujocos_camera_site_jacobian_is_the_finite_difference_of_its_pose(path: str) -> None:
    """In the scenario's world, at random joints: the camera site is vsinv's `base * fk * mount`
    (and the MuJoCo camera's vsinv frame is the site's) within 1e-9; the Jacobian
    `_mounted.camera_jacobian` (mj_jacSite, rows in the site frame) is the central difference
    of the site's pose under MuJoCo's kinematics (1e-6), and of vsinv's `camera_pose` (1e-6)."""
    d = _small(_scenario(path))
    with vm.World.from_scenario(d) as world:
        arm, m, data = world.arm, world.model, world.data
        rng = np.random.default_rng(31)
        lower, upper = np.maximum(arm.lower, -3.0), np.minimum(arm.upper, 3.0)
        h = 1e-6
        for q in rng.uniform(lower + 0.05, upper - 0.05, size=(4, len(lower))):
            data.qpos[:] = q
            mujoco.mj_kinematics(m, data)
            site = _site_pose(m, data, _mounted.CAMERA_SITE)
            np.testing.assert_allclose(site, arm.camera_pose(q), atol=1e-9)
            np.testing.assert_allclose(world.camera_pose(), site, atol=1e-9)
            J = _mounted.camera_jacobian(m, data)
            for i in range(len(q)):
                dq = np.zeros(len(q))
                dq[i] = h
                data.qpos[:] = q + dq
                mujoco.mj_kinematics(m, data)
                plus = _site_pose(m, data, _mounted.BELIEVED_SITE)
                data.qpos[:] = q - dq
                mujoco.mj_kinematics(m, data)
                minus = _site_pose(m, data, _mounted.BELIEVED_SITE)
                np.testing.assert_allclose(J[:, i], _twist_of(minus, plus, h), atol=1e-6)
                vs = _twist_of(arm.camera_pose(q - dq), arm.camera_pose(q + dq), h)
                np.testing.assert_allclose(J[:, i], vs, atol=1e-6)
            data.qpos[:] = q
            mujoco.mj_kinematics(m, data)


@needs_mujoco
@pytest.mark.parametrize("path", [UR5E, PANDA])
def test_the_arm_tracks_a_commanded_camera_twist_under_gravity(path: str) -> None:
    """Gravity on (along the base's -z, F*'s +z here), weight compensated: at zero command the
    camera holds still; a constant camera twist, mapped every 40 ms through MuJoCo's Jacobian
    and `ScenarioArm.joint_velocities`, moves the camera over 0.4 s to within 10 % of
    `exp(twist t)` (the velocity actuators lag the command by a few ms)."""
    d = _small(_scenario(path))
    with vm.World.from_scenario(d) as world:
        arm, m, data = world.arm, world.model, world.data
        np.testing.assert_allclose(m.opt.gravity, [0.0, 0.0, 9.81], atol=1e-12)
        assert m.opt.timestep == pytest.approx(0.002)
        start = world.camera_pose()
        for _ in range(100):
            mujoco.mj_step(m, data)
        held = world.camera_pose()
        assert np.linalg.norm(held[:3, 3] - start[:3, 3]) < 2e-4
        twist = np.array([0.03, -0.02, 0.05, 0.1, -0.05, 0.15])
        for _ in range(10):
            dq, limited = arm.joint_velocities(_mounted.camera_jacobian(m, data), data.qpos, twist)
            assert not limited
            data.ctrl[:] = dq
            for _ in range(20):
                mujoco.mj_step(m, data)
        moved = _twist_of(held, world.camera_pose(), 0.2)  # twist * 0.4 s / (2 * 0.2)
        np.testing.assert_allclose(moved, twist, rtol=0.0, atol=0.1 * np.abs(twist).max())
        assert np.linalg.norm(moved - twist) < 0.1 * np.linalg.norm(twist), (moved, twist)


def test_joint_velocities_saturate_and_centre_as_the_kinematic_arm() -> None:
    """`ScenarioArm.joint_velocities` is the kinematic arm's: on a Jacobian with singular values
    above the damping it solves J dq = twist exactly (six joints) or in the least-norm sense plus
    the centring task (the Panda: J dq = twist still holds); a fast twist is scaled as a whole
    to the speed limits (the largest joint at its limit, the direction kept)."""
    for path in (UR5E, PANDA):
        arm = vsinv.load_scenario(os.path.join(ROOT, path)).arm()
        n = len(arm.joint_names)
        rng = np.random.default_rng(3)
        U, _ = np.linalg.qr(rng.normal(size=(6, 6)))
        V, _ = np.linalg.qr(rng.normal(size=(n, n)))
        J = U @ np.diag(rng.uniform(0.5, 2.0, 6)) @ V[:, :6].T  # singular values 0.5-2, above the damping
        twist = np.array([0.01, -0.02, 0.015, 0.03, 0.02, -0.01])
        dq, limited = arm.joint_velocities(J, arm.start, twist)
        np.testing.assert_allclose(J @ dq, twist, atol=1e-9)
        assert not limited
        fast, limited = arm.joint_velocities(J, arm.start, 1e3 * twist)
        assert limited and np.max(np.abs(fast) / arm.velocity) == pytest.approx(1.0)
        np.testing.assert_allclose(J @ fast / np.linalg.norm(J @ fast), twist / np.linalg.norm(twist), atol=1e-6)
        with pytest.raises(vsinv.InvalidInput, match="jacobian"):
            arm.joint_velocities(J[:, :-1], arm.start, twist)


@needs_mujoco
def test_a_short_servo_run_moves_the_arm_as_the_kinematic_one() -> None:
    """40 frames (1.6 s) of the UR5e lens change through MuJoCo's renders: the camera's recorded pose is vsinv's forward kinematics of the recorded joints,
    the joint velocities stay within the limits, and the camera's path follows the kinematic
    arm's from the same start (within 15 mm: the actuators lag, the images are MuJoCo's)."""
    d = _scenario(UR5E)
    run = vm.run_loop(d, max_iterations=40)
    r = run.result
    arm = vsinv.load_scenario(d).arm()
    assert r.joints.shape == (41, 6) and np.isnan(r.joint_velocities[-1]).all()  # 40 steps, 41 images
    for q, pose in zip(r.joints[::8], r.pose[::8]):
        np.testing.assert_allclose(pose, arm.camera_pose(q), atol=1e-9)
    assert (np.abs(r.joint_velocities[:-1]) <= arm.velocity * (1 + 1e-12)).all()
    assert r.joint_limits["names"] == arm.joint_names
    kd = {k: v for k, v in d.items() if k != "world"}
    kd["stop"] = {**kd["stop"], "max_iterations": 40}
    k = vsinv.run_scenario(kd)
    gap = np.linalg.norm(r.pose[:, :3, 3] - k.pose[: len(r.pose), :3, 3], axis=1)
    assert gap.max() < 0.015, gap.max()
    assert r.translation_error[-1] < 0.8 * r.translation_error[0]
    assert set(run.seconds_per_iteration) == {"render", "servo", "control", "physics"}


@needs_mujoco
def test_eye_to_hand_moves_the_target_so_the_camera_moves_as_commanded() -> None:
    """Eye-to-hand, 40 frames of the lens change: the camera stays at the world's origin, the
    UR5e carries the dots; the recorded camera pose in F* is the inverse of the target frame's
    pose (vsinv's kinematics of the recorded joints); the law's twists, mapped through the
    camera's pose in F* to the target's opposite motion, move the camera relative to the target
    along the free camera's path of `lens-12-6` (within 40 mm), each frame's relative motion in
    the direction of the law's twist."""
    d = vsinv.load_scenario("mujoco-eye-to-hand-12-6").to_dict()
    with vm.World.from_scenario(d) as world:
        run = vm.run_loop(d, world=world, max_iterations=40)
        np.testing.assert_allclose(world.camera_pose(), np.eye(4), atol=1e-12)
        arm = world.arm
    r = run.result
    for q, pose in zip(r.joints[::8], r.pose[::8]):
        np.testing.assert_allclose(pose, np.linalg.inv(arm.camera_pose(q)), atol=1e-9)
    k = vsinv.load_scenario("lens-12-6").to_dict()
    k["stop"]["max_iterations"] = 40
    free = vsinv.run_scenario(k)
    gap = np.linalg.norm(r.pose[:, :3, 3] - free.pose[: len(r.pose), :3, 3], axis=1)
    assert gap.max() < 0.04, gap.max()  # the target 0.72 m from the flange: the wrist's lag shows more
    assert r.translation_error[-1] < 0.8 * r.translation_error[0]
    # Frame by frame, the camera's motion relative to the target is the law's twist of 1-2
    # frames before (the actuators' lag): its direction within 25 degrees after the first frames.
    for i in range(5, 40):
        moved = np.linalg.inv(r.pose[i]) @ r.pose[i + 1]
        _, thetau = vsinv.geometry.thetau_from_pose(moved)
        realised = np.concatenate([moved[:3, 3], thetau])
        commanded = r.twist[i - 1]
        cos = realised @ commanded / np.linalg.norm(realised) / np.linalg.norm(commanded)
        assert cos > np.cos(np.radians(25)), (i, realised / 0.04, commanded)
