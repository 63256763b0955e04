"""Eq. (26) from tracked keypoints (issue 32, item 1): `depths_from_translation(..., pixel_noise=sigma)`
finds the epipole by a consensus, flags the points whose depth the pair does not fix (NaN) and
`ResectionDepths` is built from the others. Checked against the projection of a synthetic cloud
computed here (numpy)."""

from __future__ import annotations

import numpy as np
import pytest

import vsinv

K = np.array([[610.0, 2.0, 330.0], [0.0, 590.0, 250.0], [0.0, 0.0, 1.0]])


def project(points: np.ndarray) -> np.ndarray:
    p = points @ K.T
    return p[:, :2] / p[:, 2:]


def pair(n: int = 120, t=(0.04, -0.02, 0.01), seed: int = 3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A non-planar cloud 0.45-0.75 m in front of a skewed camera, seen before and after the camera
    moves by `t` (its own frame): the two images' pixels and the first's true depths."""
    rng = np.random.default_rng(seed)
    x = np.c_[rng.uniform(-0.2, 0.2, n), rng.uniform(-0.15, 0.15, n), rng.uniform(0.45, 0.75, n)]
    return project(x), project(x - np.asarray(t)), x[:, 2]


def test_exact_pixels_give_the_closed_form() -> None:
    p1, p2, z = pair()
    d, epipole, residual = vsinv.calibration.depths_from_translation(p1, p2, pixel_noise=0.05)
    ratio = d / z
    np.testing.assert_allclose(ratio / ratio[0], 1.0, rtol=0, atol=1e-9)
    assert residual < 1e-9
    e = K @ np.array([0.04, -0.02, 0.01])  # the epipole is K t (eq. 26)
    np.testing.assert_allclose(epipole / epipole[2], e / e[2], rtol=1e-9)


def test_outliers_are_flagged_and_inliers_within_the_noise_bound() -> None:
    """Gaussian tracking noise sigma = 0.15 px and 10 % of tracks displaced 3-20 px in a random
    direction: every displaced track whose displacement across its epipolar line exceeds twice the
    threshold (4 sqrt(2) sigma) is flagged, and every usable depth is within its noise bound:
    4 sqrt(2) sigma / parallax (the noise along the line over the parallax) plus 1 % for the
    epipole's own error, and within the 10 % the estimate promises."""
    sigma = 0.15
    p1, p2_true, z = pair(n=200)
    rng = np.random.default_rng(7)
    p2 = p2_true + rng.normal(scale=sigma, size=p2_true.shape)
    p1n = p1 + rng.normal(scale=sigma, size=p1.shape)
    bad = rng.choice(len(z), len(z) // 10, replace=False)
    angle = rng.uniform(0, 2 * np.pi, len(bad))
    p2[bad] += rng.uniform(3, 20, len(bad))[:, None] * np.c_[np.cos(angle), np.sin(angle)]
    d, _, _ = vsinv.calibration.depths_from_translation(p1n, p2, pixel_noise=sigma)
    usable = np.isfinite(d)
    # Displacement across the true epipolar line of each displaced track.
    e = K @ np.array([0.04, -0.02, 0.01])
    line_dir = p2_true[bad] - e[:2] / e[2]
    line_dir /= np.linalg.norm(line_dir, axis=1)[:, None]
    shift = p2[bad] - p2_true[bad]
    across = np.abs(shift[:, 0] * line_dir[:, 1] - shift[:, 1] * line_dir[:, 0])
    threshold = 4 * np.sqrt(2) * sigma
    assert not usable[bad[across > 2 * threshold]].any()
    clean = np.setdiff1d(np.arange(len(z)), bad)
    good = clean[usable[clean]]
    assert len(good) > 0.8 * len(clean), (len(good), len(clean))
    scale = np.median(z[good] / d[good])
    error = np.abs(d[good] * scale / z[good] - 1)
    parallax = np.linalg.norm(p1n[good] - p2[good], axis=1)
    bound = 4 * np.sqrt(2) * sigma / parallax + 0.01
    assert (error <= bound).all(), (error - bound).max()
    assert error.max() < 0.1


def test_resection_is_built_from_the_usable_points() -> None:
    """A NaN first depth: the resection uses the other points and places that one on its ray where
    the reference image sees it; the estimated reference depths are proportional to the truth."""
    p1, p2, z = pair(n=40)
    d, _, _ = vsinv.calibration.depths_from_translation(p1, p2, pixel_noise=0.05)
    d[[2, 11, 30]] = np.nan
    rng = np.random.default_rng(1)
    x = np.linalg.inv(K) @ np.c_[p1, np.ones(len(p1))].T * z  # the cloud, first camera's frame
    t_ref = np.array([-0.03, 0.05, -0.02])
    ref = project((x.T - t_ref) + rng.normal(scale=0.0, size=(len(z), 3)))
    est = vsinv.calibration.ResectionDepths(p1, d, ref, reference_mean_depth=1.0)
    out = est.estimate(ref)
    truth = z - t_ref[2]
    np.testing.assert_allclose(out / truth / (out[0] / truth[0]), 1.0, rtol=0, atol=1e-8)


@pytest.mark.parametrize("bad", [0.0, -0.1, float("nan"), float("inf")])
def test_bad_pixel_noise_is_refused(bad: float) -> None:
    p1, p2, _ = pair(n=20)
    with pytest.raises(vsinv.errors.InvalidInput, match="pixel_noise"):
        vsinv.calibration.depths_from_translation(p1, p2, pixel_noise=bad)


def test_too_few_usable_points_are_refused_with_the_reason() -> None:
    p1, p2, _ = pair(n=20)
    with pytest.raises(ValueError, match="parallax"):
        # sigma = 2 px asks for 85 px of parallax (10 % at three standard deviations).
        vsinv.calibration.depths_from_translation(p1, p2, pixel_noise=2.0)
