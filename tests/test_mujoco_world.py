"""A world vsinv did not draw (issue 27, item 5): MuJoCo renders a box with white dots (flat
discs and shaded spheres) or AprilTags (OpenCV's drawing as textures) on three faces, lit by
MuJoCo's lights; a free camera is servoed by `vsinv.ImageServo` from those images, reference
with a 45 degree field of view, servo with 60 degrees, K_hat 30 % off, from ten starts; the
scene's poses are the truth.

Skips (saying what to install) when mujoco or an EGL/OpenGL stack is missing. MuJoCo renders on
the CPU through EGL (Mesa's llvmpipe): MUJOCO_GL=egl is set before mujoco is imported.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import mujoco_world as mw  # noqa: E402

_WHY_NOT = mw.available()
if _WHY_NOT is not None:
    pytest.skip(_WHY_NOT, allow_module_level=True)

cv2 = pytest.importorskip("cv2", reason="the tag textures are OpenCV's drawings: pip install opencv-python-headless")

import mujoco  # noqa: E402

import mujoco_servo as ms  # noqa: E402
import vsinv  # noqa: E402

LENS = ms.Lens()  # 45 -> 60 degrees, K_hat 30 % off
# Each pixel is the mean of a 3 x 3 block of MuJoCo's pixels, as a sensor's pixel integrates
# light over its area. MuJoCo's own pixels (4 samples: edge coverage in quarters) move a small
# dot's centroid by 0.02-0.04 px differently at each lens; the dots' runs then settle 0.4-1.1 mm
# from the goal with 3.4-5.1 mm allowed (`settled`), benches/lens_change_accuracy.py.
SUPERSAMPLE = 3
STARTS = 10
# The requirement: `converged` within 1 mm and 0.2 degrees of the goal.
GOAL_MM, GOAL_DEG = 1.0, 0.2
SESSION = {
    "gain": 2.5,
    "dt": 0.04,
    # The stall rule looks back over 50 images once the error stops decreasing (70-110
    # iterations here): 300 leaves room for both.
    "stop": {"max_iterations": 300, "max_translation_uncertainty": GOAL_MM * 1e-3, "max_rotation_uncertainty_deg": GOAL_DEG},
}
# IBVS is given fewer iterations: it reaches its own (wrong) equilibrium well within them.
IBVS_SESSION = {**SESSION, "stop": {**SESSION["stop"], "max_iterations": 120}}


@pytest.fixture(scope="module", params=["dots", "tags"])
def world(request: pytest.FixtureRequest):
    w = mw.BoxWorld(request.param, width=400, height=300, supersample=SUPERSAMPLE)
    yield w
    w.close()


def _spheres_world(points: np.ndarray, width: int, height: int):
    geoms = "".join(f'<geom type="sphere" size="0.004" pos="{mw._v(p)}" rgba="1 1 1 1"/>' for p in points)
    xml = f"""<mujoco><visual><global offwidth="{width}" offheight="{height}"/>
      <headlight ambient="1 1 1" diffuse="0 0 0" specular="0 0 0"/></visual>
      <worldbody>{geoms}<camera name="eye" pos="1 1 1"/></worldbody></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    return model, mujoco.MjData(model), mujoco.Renderer(model, height, width)


def test_mujoco_camera_sees_what_vsinvs_pinhole_predicts() -> None:
    """Small spheres at known points, rendered by MuJoCo from vsinv poses (x right, y down, z
    forward) with several fields of view: their centroids are where the pinhole model with
    f = (H / 2) / tan(fovy / 2) and the centre at ((W - 1) / 2, (H - 1) / 2) puts them."""
    points = np.array([[0, 0, 0], [0.08, 0.03, 0.02], [-0.06, 0.05, -0.04], [0.02, -0.07, 0.06], [-0.05, -0.04, 0.05]])
    width, height = 400, 300
    model, data, renderer = _spheres_world(points, width, height)
    residuals = []
    for eye, up, fovy in [((0.4, 0.1, 0.2), (0, 0, 1), 45.0), ((0.1, -0.45, 0.1), (0.3, 0, 1), 60.0), ((-0.3, 0.2, -0.3), (1, 1, 0), 30.0)]:
        pose = mw.look_at(eye, (0.01, 0.0, 0.005), up)
        image = mw.render_grey(model, data, renderer, pose, fovy)
        expected, _ = mw.project(pose, mw.intrinsics(fovy, width, height), points)
        weight = np.clip(image.astype(float) - 20.0, 0, None)
        count, labels = cv2.connectedComponents((image > 60).astype(np.uint8))
        assert count - 1 == len(points), (eye, count - 1)
        for label in range(1, count):
            v, u = np.nonzero(labels == label)
            w = weight[v, u]
            centroid = np.array([(u * w).sum(), (v * w).sum()]) / w.sum()
            nearest = np.linalg.norm(expected - centroid, axis=1)
            residuals.append(centroid - expected[np.argmin(nearest)])
    residuals = np.array(residuals)
    renderer.close()
    assert np.abs(residuals).max() < 0.35, residuals
    # A half-pixel convention error or a flipped axis would show as a bias.
    assert np.abs(residuals.mean(axis=0)).max() < 0.1, residuals.mean(axis=0)


def test_mujoco_camera_frame_is_vsinvs_turned_about_x() -> None:
    """MuJoCo's own camera frame (cam_xmat after kinematics) for a vsinv pose: x the same, y and z
    opposite; and a twist integrated with vsinv.geometry.exp_twist moves MuJoCo's camera along vsinv's axes."""
    model, data, renderer = _spheres_world(np.zeros((1, 3)), 64, 48)
    rng = np.random.default_rng(5)
    for _ in range(5):
        pose = vsinv.geometry.pose_from_position_thetau(rng.normal(size=3), rng.uniform(-2, 2, size=3))
        mw.render_grey(model, data, renderer, pose, 50.0)
        R = data.cam_xmat[0].reshape(3, 3).copy()
        np.testing.assert_allclose(R[:, 0], pose[:3, 0], atol=1e-9)
        np.testing.assert_allclose(R[:, 1], -pose[:3, 1], atol=1e-9)
        np.testing.assert_allclose(-R[:, 2], pose[:3, 2], atol=1e-9)  # MuJoCo looks down -z
        np.testing.assert_allclose(data.cam_xpos[0], pose[:3, 3], atol=1e-12)
        # vx: right in the image (MuJoCo's +x); vy: down (MuJoCo's -y); vz: along the view (-z)
        for axis, mj_dir in ((0, R[:, 0]), (1, -R[:, 1]), (2, -R[:, 2])):
            twist = np.zeros(6)
            twist[axis] = 0.1
            moved = pose @ vsinv.geometry.exp_twist(twist, 1.0)
            mw.render_grey(model, data, renderer, moved, 50.0)
            np.testing.assert_allclose(data.cam_xpos[0] - pose[:3, 3], 0.1 * mj_dir, atol=1e-9)
        # wz turns the camera about its optical axis: right (x) goes to down (y)
        moved = pose @ vsinv.geometry.exp_twist([0, 0, 0, 0, 0, np.pi / 2], 1.0)
        mw.render_grey(model, data, renderer, moved, 50.0)
        np.testing.assert_allclose(data.cam_xmat[0].reshape(3, 3)[:, 0], -R[:, 1], atol=1e-9)
    renderer.close()


def test_the_scene_is_what_it_says(world: mw.BoxWorld) -> None:
    """The targets are where the scene says, checked with OpenCV (an independent detector): the
    three tags decode with their identities near their projected corners; every dot is a bright
    blob near its projected centre, in the reference image and in a start image."""
    for pose, fovy in ((ms.REFERENCE_POSE, LENS.fovy_reference), (ms.start_poses(world, LENS, 1)[0], LENS.fovy_servo)):
        image = world.render(pose, fovy)
        K = world.intrinsics(fovy)
        if world.target == "tags":
            detector = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11))
            corners, ids, _ = detector.detectMarkers(image)
            assert ids is not None and sorted(ids.ravel()) == sorted(mw.TAG_IDS.values())
            truth = world.tag_corners()
            for c, i in zip(corners, ids.ravel()):
                px, _ = mw.project(pose, K, truth[int(i)])
                gap = np.linalg.norm(c[0][:, None, :] - px[None], axis=2).min(axis=1)
                assert gap.max() < 3.0, (i, gap)  # OpenCV's corners are about 1 px off (issue 27)
        else:
            count, _, _, centroids = cv2.connectedComponentsWithStats((image > 120).astype(np.uint8))
            px, _ = mw.project(pose, K, world.dot_centres())
            gap = np.linalg.norm(px[:, None, :] - centroids[None, 1:], axis=2).min(axis=1)
            flat = np.array([face not in world.sphere_faces for face in mw.FACES for _ in mw.DOT_OFFSETS])
            assert gap[flat].max() < 0.5, gap  # a disc's centroid: its centre's image within perspective bias
            assert gap[~flat].max() < 2.0, gap  # a sphere's lit part is off its centre by a pixel or so


# Lights of the lit dots: from above, and oblique from the left and behind; each without and
# with a specular highlight.
LIGHTS = [((0, 0, -1), 0.0, 0.5), ((0, 0, -1), 0.8, 0.9), ((-0.6, 0.3, -1), 0.0, 0.5), ((-0.6, 0.3, -1), 0.8, 0.9)]


@pytest.mark.parametrize(("light", "specular", "shininess"), LIGHTS, ids=["above", "above-highlight", "oblique", "oblique-highlight"])
def test_detect_dots_and_the_tracker_find_shaded_spheres_and_lit_discs(light, specular: float, shininess: float) -> None:
    """Issue 27, item 4: white spheres shaded by a directional light (their far side dim, a
    highlight on the near one) and tilted discs, rendered by MuJoCo. detect_dots finds every
    one and nothing else: a disc within 0.3 px of its centre's projection (the perspective
    bias of an ellipse's centre), a sphere within 0.35 of its radius (its weighted centroid
    leans towards the light); the DotTracker starts on every one from the projections (the
    shape check passes) and follows them while the camera moves, within half a radius."""
    width, height, fovy = 640, 480, 50.0
    model, data, renderer = mw.lit_dots(width, height, light, specular, shininess)
    K = mw.intrinsics(fovy, width, height)
    centres = np.array([c for c, _ in mw.LIT_SPHERES] + [c for c, _, _ in mw.LIT_DISCS])
    pose = mw.look_at(*mw.LIT_EYE)
    image = mw.render_grey(model, data, renderer, pose, fovy)
    truth, depth = mw.project(pose, K, centres)
    radius = np.array([r for _, r in mw.LIT_SPHERES]) * K[0] / depth[: len(mw.LIT_SPHERES)]
    spheres = slice(0, len(mw.LIT_SPHERES))
    found = vsinv.vision.detect_dots(image).centroids
    assert len(found) == len(centres), found
    gap = np.linalg.norm(found[None, :, :] - truth[:, None, :], axis=2).min(axis=1)
    assert (gap[spheres] < 0.35 * radius).all(), gap[spheres] / radius
    assert (gap[len(mw.LIT_SPHERES) :] < 0.3).all(), gap
    tracker = vsinv.vision.DotTracker(image, truth)
    for step in range(1, 6):
        moved = pose @ vsinv.geometry.pose_from_position_thetau([0.002 * step, -0.001 * step, 0.0], [0.0, 0.002 * step, 0.0])
        pixels, ok = tracker.track(mw.render_grey(model, data, renderer, moved, fovy))
        want, _ = mw.project(moved, K, centres)
        assert ok.all(), step
        miss = np.linalg.norm(pixels - want, axis=1)
        assert (miss[spheres] < 0.5 * radius).all() and (miss[len(mw.LIT_SPHERES) :] < 0.3).all(), miss
    renderer.close()


def _runs(world: mw.BoxWorld, law: str, session: dict) -> list[ms.RunEnd]:
    return [ms.run(world, LENS, law, start, k, session) for k, start in enumerate(ms.start_poses(world, LENS, STARTS))]


@pytest.mark.slow
def test_invariant_law_converges_through_mujoco_images(world: mw.BoxWorld) -> None:
    """The issue's requirement: from every start the invariant law ends `converged`, and the
    camera is within 1 mm and 0.2 degrees of the reference pose."""
    ends = _runs(world, "invariant", SESSION)
    table = "\n".join(e.row() + f" ({e.reason})" for e in ends)
    print(table)
    assert all(e.verdict == "converged" for e in ends), table
    assert all(e.error_mm < GOAL_MM and e.error_deg < GOAL_DEG for e in ends), table


@pytest.mark.slow
def test_ibvs_never_claims_converged_on_the_lens_change(world: mw.BoxWorld) -> None:
    """IBVS on the same lens change matches pixels of another lens: it ends away from the goal
    and must never say `converged`."""
    ends = _runs(world, "ibvs", IBVS_SESSION)
    table = "\n".join(e.row() + f" ({e.reason})" for e in ends)
    print(table)
    assert not any(e.claimed_converged for e in ends), table
    # The lens change is real: IBVS's end is far from the goal (so "converged" would be a lie).
    assert min(e.error_mm for e in ends) > 10.0, table
