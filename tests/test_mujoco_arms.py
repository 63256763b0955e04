"""Arms with mass (issue 31, item 2): the Panda of `vsinv.mujoco.panda_mjcf` (Franka's modified
DH table and limits, Gaz et al.'s identified inertials) and the project's URDFs with the same
inertials, which MuJoCo now loads.

The independent checks: vsinv's own forward kinematics (`vsinv.kinematics.fk`, the URDF reader
of the Rust core) against MuJoCo's kinematics of the MJCF and of the URDFs; the inertials MuJoCo
reads from the URDFs against those of the MJCF models; a commanded twist against the motion the
physics produces. Skips (saying what to install) when mujoco is missing.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import vsinv  # noqa: E402
import vsinv.mujoco as vm  # noqa: E402

pytestmark = pytest.mark.sim

mujoco = pytest.importorskip("mujoco", reason="pip install 'vsinv[mujoco]'")

ROBOTS = Path(__file__).resolve().parents[1] / "robots"
RNG_SEED = 31


def _pose(xpos: np.ndarray, xmat: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = np.asarray(xmat).reshape(3, 3)
    T[:3, 3] = xpos
    return T


def _limits(arm: str) -> tuple[np.ndarray, np.ndarray]:
    if arm == "panda":
        return np.array(vm._panda.PANDA_LOWER), np.array(vm._panda.PANDA_UPPER)
    return -np.pi * np.ones(6), np.pi * np.ones(6)


def _random_joints(arm: str, count: int = 25) -> np.ndarray:
    lower, upper = _limits(arm)
    return np.random.default_rng(RNG_SEED).uniform(lower, upper, size=(count, len(lower)))


def test_the_panda_sites_are_vsinvs_forward_kinematics() -> None:
    """At random joints within the limits, MuJoCo's `tcp` site is vsinv's fk("panda", q)
    within 1e-9 (m and rotation matrix entries), `flange` is that pose 0.103 m back, and the
    camera `wrist` looks down the TCP's z axis (its frame is the TCP's turned by pi about x)."""
    model = mujoco.MjModel.from_xml_string(vm.panda_mjcf())
    data = mujoco.MjData(model)
    tcp, flange = (mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, n) for n in ("tcp", "flange"))
    cam = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, "wrist")
    c, s = np.cos(-np.pi / 4), np.sin(-np.pi / 4)
    # panda_link8 in the TCP frame: the inverse of Tz(0.103) Rz(-pi/4) (robots/panda.urdf)
    back = np.linalg.inv(np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0.103], [0, 0, 0, 1.0]]))
    for q in _random_joints("panda"):
        data.qpos[:] = q
        mujoco.mj_forward(model, data)
        expected = np.asarray(vsinv.kinematics.fk("panda", q))
        np.testing.assert_allclose(_pose(data.site_xpos[tcp], data.site_xmat[tcp]), expected, atol=1e-9)
        np.testing.assert_allclose(_pose(data.site_xpos[flange], data.site_xmat[flange]), expected @ back, atol=1e-9)
        camera = _pose(data.cam_xpos[cam], data.cam_xmat[cam]) @ np.diag([1.0, -1.0, -1.0, 1.0])
        np.testing.assert_allclose(camera, expected, atol=1e-9)


def test_the_panda_model_carries_the_published_numbers() -> None:
    """Masses (Gaz et al. 2019: 16.06 kg in all), joint ranges, speed and torque limits as in
    robots/panda.urdf (vsinv's reader of it gives the same limits)."""
    model = mujoco.MjModel.from_xml_string(vm.panda_mjcf())
    assert model.body_mass.sum() == pytest.approx(16.062132, abs=1e-6)
    np.testing.assert_allclose(model.jnt_range, np.column_stack(_limits("panda")))
    np.testing.assert_allclose(model.actuator_forcerange[:, 1], [87] * 4 + [12] * 3)
    np.testing.assert_allclose(model.actuator_ctrlrange[:, 1], [2.175] * 4 + [2.61] * 3)
    limits = vsinv.run_scenario("arm-panda-12-6", record=False).joint_limits
    np.testing.assert_allclose(limits["lower"], model.jnt_range[:, 0])
    np.testing.assert_allclose(limits["upper"], model.jnt_range[:, 1])
    np.testing.assert_allclose(limits["velocity"], model.actuator_ctrlrange[:, 1])


@pytest.mark.parametrize(
    ("arm", "last_link", "tool"),
    [
        # the end-effector in the last moving link: fixed joints MuJoCo merges into it
        ("ur5", "wrist_3_link", np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0.0823], [0, 0, 0, 1.0]])),
        ("panda", "panda_link7", np.array([[np.cos(-np.pi / 4), -np.sin(-np.pi / 4), 0, 0],
                                           [np.sin(-np.pi / 4), np.cos(-np.pi / 4), 0, 0], [0, 0, 1, 0.21], [0, 0, 0, 1]])),
    ],
)
def test_the_project_urdfs_load_in_mujoco_with_vsinvs_kinematics(arm: str, last_link: str, tool: np.ndarray) -> None:
    """robots/<arm>.urdf loads in MuJoCo (it refused the kinematics-only files: "mass and
    inertia of moving bodies must be larger than mjMINVAL"); its last moving link is where
    vsinv's fk puts it (fk = link @ tool) within 1e-9, and its masses, centres of mass and
    principal moments are those of the MJCF model of the same arm."""
    model = mujoco.MjModel.from_xml_path(str(ROBOTS / f"{arm}.urdf"))
    data = mujoco.MjData(model)
    body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, last_link)
    assert body > 0 and model.nv == (7 if arm == "panda" else 6)
    for q in _random_joints(arm):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        link = _pose(data.xpos[body], data.xmat[body])
        np.testing.assert_allclose(link @ tool, np.asarray(vsinv.kinematics.fk(arm, q)), atol=1e-9)
    mjcf = mujoco.MjModel.from_xml_string(vm.panda_mjcf() if arm == "panda" else vm.ur5_mjcf())
    moving = [mujoco.mj_name2id(mjcf, mujoco.mjtObj.mjOBJ_BODY, model.body(i).name) for i in range(1, model.nbody)]
    np.testing.assert_allclose(model.body_mass[1:], mjcf.body_mass[moving], rtol=1e-8)
    np.testing.assert_allclose(model.body_ipos[1:], mjcf.body_ipos[moving], atol=1e-9)
    np.testing.assert_allclose(np.sort(model.body_inertia[1:], axis=1), np.sort(mjcf.body_inertia[moving], axis=1), rtol=1e-7)


def test_the_panda_moves_its_camera_as_commanded_under_gravity() -> None:
    """Gravity on, weight compensated: with zero commands the arm holds still (within 0.1 mm
    over 0.2 s); a camera twist through `joint_velocities` (MuJoCo's Jacobian of the TCP site,
    vsinv's damped least squares) moves the camera by about twist * dt in one 25 Hz frame of
    500 Hz physics (the velocity actuators lag a little: 75-105 % of the commanded motion)."""
    model = mujoco.MjModel.from_xml_string(vm.panda_mjcf())
    data = mujoco.MjData(model)
    data.qpos[:] = [0.1, -0.4, 0.05, -2.0, 0.05, 1.7, 0.7]
    mujoco.mj_forward(model, data)
    tcp = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "tcp")
    start = _pose(data.site_xpos[tcp], data.site_xmat[tcp])
    for _ in range(100):
        mujoco.mj_step(model, data)
    held = _pose(data.site_xpos[tcp], data.site_xmat[tcp])
    assert np.linalg.norm(held[:3, 3] - start[:3, 3]) < 1e-4
    twist = np.array([0.0, 0.0, 0.05, 0.0, 0.0, 0.1])
    data.ctrl[:] = vm.joint_velocities(model, data, "tcp", twist)
    for _ in range(20):
        mujoco.mj_step(model, data)
    moved = np.linalg.inv(held) @ _pose(data.site_xpos[tcp], data.site_xmat[tcp])
    commanded = 0.05 * 0.04
    assert 0.75 * commanded < moved[2, 3] < 1.05 * commanded, moved[:3, 3]
    assert np.linalg.norm(moved[:2, 3]) < 0.2 * commanded
