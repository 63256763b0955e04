"""Pose helpers against independent computations: the 4x4 matrix exponential of the twist
(Taylor series with scaling and squaring) and Rodrigues' formula."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import vsinv


def hat(w: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def expm_series(a: np.ndarray) -> np.ndarray:
    """exp(A) by scaling, a 30-term Taylor series and squaring."""
    k = max(0, int(np.ceil(np.log2(max(np.abs(a).sum(), 1e-12)))) + 1)
    scaled, term, total = a / 2**k, np.eye(4), np.eye(4)
    for i in range(1, 30):
        term = term @ scaled / i
        total = total + term
    for _ in range(k):
        total = total @ total
    return total


def rodrigues(thetau: np.ndarray) -> np.ndarray:
    theta = np.linalg.norm(thetau)
    if theta < 1e-12:
        return np.eye(3)
    k = hat(thetau / theta)
    return np.eye(3) + np.sin(theta) * k + (1 - np.cos(theta)) * k @ k


vectors = st.lists(st.floats(-3.0, 3.0), min_size=6, max_size=6).map(np.array)


@settings(max_examples=200, deadline=None)
@given(vectors, st.floats(0.001, 2.0))
def test_exp_twist_is_the_matrix_exponential(twist: np.ndarray, dt: float) -> None:
    xi = np.zeros((4, 4))
    xi[:3, :3], xi[:3, 3] = hat(twist[3:]), twist[:3]
    assert np.allclose(vsinv.geometry.exp_twist(twist, dt), expm_series(xi * dt), atol=1e-9)


@settings(max_examples=200, deadline=None)
@given(vectors)
def test_pose_from_position_thetau_is_rodrigues_and_inverts(v: np.ndarray) -> None:
    position, thetau = v[:3], v[3:]
    pose = vsinv.geometry.pose_from_position_thetau(position, thetau)
    assert np.allclose(pose[:3, :3], rodrigues(thetau), atol=1e-12)
    assert np.allclose(pose[:3, 3], position) and np.array_equal(pose[3], [0, 0, 0, 1])
    p, tu = vsinv.geometry.thetau_from_pose(pose)
    assert np.allclose(p, position)
    assert np.allclose(vsinv.geometry.pose_from_position_thetau(p, tu), pose, atol=1e-12)  # same rotation
    assert np.linalg.norm(tu) <= np.pi + 1e-12


def test_pose_helpers_refuse_bad_input() -> None:
    with pytest.raises(vsinv.InvalidInput, match=r"twist: expected shape \(6\), got \[5\]"):
        vsinv.geometry.exp_twist([0.0] * 5)
    with pytest.raises(vsinv.InvalidInput, match="twist: non-finite value at index 0"):
        vsinv.geometry.exp_twist([np.nan] + [0.0] * 5)
    with pytest.raises(vsinv.InvalidInput, match="dt: non-finite value"):
        vsinv.geometry.exp_twist([0.0] * 6, np.inf)
    with pytest.raises(vsinv.InvalidInput, match=r"invalid parameter `pose`: not a rigid motion \(rotation block must be orthonormal with det \+1, last row 0 0 0 1\)"):
        vsinv.geometry.thetau_from_pose(np.ones((4, 4)))
    with pytest.raises(vsinv.InvalidInput, match=r"thetau: expected shape \(3\), got \[2\]"):
        vsinv.geometry.pose_from_position_thetau([0, 0, 0], [0, 0])
