"""Arms from a user's own description in MuJoCo (issue 31, item 2): a URDF file in a scenario's
`[robot] urdf` (`vsinv.mujoco._urdf`) and an MJCF file's arm named by `World.from_mjcf(...,
arm_joints=, camera_site=)` (`vsinv.mujoco._user_arm`).

The independent checks: the project's `robots/ur5e.urdf` given as a user's file runs as the
built-in UR5e (MJCF written by vsinv) from the same start: the same verdict, joints within the
stated tolerance (1e-2 rad, 2 mm: the two differ in their actuators' gains and the built-in's joint damping and
armature); an arm written here in MJCF servoes through its own camera's images to the goal
joints; its camera site's Jacobian against central differences of MuJoCo's kinematics; bad
files and names refused naming their key. Skips (saying what to install) without mujoco or EGL.
"""

from __future__ import annotations

import os
import re
import shutil
import warnings
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import vsinv  # noqa: E402
import vsinv.mujoco as vm  # noqa: E402

pytestmark = pytest.mark.sim

_WHY_NOT = vm.available()
needs_mujoco = pytest.mark.skipif(_WHY_NOT is not None, reason=_WHY_NOT or "")
mujoco = pytest.importorskip("mujoco", reason="pip install 'vsinv[mujoco]'")

ROOT = Path(__file__).resolve().parent.parent
UR5E = ROOT / "scenarios" / "mujoco-arm-ur5e-12-6.toml"


def _user_ur5e(tmp_path: Path, urdf_text: str | None = None) -> None:
    """The file `ur5e.urdf` in `tmp_path` (the working folder: a scenario dict's relative
    `robot.urdf` is read from there): robots/ur5e.urdf, or `urdf_text`."""
    target = tmp_path / "ur5e.urdf"
    if urdf_text is None:
        shutil.copy(ROOT / "robots" / "ur5e.urdf", target)
    else:
        target.write_text(urdf_text)


def _half(d: dict) -> dict:
    """The scenario's cameras at half their resolution (rendering is most of a frame; at a
    quarter its 4 mm dots are too small to be found)."""
    for key in ("reference_camera", "camera", "estimate"):
        c = d[key]
        c.update(fku=c["fku"] / 2, fkv=c["fkv"] / 2, u0=(c["u0"] + 0.5) / 2 - 0.5, v0=(c["v0"] + 0.5) / 2 - 0.5)
        if "width" in c:
            c.update(width=c["width"] // 2, height=c["height"] // 2)
    return d


def _users_ur5e_world(tmp_path: Path, urdf_text: str | None = None) -> tuple[dict, vm.World]:
    """mujoco-arm-ur5e-12-6 at half resolution with `ur5e.urdf` written in `tmp_path` as the
    user's arm (the project's file, or `urdf_text`), and its MuJoCo world (the warning about
    the actuators vsinv adds left out)."""
    _user_ur5e(tmp_path, urdf_text)
    d = _half(vsinv.load_scenario(str(UR5E)).to_dict())
    d["robot"]["urdf"] = "ur5e.urdf"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return d, vm.World.from_scenario(d)


def _forty_frames_beside_the_builtin(user: dict, d: dict):
    """40 frames of the scenario with the user's URDF arm (`user`) and with the built-in UR5e
    (`d`): the two results, after checking which arm each loaded and the warning about the
    actuators vsinv adds to a URDF arm."""
    arm = vsinv.load_scenario(user).arm()
    assert arm.source.endswith("ur5e.urdf") and vsinv.load_scenario(d).arm().source == "builtin:ur5e"
    with pytest.warns(UserWarning, match="velocity actuators"):
        mine = vm.run_loop(user, max_iterations=40)
    builtin = vm.run_loop(d, max_iterations=40)
    a, b = mine.result, builtin.result
    assert len(a.time) == len(b.time) == 41  # the start and 40 steps
    return a, b


@needs_mujoco
@pytest.mark.slow
def test_the_projects_ur5e_urdf_as_a_users_file_runs_as_the_built_in_arm(tmp_path: Path, monkeypatch) -> None:
    """robots/ur5e.urdf as `robot.urdf = "ur5e.urdf"` (a user's file, not the built-in name):
    MuJoCo reads its inertials, vsinv adds velocity actuators (and warns), and 40 frames of the
    servo from mujoco-arm-ur5e-12-6's start follow the built-in arm's: the same frames
    recorded, joints within 1e-2 rad and the camera within 2 mm of the built-in run's at every
    frame (measured 6.8e-3 rad on a wrist, 0.99 mm; the actuators differ: kv = M_jj / 2 ms here
    against the built-in's fixed gains, and the URDF has no joint damping or armature), the
    same verdict."""
    monkeypatch.chdir(tmp_path)
    _user_ur5e(tmp_path)
    d = _half(vsinv.load_scenario(str(UR5E)).to_dict())
    user = {**d, "robot": {**d["robot"], "urdf": "ur5e.urdf"}}
    a, b = _forty_frames_beside_the_builtin(user, d)
    assert a.summary["status"] == b.summary["status"]
    joints, camera = np.abs(a.joints - b.joints).max(), np.abs(a.pose[:, :3, 3] - b.pose[:, :3, 3]).max()
    assert joints < 1e-2 and camera < 2e-3, (joints, camera)  # measured: 6.8e-3 rad, 0.99 mm
    assert a.summary["final_invariant_error"] < 0.5 * a.invariant_error[0]  # it servoes


@needs_mujoco
def test_the_urdf_arms_camera_site_jacobian_is_the_finite_difference(monkeypatch, tmp_path: Path) -> None:
    """The URDF arm's world: the camera site is vsinv's `base * fk * mount` (1e-9) and MuJoCo's
    Jacobian of the believed site (`_mounted.camera_jacobian`) the central difference of its pose."""
    from vsinv.mujoco import _mounted

    monkeypatch.chdir(tmp_path)
    d, world = _users_ur5e_world(tmp_path)
    with world:
        arm, m, data = world.arm, world.model, world.data
        assert m.nu == 6 and m.nq == 6
        for q in np.random.default_rng(5).uniform(-2.5, 2.5, size=(3, 6)):
            data.qpos[:] = q
            mujoco.mj_kinematics(m, data)
            np.testing.assert_allclose(_site(m, data, _mounted.CAMERA_SITE), arm.camera_pose(q), atol=1e-9)
            J = _mounted.camera_jacobian(m, data)
            np.testing.assert_allclose(J, _finite_jacobian(m, data, _mounted.BELIEVED_SITE, q, np.arange(6)), atol=1e-6)


@needs_mujoco
@pytest.mark.slow
def test_eye_to_hand_with_a_users_urdf_runs_as_the_built_in_arm(tmp_path: Path, monkeypatch) -> None:
    """`[world.eye_to_hand] urdf = "ur5e.urdf"` (robots/ur5e.urdf as a user's file): the URDF
    arm carries the dots (their body moved onto its `tool0`) before the fixed camera, and 40
    frames of mujoco-eye-to-hand-12-6 follow the built-in arm's: the same first detections
    (0.5 px; measured equal: the same start joints and target pose), joints within 1e-2 rad and F* within 2 mm of the built-in run's at every frame
    (the actuators differ, as eye-in-hand above), the invariant error falling."""
    monkeypatch.chdir(tmp_path)
    _user_ur5e(tmp_path)
    d = _half(vsinv.load_scenario("mujoco-eye-to-hand-12-6").to_dict())
    user = {**d, "world": {**d["world"], "eye_to_hand": {**d["world"]["eye_to_hand"], "urdf": "ur5e.urdf"}}}
    a, b = _forty_frames_beside_the_builtin(user, d)
    seen = a.visible[0]  # at half resolution one dot is lost in the first image by both
    assert (seen == b.visible[0]).all() and seen.sum() >= 10
    assert np.abs(a.pixels[0][seen] - b.pixels[0][seen]).max() < 0.5  # measured: equal
    joints, target = np.abs(a.joints - b.joints).max(), np.abs(a.pose[:, :3, 3] - b.pose[:, :3, 3]).max()
    assert joints < 1e-2 and target < 2e-3, (joints, target)
    assert a.summary["final_invariant_error"] < 0.5 * a.invariant_error[0]


@needs_mujoco
def test_a_start_pose_is_reached_by_the_users_urdf_not_the_built_in_of_its_name(tmp_path: Path, monkeypatch) -> None:
    """A user's `ur5e.urdf` (its `<robot name="ur5e">`, the built-in's name) with a longer upper
    arm (0.47 m, the built-in 0.425 m): a start *pose* puts the arm where this URDF's forward
    kinematics (`ScenarioArm.camera_pose`, and MuJoCo's camera site built from the same file)
    reach it within 1e-6, not where the built-in UR5e's inverse kinematics would (the pose
    through this URDF's kinematics at the built-in's joints is centimetres away)."""
    from vsinv import geometry, kinematics
    from vsinv.mujoco import _arm_loop

    monkeypatch.chdir(tmp_path)
    text = (ROOT / "robots" / "ur5e.urdf").read_text()
    longer = text.replace('<origin xyz="-0.425 0 0" rpy="0 0 0"/>', '<origin xyz="-0.47 0 0" rpy="0 0 0"/>')
    assert longer != text
    d, world = _users_ur5e_world(tmp_path, longer)
    with world:
        arm = world.arm
        assert not arm.source.startswith("builtin:")
        s = d["start"]
        start = geometry.pose_from_position_thetau(s["position"], np.radians(s["rotation_deg"]))
        pose = start @ geometry.pose_from_position_thetau([0.02, -0.01, 0.015], np.radians([3.0, -2.0, 4.0]))
        q = _arm_loop.start_joints(arm, pose)
        np.testing.assert_allclose(arm.camera_pose(q), pose, atol=1e-6)
        world.data.qpos[:] = q
        mujoco.mj_kinematics(world.model, world.data)
        np.testing.assert_allclose(world.camera_pose(), pose, atol=1e-6)  # MuJoCo's own kinematics of the file
        ee = np.linalg.inv(np.asarray(arm.base)) @ pose @ np.linalg.inv(np.asarray(arm.mount))
        builtin_q = np.asarray(kinematics.ik("ur5e", ee, seed=arm.start).joints)  # what the built-in's IK gives
        assert np.linalg.norm(np.asarray(arm.camera_pose(builtin_q))[:3, 3] - pose[:3, 3]) > 0.01
        run = vm.run_loop(d, world=world, start=pose, max_iterations=1)
        np.testing.assert_allclose(run.pose[0], pose, atol=1e-6)  # the run starts there


def test_a_kinematics_only_urdf_is_refused_naming_the_link(tmp_path: Path, monkeypatch) -> None:
    """A moving link without <inertial>: vsinv's error names robot.urdf and the link, not
    MuJoCo's mjMINVAL message."""
    if _WHY_NOT is not None:
        pytest.skip(_WHY_NOT)
    monkeypatch.chdir(tmp_path)
    text = (ROOT / "robots" / "ur5e.urdf").read_text()
    text = re.sub(r'(<link name="wrist_2_link">)\s*<inertial>.*?</inertial>', r"\1", text, flags=re.S)
    _user_ur5e(tmp_path, text)
    d = _half(vsinv.load_scenario(str(UR5E)).to_dict())
    d["robot"]["urdf"] = "ur5e.urdf"
    with pytest.raises(vsinv.InvalidInput, match=r"robot\.urdf: link 'wrist_2_link' .* has no mass") as e:
        vm.World.from_scenario(d)
    assert "mjMINVAL" not in str(e.value)


# -- an arm written in MJCF -------------------------------------------------------------------
DOTS = ((-0.1, -0.08, 0.0), (0.1, -0.08, 0.06), (0.1, 0.08, 0.02), (-0.1, 0.08, 0.08), (0.03, 0.02, 0.1), (-0.04, 0.03, 0.03))


def _arm_mjcf(actuators: str = "") -> str:
    """Three slides (x, y, z) then three hinges (z, y, x) carrying a camera 0.6 m above six white
    dots at heights 0 to 0.1 m over a black plate (not planar), looking down; weight compensated."""
    dots = "".join(f'<geom type="cylinder" size="0.012 0.001" pos="{x} {y} {z}" rgba="1 1 1 1" contype="0" conaffinity="0"/>'
                   for x, y, z in DOTS)
    inertial = '<inertial pos="0 0 0" mass="0.5" diaginertia="0.002 0.002 0.002"/>'
    chain = '<camera name="eye" fovy="60"/>'
    for name, kind, axis in reversed([("x", "slide", "1 0 0"), ("y", "slide", "0 1 0"), ("z", "slide", "0 0 1"),
                                      ("yaw", "hinge", "0 0 1"), ("pitch", "hinge", "0 1 0"), ("roll", "hinge", "1 0 0")]):
        chain = f'<body name="{name}_link" gravcomp="1"><joint name="{name}" type="{kind}" axis="{axis}" damping="0.5"/>{inertial}{chain}</body>'
    return f"""<mujoco model="test-arm">
  <option timestep="0.002" integrator="implicitfast"/>
  <visual><global offwidth="320" offheight="240"/></visual>
  <worldbody>
    <light directional="true" pos="0 0 3" dir="0 0 -1" diffuse="0.6 0.6 0.6"/>
    <geom type="box" pos="0 0 -0.006" size="0.4 0.4 0.005" rgba="0 0 0 1" contype="0" conaffinity="0"/>
    {dots}
    <body name="mount" pos="0 0 0.6">{chain}</body>
  </worldbody>
  <actuator>{actuators}</actuator>
</mujoco>"""


def _site(m, data, name: str) -> np.ndarray:
    s = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, name)
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = data.site_xmat[s].reshape(3, 3), data.site_xpos[s]
    return pose


def _finite_jacobian(m, data, site: str, q: np.ndarray, qpos: np.ndarray, h: float = 1e-6) -> np.ndarray:
    """Columns: the site's body twist (v, w in its own frame) per joint, by central differences."""
    out = []
    for i in qpos:
        poses = []
        for sign in (-1.0, 1.0):
            data.qpos[:] = q
            data.qpos[i] += sign * h
            mujoco.mj_kinematics(m, data)
            poses.append(_site(m, data, site))
        delta = np.linalg.inv(poses[0]) @ poses[1]
        _, thetau = vsinv.geometry.thetau_from_pose(delta)
        out.append(np.concatenate([delta[:3, 3], thetau]) / (2 * h))
    data.qpos[:] = q
    mujoco.mj_kinematics(m, data)
    return np.array(out).T


def _world(tmp_path: Path, **kwargs) -> vm.World:
    path = tmp_path / "arm.xml"
    path.write_text(_arm_mjcf(kwargs.pop("actuators", "")))
    return vm.World.from_mjcf(path, "eye", width=320, height=240, **kwargs)


JOINTS = ("x", "y", "z", "yaw", "pitch", "roll")


@needs_mujoco
def test_an_mjcf_arms_camera_site_is_the_camera_and_its_jacobian_the_finite_difference(tmp_path: Path) -> None:
    with pytest.warns(UserWarning, match="velocity actuators"):
        world = _world(tmp_path, arm_joints=JOINTS)
    with world:
        m, data = world.model, world.data
        assert m.nu == 6
        for q in np.random.default_rng(3).uniform(-0.4, 0.4, size=(3, 6)):
            data.qpos[:] = q
            mujoco.mj_kinematics(m, data)
            np.testing.assert_allclose(_site(m, data, world.user_arm.site), world.camera_pose(), atol=1e-9)
            J = world.user_arm.jacobian(m, data)
            np.testing.assert_allclose(J, _finite_jacobian(m, data, world.user_arm.site, q, world.user_arm.qpos), atol=1e-6)


@needs_mujoco
@pytest.mark.slow
def test_an_mjcf_arm_servoes_through_its_camera(tmp_path: Path) -> None:
    """The invariant law on the arm's own renders (reference image at the goal joints 0, K_hat
    5 % off), `World.move_arm` every 40 ms: from 78 mm and 18 degrees away the camera ends
    within 10 mm and 0.5 degrees of the goal."""
    with pytest.warns(UserWarning):
        world = _world(tmp_path, arm_joints=JOINTS)
    with world:
        m, data = world.model, world.data
        mujoco.mj_forward(m, data)
        goal = world.camera_pose()
        points = np.array(DOTS)
        reference = world.render()
        ref_px, depths = world.project(points)
        k = world.K
        data.qpos[:] = [0.04, -0.03, 0.06, 0.3, 0.08, -0.06]
        mujoco.mj_forward(m, data)
        first_px, _ = world.project(points)
        servo = vsinv.ImageServo(reference, "dots", vsinv.Intrinsics(k.fku * 1.05, k.fkv * 0.97, k.u0 + 3, k.v0 - 2),
                                 reference_points=ref_px, first_points=first_px, reference_depths=depths,
                                 law="invariant", dt=0.04, stop={"max_iterations": 400})
        image = world.render()
        step = servo.step(image)
        while step.running:
            world.move_arm(step.twist, 0.04)
            step = servo.step(world.render())
        # 320 x 240 px and 24 mm dots: the images pin the pose to a few mm (the session says
        # "settled" where the law's error stops decreasing above its threshold)
        assert step.verdict in ("converged", "settled"), step.reason
        pose = world.camera_pose()
        t, r = np.linalg.norm(pose[:3, 3] - goal[:3, 3]), np.arccos(np.clip((np.trace(goal[:3, :3].T @ pose[:3, :3]) - 1) / 2, -1, 1))
        assert t < 0.01 and np.degrees(r) < 0.5, (t, np.degrees(r))  # from 78 mm and 18 degrees


@needs_mujoco
@pytest.mark.parametrize(("kwargs", "key"), [
    ({"arm_joints": ("x", "nope")}, "arm_joints: no joint named 'nope'"),
    ({"arm_joints": JOINTS, "camera_site": "nope"}, "camera_site: no site named 'nope'"),
    ({"arm_joints": JOINTS, "actuators": '<position joint="yaw" kp="10"/>'}, "arm_joints: joint 'yaw' is driven"),
])
def test_bad_names_are_refused_naming_the_key(tmp_path: Path, kwargs: dict, key: str) -> None:
    with pytest.raises(vsinv.InvalidInput, match=re.escape(key)), warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        _world(tmp_path, **kwargs)


@needs_mujoco
def test_move_arm_without_an_arm_or_with_a_bad_twist_is_refused(tmp_path: Path) -> None:
    with _world(tmp_path) as world, pytest.raises(vsinv.InvalidInput, match="arm_joints"):
        world.move_arm(np.zeros(6), 0.04)
    with pytest.warns(UserWarning):
        world = _world(tmp_path, arm_joints=JOINTS)
    with world, pytest.raises(vsinv.InvalidInput, match="twist"):
        world.move_arm(np.zeros(5), 0.04)
