"""The Python API: results against independent NumPy computations, and the contract."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import vsinv
from conftest import lens, object_points, pose, view


def test_intrinsics_round_trip_and_matrix():
    k = vsinv.Intrinsics(1200.0, 1100.0, 390.0, 280.0, skew=1.4)
    m = k.matrix
    assert m.shape == (3, 3)
    np.testing.assert_allclose(m[0], [1200.0, -1200.0 / math.tan(1.4), 390.0])
    np.testing.assert_allclose(m[1], [0.0, 1100.0 / math.sin(1.4), 280.0])
    back = vsinv.Intrinsics.from_matrix(m)
    assert back.fkv == pytest.approx(1100.0) and back.skew == pytest.approx(1.4)
    assert vsinv.Intrinsics(1.0, 1.0, 0.0, 0.0).matrix[0, 1] == 0.0


def test_project_matches_pinhole():
    k = vsinv.Intrinsics(800.0, 750.0, 320.0, 240.0, skew=1.45)
    pts = np.array([[0.1, -0.05, 0.7], [0.0, 0.0, 1.0], [-0.2, 0.3, 2.0]])
    px, z = vsinv.geometry.project(pts, k)
    h = (k.matrix @ (pts / pts[:, 2:]).T).T
    np.testing.assert_allclose(px, h[:, :2])
    np.testing.assert_allclose(z, pts[:, 2])


@settings(max_examples=40, deadline=None)
@given(
    fku=st.floats(200, 4000), fkv=st.floats(200, 4000), u0=st.floats(-300, 1000),
    v0=st.floats(-300, 800), skew=st.floats(1.0, 2.1), rz=st.floats(-3.1, 3.1),
)
def test_invariant_points_ignore_intrinsics_and_roll(fku, fkv, u0, v0, skew, rz):
    obj = object_points()
    base = pose((0.03, -0.02, 0.05), (0.1, 0.2, 0.0))
    px1, _ = view(obj, base, lens(1200.0))
    px2, _ = view(obj, base @ pose(thetau=(0.0, 0.0, rz)), vsinv.Intrinsics(fku, fkv, u0, v0, skew))
    np.testing.assert_allclose(vsinv.laws.invariant_points(px1), vsinv.laws.invariant_points(px2), atol=1e-9)


def test_invariant_points_against_numpy(scene):
    px = scene["cur"]
    q = vsinv.laws.invariant_points(px, basis=(0, 3, 8))
    qmat = np.vstack([px[[0, 3, 8]].T, np.ones(3)])
    expected = np.linalg.solve(qmat, np.vstack([px.T, np.ones(len(px))])).T
    np.testing.assert_allclose(q, expected, atol=1e-12)
    np.testing.assert_allclose(q.sum(axis=1), 1.0)


def test_jacobian_against_finite_differences(scene):
    obj, k = scene["object"], vsinv.Intrinsics(700.0, 650.0, 400.0, 250.0, skew=1.5)
    start = pose((0.05, -0.03, -0.08), (0.1, -0.2, 0.3))
    px, z = view(obj, start, k)
    j = vsinv.laws.invariant_jacobian(px, z, k)
    assert j.shape == (27, 5)
    others = [i for i in range(12) if i not in (0, 1, 2)]

    def s_at(m):
        p, _ = view(obj, m, k)
        return vsinv.laws.invariant_points(p)[others].ravel()

    h = 1e-6
    for col in range(5):
        d = np.zeros(6)
        d[col] = h
        # small body-frame motion: first order is enough for a central difference
        plus = start @ pose(d[:3], d[3:])
        minus = start @ pose(-d[:3], -d[3:])
        fd = (s_at(plus) - s_at(minus)) / (2 * h)
        np.testing.assert_allclose(fd, j[:, col], atol=1e-5 * max(1.0, np.abs(j[:, col]).max()))


def test_invariant_step_against_numpy_pseudo_inverse(scene):
    k_hat = vsinv.Intrinsics(650.0, 570.0, 395.0, 280.0)
    ctl = vsinv.laws.InvariantController(scene["ref"], k_hat, gain=0.7, gain_rz=1.3, basis=(0, 1, 2))
    twist = ctl.step(scene["cur"], scene["z_star"])
    assert twist.shape == (6,) and twist.dtype == np.float64
    j = vsinv.laws.invariant_jacobian(scene["cur"], scene["z_star"], k_hat)
    s = vsinv.laws.invariant_points(scene["cur"])[3:].ravel()
    s_star = vsinv.laws.invariant_points(scene["ref"])[3:].ravel()
    eps = np.linalg.pinv(j) @ (s - s_star)
    np.testing.assert_allclose(ctl.eps, eps, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(twist[:5], -0.7 * eps, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(ctl.reference_invariants.ravel(), s_star)
    assert ctl.invariant_error == pytest.approx(np.linalg.norm(s - s_star))
    # T = Q Q*^-1 and eps_z = det(Q*) tau_21
    qm = np.vstack([scene["cur"][:3].T, np.ones(3)])
    qs = np.vstack([scene["ref"][:3].T, np.ones(3)])
    t = qm @ np.linalg.inv(qs)
    np.testing.assert_allclose(ctl.t_matrix, t, rtol=1e-9, atol=1e-12)
    assert ctl.eps_z == pytest.approx(np.linalg.det(qs) * t[1, 0])
    assert (ctl.tau_11, ctl.tau_21, ctl.tau_22) == pytest.approx((t[0, 0], t[1, 0], t[1, 1]))


def test_controller_is_zero_at_the_goal_with_another_lens(scene):
    obj = scene["object"]
    cur, z = view(obj, np.eye(4), scene["k"])
    ctl = vsinv.laws.InvariantController(scene["ref"], scene["k"], basis="auto")
    np.testing.assert_allclose(ctl.step(cur, z), np.zeros(6), atol=1e-9)
    assert ctl.converged()


def test_ibvs_against_numpy(scene):
    k = scene["k"]
    ctl = vsinv.laws.IbvsController(scene["ref"], k, gain=0.5)
    tw = ctl.step(scene["cur"], scene["z"])
    km = k.matrix
    rows = []
    for (u, v), zz in zip(scene["cur"], scene["z"]):
        x, y, _ = np.linalg.solve(km, [u, v, 1.0])
        lx = np.array([[-1 / zz, 0, x / zz, x * y, -(1 + x * x), y], [0, -1 / zz, y / zz, 1 + y * y, -x * y, -x]])
        rows.append(km[:2, :2] @ lx)
    lmat = np.vstack(rows)
    expected = -0.5 * np.linalg.pinv(lmat) @ (scene["cur"] - scene["ref"]).ravel()
    np.testing.assert_allclose(tw, expected, rtol=1e-7, atol=1e-10)
    assert ctl.pixel_error == pytest.approx(np.sqrt(((scene["cur"] - scene["ref"]) ** 2).sum(axis=1).mean()))


def test_inputs_are_read_in_place_and_other_dtypes_converted(scene):
    ctl = vsinv.laws.InvariantController(scene["ref"], scene["k"])
    a = ctl.step(scene["cur"], scene["z"])
    f32 = ctl.step(scene["cur"].astype(np.float32), scene["z"].astype(np.float32))
    np.testing.assert_allclose(a, f32, rtol=1e-3)
    fortran = ctl.step(np.asfortranarray(scene["cur"]), list(scene["z"]))
    np.testing.assert_allclose(a, fortran)
    strided = np.zeros((12, 4))
    strided[:, ::2] = scene["cur"]
    np.testing.assert_allclose(a, ctl.step(strided[:, ::2], scene["z"]))


def test_check_stability_report():
    k = lens(1200.0)
    r = vsinv.laws.check_stability(k, vsinv.Intrinsics(600.0, 1800.0, 300.0, 200.0))
    assert r.prop1 and r.prop2 and r.sigma > 0
    assert r.eigenvalues.shape == (5,) and np.iscomplexobj(r.eigenvalues)
    np.testing.assert_allclose(sorted(r.eigenvalues.real), sorted([2.0, 1 / 1.5, 1.0, 1.5, 0.5]))
    neg = np.array([[-600.0, 0, 300], [0, 1800, 200], [0, 0, 1]])
    r = vsinv.laws.check_stability(k.matrix, neg)
    assert not r.prop1 and not r.prop2 and (r.eigenvalues.real < 0).any()
    assert repr(r).startswith("StabilityReport(prop1=False, prop2=False, sigma=")  # Python's bools
    sched = np.stack([lens(f).matrix for f in (2250.0, 1900.0, 1550.0)])
    r = vsinv.laws.check_stability(sched, lens(1500.0), kappa=0.8, gain=2.0)
    assert r.eigenvalues.shape == (3, 5) and r.prop2
    assert r.tracking_bound(0.1) == pytest.approx(vsinv.laws.tracking_bound(2.0, r.sigma, 0.1))
    assert vsinv.laws.tracking_bound(2.0, 0.5, 0.1) == pytest.approx(0.2)


def test_interaction_matrix_and_factors(scene):
    k = vsinv.Intrinsics(700.0, 650.0, 400.0, 250.0, skew=1.5)
    px, z = scene["cur"], scene["z"]
    ls = vsinv.laws.interaction_matrix(px, z, k)
    assert ls.shape == (12, 2, 6)
    km = k.matrix
    x, y, _ = np.linalg.solve(km, [px[4, 0], px[4, 1], 1.0])
    zz = z[4]
    lx = np.array([[-1 / zz, 0, x / zz, x * y, -(1 + x * x), y], [0, -1 / zz, y / zz, 1 + y * y, -x * y, -x]])
    np.testing.assert_allclose(ls[4], km[:2, :2] @ lx, rtol=1e-10)
    phi, psi = vsinv.laws.jacobian_factors(px, z)
    assert phi.shape == (27, 3) and psi.shape == (27, 2)
    s, c = np.sin(k.skew), np.cos(k.skew)
    f = np.array([[s / k.fkv, -c / k.fkv], [0.0, 1.0 / k.fku]])
    j = np.hstack([phi @ km, psi @ f])
    np.testing.assert_allclose(j, vsinv.laws.invariant_jacobian(px, z, k), rtol=1e-8, atol=1e-12)


def test_rz_coefficients_drive_eps_z(scene):
    """a and c predict the change of eps_z for a small motion (eq. 23)."""
    obj, k = scene["object"], scene["k"]
    start = pose((0.05, -0.03, -0.08), (0.1, -0.2, 0.3))
    px, z = view(obj, start, k)
    a, c = vsinv.laws.rz_coefficients(px, z, scene["ref"], k)
    ref = scene["ref"]

    def eps_z(m):
        p, _ = view(obj, m, k)
        qs = np.vstack([ref[:3].T, np.ones(3)])
        t = np.vstack([p[:3].T, np.ones(3)]) @ np.linalg.inv(qs)
        return np.linalg.det(qs) * t[1, 0]

    tw = np.array([0.01, -0.02, 0.015, 0.02, -0.01, 0.03]) * 1e-4
    moved = start @ pose(tw[:3], tw[3:])
    predicted = a * tw[5] + c @ tw[:5]
    assert eps_z(moved) - eps_z(start) == pytest.approx(predicted, rel=1e-3)
