"""vsinv.mujoco (issue 31, item 1): worlds made from scenarios or from a user's MJCF file,
rendered by MuJoCo in vsinv's conventions, and the closed loop through those images.

The independent checks: MuJoCo's own renders (centroids of small spheres, MuJoCo's camera frame
after its kinematics) against vsinv's pinhole projection; a scenario's target rendered by MuJoCo
against vsinv's own renderer of the same scenario; the loop's end against the scene's truth.
Skips (saying what to install) when mujoco or an EGL/OpenGL stack is missing.
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

_WHY_NOT = vm.available()
if _WHY_NOT is not None:
    pytest.skip(_WHY_NOT, allow_module_level=True)

import mujoco  # noqa: E402

POINTS = np.array([[0, 0, 0], [0.08, 0.03, 0.02], [-0.06, 0.05, -0.04], [0.02, -0.07, 0.06], [-0.05, -0.04, 0.05]])


def _spheres_mjcf(path: Path, camera_fovy: float = 45.0) -> Path:
    """A user's MJCF: small white spheres at POINTS lit by a full ambient light, a free camera."""
    geoms = "".join(f'<geom type="sphere" size="0.004" pos="{x} {y} {z}" rgba="1 1 1 1"/>' for x, y, z in POINTS)
    path.write_text(
        f"""<mujoco><visual><headlight ambient="1 1 1" diffuse="0 0 0" specular="0 0 0"/></visual>
        <worldbody>{geoms}<camera name="eye" pos="1 1 1" fovy="{camera_fovy}"/></worldbody></mujoco>"""
    )
    return path


def _look_at(eye, target, up) -> np.ndarray:
    eye, target, up = (np.asarray(v, float) for v in (eye, target, up))
    z = (target - eye) / np.linalg.norm(target - eye)
    x = np.cross(z, up)
    x /= np.linalg.norm(x)
    pose = np.eye(4)
    pose[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    pose[:3, 3] = eye
    return pose


def _centroids(image: np.ndarray, count: int) -> np.ndarray:
    """Intensity-weighted centroids of the bright blobs (OpenCV's labelling, not vsinv's detector)."""
    cv2 = pytest.importorskip("cv2", reason="pip install opencv-python-headless")
    n, labels = cv2.connectedComponents((image > 60).astype(np.uint8))
    found = n - 1
    assert found == count, found
    weight = np.clip(image.astype(float) - 20.0, 0, None)
    out = []
    for label in range(1, found + 1):
        v, u = np.nonzero(labels == label)
        w = weight[v, u]
        out.append([(u * w).sum() / w.sum(), (v * w).sum() / w.sum()])
    return np.array(out)


KS = [None, (520.0, 470.0, 183.3, 161.8), (300.0, 300.0, 214.0, 139.5)]  # None: the MJCF's fovy


@pytest.mark.parametrize("K", KS, ids=["fovy", "anisotropic-off-centre", "wide-off-centre"])
def test_K_is_what_mujoco_renders(tmp_path: Path, K) -> None:
    """Spheres at known points rendered by MuJoCo from vsinv poses: their centroids are where
    vsinv.geometry.project puts them with `world.K` (from MuJoCo's fovy, or set through its
    camera intrinsics), within 0.2 px (0.06-0.09 measured) and without bias."""
    with vm.World.from_mjcf(_spheres_mjcf(tmp_path / "spheres.xml"), camera="eye", width=400, height=300) as world:
        if K is not None:
            world.set_K(K)
        else:  # f = (H / 2) / tan(fovy / 2), centre ((W - 1) / 2, (H - 1) / 2)
            np.testing.assert_allclose(
                [world.K.fku, world.K.fkv, world.K.u0, world.K.v0], [150 / np.tan(np.radians(22.5))] * 2 + [199.5, 149.5], rtol=1e-6
            )
        residuals = []
        for eye, up in [((0.4, 0.1, 0.2), (0, 0, 1)), ((0.1, -0.45, 0.1), (0.3, 0, 1)), ((-0.3, 0.2, -0.3), (1, 1, 0))]:
            pose = _look_at(eye, (0.01, 0.0, 0.005), up)
            image = world.render(pose)
            cam = (POINTS - pose[:3, 3]) @ pose[:3, :3]
            expected, _ = vsinv.geometry.project(cam, world.K)
            for c in _centroids(image, len(POINTS)):
                residuals.append(c - expected[np.argmin(np.linalg.norm(expected - c, axis=1))])
        residuals = np.array(residuals)
        print(f"K residuals: max {np.abs(residuals).max():.3f} px, mean {residuals.mean(axis=0).round(3)}")
        assert np.abs(residuals).max() < 0.2, residuals  # measured 0.06-0.09 px
        assert np.abs(residuals.mean(axis=0)).max() < 0.05, residuals.mean(axis=0)  # a half pixel or a flip would show


def test_camera_frame_and_move_camera(tmp_path: Path) -> None:
    """MuJoCo's camera frame (cam_xmat after kinematics) of a vsinv pose is vsinv's turned by pi
    about x; camera_pose() reads it back; move_camera integrates the twist as exp_twist does."""
    rng = np.random.default_rng(31)
    with vm.World.from_mjcf(_spheres_mjcf(tmp_path / "s.xml"), camera="eye", width=64, height=48) as world:
        assert world.free_camera
        for _ in range(5):
            pose = vsinv.geometry.pose_from_position_thetau(rng.normal(size=3), rng.uniform(-2, 2, size=3))
            world.render(pose)
            R = world.data.cam_xmat[world.camera_id].reshape(3, 3)
            np.testing.assert_allclose(R, pose[:3, :3] @ np.diag([1, -1, -1]), atol=1e-9)
            np.testing.assert_allclose(world.camera_pose(), pose, atol=1e-9)
            twist = rng.normal(size=6) * 0.2
            moved = world.move_camera(twist, 0.5)
            np.testing.assert_allclose(moved, pose @ vsinv.geometry.exp_twist(twist, 0.5), atol=1e-12)
            np.testing.assert_allclose(world.camera_pose(), moved, atol=1e-9)
            # vz moves MuJoCo's camera along its -z (where it looks)
            before = world.camera_pose()
            world.move_camera([0, 0, 0.1, 0, 0, 0], 1.0)
            mujoco.mj_kinematics(world.model, world.data)
            R = world.data.cam_xmat[world.camera_id].reshape(3, 3)
            np.testing.assert_allclose(world.camera_pose()[:3, 3] - before[:3, 3], -0.1 * R[:, 2], atol=1e-9)


def test_from_mjcf_with_a_camera_on_a_moving_body(tmp_path: Path) -> None:
    """A user's arm-like MJCF: the camera on a hinged link follows the joint; the target body is
    named; render(pose) is refused for a carried camera; wrong names are refused by name."""
    path = tmp_path / "arm.xml"
    path.write_text(
        """<mujoco><visual><headlight ambient="0.6 0.6 0.6"/></visual><worldbody>
        <body name="target" pos="0 0 -1"><geom type="box" size="0.1 0.1 0.01" rgba="1 1 1 1"/></body>
        <body name="link"><joint name="pan" type="hinge" axis="0 1 0"/>
          <geom type="capsule" fromto="0 0 0 0 0 0.1" size="0.02" mass="0.5"/>
          <camera name="wrist" pos="0 0 0" fovy="50"/></body>
        </worldbody></mujoco>"""
    )
    with pytest.raises(vsinv.InvalidInput, match="camera"):
        vm.World.from_mjcf(path, camera="nope")
    with pytest.raises(vsinv.InvalidInput, match="target_bodies"):
        vm.World.from_mjcf(path, camera="wrist", target_bodies=("table",))
    with vm.World.from_mjcf(path, camera="wrist", width=160, height=120, target_bodies=("target",)) as world:
        assert not world.free_camera
        image = world.render()
        # MuJoCo's camera looks down its -z, at the target: the white box fills the image centre.
        assert image[50:70, 70:90].min() > 100, image[50:70, 70:90]
        px, z = world.project([[0.0, 0.0, -1.0]])
        np.testing.assert_allclose(px[0], [79.5, 59.5], atol=1e-9)
        assert z[0] == pytest.approx(1.0)
        world.data.qpos[0] = 0.6  # turn the link: the camera follows, the box leaves the centre
        turned = world.camera_pose()
        np.testing.assert_allclose(np.degrees(np.arccos(turned[:3, :3] @ [0, 0, 1] @ [0, 0, -1])), np.degrees(0.6), atol=1e-6)
        assert world.render()[50:70, 70:90].max() < image[50:70, 70:90].min()
        with pytest.raises(vsinv.InvalidInput, match="carried"):
            world.render(np.eye(4))


@pytest.mark.parametrize("name", ["lens-12-6", "tags-12-6"])
def test_world_from_a_builtin_renders_its_target(name: str) -> None:
    """The scenario's target in MuJoCo at F* with [reference_camera]'s K is where vsinv's own
    renderer draws it: dots' centroids within 0.1 px of their projections, the tags decoded with
    the same identities and corners within 0.1 px."""
    d = vsinv.load_scenario(name).to_dict()
    r = d["reference_camera"]
    drawn, pixels, _ = vsinv.vision.render_view(name, reference=True)
    with vm.World.from_scenario(name) as world:
        assert (world.width, world.height) == (832, 624)
        np.testing.assert_allclose([world.K.fku, world.K.u0], [600.0, 416.0], rtol=1e-6)  # [camera]
        world.set_K((r["fku"], r["fkv"], r["u0"], r["v0"]))
        image = world.render(np.eye(4))
    if world.target == "dots":
        found = vsinv.vision.detect_dots(image).centroids
        assert len(found) == len(pixels)
        gap = np.linalg.norm(found[:, None] - pixels[None], axis=2).min(axis=0)
        assert gap.max() < 0.1, gap
    else:
        ours, theirs = vsinv.vision.detect_tags(image), vsinv.vision.detect_tags(drawn)
        assert list(ours.ids) == list(theirs.ids) == [1, 2, 3]
        gap = np.linalg.norm(np.asarray(ours.corners) - np.asarray(theirs.corners), axis=2)
        assert gap.max() < 0.1, gap


def test_bad_arguments_are_refused(tmp_path: Path) -> None:
    with pytest.raises(vsinv.InvalidInput, match="path"):
        vm.World.from_mjcf(tmp_path / "missing.xml", camera="eye")
    with vm.World.from_mjcf(_spheres_mjcf(tmp_path / "s.xml"), camera="eye", width=32, height=24) as world:
        with pytest.raises(vsinv.InvalidInput, match="K"):
            world.set_K((-1.0, 100.0, 10.0, 10.0))
        with pytest.raises(vsinv.InvalidInput, match="pose"):
            world.render(np.full((4, 4), np.nan))
    with pytest.raises(vsinv.InvalidInput, match="supersample"):
        vm.World.from_scenario("lens-12-6", supersample=9)


def test_hostile_mjcf_files_and_sizes_are_refused(tmp_path: Path) -> None:
    """A file that is not MJCF, one too large, a FIFO, and image sizes past the bound: each an
    InvalidInput naming the argument, the file's text never in the message."""
    bad = tmp_path / "bad.xml"
    bad.write_text("<mujoco><worldbody><body name='SECRET-TEXT'><geom size='x'/></body></mujoco>")
    with pytest.raises(vsinv.InvalidInput, match="^path: MuJoCo could not load") as err:
        vm.World.from_mjcf(bad, camera="eye")
    assert "SECRET" not in str(err.value)
    huge = tmp_path / "huge.xml"
    with huge.open("wb") as f:
        f.truncate(vm.MAX_MJCF_BYTES + 1)
    with pytest.raises(vsinv.InvalidInput, match="^path: .* is larger than 16 MiB"):
        vm.World.from_mjcf(huge, camera="eye")
    fifo = tmp_path / "fifo.xml"
    os.mkfifo(fifo)
    with pytest.raises(vsinv.InvalidInput, match="^path: no MJCF file"):
        vm.World.from_mjcf(fifo, camera="eye")
    spheres = _spheres_mjcf(tmp_path / "s.xml")
    for size in [(100_000, 480), (640, 0), (640.5, 480), (True, 480)]:
        with pytest.raises(vsinv.InvalidInput, match="^width, height: expected"):
            vm.World.from_mjcf(spheres, camera="eye", width=size[0], height=size[1])


# -- the closed loop -------------------------------------------------------------------------
# The lens change of sec. 5.2 (12 mm -> 6 mm, K_hat off) from the paper's start (290 mm, 80
# degrees) and two others, with the requirement as the stop tolerance. The invariant
# law's frames are rendered 2 x 2 supersampled (a sensor's pixel integrates light over its
# area): with MuJoCo's own pixels (4 samples each) the runs end 0.2-0.9 mm from F* but the
# detections of the two lenses disagree too much for the images to certify 1 mm (`settled`).
GOAL_MM, GOAL_DEG = 1.0, 0.2
STARTS = [
    None,  # the scenario's [start]
    ([-0.1, 0.05, -0.12], [5.0, -10.0, -45.0]),  # every dot 20 px or more inside the image
    ([0.1, -0.05, -0.1], [-5.0, 8.0, 50.0]),
]


def _lens_change() -> dict:
    d = vsinv.load_scenario("lens-12-6").to_dict()
    d["stop"]["max_translation_uncertainty"] = GOAL_MM * 1e-3
    d["stop"]["max_rotation_uncertainty_deg"] = GOAL_DEG
    return d


def _start(s) -> np.ndarray:
    if s is None:
        s = (vsinv.load_scenario("lens-12-6").to_dict()["start"][k] for k in ("position", "rotation_deg"))
    position, rotation_deg = s
    return vsinv.geometry.pose_from_position_thetau(position, np.radians(rotation_deg))


def _runs(law: str, supersample: int) -> list[vm.MujocoRun]:
    d = _lens_change()
    with vm.World.from_scenario(d, supersample=supersample) as world:
        return [vm.run_loop(d, law=law, world=world, start=None if s is None else _start(s)) for s in STARTS]


def _table(runs: list[vm.MujocoRun]) -> str:
    return "\n".join(
        f"{r.summary['status']:10} {r.summary['iterations']:4d} it {1e3 * r.summary['final_translation_error']:8.3f} mm "
        f"{np.degrees(r.summary['final_rotation_error']):7.3f} deg ({r.summary['message']})" for r in runs
    )


def test_the_lens_change_converges_through_mujoco_images() -> None:
    """From three starts the invariant law ends `converged` within 1 mm and 0.2 degrees of F*
    (the truth is the scene's pose); the summary has RunResult.summary's keys."""
    runs = _runs("invariant", supersample=2)
    table = _table(runs)
    print(table)
    keys = set(vsinv.run_scenario("lens-12-6", record=False).summary)
    for r, s in zip(runs, STARTS):
        np.testing.assert_allclose(r.pose[0], _start(s), atol=1e-12)  # recorded from the start
        assert keys <= set(r.summary), keys - set(r.summary)
        assert r.summary["status"] == "converged", table
        assert 1e3 * r.summary["final_translation_error"] < GOAL_MM, table
        assert np.degrees(r.summary["final_rotation_error"]) < GOAL_DEG, table
        assert r.pose.shape == (r.summary["iterations"] + 1, 4, 4) and r.found.all()


def test_ibvs_never_claims_converged_on_the_lens_change() -> None:
    """IBVS matches pixels of another lens: it ends far from F* and never says `converged`."""
    runs = _runs("ibvs", supersample=1)
    table = _table(runs)
    print(table)
    assert all(r.summary["status"] != "converged" for r in runs), table
    assert min(r.summary["final_translation_error"] for r in runs) > 0.01, table



def test_a_zoom_during_the_servo_changes_the_rendered_K() -> None:
    """zoom-servo (12 mm -> 7 mm over the first 6 s, K_hat fixed): each frame is rendered with
    the scenario's K(t) (piecewise linear in time, as the simulator's) and the invariant law
    still converges (the scenario's 5 mm tolerance: MuJoCo's own pixels certify about 1-1.6 mm)
    and ends within 1 mm and 0.2 degrees of F*."""
    d = vsinv.load_scenario("zoom-servo").to_dict()
    zoom = d["camera"]["zoom"]
    run = vm.run_loop(d)
    s = run.summary
    expected = np.interp(run.time, zoom["times"], zoom["fku"])
    np.testing.assert_allclose(run.K[:, 0], expected, rtol=1e-6)
    assert run.K[0, 0] == pytest.approx(1200.0) and run.K[-1, 0] == pytest.approx(700.0)  # the run outlasts the zoom
    assert s["status"] == "converged", s["message"]
    assert 1e3 * s["final_translation_error"] < GOAL_MM and np.degrees(s["final_rotation_error"]) < GOAL_DEG, s


# -- an arm with mass (issue 31, item 2) --------------------------------------------------------
def _ur5(tmp_path: Path) -> Path:
    path = tmp_path / "ur5.xml"
    path.write_text(vm.ur5_mjcf())
    return path


def _site_pose(model, data, name: str) -> np.ndarray:
    s = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, name)
    pose = np.eye(4)
    pose[:3, :3] = data.site_xmat[s].reshape(3, 3)
    pose[:3, 3] = data.site_xpos[s]
    return pose


def test_the_ur5_with_mass_has_vsinvs_kinematics(tmp_path: Path) -> None:
    """MuJoCo's UR5: the flange site is vsinv.kinematics.fk("ur5", q) (vsinv's URDF through its
    own kinematics), MuJoCo's site Jacobian (mj_jacSite) is the finite difference of vsinv's fk,
    the wrist camera's vsinv frame is the flange's; every link has its published mass."""
    world = vm.World.from_mjcf(_ur5(tmp_path), camera="wrist", width=64, height=48)
    m, d = world.model, world.data
    np.testing.assert_allclose(m.body_mass[1:], [3.7, 8.393, 2.33, 1.219, 1.219, 0.1879])
    s = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "flange")
    rng = np.random.default_rng(2)
    for _ in range(5):
        q = rng.uniform(-3, 3, 6)
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        fk = vsinv.kinematics.fk("ur5", q)
        np.testing.assert_allclose(_site_pose(m, d, "flange"), fk, atol=1e-12)
        np.testing.assert_allclose(world.camera_pose(), fk, atol=1e-9)
        jp, jr = np.zeros((3, 6)), np.zeros((3, 6))
        mujoco.mj_jacSite(m, d, jp, jr, s)
        h = 1e-6
        for i in range(6):
            dq = np.zeros(6)
            dq[i] = h
            plus, minus = vsinv.kinematics.fk("ur5", q + dq), vsinv.kinematics.fk("ur5", q - dq)
            np.testing.assert_allclose(jp[:, i], (plus[:3, 3] - minus[:3, 3]) / (2 * h), atol=1e-8)
            skew = (plus[:3, :3] - minus[:3, :3]) / (2 * h) @ fk[:3, :3].T  # d R R^T = [w]x
            np.testing.assert_allclose(jr[:, i], [skew[2, 1], skew[0, 2], skew[1, 0]], atol=1e-8)
    world.close()


def test_the_ur5s_velocity_actuators_track_under_gravity(tmp_path: Path) -> None:
    """Gravity on, 500 Hz physics: with zero commands the arm holds its pose; commanded joint
    velocities are reached within 2 % in 0.1 s; a command above the speed limit is clipped and
    the torques stay within the effort limits."""
    model = mujoco.MjModel.from_xml_path(str(_ur5(tmp_path)))
    data = mujoco.MjData(model)
    assert model.opt.timestep == pytest.approx(0.002) and model.opt.gravity[2] == pytest.approx(-9.81)
    q0 = np.array([0.3, -1.2, 1.4, -0.5, 0.8, 0.1])
    data.qpos[:] = q0
    for _ in range(500):  # one second holding still
        mujoco.mj_step(model, data)
    assert np.abs(data.qpos - q0).max() < 1e-3, data.qpos - q0
    command = np.array([0.4, -0.3, 0.5, 0.8, -0.6, 1.0])
    data.ctrl[:] = command
    for _ in range(50):
        mujoco.mj_step(model, data)
    np.testing.assert_allclose(data.qvel, command, rtol=0.02, atol=0.005)
    data.ctrl[:] = 10.0
    mujoco.mj_step(model, data)
    assert (np.abs(data.actuator_force) <= [150.0] * 3 + [28.0] * 3).all(), data.actuator_force
    for _ in range(200):
        mujoco.mj_step(model, data)
    # ctrl is clipped to the speed limit; the arm's coupling moves a joint up to 1 % past it
    assert 3.0 < data.qvel.min() and data.qvel.max() < 3.15 * 1.02, data.qvel


Q_GOAL = np.array([0.3, -1.2, 1.4, -0.5, 0.8, 0.1])
# Dots in the wrist camera's frame at the goal (metres): spread and with relief (0.3-0.6 m
# ahead), so that the invariants fix the pose well (flat or shallow targets leave it weakly seen).
DOTS_AT_GOAL = np.array([[-0.12, -0.09, 0.40], [0.1, -0.1, 0.32], [0.14, 0.09, 0.55], [-0.1, 0.1, 0.34],
                         [0.0, -0.03, 0.6], [-0.16, 0.01, 0.5], [0.06, 0.14, 0.45], [0.16, -0.01, 0.36]])


def _ur5_with_dots(tmp_path: Path) -> tuple[Path, np.ndarray]:
    goal = vsinv.kinematics.fk("ur5", Q_GOAL)
    world_dots = (np.c_[DOTS_AT_GOAL, np.ones(len(DOTS_AT_GOAL))] @ goal.T)[:, :3]
    spheres = "".join(
        f'<geom type="sphere" size="0.008" pos="{x} {y} {z}" rgba="1 1 1 1" contype="0" conaffinity="0"/>' for x, y, z in world_dots
    )
    xml = vm.ur5_mjcf(camera_fovy=55.0).replace("</worldbody>", spheres + "</worldbody>")
    xml = xml.replace("<worldbody>", '<visual><headlight ambient="0.5 0.5 0.5" diffuse="0.4 0.4 0.4"/></visual><worldbody>', 1)
    path = tmp_path / "ur5-dots.xml"
    path.write_text(xml)
    return path, world_dots


def test_the_ur5_with_mass_servoes_through_its_wrist_camera(tmp_path: Path) -> None:
    """Eye-in-hand with physics: the UR5 (gravity, 500 Hz, velocity actuators) carries the wrist
    camera; each 25 Hz frame MuJoCo renders goes through ImageServo, its twist through mj_jacSite
    and the arm's damped least squares (joint_velocities) to the actuators. From a start 0.04-0.08
    rad per joint away the arm ends `converged` (the images certify about 1.1 mm and 0.16 degrees,
    within the default 5 mm and 0.5 degrees) with the flange within 1 mm and 0.2 degrees of its
    pose at the reference image (vsinv's fk of the final joints against the goal's)."""
    path, world_dots = _ur5_with_dots(tmp_path)
    with vm.World.from_mjcf(path, camera="wrist", width=640, height=480) as world:
        m, d = world.model, world.data
        d.qpos[:] = Q_GOAL
        reference = world.render()
        ref_px, depths = world.project(world_dots)
        d.qpos[:] = Q_GOAL + np.array([0.05, -0.04, 0.06, 0.05, -0.05, 0.08])
        first_px, _ = world.project(world_dots)
        assert (first_px > 15).all() and (first_px < [625, 465]).all(), first_px
        k = world.K
        K_hat = vsinv.Intrinsics(k.fku * 1.15, k.fkv * 0.9, k.u0 + 6, k.v0 - 4)
        servo = vsinv.ImageServo(reference, "dots", K_hat, reference_points=ref_px, first_points=first_px,
                                 reference_depths=depths, gain=1.0, dt=0.04, stop={"max_iterations": 400})
        steps_per_frame = round(0.04 / m.opt.timestep)
        assert steps_per_frame == 20
        while True:
            step = servo.step(world.render())
            if not step.running:
                break
            d.ctrl[:] = vm.joint_velocities(m, d, "flange", step.twist)
            for _ in range(steps_per_frame):
                mujoco.mj_step(m, d)
        d.ctrl[:] = 0.0
        mm, deg = _pose_error(vsinv.kinematics.fk("ur5", d.qpos.copy()), vsinv.kinematics.fk("ur5", Q_GOAL))
        print(f"{step.verdict} after {servo.iterations} frames: {mm:.3f} mm, {deg:.4f} deg ({step.reason})")
        assert step.verdict == "converged", step.reason
        assert mm < GOAL_MM and deg < GOAL_DEG, (mm, deg)


def _pose_error(pose: np.ndarray, goal: np.ndarray) -> tuple[float, float]:
    delta = np.linalg.inv(goal) @ pose
    angle = np.arccos(np.clip((np.trace(delta[:3, :3]) - 1.0) / 2.0, -1.0, 1.0))
    return 1e3 * float(np.linalg.norm(delta[:3, 3])), float(np.degrees(angle))
