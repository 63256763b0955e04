"""The lens change closed through MuJoCo's images: `vsinv.ImageServo` sees frames of a
`mujoco_world.BoxWorld`, its twists move the free camera (pose @ exp_twist(twist, dt)), and the
scene's own poses give the truth (the final camera pose against the reference pose).

The reference image is taken with one field of view at REFERENCE_POSE, the servo camera has
another and a K_hat 30 % off; start poses are drawn around the reference pose, every target
point in view. Shared by tests/test_mujoco_world.py and benches/lens_change_accuracy.py.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

import mujoco_world as mw
import vsinv

REFERENCE_POSE = mw.look_at((0.30, 0.25, 0.30), (0.0, 0.0, 0.0))


@dataclass(frozen=True)
class Lens:
    """The lens change: reference field of view, servo field of view (vertical, degrees), and
    how far K_hat is from the servo camera's K (relative focal error, principal point offset px)."""

    fovy_reference: float = 45.0
    fovy_servo: float = 60.0
    focal_error: float = 0.30
    principal_offset: tuple[float, float] = (12.0, -9.0)

    def k_hat(self, world: mw.BoxWorld) -> vsinv.Intrinsics:
        fx, fy, cx, cy = world.intrinsics(self.fovy_servo)
        return vsinv.Intrinsics(fx * (1 + self.focal_error), fy * (1 + self.focal_error), cx + self.principal_offset[0], cy + self.principal_offset[1])


@dataclass
class RunEnd:
    """How one run ended."""

    law: str
    target: str
    start: int
    verdict: str
    reason: str | None
    iterations: int
    error_mm: float
    error_deg: float
    invariant_error: float
    frames_missing: int  # frames in which at least one point was not found
    claimed_converged: bool  # any step said "converged"
    first_within: int | None  # first iteration with the camera within 1 mm and 0.2 degrees of the goal

    def row(self) -> str:
        return (
            f"{self.target:5} {self.law:9} start {self.start:2d}: {self.verdict:15} {self.iterations:4d} it "
            f"{self.error_mm:8.3f} mm {self.error_deg:7.3f} deg  |s-s*| {self.invariant_error:.2e}  "
            f"frames missing a point {self.frames_missing}; within 1 mm, 0.2 deg from iteration {self.first_within}"
        )


def start_poses(world: mw.BoxWorld, lens: Lens, count: int, seed: int = 27) -> list[np.ndarray]:
    """`count` start poses around REFERENCE_POSE (4-8 cm away, 8-20 degrees turned), each with
    every target point at least 25 px inside the servo camera's image."""
    rng = np.random.default_rng(seed)
    K = world.intrinsics(lens.fovy_servo)
    points = world.dot_centres() if world.target == "dots" else np.concatenate(list(world.tag_corners().values()))
    poses: list[np.ndarray] = []
    while len(poses) < count:
        t = rng.normal(size=3)
        t *= rng.uniform(0.04, 0.08) / np.linalg.norm(t)
        w = rng.normal(size=3)
        w *= np.radians(rng.uniform(8.0, 20.0)) / np.linalg.norm(w)
        pose = REFERENCE_POSE @ vsinv.geometry.pose_from_position_thetau(t, w)
        px, z = mw.project(pose, K, points)
        margin = 25.0
        if (z > 0.1).all() and (px[:, 0] > margin).all() and (px[:, 0] < world.width - 1 - margin).all() and (
            px[:, 1] > margin
        ).all() and (px[:, 1] < world.height - 1 - margin).all():
            poses.append(pose)
    return poses


def pipeline(world: mw.BoxWorld, lens: Lens, law: str, start: np.ndarray, session: dict[str, Any]) -> tuple[Any, np.ndarray]:
    """The ImageServo on the reference image, and the first frame."""
    reference = world.render(REFERENCE_POSE, lens.fovy_reference)
    first = world.render(start, lens.fovy_servo)
    K_ref = world.intrinsics(lens.fovy_reference)
    args: dict[str, Any] = {"law": law, **session}
    if world.target == "dots":
        ref_px, depths = mw.project(REFERENCE_POSE, K_ref, world.dot_centres())
        start_px, _ = mw.project(start, world.intrinsics(lens.fovy_servo), world.dot_centres())
        servo = vsinv.ImageServo(reference, "dots", lens.k_hat(world), reference_points=ref_px, first_points=start_px, reference_depths=depths, **args)
    else:
        ids, depths = tag_reference_depths(world, reference, K_ref)
        servo = vsinv.ImageServo(reference, "tags", lens.k_hat(world), reference_depths=depths, **args)
        if not np.array_equal(servo.ids, ids):
            raise AssertionError(f"the session's identities {servo.ids} are not the reference tags' corners {ids}")
    return servo, first


def tag_reference_depths(world: mw.BoxWorld, reference: np.ndarray, K_ref: tuple[float, float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Identities 4 t + c of the tag corners decoded in the reference image and their true depths
    (each decoded corner matched to the nearest projected corner of its tag)."""
    tags = vsinv.vision.detect_tags(reference)
    truth = world.tag_corners()
    ids, depths = [], []
    for tag_id, corners in zip(tags.ids, tags.corners):
        px, z = mw.project(REFERENCE_POSE, K_ref, truth[int(tag_id)])
        for c, corner in enumerate(corners):
            nearest = int(np.argmin(np.linalg.norm(px - corner, axis=1)))
            ids.append(4 * int(tag_id) + c)
            depths.append(z[nearest])
    return np.array(ids, np.uint32), np.array(depths)


def run(world: mw.BoxWorld, lens: Lens, law: str, start: np.ndarray, index: int, session: dict[str, Any]) -> RunEnd:
    """One run from `start` until the session stops; how it ended, against the scene's truth."""
    servo, image = pipeline(world, lens, law, start, session)
    dt = float(session.get("dt", 0.04))
    pose, missing, claimed, within = start, 0, False, None
    while True:
        step = servo.step(image)
        missing += int(not step.found.all())
        claimed |= step.verdict == "converged"
        if not step.running:
            break
        pose = pose @ vsinv.geometry.exp_twist(step.twist, dt)
        mm, deg = mw.pose_error(pose, REFERENCE_POSE)
        if within is None and mm < 1.0 and deg < 0.2:
            within = servo.iterations
        image = world.render(pose, lens.fovy_servo)
    error_mm, error_deg = mw.pose_error(pose, REFERENCE_POSE)
    return RunEnd(
        law, world.target, index, step.verdict, step.reason, servo.iterations, error_mm, error_deg,
        float(step.telemetry["invariant_error"]), missing, claimed, within,
    )
