"""A robot program's servo loop on a `vsinv.Servo` session, with no simulator: the camera's
view is computed here, with a little pixel noise, and the session decides when to stop. The
reference image was taken with a 12 mm lens, the servo camera has a 6 mm lens known only
roughly. Exits non-zero unless the session ends "converged" with the camera within the pose
uncertainty the images allowed.

    python examples/python_servo.py
"""

from __future__ import annotations

import sys

import numpy as np

import vsinv


def view(points: np.ndarray, pose: np.ndarray, k: vsinv.Intrinsics) -> tuple[np.ndarray, np.ndarray]:
    """Pixels and depths of `points` (in F*) for a camera at `pose` (camera frame in F*)."""
    rot, centre = pose[:3, :3], pose[:3, 3]
    return vsinv.geometry.project((points - centre) @ rot, k)


def main() -> int:
    relief = [0.0, 0.06, -0.04, 0.03, -0.06, 0.05, 0.02, -0.03, 0.04, -0.05, 0.01, 0.06]
    points = np.array([[-0.15 + 0.1 * (i % 4), -0.12 + 0.12 * (i // 4), 0.6 + relief[i]] for i in range(12)])
    k_star = vsinv.Intrinsics(1200, 1200, 384, 288)  # the lens of the reference image
    k = vsinv.Intrinsics(600, 600, 384, 288)  # the servo lens
    k_hat = vsinv.Intrinsics(650, 570, 395, 280)  # a rough estimate of it
    rng = np.random.default_rng(7)
    reference, z_star = view(points, np.eye(4), k_star)
    # Average the errors of the last 10 images before the stop rule reads them: the noise
    # averages out. The session certifies convergence with the pose uncertainty it measures.
    stop = {"window": 10, "invariant_error": 1e-3, "tau21": 1e-3}
    servo = vsinv.Servo(reference, k_hat, "invariant", reference_depths=z_star, stop=stop)

    pose = vsinv.geometry.exp_twist([0.08, -0.06, -0.1, 0.1, -0.15, 0.9])  # about 140 mm, 53 degrees away
    while True:
        pixels, _ = view(points, pose, k)
        step = servo.step(pixels + rng.normal(0.0, 0.03, pixels.shape))
        if not step.running:
            break
        pose = pose @ vsinv.geometry.exp_twist(step.twist * 0.04)  # the robot moves for one period
    t, r = np.linalg.norm(pose[:3, 3]), np.degrees(np.arccos(np.clip((np.trace(pose[:3, :3]) - 1) / 2, -1, 1)))
    print(f"servo session: {step.verdict} after {servo.iterations} iterations ({step.reason})")
    print(f"  final error {t * 1e3:.3f} mm, {r:.4f} deg")
    c = servo.certainty()
    if c is None:
        return 1
    print(f"  the images allowed {c['translation_bound'] * 1e3:.3f} mm, {np.degrees(c['rotation_bound']):.4f} deg")
    ok = step.verdict == "converged" and t <= c["translation_bound"] and np.radians(r) <= c["rotation_bound"]
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
