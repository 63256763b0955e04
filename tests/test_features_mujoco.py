"""The keypoint target through images nobody here drew (issue 32, item 2): MuJoCo renders a box
carrying photographs from ViSP's image data on three faces (`feature_world.TexturedBox`, a
non-planar object); the reference image is taken with one lens (f = 1200 px) and the servo camera
has another (f = 600 px, K_hat 20 % off); `vsinv.ImageServo(reference, "features", K_hat)` servoes
with no marker and no click. Here: the matches across the lens change against the scene's truth,
and the closed loop through these images from ten starts, and through the project's renderer's
images of the same box.

The truth: each matched pixel of the reference image is cast onto the box (the scene's geometry)
and projected into the frame; the final camera pose against the reference pose.
"""

from __future__ import annotations


import numpy as np
import pytest

import feature_world as fw

_WHY_NOT = fw.available()
if _WHY_NOT is not None:
    pytest.skip(_WHY_NOT, allow_module_level=True)

import mujoco_world as mw  # noqa: E402
import vsinv  # noqa: E402

F_REFERENCE, F_SERVO = 1200.0, 600.0
WIDTH, HEIGHT = 640, 480
FOVY_REFERENCE = float(np.degrees(2 * np.arctan(0.5 * HEIGHT / F_REFERENCE)))
FOVY_SERVO = float(np.degrees(2 * np.arctan(0.5 * HEIGHT / F_SERVO)))
REFERENCE_POSE = mw.look_at((0.54, 0.45, 0.54), (0.0, 0.0, 0.0))
DISTANCE = float(np.linalg.norm(REFERENCE_POSE[:3, 3]))
K_HAT = vsinv.Intrinsics(1.2 * F_SERVO, 1.2 * F_SERVO, (WIDTH - 1) / 2 + 10.0, (HEIGHT - 1) / 2 - 8.0)
GOAL_MM, GOAL_DEG = 2.0, 0.3
# A match farther than this from the pixel the scene's geometry gives is a wrong match (another
# scene point), not an imprecise one.
WRONG_PX = 4.0
SESSION = {
    "gain": 2.0,
    "dt": 0.04,
    "stop": {"max_iterations": 300, "max_translation_uncertainty": 0.5e-3, "max_rotation_uncertainty_deg": 0.1},
}
CORNERS = np.array([[x, y, z] for x in (-mw.HALF, mw.HALF) for y in (-mw.HALF, mw.HALF) for z in (-mw.HALF, mw.HALF)])


@pytest.fixture(scope="module")
def world():
    w = fw.TexturedBox(WIDTH, HEIGHT)
    yield w
    w.close()


@pytest.fixture(scope="module")
def reference(world: fw.TexturedBox) -> np.ndarray:
    return world.render(REFERENCE_POSE, FOVY_REFERENCE)


def start_poses(world: fw.TexturedBox, count: int, seed: int = 32) -> list[np.ndarray]:
    """`count` start poses 3-6 cm and 4-10 degrees from the reference pose, the whole box in view."""
    rng = np.random.default_rng(seed)
    K = world.intrinsics(FOVY_SERVO)
    poses: list[np.ndarray] = []
    while len(poses) < count:
        t = rng.normal(size=3)
        t *= rng.uniform(0.03, 0.06) / np.linalg.norm(t)
        w = rng.normal(size=3)
        w *= np.radians(rng.uniform(4.0, 10.0)) / np.linalg.norm(w)
        pose = REFERENCE_POSE @ vsinv.geometry.pose_from_position_thetau(t, w)
        px, z = mw.project(pose, K, CORNERS)
        if (z > 0.1).all() and (px > 20).all() and (px[:, 0] < WIDTH - 21).all() and (px[:, 1] < HEIGHT - 21).all():
            poses.append(pose)
    return poses


def true_pixels(world: fw.TexturedBox, reference_pixels: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """Where the scene points seen at `reference_pixels` in the reference image are in the frame seen from `pose`."""
    points = world.surface_point(REFERENCE_POSE, FOVY_REFERENCE, reference_pixels)
    px, _ = mw.project(pose, world.intrinsics(FOVY_SERVO), points)
    return px


def test_matches_across_the_lens_change_are_true(world: fw.TexturedBox, reference: np.ndarray) -> None:
    """Matches between the reference image (f = 1200) and a frame of another lens (f = 600) from
    other poses: many, and none far from where the scene's geometry puts it."""
    rows = []
    for k, pose in enumerate(start_poses(world, 4)):
        frame = world.render(pose, FOVY_SERVO)
        ref_px, px = vsinv.vision.match_features(reference, frame)
        error = np.linalg.norm(px - true_pixels(world, ref_px, pose), axis=1)
        rows.append((k, len(px), float(np.median(error)), int((error > 2.0).sum()), int((error > WRONG_PX).sum())))
    print("\n".join(f"start {k}: {n} matches, median error {med:.3f} px, {far} beyond 2 px, {wrong} wrong (beyond {WRONG_PX} px)"
                    for k, n, med, far, wrong in rows))
    for k, n, med, far, wrong in rows:
        assert n >= 40, rows
        assert med < 0.6, rows
        assert far <= max(3, n // 40), rows  # SIFT's position at the other scale: a few at 2-2.5 px
        assert wrong == 0, rows


def settle_from_starts(world: fw.TexturedBox | fw.RenderedBox, starts: list[int], max_iterations: int = 800) -> list[tuple]:
    """The session through `world`'s images from each of `starts` (of `start_poses`; the reference
    depths from the scene): per start its verdict, images, final pose error (mm, degrees) and the
    points ever reported found farther than WRONG_PX from their true pixels."""
    reference = world.render(REFERENCE_POSE, FOVY_REFERENCE)
    session = {**SESSION, "stop": {**SESSION["stop"], "max_iterations": max_iterations}}
    reference_pixels = vsinv.ImageServo(reference, "features", K_HAT, depths="per_step").reference_pixels
    points = world.surface_point(REFERENCE_POSE, FOVY_REFERENCE, reference_pixels)
    _, z = mw.project(REFERENCE_POSE, world.intrinsics(FOVY_REFERENCE), points)
    K = world.intrinsics(FOVY_SERVO)
    rows = []
    poses = start_poses(world, max(starts) + 1)
    for k in starts:
        pose = poses[k]
        servo = vsinv.ImageServo(reference, "features", K_HAT, law="invariant", reference_depths=z, **session)
        wrong = 0
        while True:
            step = servo.step(world.render(pose, FOVY_SERVO))
            truth, _ = mw.project(pose, K, points)
            wrong += int((np.linalg.norm(step.pixels[step.found] - truth[step.found], axis=1) > WRONG_PX).sum())
            if not step.running:
                break
            pose = pose @ vsinv.geometry.exp_twist(step.twist, session["dt"])
        mm, deg = mw.pose_error(pose, REFERENCE_POSE)
        rows.append((k, step.verdict, servo.iterations, round(mm, 3), round(deg, 3), wrong))
    return rows


@pytest.mark.slow
def test_the_closed_loop_settles_within_the_goal_from_ten_starts(world: fw.TexturedBox) -> None:
    """From each of ten starts 3-6 cm and 4-10 degrees off, the session through MuJoCo's images ends
    `settled` within GOAL_MM and GOAL_DEG of the reference pose, and no point is ever reported
    found farther than WRONG_PX from its true pixel."""
    rows = settle_from_starts(world, list(range(10)))
    assert all(verdict == "settled" and mm < GOAL_MM and deg < GOAL_DEG and wrong == 0 for _, verdict, _, mm, deg, wrong in rows), rows


@pytest.mark.slow
def test_the_closed_loop_settles_within_the_goal_in_the_projects_renderer() -> None:
    """Starts 0 and 6 (the two that took the most images in the bench's ten) through the project's
    renderer's images of the same box (`feature_world.RenderedBox`: a PSF of 0.8 px and noise in
    every image, each in its own pixels, so the servo camera's images are twice as blurred as the
    reference in the reference's pixels: the keypoint target measures that blur on its first frame
    and blurs the reference to match). The renderer takes about 0.5 s an image here, so the ten
    starts are the bench's (`benches/features_mujoco.py --renderer`); the noise keeps the stall
    rule waiting longer than in MuJoCo, hence 1600 images at most."""
    rows = settle_from_starts(fw.RenderedBox(WIDTH, HEIGHT), [0, 6], max_iterations=1600)
    assert all(verdict == "settled" and mm < GOAL_MM and deg < GOAL_DEG and wrong == 0 for _, verdict, _, mm, deg, wrong in rows), rows
