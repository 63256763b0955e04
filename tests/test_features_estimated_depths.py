"""The keypoint loop with no depth from the scene (issue 32, item 1: "depths from the paper's
appendix A when the reference depths are unknown, which is the normal case for a natural
object"): MuJoCo's textured box (`feature_world`), the reference image with f = 1200 px, the servo
camera f = 600 px and K_hat 20 % off. At the start the camera makes a 3 cm pure translation; the
features target's points tracked across it give their depths up to scale by eq. (26)
(`depths_from_translation` with `pixel_noise`), `ResectionDepths` gives the current depths at
every step, and `ImageServo` servoes from where the translation ended, as a user without a depth
sensor or a model would. The truth: each point's scene point (its reference pixel's ray on the box)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

import feature_world as fw

_WHY_NOT = fw.available()
if _WHY_NOT is not None:
    pytest.skip(_WHY_NOT, allow_module_level=True)

import mujoco_world as mw  # noqa: E402
import test_features_mujoco as scene  # noqa: E402
import vsinv  # noqa: E402

# The features target's tracks: sigma about 0.1 px per coordinate (tests/test_robust_depth_mujoco.py).
PIXEL_NOISE = 0.1
STEP = 0.03


@dataclass
class TranslationPair:
    """The points tracked across the translation and what appendix A made of them."""

    ids: np.ndarray  # the features target's identities of the points tracked in both frames
    first: np.ndarray  # their pixels in the first frame (n, 2)
    reference: np.ndarray  # their pixels in the reference image (n, 2)
    depths: np.ndarray  # eq. (26) up to scale, NaN where not usable
    residual: float
    estimator: vsinv.calibration.ResectionDepths
    pose: np.ndarray  # the first frame's camera pose
    moved: np.ndarray  # the camera pose after the translation

    def depth_errors(self, world: fw.TexturedBox) -> np.ndarray:
        """Each usable depth's relative error against the scene's depth in the first frame, up to
        the depths' common scale (the median ratio)."""
        points = world.surface_point(self.pose, scene.FOVY_SERVO, self.first)
        _, z = mw.project(self.pose, world.intrinsics(scene.FOVY_SERVO), points)
        usable = np.isfinite(self.depths) & np.isfinite(z)
        scale = np.median(z[usable] / self.depths[usable])
        return np.abs(self.depths[usable] * scale / z[usable] - 1)


def translation_pair(world: fw.TexturedBox, reference: np.ndarray, pose: np.ndarray) -> TranslationPair:
    """The camera at `pose` and after a 3 cm translation (a direction drawn from the pose): the
    features target's points found in both frames and their depths by appendix A. The frames are
    read by a probe session of the same target (its twists are not applied), so the pixels are
    those the servo's tracking gives."""
    probe = vsinv.ImageServo(reference, "features", scene.K_HAT, law="ibvs", depths=1.0)
    a = probe.step(world.render(pose, scene.FOVY_SERVO))
    d = np.random.default_rng(int(1e6 * abs(pose[0, 3]))).normal(size=3)
    moved = pose.copy()
    moved[:3, 3] += pose[:3, :3] @ (d * STEP / np.linalg.norm(d))
    b = probe.step(world.render(moved, scene.FOVY_SERVO))
    both = a.found & b.found
    depths, _, residual = vsinv.calibration.depths_from_translation(a.pixels[both], b.pixels[both], pixel_noise=PIXEL_NOISE)
    reference_pixels = probe.reference_pixels[both]
    estimator = vsinv.calibration.ResectionDepths(a.pixels[both], depths, reference_pixels)
    return TranslationPair(probe.ids[both], a.pixels[both], reference_pixels, depths, residual, estimator, pose, moved)


@pytest.fixture(scope="module")
def world():
    w = fw.TexturedBox(scene.WIDTH, scene.HEIGHT)
    yield w
    w.close()


def servo_from(world: fw.TexturedBox, reference: np.ndarray, pose: np.ndarray, **depths) -> tuple[str, float, float]:
    """The keypoint loop from `pose` (at most 300 iterations): its verdict and final pose error (mm, deg)."""
    servo = vsinv.ImageServo(reference, "features", scene.K_HAT, law="invariant", **depths, **scene.SESSION)
    while (step := servo.step(world.render(pose, scene.FOVY_SERVO))).running:
        pose = pose @ vsinv.geometry.exp_twist(step.twist, scene.SESSION["dt"])
    mm, deg = mw.pose_error(pose, scene.REFERENCE_POSE)
    return step.verdict, mm, deg


@pytest.mark.slow
def test_the_keypoint_loop_with_depths_from_appendix_a_ends_where_scene_depths_do(world: fw.TexturedBox) -> None:
    """Eq. (26) over a 3 cm translation: most tracked points usable, each usable depth within 5 %
    of the truth (up to scale); the loop on `ResectionDepths` from where the translation ended
    settles as near the reference pose as the same loop given the scene's reference depths of
    the same points (within 1.5 mm and 0.15 degrees of it)."""
    reference = world.render(scene.REFERENCE_POSE, scene.FOVY_REFERENCE)
    pair = translation_pair(world, reference, scene.start_poses(world, 1)[0])
    errors = pair.depth_errors(world)
    usable = int(np.isfinite(pair.depths).sum())
    estimated = servo_from(world, reference, pair.moved, depths=pair.estimator, point_ids=pair.ids.tolist())
    points = world.surface_point(scene.REFERENCE_POSE, scene.FOVY_REFERENCE, pair.reference)
    _, z = mw.project(scene.REFERENCE_POSE, world.intrinsics(scene.FOVY_REFERENCE), points)
    given = servo_from(world, reference, pair.moved, reference_depths=z, point_ids=pair.ids.tolist())
    print(f"{usable} usable of {len(pair.ids)}; depth error median {np.median(errors):.4f}, max {errors.max():.4f}; "
          f"estimated: {estimated}; scene depths: {given}")
    assert usable >= 0.8 * len(pair.ids) and len(pair.ids) >= 60
    assert errors.max() < 0.05
    assert estimated[0] in ("settled", "converged")
    assert abs(estimated[1] - given[1]) < 1.5 and abs(estimated[2] - given[2]) < 0.15

