"""The pose uncertainty that pixel noise leaves, the noise meter, the `settled` verdict and the
honesty of `converged` under noise (benches/noise_honesty.py makes the table of docs/results/noise.md)."""

import sys
from pathlib import Path

import numpy as np
import pytest

import vsinv

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
import noise_honesty  # noqa: E402

K = vsinv.Intrinsics(800.0, 790.0, 330.0, 250.0)
POINTS = np.array(noise_honesty.OBJECTS[8])


def test_noise_meter_measures_the_noise_of_a_moving_stream() -> None:
    rng = np.random.default_rng(4)
    meter = vsinv.vision.PixelNoiseMeter(capacity=400)
    assert meter.sigma is None
    base = rng.uniform(0, 800, size=(9, 2))
    for k in range(400):
        meter.push(base + [0.5 * k, -0.25 * k] + rng.normal(0, 0.6, size=(9, 2)))
    assert len(meter) == 400 and abs(meter.sigma / 0.6 - 1) < 0.05
    meter.clear()
    assert len(meter) == 0 and meter.sigma is None
    with pytest.raises(vsinv.InvalidInput, match="invalid parameter `capacity`: must be from 3 to 4096 images"):
        vsinv.vision.PixelNoiseMeter(2)
    with pytest.raises(vsinv.InvalidInput, match=r"visible: expected shape \(9,\)"):
        meter.push(base, visible=np.ones(3, bool))


def test_ibvs_uncertainty_is_the_least_squares_covariance() -> None:
    # Under the pixel rule G = I, so Cov = (sigma^2 / N + sigma*^2) (L^T L)^-1 with L the stacked
    # interaction matrices (vsinv.laws.interaction_matrix, computed independently of the propagation).
    pixels, depths = vsinv.geometry.project(POINTS, K)
    ctl = vsinv.laws.IbvsController(pixels, K)
    u = ctl.pose_uncertainty(pixels, depths, pixel_sigma=0.8, reference_sigma=0.3, averaged_images=4)
    L = vsinv.laws.interaction_matrix(pixels, depths, K).reshape(-1, 6)
    expected = (0.8**2 / 4 + 0.3**2) * np.linalg.inv(L.T @ L)
    assert np.allclose(u.covariance, expected, rtol=1e-9, atol=0)
    assert np.allclose(u.offset, 0, atol=1e-12)
    assert u.translation_sigma == pytest.approx(np.sqrt(np.trace(expected[:3, :3])), rel=1e-12)
    assert u.translation_bound() == pytest.approx(3 * u.translation_sigma, rel=1e-12)


def test_invariant_uncertainty_scales_with_the_noise_and_sees_the_error() -> None:
    reference, _ = vsinv.geometry.project(POINTS, vsinv.Intrinsics(1600, 1600, 400, 300))
    pixels, depths = vsinv.geometry.project(POINTS, K)
    ctl = vsinv.laws.InvariantController(reference, K)
    one = ctl.pose_uncertainty(pixels, depths, pixel_sigma=1.0)
    half = ctl.pose_uncertainty(pixels, depths, pixel_sigma=0.5)
    assert np.allclose(half.covariance, one.covariance / 4, rtol=1e-12)
    averaged = ctl.pose_uncertainty(pixels, depths, pixel_sigma=1.0, reference_sigma=0.0, averaged_images=50)
    assert averaged.translation_sigma < one.translation_sigma / 5
    # 2 mm along x: the offset finds it.
    moved, _ = vsinv.geometry.project(POINTS - [0.002, 0, 0], K)
    u = ctl.pose_uncertainty(moved, depths, pixel_sigma=0.0)
    assert u.offset[:3] == pytest.approx([0.002, 0, 0], abs=5e-5) and u.translation_sigma == 0
    for bad in ({"pixel_sigma": np.nan}, {"pixel_sigma": 1.0, "averaged_images": 0}, {"pixel_sigma": -1.0}):
        with pytest.raises(vsinv.InvalidInput):
            ctl.pose_uncertainty(pixels, depths, **bad)
    with pytest.raises(vsinv.InvalidInput, match=r"pixels: expected 8 points \(as in the reference image\)"):
        ctl.pose_uncertainty(pixels[:5], depths[:5], pixel_sigma=1.0)
    with pytest.raises(vsinv.InvalidInput, match="sigmas: must be finite and > 0"):
        u.translation_bound(sigmas=0)


def test_every_run_reports_its_uncertainty() -> None:
    s = vsinv.run_scenario("lens-12-6", record=False).summary
    assert s["status"] == "converged" and s["within_tolerance"] is True
    assert s["pixel_sigma"] < 1e-3 and s["translation_uncertainty"] < 1e-4
    s = vsinv.run_scenario("ibvs-12-6", record=False).summary
    assert s["status"] == "max_iterations" and s["within_tolerance"] is False
    assert s["translation_uncertainty"] is not None


def test_settled_instead_of_converged_when_the_images_cannot_tell() -> None:
    # The audit's case: 8 points, 25 -> 6 mm, 1 px: the images meet the rule but allow more than
    # 5 mm; no run is reported converged outside the tolerance.
    table = noise_honesty.run_case(8, "25->6", 1.0, seeds=10)
    assert noise_honesty.wrong_reports(table) == 0
    assert (table["status"] == "settled").sum() >= 5
    settled = table["status"] == "settled"
    too_uncertain = (table["translation_uncertainty"] * 1e3 > noise_honesty.TOLERANCE_MM) | (
        np.degrees(table["rotation_uncertainty"]) > noise_honesty.TOLERANCE_DEG
    )
    assert np.all(too_uncertain[settled])


@pytest.mark.parametrize("case", [(12, "12->6", 0.25), (20, "12->12", 0.5), (12, "25->6", 2.0)])
def test_converged_is_never_outside_the_tolerance(case: tuple[int, str, float]) -> None:
    points, lenses, sigma = case
    table = noise_honesty.run_case(points, lenses, sigma, seeds=8)
    assert noise_honesty.wrong_reports(table) == 0
    if sigma <= 0.5:  # low noise: the rule is met and certified
        assert (table["status"] == "converged").sum() >= 6
