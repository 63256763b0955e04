"""The invariant controller in a hand-written loop (what a robot program does with vsinv):
reference image taken with a 12 mm lens, servo with a 6 mm lens and a rough estimate of it,
the camera moved by integrating the twist with the SE(3) exponential. Exits non-zero unless
the camera ends within 1 mm and 0.1 degrees of the reference pose.

    python examples/python_controller.py
"""

from __future__ import annotations

import sys

import numpy as np

import vsinv


def hat(w: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def exp_twist(twist: np.ndarray) -> np.ndarray:
    """The 4x4 rigid motion exp([v, w]) of a twist (v, w) applied for unit time."""
    v, w = twist[:3], twist[3:]
    theta, wx = np.linalg.norm(w), hat(w)
    if theta < 1e-12:
        rot, left = np.eye(3) + wx, np.eye(3) + wx / 2
    else:
        a, b = np.sin(theta) / theta, (1 - np.cos(theta)) / theta**2
        rot = np.eye(3) + a * wx + b * wx @ wx
        left = np.eye(3) + b * wx + (1 - a) / theta**2 * wx @ wx
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = rot, left @ v
    return out


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
    reference, z_star = vsinv.geometry.project(points, k_star)
    ctl = vsinv.laws.InvariantController(reference, k_hat, basis="auto")

    pose = exp_twist(np.array([0.08, -0.06, -0.1, 0.1, -0.15, 0.9]))  # about 140 mm, 53 degrees away
    dt, iterations = 0.04, 0
    while iterations < 2000:
        pixels, _ = view(points, pose, k)
        twist = ctl.step(pixels, z_star)  # reference depths, as in the paper's sec. 5.2
        if ctl.converged(invariant_tol=1e-5, tau21_tol=1e-5):
            break
        pose = pose @ exp_twist(twist * dt)
        iterations += 1
    distance_mm = 1e3 * np.linalg.norm(pose[:3, 3])
    angle_deg = np.degrees(np.arccos(np.clip((np.trace(pose[:3, :3]) - 1) / 2, -1, 1)))
    print(f"converged after {iterations} steps: {distance_mm:.3f} mm, {angle_deg:.4f} deg from the reference pose")
    return 0 if distance_mm < 1.0 and angle_deg < 0.1 else 1


if __name__ == "__main__":
    sys.exit(main())
