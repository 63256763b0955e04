"""vsinv.kinematics.damped_least_squares (issue 31, item 2): the kinematic arm's resolution of a
twist into joint velocities, for a Jacobian from elsewhere (MuJoCo's), against NumPy's
computation of the same formulas (exact inverse when well conditioned; the damped solution with
mu^2 = d^2 - sigma_min^2 near a singularity; the null-space term of a redundant arm)."""

from __future__ import annotations

import numpy as np
import pytest

import vsinv

pytestmark = pytest.mark.sim


def _jacobian_of_fk(q: np.ndarray) -> np.ndarray:
    """The UR5's flange Jacobian in the flange frame, by central differences of vsinv's fk."""
    pose = vsinv.kinematics.fk("ur5", q)
    R = pose[:3, :3]
    J = np.zeros((6, 6))
    h = 1e-6
    for i in range(6):
        dq = np.zeros(6)
        dq[i] = h
        plus, minus = vsinv.kinematics.fk("ur5", q + dq), vsinv.kinematics.fk("ur5", q - dq)
        skew = (plus[:3, :3] - minus[:3, :3]) / (2 * h) @ R.T
        J[:3, i] = R.T @ (plus[:3, 3] - minus[:3, 3]) / (2 * h)
        J[3:, i] = R.T @ np.array([skew[2, 1], skew[0, 2], skew[1, 0]])
    return J


def _numpy_dls(J: np.ndarray, v: np.ndarray, d: float, z: np.ndarray | None = None) -> np.ndarray:
    sigma_min = np.linalg.svd(J, compute_uv=False).min() if J.shape[1] >= 6 else np.linalg.svd(J.T @ J, compute_uv=False).min() ** 0.5
    mu2 = max(d * d - sigma_min**2, 0.0)
    if J.shape[1] < 6:
        return np.linalg.solve(J.T @ J + mu2 * np.eye(J.shape[1]), J.T @ v)
    A = np.linalg.inv(J @ J.T + mu2 * np.eye(6))
    dq = J.T @ A @ v
    if z is not None and J.shape[1] > 6:
        dq += z - J.T @ A @ J @ z
    return dq


def test_a_well_conditioned_jacobian_is_inverted_exactly() -> None:
    """Away from singularities (sigma_min > damping) the result is J^-1 v, and fk moves by the twist."""
    q = np.array([0.3, -1.2, 1.4, -0.5, 0.8, 0.1])
    J = _jacobian_of_fk(q)
    assert np.linalg.svd(J, compute_uv=False).min() > 0.02
    v = np.array([0.05, -0.02, 0.03, 0.1, -0.2, 0.15])
    dq = vsinv.kinematics.damped_least_squares(J, v)
    np.testing.assert_allclose(dq, np.linalg.solve(J, v), rtol=1e-9, atol=1e-12)
    # a small step of the joints moves the flange by the twist (first order)
    dt = 1e-4
    moved = np.linalg.inv(vsinv.kinematics.fk("ur5", q)) @ vsinv.kinematics.fk("ur5", q + dq * dt)
    np.testing.assert_allclose(moved[:3, 3] / dt, v[:3], atol=1e-4)


def test_near_a_singularity_the_damping_is_numpys() -> None:
    """The UR5 with the wrist straight (q5 = 0) is singular: the result is NumPy's damped least
    squares with mu^2 = d^2 - sigma_min^2, finite and bounded."""
    q = np.array([0.3, -1.2, 1.4, -0.5, 0.0, 0.1])
    J = _jacobian_of_fk(q)
    assert np.linalg.svd(J, compute_uv=False).min() < 1e-6
    v = np.array([0.05, -0.02, 0.03, 0.1, -0.2, 0.15])
    for d in (0.02, 0.1):
        dq = vsinv.kinematics.damped_least_squares(J, v, damping=d)
        np.testing.assert_allclose(dq, _numpy_dls(J, v, d), rtol=1e-6, atol=1e-9)
        assert np.abs(dq).max() < 1e3


def test_redundant_and_short_arms() -> None:
    """Seven joints: the null-space term (I - J^T (J J^T + mu^2 I)^-1 J) z is added and leaves the
    twist unchanged; five joints: (J^T J + mu^2 I)^-1 J^T v. Both as NumPy computes them."""
    rng = np.random.default_rng(7)
    J7 = rng.normal(size=(6, 7))
    v = rng.normal(size=6)
    z = rng.normal(size=7)
    dq = vsinv.kinematics.damped_least_squares(J7, v, null_space=z)
    np.testing.assert_allclose(dq, _numpy_dls(J7, v, 0.02, z), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(J7 @ dq, v, atol=1e-9)  # well conditioned: the twist is exact
    assert np.abs(dq - vsinv.kinematics.damped_least_squares(J7, v)).max() > 1e-3  # z did something
    J5 = rng.normal(size=(6, 5))
    np.testing.assert_allclose(vsinv.kinematics.damped_least_squares(J5, v), _numpy_dls(J5, v, 0.02), rtol=1e-9, atol=1e-12)


def test_bad_arguments_are_refused_by_name() -> None:
    J = np.eye(6)
    v = np.ones(6)
    for kwargs, name in [
        ({"jacobian": np.eye(5)}, "jacobian"),
        ({"jacobian": np.full((6, 6), np.nan)}, "jacobian"),
        ({"twist": np.ones(5)}, "twist"),
        ({"twist": [np.inf] * 6}, "twist"),
        ({"damping": 0.0}, "damping"),
        ({"damping": -1.0}, "damping"),
        ({"damping": np.nan}, "damping"),
        ({"jacobian": np.ones((6, 7)), "null_space": np.ones(6)}, "null_space"),
    ]:
        args = {"jacobian": J, "twist": v, **kwargs}
        with pytest.raises(vsinv.InvalidInput) as e:
            vsinv.kinematics.damped_least_squares(**args)
        assert name in str(e.value), (kwargs, e.value)
