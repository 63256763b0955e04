"""`[vision]` blur and noise on MuJoCo's renders (issue 31, item 1): `vsinv.vision.degrade` is
the kinematic renderer's PSF and sensor noise applied to an image drawn elsewhere, and the MuJoCo
loop passes every render through it.

Independent checks: OpenCV's Gaussian blur of the same image (inside the border), the sample
statistics of the noise against `noise_sigma`, and statistics of a MuJoCo frame with and without
`[vision]` (the residual's spread on the flat background, the Laplacian's energy)."""

from __future__ import annotations

import math
import os

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import vsinv  # noqa: E402
import vsinv.vision  # noqa: E402

cv2 = pytest.importorskip("cv2")


def _image() -> np.ndarray:
    rng = np.random.default_rng(3)
    image = np.full((60, 80), 40, np.uint8)
    image[20:40, 25:55] = 200
    return (image + rng.integers(0, 20, image.shape)).astype(np.uint8)


@pytest.mark.parametrize("sigma", [0.6, 1.0, 2.5])
def test_the_blur_is_opencvs_gaussian_inside_the_border(sigma: float) -> None:
    image = _image()
    out = vsinv.vision.degrade(image, blur_sigma=sigma, noise_sigma=0.0)
    r = int(np.ceil(3 * sigma))
    expected = cv2.GaussianBlur(image.astype(np.float64), (2 * r + 1, 2 * r + 1), sigma, borderType=cv2.BORDER_REFLECT)
    inner = (slice(r, -r), slice(r, -r))
    assert np.abs(out[inner].astype(float) - expected[inner]).max() <= 0.5 + 1e-3
    flat = np.full((30, 30), 77, np.uint8)  # the border renormalised: a uniform image stays uniform
    np.testing.assert_array_equal(vsinv.vision.degrade(flat, blur_sigma=sigma, noise_sigma=0.0), flat)


def test_the_noise_has_the_stated_spread_and_a_draw_per_frame() -> None:
    flat = np.full((200, 300), 100, np.uint8)
    a = vsinv.vision.degrade(flat, blur_sigma=0.0, noise_sigma=4.0, seed=2, frame=1).astype(float) - 100
    b = vsinv.vision.degrade(flat, blur_sigma=0.0, noise_sigma=4.0, seed=2, frame=2).astype(float) - 100
    for x in (a, b):  # rounding adds 1/12 of a grey level squared
        assert abs(x.mean()) < 0.1 and abs(x.std() - np.sqrt(16 + 1 / 12)) < 0.1
    assert abs(np.corrcoef(a.ravel(), b.ravel())[0, 1]) < 0.02
    again = vsinv.vision.degrade(flat, blur_sigma=0.0, noise_sigma=4.0, seed=2, frame=1).astype(float) - 100
    np.testing.assert_array_equal(a, again)
    np.testing.assert_array_equal(vsinv.vision.degrade(flat, blur_sigma=0.0, noise_sigma=0.0), flat)


@pytest.mark.parametrize("bad", [{"blur_sigma": -1.0}, {"blur_sigma": 25.0}, {"noise_sigma": float("nan")},
                                 {"seed": -1}, {"frame": 2**64}])
def test_bad_options_are_refused_by_name(bad: dict) -> None:
    with pytest.raises(vsinv.InvalidInput, match=next(iter(bad))):
        vsinv.vision.degrade(_image(), **bad)


def _mujoco():  # type: ignore[no-untyped-def]
    vm = pytest.importorskip("vsinv.mujoco")
    why = vm.available()
    if why is not None:
        pytest.skip(why)
    return vm


def _laplacian_energy(image: np.ndarray) -> float:
    return float(np.var(cv2.Laplacian(image.astype(np.float64), cv2.CV_64F)))


def test_mujoco_frames_get_the_blur_and_the_noise() -> None:
    vm = _mujoco()
    from vsinv.mujoco._effects import camera_image

    d = vsinv.load_scenario("mujoco-lens-12-6").to_dict()
    pose = vsinv.geometry.pose_from_position_thetau(d["start"]["position"], np.radians(d["start"]["rotation_deg"]))
    with vm.World.from_scenario(d) as world:
        clean = camera_image(world, d, pose, 1)
        np.testing.assert_array_equal(clean, world.render(pose))  # no [vision]: the render itself
        blurred = camera_image(world, {**d, "vision": {"blur_sigma": 1.5, "noise_sigma": 0.0}}, pose, 1)
        noisy = camera_image(world, {**d, "vision": {"blur_sigma": 0.0, "noise_sigma": 5.0, "seed": 4}}, pose, 1)
    assert _laplacian_energy(blurred) < 0.5 * _laplacian_energy(clean)
    # MuJoCo's background is black: the noise clipped at 0, a pixel brightens when the draw
    # passes half a level, P = 1 - Phi(0.5 / sigma) (0.460 for sigma = 5).
    moved = 0.5 * (1.0 - math.erf(0.5 / 5.0 / math.sqrt(2.0)))
    black = clean == 0
    assert black.sum() > 50_000
    assert abs(np.mean(noisy[black] > 0) - moved) < 0.01
    # ... and by the draw's spread: the levels reached above black, E[n | n > 0.5] about 4.1 for sigma = 5.
    grid = np.linspace(0.5, 60.0, 200_001)
    density = np.exp(-(grid**2) / 50.0)
    expected = float((np.round(grid) * density).sum() / density.sum())
    assert abs(noisy[black][noisy[black] > 0].mean() - expected) < 0.15


def test_the_mujoco_loop_sees_the_degraded_frames() -> None:
    vm = _mujoco()
    from vsinv.mujoco._effects import camera_image

    d = vsinv.load_scenario("mujoco-lens-12-6").to_dict()
    d["vision"] = {"blur_sigma": 0.8, "noise_sigma": 3.0, "seed": 9}
    run = vm.run_loop(d, max_iterations=3)
    n = len(run.result.time)
    with vm.World.from_scenario(d) as world:
        np.testing.assert_array_equal(run.last_image, camera_image(world, d, run.result.pose[-1], n))
        assert not np.array_equal(run.last_image, world.render(run.result.pose[-1]))
