"""Path planning (sec. 3) and depth estimation (appendix A) from Python."""

import numpy as np
import pytest

import vsinv
from conftest import lens, object_points, pose, view


@pytest.fixture
def images():
    obj = object_points()
    ref, z_star = view(obj, np.eye(4), lens(1200.0))
    k = vsinv.Intrinsics(700.0, 650.0, 400.0, 250.0, skew=1.5)
    cur, z = view(obj, pose((0.08, -0.05, -0.15), (0.1, -0.15, 0.4)), k)
    return obj, ref, z_star, cur, z


def test_plane_parallax_reproduces_current_points(images):
    _, ref, _, cur, _ = images
    est = vsinv.calibration.estimate_plane_parallax(cur, ref, basis=(0, 3, 5))
    q = vsinv.laws.invariant_points(cur, basis=(0, 3, 5))
    q_star = vsinv.laws.invariant_points(ref, basis=(0, 3, 5))
    others = [i for i in range(12) if i not in (0, 3, 5)]
    pred = est.gamma * (q_star[others] + est.mu_e)
    pred /= pred.sum(axis=1, keepdims=True)
    np.testing.assert_allclose(pred, q[others], atol=1e-9)
    assert est.gamma[2] == 1.0 and (est.gamma > 0).all() and est.residual < 1e-9
    assert np.linalg.norm(est.epipole) == pytest.approx(1.0)
    # seven points: the minimal method
    est7 = vsinv.calibration.estimate_plane_parallax(cur[:7], ref[:7], basis=(0, 3, 5))
    assert est7.candidates in (1, 3) and est7.residual < 1e-9


def test_path_starts_at_current_image_and_ends_at_reference(images):
    _, ref, _, cur, _ = images
    path = vsinv.laws.InvariantPath(cur, ref, duration=20.0)
    q0, r0 = path.sample(0.0)
    np.testing.assert_allclose(q0, vsinv.laws.invariant_points(cur)[3:], atol=1e-9)
    qt, rt = path.sample(20.0)
    np.testing.assert_allclose(qt, vsinv.laws.invariant_points(ref)[3:], atol=1e-12)
    assert not rt.any() and r0.any()
    # the controller accepts the samples as a moving reference
    ctl = vsinv.laws.InvariantController(ref, lens(1200.0))
    ctl.set_reference(*path.sample(5.0))


def test_depths_up_to_scale(images):
    obj, ref, z_star, cur, z = images
    k_bar = vsinv.Intrinsics(900.0, 880.0, 300.0, 260.0)
    first = pose((0.05, 0.02, -0.1), (0.05, -0.1, 0.3))
    second = first.copy()
    second[:3, 3] += [0.1, -0.02, 0.05]
    p1, z1 = view(obj, first, k_bar)
    p2, _ = view(obj, second, k_bar)
    depths, epipole, residual = vsinv.calibration.depths_from_translation(p1, p2)
    ratio = depths / z1
    np.testing.assert_allclose(ratio, ratio[0], rtol=1e-9)
    assert residual < 1e-9 and depths.mean() == pytest.approx(1.0)
    est = vsinv.calibration.ResectionDepths(p1, depths, ref, reference_mean_depth=z_star.mean())
    at_ref = est.estimate(ref)
    np.testing.assert_allclose(at_ref, z_star, rtol=1e-9)  # the true mean depth gives kappa = 1
    now = est.estimate(cur, visible=[i != 4 for i in range(12)])
    kappa = now / z
    np.testing.assert_allclose(kappa, kappa[0], rtol=1e-8)
    assert kappa[0] > 0


def test_bad_inputs():
    obj = object_points()
    ref, _ = view(obj, np.eye(4), lens(1200.0))
    planar = obj.copy()
    planar[:, 2] = 0.6 + 0.2 * planar[:, 0]
    pref, _ = view(planar, np.eye(4), lens(1200.0))
    pcur, _ = view(planar, pose((0.05, 0.0, -0.1), (0.0, 0.1, 0.2)), lens(1200.0))
    with pytest.raises(vsinv.DegenerateGeometry):
        vsinv.calibration.estimate_plane_parallax(pcur, pref, basis=(0, 3, 8))
    with pytest.raises(vsinv.DegenerateGeometry, match=r"too few points: 7 needed \(plane \+ parallax needs four non-basis points \(seven in all\)\)"):
        vsinv.calibration.estimate_plane_parallax(ref[:6], ref[:6])
    with pytest.raises(vsinv.InvalidInput):
        vsinv.calibration.estimate_plane_parallax(ref, ref[:8])
    with pytest.raises(vsinv.InvalidInput):
        vsinv.laws.InvariantPath(view(obj, pose((0.05, 0.0, -0.1)), lens(900.0))[0], ref, duration=0.0)
    with pytest.raises(vsinv.DegenerateGeometry):
        vsinv.calibration.depths_from_translation(ref, ref)
    with pytest.raises(vsinv.InvalidInput):
        vsinv.calibration.ResectionDepths(ref, np.ones(12), ref, reference_mean_depth=-1.0)
    with pytest.raises(vsinv.DegenerateGeometry, match=r"point 0 is at or behind the camera \(depth -1\)"):
        vsinv.calibration.ResectionDepths(ref, -np.ones(12), ref)


def test_path_scenarios_report_prop3():
    s = vsinv.run_scenario("path-500-feedforward").summary
    assert s["status"] == "converged"
    assert s["observed_max_eps"] <= s["tracking_bound"]
    assert s["path_duration"] == pytest.approx(20.0)
    assert vsinv.run_scenario("lens-12-6").summary["tracking_bound"] is None
