"""The UR5e (issue 31, item 2): robots/ur5e.urdf and `vsinv.mujoco.ur5e_mjcf` from Universal
Robots' published UR5e DH parameters, masses and centres of mass, and the inertia tensors of its
ROS 2 description.

The independent checks: a standard DH forward kinematics of the published table written here
(numpy), and roboticstoolbox-python's DH kinematics and gravity load (its `DHRobot` of the same
table: it ships no UR5e model; test-only, skipped when not installed), against vsinv's
`fk("ur5e")` (the Rust URDF reader), MuJoCo's flange site of the MJCF and MuJoCo's last link of
the URDF; MuJoCo's gravity torques against those of the published masses and centres of mass
(the Jacobians of the centres of mass by central differences of the DH kinematics); the MJCF's
and the URDF's inertials and limits against each other and the datasheet.
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

URDF = Path(__file__).resolve().parents[1] / "robots" / "ur5e.urdf"
# Universal Robots' UR5e table: d, a, alpha (standard DH), masses, centres of mass in DH frame i.
D = (0.1625, 0.0, 0.0, 0.1333, 0.0997, 0.0996)
A = (0.0, -0.425, -0.3922, 0.0, 0.0, 0.0)
ALPHA = (np.pi / 2, 0.0, 0.0, np.pi / 2, -np.pi / 2, 0.0)
MASS = (3.761, 8.058, 2.846, 1.37, 1.3, 0.365)
COM = ((0.0, -0.02561, 0.00193), (0.2125, 0.0, 0.11336), (0.15, 0.0, 0.0265),
       (0.0, -0.0018, 0.01634), (0.0, 0.0018, 0.01634), (0.0, 0.0, -0.001159))


def dh_frames(q: np.ndarray) -> list[np.ndarray]:
    """The DH frames 1..6 in the base: prod Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)."""
    T, out = np.eye(4), []
    for qi, d, a, al in zip(q, D, A, ALPHA):
        c, s, ca, sa = np.cos(qi), np.sin(qi), np.cos(al), np.sin(al)
        T = T @ np.array([[c, -s * ca, s * sa, a * c], [s, c * ca, -c * sa, a * s], [0, sa, ca, d], [0, 0, 0, 1.0]])
        out.append(T)
    return out


def _joints(count: int = 20) -> np.ndarray:
    return np.random.default_rng(5).uniform(-np.pi, np.pi, size=(count, 6))


def _pose(xpos: np.ndarray, xmat: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = np.asarray(xmat).reshape(3, 3), xpos
    return T


def test_the_flange_is_the_published_dh_kinematics() -> None:
    """At random joints: vsinv's fk("ur5e", q) (robots/ur5e.urdf through the Rust reader), the
    MJCF's `flange` site and the URDF's wrist_3_link then Tz(d6) in MuJoCo are the DH frame 6
    of the published table within 1e-9."""
    mjcf = mujoco.MjModel.from_xml_string(vm.ur5e_mjcf())
    urdf = mujoco.MjModel.from_xml_path(str(URDF))
    dm, du = mujoco.MjData(mjcf), mujoco.MjData(urdf)
    site = mujoco.mj_name2id(mjcf, mujoco.mjtObj.mjOBJ_SITE, "flange")
    wrist = mujoco.mj_name2id(urdf, mujoco.mjtObj.mjOBJ_BODY, "wrist_3_link")
    tool = np.eye(4)
    tool[2, 3] = D[5]
    for q in _joints():
        expected = dh_frames(q)[-1]
        np.testing.assert_allclose(vsinv.kinematics.fk("ur5e", q), expected, atol=1e-9)
        dm.qpos[:], du.qpos[:] = q, q
        mujoco.mj_kinematics(mjcf, dm)
        mujoco.mj_kinematics(urdf, du)
        np.testing.assert_allclose(_pose(dm.site_xpos[site], dm.site_xmat[site]), expected, atol=1e-9)
        np.testing.assert_allclose(_pose(du.xpos[wrist], du.xmat[wrist]) @ tool, expected, atol=1e-9)
    # not the UR5: the tables differ (d1 0.1625 against 0.089159 m)
    assert np.linalg.norm(vsinv.kinematics.fk("ur5e", q)[:3, 3] - vsinv.kinematics.fk("ur5", q)[:3, 3]) > 0.01


def test_gravity_torques_are_those_of_the_published_masses_and_centres() -> None:
    """Without weight compensation, MuJoCo's bias forces at rest (the MJCF and the URDF) are the
    gravity torques -sum_i m_i J_ci^T g of the published masses and centres of mass, with the
    centres' Jacobians by central differences of the DH kinematics (1e-6 N m)."""
    mjcf = mujoco.MjModel.from_xml_string(vm.ur5e_mjcf().replace('gravcomp="1"', ""))
    urdf = mujoco.MjModel.from_xml_path(str(URDF))
    g = np.array([0.0, 0.0, -9.81])
    for model in (mjcf, urdf):
        model.opt.gravity[:] = g
        data = mujoco.MjData(model)
        for q in _joints(5):
            data.qpos[:], data.qvel[:] = q, 0.0
            mujoco.mj_forward(model, data)
            tau = np.zeros(6)
            h = 1e-6
            for j in range(6):
                dq = np.zeros(6)
                dq[j] = h
                plus, minus = dh_frames(q + dq), dh_frames(q - dq)
                for i in range(6):
                    c = np.append(COM[i], 1.0)
                    tau[j] -= MASS[i] * ((plus[i] @ c - minus[i] @ c)[:3] / (2 * h)) @ g
            np.testing.assert_allclose(data.qfrc_bias, tau, atol=1e-6)


def test_the_mjcf_and_the_urdf_carry_the_published_inertials_and_limits() -> None:
    """Masses (19.7 kg in all), centres of mass and principal inertias are the same in the MJCF
    and the URDF as MuJoCo reads them; the inertia tensors are the diagonals of Universal Robots'
    ROS 2 description; joint ranges +-2 pi, speeds pi rad/s, torques 150 N m (size-3 joints) and 28 N m (wrists), in the
    MJCF's actuators and in vsinv's reading of the URDF."""
    mjcf = mujoco.MjModel.from_xml_string(vm.ur5e_mjcf())
    urdf = mujoco.MjModel.from_xml_path(str(URDF))
    moving = [mujoco.mj_name2id(mjcf, mujoco.mjtObj.mjOBJ_BODY, urdf.body(i).name) for i in range(1, urdf.nbody)]
    np.testing.assert_allclose(urdf.body_mass[1:], MASS)
    np.testing.assert_allclose(mjcf.body_mass[moving], MASS)
    np.testing.assert_allclose(urdf.body_ipos[1:], mjcf.body_ipos[moving], atol=1e-9)
    # The diagonals of Universal Robots' ROS 2 description (config/ur5e/physical_parameters.yaml).
    published = np.sort(np.array([(0.0070021, 0.00648091, 0.00657286), (0.01505885, 0.33388086, 0.33247207),
                                  (0.00399632, 0.07879254, 0.0784851), (0.00165491, 0.00135962, 0.00126279),
                                  (0.00135617, 0.00127827, 0.00096614), (0.00018694, 0.00018908, 0.00025756)]), axis=1)
    np.testing.assert_allclose(np.sort(urdf.body_inertia[1:], axis=1), published, rtol=1e-9)
    np.testing.assert_allclose(np.sort(mjcf.body_inertia[moving], axis=1), published, rtol=1e-9)
    np.testing.assert_allclose(mjcf.jnt_range, np.tile([-2 * np.pi, 2 * np.pi], (6, 1)))
    np.testing.assert_allclose(mjcf.actuator_ctrlrange[:, 1], np.pi)
    np.testing.assert_allclose(mjcf.actuator_forcerange[:, 1], [150.0] * 3 + [28.0] * 3)
    d = vsinv.load_scenario("arm-ur5-12-6").to_dict()
    d["robot"]["urdf"] = "ur5e"
    d["robot"].pop("joints")  # placed by [start] (the UR5e's own inverse kinematics)
    arm = vsinv.load_scenario({**d, "start": {"position": [0.2, -0.15, -0.15], "rotation_deg": [-19.33, -4.86, 77.28]}}).arm()
    np.testing.assert_allclose(arm.lower, -2 * np.pi)
    np.testing.assert_allclose(arm.upper, 2 * np.pi)
    np.testing.assert_allclose(arm.velocity, np.pi, rtol=1e-5)


def test_roboticstoolbox_agrees_on_kinematics_and_gravity_load() -> None:
    """roboticstoolbox-python (test-only) builds the published table as a `DHRobot` (it ships
    no UR5e): its forward kinematics is vsinv's fk("ur5e") within 1e-9 and its gravity load (its
    own recursive Newton-Euler) MuJoCo's bias forces within 1e-6 N m."""
    rtb = pytest.importorskip("roboticstoolbox", reason="pip install roboticstoolbox-python")
    links = [rtb.RevoluteDH(d=d, a=a, alpha=al, m=m, r=c, I=np.zeros(3)) for d, a, al, m, c in zip(D, A, ALPHA, MASS, COM)]
    robot = rtb.DHRobot(links, name="UR5e", gravity=[0.0, 0.0, -9.81])
    model = mujoco.MjModel.from_xml_string(vm.ur5e_mjcf().replace('gravcomp="1"', ""))
    data = mujoco.MjData(model)
    for q in _joints(5):
        np.testing.assert_allclose(robot.fkine(q).A, vsinv.kinematics.fk("ur5e", q), atol=1e-9)
        data.qpos[:], data.qvel[:] = q, 0.0
        mujoco.mj_forward(model, data)
        np.testing.assert_allclose(robot.gravload(q), data.qfrc_bias, atol=1e-6)
