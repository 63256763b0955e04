"""Bad input raises the package's own exceptions, never a panic or a silent answer."""

import re

import numpy as np
import pytest

import vsinv
from conftest import lens, object_points, view


def test_hierarchy():
    assert issubclass(vsinv.InvalidInput, vsinv.VsinvError)
    assert issubclass(vsinv.InvalidInput, ValueError)
    assert issubclass(vsinv.DegenerateGeometry, vsinv.VsinvError)
    assert issubclass(vsinv.DegenerateGeometry, ValueError)
    assert not issubclass(vsinv.VsinvError, ValueError)


@pytest.mark.parametrize(
    "args",
    [
        (-1.0, 1.0, 0.0, 0.0),
        (1.0, 0.0, 0.0, 0.0),
        (np.nan, 1.0, 0.0, 0.0),
        (1.0, 1.0, np.inf, 0.0),
        (1.0, 1.0, 0.0, 0.0, 0.0),
        (1.0, 1.0, 0.0, 0.0, np.pi),
    ],
)
def test_bad_intrinsics(args):
    with pytest.raises(vsinv.InvalidInput):
        vsinv.Intrinsics(*args)


def test_bad_matrices():
    with pytest.raises(vsinv.InvalidInput, match=r"invalid intrinsics: K must be upper triangular with last row \(0, 0, 1\)"):
        vsinv.Intrinsics.from_matrix(np.ones((3, 3)))
    with pytest.raises(vsinv.InvalidInput, match=r"K: expected shape \(3, 3\)"):
        vsinv.Intrinsics.from_matrix(np.eye(4))
    with pytest.raises(vsinv.InvalidInput):
        vsinv.Intrinsics.from_matrix(np.diag([-500.0, 500.0, 1.0]))
    with pytest.raises(vsinv.InvalidInput):
        vsinv.Intrinsics.from_matrix(np.diag([np.nan, 500.0, 1.0]))


@pytest.fixture
def ref():
    px, z = view(object_points(), np.eye(4), lens(1200.0))
    return px, z


def controllers(px):
    return [vsinv.laws.InvariantController(px, lens(1200.0)), vsinv.laws.IbvsController(px, lens(1200.0))]


def test_nan_and_inf_pixels_and_depths(ref):
    px, z = ref
    for ctl in controllers(px):
        bad = px.copy()
        bad[4, 1] = np.nan
        with pytest.raises(vsinv.InvalidInput, match="pixels: non-finite value at row 4, column 1"):
            ctl.step(bad, z)
        badz = z.copy()
        badz[5] = np.inf
        with pytest.raises(vsinv.InvalidInput, match="depths: non-finite value at index 5"):
            ctl.step(px, badz)
    with pytest.raises(vsinv.InvalidInput):
        vsinv.laws.invariant_points(np.full((6, 2), np.nan))
    with pytest.raises(vsinv.InvalidInput):
        vsinv.geometry.project(np.array([[0.0, np.nan, 1.0]]), lens(100.0))


@pytest.mark.parametrize(
    "pixels",
    [np.zeros((12, 3)), np.zeros(24), np.zeros((12, 2, 1)), "abc", [[1, 2], [3]], np.zeros((12, 2), complex)],
)
def test_wrong_shapes_and_dtypes(ref, pixels):
    _, z = ref
    for ctl in controllers(ref[0]):
        with pytest.raises(vsinv.InvalidInput):
            ctl.step(pixels, z)


def test_wrong_counts(ref):
    px, z = ref
    for ctl in controllers(px):
        with pytest.raises(vsinv.InvalidInput, match=r"pixels: expected 12 points \(as in the reference image\)"):
            ctl.step(px[:10], z[:10])
        with pytest.raises(vsinv.InvalidInput, match=r"depths: expected 12 values \(one per point\)"):
            ctl.step(px, z[:5])
        with pytest.raises(vsinv.InvalidInput):
            ctl.step(px, z.reshape(3, 4))


def test_too_few_points(ref):
    px, z = ref
    with pytest.raises(vsinv.DegenerateGeometry, match="too few points"):
        vsinv.laws.InvariantController(px[:5], lens(1200.0))
    with pytest.raises(vsinv.DegenerateGeometry, match="too few points"):
        vsinv.laws.IbvsController(px[:3], lens(1200.0))


def test_collinear_basis(ref):
    px, z = ref
    line = px.copy()
    line[2] = (line[0] + line[1]) / 2
    with pytest.raises(vsinv.DegenerateGeometry, match=r"basis points \[0, 1, 2\] are collinear in the reference image"):
        vsinv.laws.InvariantController(line, lens(1200.0), basis=(0, 1, 2))
    with pytest.raises(vsinv.DegenerateGeometry, match=r"basis points \[0, 1, 2\] are collinear in the current image"):
        vsinv.laws.invariant_points(line)
    ctl = vsinv.laws.InvariantController(px, lens(1200.0), basis=(0, 1, 2))
    with pytest.raises(vsinv.DegenerateGeometry, match=r"basis points \[0, 1, 2\] are collinear in the current image"):
        ctl.step(line, z)


def test_points_behind_the_camera(ref):
    px, z = ref
    for ctl in controllers(px):
        for value in (0.0, -0.5):
            bad = z.copy()
            bad[7] = value
            with pytest.raises(vsinv.DegenerateGeometry, match="behind the camera"):
                ctl.step(px, bad)
    with pytest.raises(vsinv.DegenerateGeometry, match="behind the camera"):
        vsinv.geometry.project(np.array([[0.0, 0.0, 1.0], [0.1, 0.1, -1.0]]), lens(100.0))


def test_planar_object_and_equal_depths(ref):
    px, z = ref
    planar = object_points()
    planar[:, 2] = 0.6 + 0.2 * planar[:, 0]
    ppx, pz = view(planar, np.eye(4), lens(1200.0))
    ctl = vsinv.laws.InvariantController(ppx, lens(1200.0), basis=(0, 3, 8))
    with pytest.raises(vsinv.DegenerateGeometry, match="the object is planar or the depth estimates are all equal"):
        ctl.step(ppx + 3.0, pz)
    ctl = vsinv.laws.InvariantController(px, lens(1200.0))
    with pytest.raises(vsinv.DegenerateGeometry, match="the object is planar or the depth estimates are all equal"):
        ctl.step(px + 3.0, np.full(12, 0.6))
    assert vsinv.laws.structure_ratio(ppx, pz, lens(1200.0), basis=(0, 3, 8)) < 1e-6


@pytest.mark.parametrize("k_hat", [np.diag([-1200.0, 1200.0, 1.0]), np.diag([1200.0, 0.0, 1.0])])
def test_non_positive_focal_estimate(ref, k_hat):
    with pytest.raises(vsinv.InvalidInput, match=r"K\[0,0\] and K\[1,1\] must be > 0"):
        vsinv.laws.InvariantController(ref[0], k_hat)
    with pytest.raises(vsinv.InvalidInput):
        vsinv.laws.IbvsController(ref[0], k_hat)


def test_bad_parameters(ref):
    px, z = ref
    with pytest.raises(vsinv.InvalidInput, match="invalid parameter `gain`: must be finite and > 0"):
        vsinv.laws.InvariantController(px, lens(1200.0), gain=0.0)
    with pytest.raises(vsinv.InvalidInput, match="invalid parameter `gain_rz`: must be finite and > 0"):
        vsinv.laws.InvariantController(px, lens(1200.0), gain_rz=np.nan)
    with pytest.raises(vsinv.InvalidInput, match=r"invalid parameter `basis`: indices \[0, 1, 12\] out of range for 12 points"):
        vsinv.laws.InvariantController(px, lens(1200.0), basis=(0, 1, 12))
    with pytest.raises(vsinv.InvalidInput, match=r"invalid parameter `basis`: indices \[0, 0, 1\] must be distinct"):
        vsinv.laws.InvariantController(px, lens(1200.0), basis=(0, 0, 1))
    with pytest.raises(vsinv.InvalidInput, match="basis: expected three non-negative indices"):
        vsinv.laws.InvariantController(px, lens(1200.0), basis=(0, -1, 2))
    with pytest.raises(vsinv.InvalidInput, match='basis: expected three indices or "auto"'):
        vsinv.laws.InvariantController(px, lens(1200.0), basis="widest")
    with pytest.raises(vsinv.InvalidInput, match='invalid parameter `interaction`: expected "current", "desired" or "mean"'):
        vsinv.laws.IbvsController(px, lens(1200.0), interaction="sideways")
    with pytest.raises(vsinv.InvalidInput, match="invalid parameter `reference_depths`: required when the interaction matrix uses the desired points"):
        vsinv.laws.IbvsController(px, lens(1200.0), interaction="desired")
    ctl = vsinv.laws.InvariantController(px, lens(1200.0))
    with pytest.raises(vsinv.InvalidInput, match="sum to 1"):
        ctl.set_reference(np.zeros((9, 3)))
    with pytest.raises(vsinv.InvalidInput, match=r"s_star: expected 9 invariant points \(one per non-basis point\)"):
        ctl.set_reference(np.zeros((8, 3)))
    with pytest.raises(vsinv.NotReady, match="no control step"):
        _ = ctl.eps
    assert issubclass(vsinv.NotReady, vsinv.VsinvError) and issubclass(vsinv.NotReady, RuntimeError)
    with pytest.raises(vsinv.InvalidInput):
        vsinv.laws.check_stability(np.ones((3, 3)), lens(1.0))
    with pytest.raises(vsinv.InvalidInput):
        vsinv.laws.check_stability(lens(1.0), np.diag([0.0, 1.0, 1.0]))
    with pytest.raises(vsinv.InvalidInput):
        vsinv.laws.tracking_bound(-1.0, 1.0, 1.0)


def test_no_panic_ever_reaches_python(ref):
    """Fuzz the step with junk: only package exceptions come out."""
    rng = np.random.default_rng(0)
    px, z = ref
    ctl = vsinv.laws.InvariantController(px, lens(1200.0))
    for _ in range(300):
        p = px + rng.normal(0, 10 ** rng.uniform(-3, 4), px.shape)
        d = z * rng.choice([1.0, -1.0, 0.0, 1e-300, 1e300], size=12, p=[0.9, 0.025, 0.025, 0.025, 0.025])
        try:
            tw = ctl.step(p, d)
            assert np.isfinite(tw).all()
        except vsinv.VsinvError:
            pass


def test_nan_in_a_point_array_is_reported_by_row_and_column(scene):
    cur = scene["cur"].copy()
    cur[5, 1] = np.nan
    ctl = vsinv.laws.InvariantController(scene["ref"], scene["k"])
    with pytest.raises(vsinv.InvalidInput, match=r"pixels: non-finite value at row 5, column 1"):
        ctl.step(cur, scene["z_star"])
    ref = scene["ref"].copy()
    ref[4, 0] = np.inf
    with pytest.raises(vsinv.InvalidInput, match=r"reference_pixels: non-finite value at row 4, column 0"):
        vsinv.laws.IbvsController(ref, scene["k"])


def test_equal_depths_are_refused_with_what_to_do_instead(scene):
    ctl = vsinv.laws.InvariantController(scene["ref"], scene["k"])
    with pytest.raises(vsinv.DegenerateGeometry, match="with a constant-depth guess, pass the reference depths zeta") as info:
        ctl.step(scene["cur"], np.full(len(scene["cur"]), 0.6))
    assert "estimated" in str(info.value)


# Regressions found by tests/test_robustness_*.py ----------------------------------------------


def test_non_finite_entries_of_2d_arrays_are_reported_by_row_and_column(scene):
    k = scene["k"].matrix.copy()
    k[0, 2] = np.nan  # was "K: non-finite value at index 6" (column-major storage)
    with pytest.raises(vsinv.InvalidInput, match=r"K: non-finite value at row 0, column 2"):
        vsinv.Intrinsics.from_matrix(k)
    with pytest.raises(vsinv.InvalidInput, match=r"K_hat: non-finite value at row 0, column 2"):
        vsinv.laws.InvariantController(scene["ref"], k)
    with pytest.raises(vsinv.InvalidInput, match=r"K: non-finite value in matrix 1, row 0, column 2"):
        vsinv.laws.check_stability(np.stack([scene["k"].matrix, k]), scene["k"])
    pts = object_points()
    pts[3, 2] = np.inf  # was "index 11"
    with pytest.raises(vsinv.InvalidInput, match=r"points: non-finite value at row 3, column 2"):
        vsinv.geometry.project(pts, scene["k"])
    pose = np.eye(4)
    pose[1, 3] = np.nan  # was "index 13"
    with pytest.raises(vsinv.InvalidInput, match=r"pose: non-finite value at row 1, column 3"):
        vsinv.geometry.thetau_from_pose(pose)
    ctl = vsinv.laws.InvariantController(scene["ref"], scene["k_star"])
    s = ctl.reference_invariants.copy()
    s[2, 1] = np.nan
    with pytest.raises(vsinv.InvalidInput, match=r"s_star: non-finite value at row 2, column 1"):
        ctl.set_reference(s)
    with pytest.raises(vsinv.InvalidInput, match=r"rate: non-finite value at row 2, column 1"):
        ctl.set_reference(ctl.reference_invariants, s)  # was "s_star_rate: ... index 7"
    cur = scene["cur"].copy()
    cur[4, 1] = np.nan  # was "pixels: non-finite value at index 8"
    with pytest.raises(vsinv.InvalidInput, match=r"pixels: non-finite value at row 4, column 1"):
        ctl.step(cur, scene["z"], np.ones(len(cur), bool))


@pytest.mark.parametrize("i, name", list(enumerate(["fku", "fkv", "u0", "v0", "skew"])))
def test_non_finite_intrinsics_name_the_parameter(i, name):
    args = [600.0, 600.0, 384.0, 288.0, np.pi / 2]
    args[i] = np.nan
    with pytest.raises(vsinv.InvalidInput, match=f"invalid intrinsics: {name} must be finite, got NaN"):
        vsinv.Intrinsics(*args)


def test_tracking_bound_names_its_arguments():
    for args, name in [((np.nan, 1.0, 1.0), "gain: non-finite value at index 0"),
                       ((1.0, np.nan, 1.0), "sigma: non-finite value at index 0"),
                       ((1.0, 1.0, np.inf), "max_b: non-finite value at index 0"),
                       ((0.0, 1.0, 1.0), "invalid parameter `gain`: must be > 0, got 0"),
                       ((1.0, 1.0, -1.0), "invalid parameter `max_b`: must be >= 0, got -1")]:
        with pytest.raises(vsinv.InvalidInput, match=name):
            vsinv.laws.tracking_bound(*args)
    with pytest.raises(vsinv.InvalidInput, match="kappa: non-finite value at index 0"):
        vsinv.laws.check_stability(lens(600.0), lens(600.0), kappa=np.nan)


def test_out_of_range_integers_raise_invalid_input_naming_the_argument(scene):
    image = np.zeros((20, 20), np.uint8)
    image[5:9, 5:9] = 200
    for kwargs, name in [({"threshold": 300}, r"threshold: expected an integer in \[0, 255\], got 300"),
                         ({"threshold": -1}, r"threshold: expected an integer in \[0, 255\], got -1"),
                         ({"min_area": -1}, r"min_area: expected an integer in \[0, 18446744073709551615\], got -1"),
                         ({"max_area": -1}, r"max_area: expected an integer in \[0, 18446744073709551615\], got -1"),
                         ({"max_area": 2**70}, r"max_area: expected an integer in \[0, 18446744073709551615\], got 2{70}".replace("2{70}", str(2**70)))]:
        with pytest.raises(vsinv.InvalidInput, match=name):  # was OverflowError
            vsinv.vision.detect_dots(image, **kwargs)
    with pytest.raises(vsinv.InvalidInput, match=r"min_area: expected an integer in \[0, 18446744073709551615\]"):
        vsinv.vision.DotTracker(image, [[7.0, 7.0]], min_area=-4)
    with pytest.raises(vsinv.InvalidInput, match=r"max_iter: expected an integer in \[0, 18446744073709551615\]"):
        vsinv.vision.undistort_points(scene["cur"], scene["k"], [0.1, 0.0, 0.0, 0.0], max_iter=-1)
    for threads in (-1, 2**31, 2**70):  # 2**31 used to start that many threads
        limit = r"invalid parameter `threads`: must be at most 1024" if threads == 2**31 else r"threads: expected an integer"
        with pytest.raises(vsinv.InvalidInput, match=f"{limit}.*, got {threads}"):
            vsinv.sim.run_batch([], threads=threads)
    with pytest.raises(TypeError, match=r"progress: expected a callable progress\(done, total\) or None"):
        vsinv.run_scenario("lens-12-12", progress="abc")


@pytest.mark.parametrize("bad", [(1.0, 2.0), (1.0, 2.0, 3.0, 4.0)])
def test_adaptive_gain_of_the_wrong_length(scene, bad):
    for cls in (vsinv.laws.InvariantController, vsinv.laws.IbvsController):
        with pytest.raises(vsinv.InvalidInput, match=r"adaptive_gain: expected \(lambda_0, lambda_inf, lambda'_0\), three numbers"):  # was ValueError
            cls(scene["ref"], scene["k"], adaptive_gain=bad)


def test_overflowing_results_raise_instead_of_returning_nan(scene):
    with pytest.raises(vsinv.InvalidInput, match=r"twist, dt: the motion twist \* dt overflows \(twist \[1\.0, 1\.0, 1\.0, 1\.0, 1\.0, 1\.0\], dt 1\.0e300\)"):
        vsinv.geometry.exp_twist(np.ones(6), 1e300)
    with pytest.raises(vsinv.InvalidInput, match=r"invalid parameter `thetau`: out of range: the rotation \(angle too large\) overflow"):
        vsinv.geometry.pose_from_position_thetau([0.0, 0.0, 0.0], [1e300, 0.0, 0.0])
    huge = scene["cur"] * 1e300
    with pytest.raises(vsinv.VsinvError, match="invalid parameter `pixels, depths`: out of range: the interaction matrices overflow"):
        vsinv.laws.interaction_matrix(huge, scene["z"], scene["k"])
    with pytest.raises(vsinv.VsinvError, match="invalid parameter `pixels, depths`: out of range: the rz coefficients overflow"):
        vsinv.laws.rz_coefficients(huge, scene["z"], scene["ref"], scene["k"])


def test_length_mismatches_name_the_arguments(scene):
    with pytest.raises(vsinv.InvalidInput, match=r"reference_depths: expected 12 values \(one per reference pixel\)"):
        vsinv.laws.IbvsController(scene["ref"], scene["k"], reference_depths=scene["z_star"][:5])
    with pytest.raises(vsinv.InvalidInput, match="first_depths.*first_pixels"):
        vsinv.calibration.ResectionDepths(scene["cur"][:0], scene["z"], scene["ref"])
    with pytest.raises(vsinv.InvalidInput, match="second_pixels.*first_pixels"):
        vsinv.calibration.depths_from_translation(scene["cur"][:0], scene["cur"])


def test_resection_visibility_is_a_bool_array_like_step_visible(scene):
    est = vsinv.calibration.ResectionDepths(scene["cur"], scene["z"], scene["ref"])
    n = len(scene["cur"])
    a = est.estimate(scene["cur"], np.ones(n, bool))
    np.testing.assert_allclose(a, est.estimate(scene["cur"], [True] * n))
    for bad in ("abc", np.ones(n, int), np.ones(n - 1, bool)):
        with pytest.raises(vsinv.InvalidInput, match=r"visible: expected (a bool array, got dtype|shape \(12,\), got \(11,\))"):  # "abc" was a TypeError
            est.estimate(scene["cur"], bad)


def test_bytes_paths_and_geometry_failures_of_depths_from_translation(scene):
    with pytest.raises(vsinv.InvalidInput, match="neither a scenario file"):
        vsinv.load_scenario(b"/nonexistent.toml")  # was TypeError
    assert vsinv.load_scenario(b"lens-12-12").name == "lens-12-12"
    flipped = scene["cur"].copy()
    with pytest.raises(vsinv.VsinvError, match="first_pixels|second_pixels") as info:
        vsinv.calibration.depths_from_translation(scene["ref"], flipped[::-1])
    assert "depth_estimation" not in str(info.value)


def test_sweep_helpers_refuse_bad_input_with_invalid_input():
    from vsinv.sweep import Choice, LogUniform, Uniform, noise_seeds, rotation_from_thetau, thetau_from_rotation

    for seed, points in [(-1, [0]), (0, [-1]), (0, [np.nan]), (0, [[1], [2, 3]]), (0, ["a"])]:
        with pytest.raises(vsinv.InvalidInput):
            noise_seeds(seed, points, np.zeros(len(points), int) if points and not isinstance(points[0], list) else [0])
    assert noise_seeds(np.int64(7), [0, 1], [0, 0]).tolist() == noise_seeds(7, [0, 1], [0, 0]).tolist()  # was OverflowError
    for bad, message in [([np.nan, 0.0, 0.0], "thetau: non-finite value at index 0"),
                         ("abc", "thetau: expected real numbers, got dtype <U3"),
                         ([1e300, 1e300, 0.0], r"invalid parameter `thetau`: out of range: the rotation \(angle too large\)"),
                         ([1.0, 2.0], r"thetau: expected shape \(3,\), got \(2,\)")]:
        with pytest.raises(vsinv.InvalidInput, match=message):  # NaN matrices or ValueError before
            rotation_from_thetau(bad)
    with pytest.raises(vsinv.InvalidInput, match="rot: non-finite value at row 0, column 0"):
        thetau_from_rotation(np.full((3, 3), np.nan))
    s = Uniform(-1e308, 1e308).sample(np.random.default_rng(0), 100)  # was OverflowError
    assert np.isfinite(s).all() and (np.abs(s) <= 1e308).all()
    s = LogUniform(1e300, 1e300).sample(np.random.default_rng(0), 10)  # rounded past hi before
    assert (s == 1e300).all()
    with pytest.raises(vsinv.InvalidInput, match="Choice: values must be a sequence"):
        Choice(None)


def test_summary_by_an_unknown_column_raises_invalid_input():
    from vsinv.sweep import SweepResult

    res = SweepResult(columns={"repeat": np.array([0]), "status": np.array(["converged"])})
    with pytest.raises(vsinv.InvalidInput, match=r"summary_by: keys: no column 'nope' \(columns: repeat, status\)"):  # was KeyError
        res.summary_by("nope")


def test_a_huge_search_radius_does_not_rescan_the_image_for_ever():
    import time

    image = np.zeros((120, 160), np.uint8)
    image[40:46, 60:66] = 220
    tracker = vsinv.vision.DotTracker(image, [[62.0, 42.0]], max_search_radius=1e300)
    t0 = time.perf_counter()
    pixels, found = tracker.track(np.zeros_like(image))  # the dot is gone: search the whole image once
    assert time.perf_counter() - t0 < 1.0  # took ~1000 full-image scans before
    assert not found[0]


def test_more_regressions(scene):
    out = vsinv.sim.run_batch([])
    assert out["status"].dtype.kind == "U" and out["message"].dtype.kind == "U"  # float64 when empty before
    base = vsinv.load_scenario("lens-12-12").to_dict()
    with pytest.raises(vsinv.InvalidInput, match=r"repeats, draws, vary: 1180591620717411303424 runs .*; at most 2147483648 in one sweep"):  # was NumPy's ValueError
        vsinv.sim.run_sweep(base, {"control.gain": [1.0]}, repeats=2**70, progress=False)
    base["object"]["points"][7][1] = 2.0**70
    once = vsinv.sim.Scenario.from_dict(base).to_dict()
    assert vsinv.sim.Scenario.from_dict(once).to_dict() == once  # JSON floats lost an ulp before
    with pytest.raises(vsinv.InvalidInput, match="reference_depths: non-finite value at index 3"):
        vsinv.laws.IbvsController(scene["ref"], scene["k"], reference_depths=np.where(np.arange(12) == 3, np.nan, 1.0))
    bad = scene["cur"].copy()
    bad[0, 0] = np.nan
    with pytest.raises(vsinv.InvalidInput, match="first_pixels: non-finite value at row 0, column 0"):
        vsinv.calibration.depths_from_translation(bad, scene["cur"])  # said "first image" before


def test_issue16_non_finite_results_raise_invalid_input():
    """Issue 16, item 4: these returned inf/NaN or accepted values the paper excludes."""
    for twist, dt in [([0, 0, 0, 1e300, 0, 0], 1.0), ([1.0, 0, 0, 1e200, 0, 0], 1.0), ([1e300] * 6, 1e10)]:
        with pytest.raises(vsinv.InvalidInput, match=r"twist, dt: the motion twist \* dt overflows"):
            vsinv.geometry.exp_twist(twist, dt)
    for position, thetau, name in [([0, 0, 0], [np.nan, 0, 0], "thetau: non-finite value at index 0"),
                                   ([np.inf, 0, 0], [0, 0, 0], "position: non-finite value at index 0"),
                                   ([0, 0, 0], [1e300, 1e300, 0], r"invalid parameter `thetau`: out of range: the rotation")]:
        with pytest.raises(vsinv.InvalidInput, match=name):
            vsinv.geometry.pose_from_position_thetau(position, thetau)
    for skew in (1e-300, 1e-4, np.pi - 1e-4):
        with pytest.raises(vsinv.InvalidInput, match=r"invalid intrinsics: skew angle must be in \[1e-3, pi - 1e-3\] rad"):
            vsinv.Intrinsics(800.0, 800.0, 384.0, 288.0, skew=skew)
    for kappa in (0.0, -1.0, -1e-320):
        with pytest.raises(vsinv.InvalidInput, match=r"invalid parameter `kappa`: the depth scale of sec\. 4\.1 must be > 0"):
            vsinv.laws.check_stability(lens(600.0), lens(600.0), kappa=kappa)
    for sigma in (0.0, -0.5, -1e300):
        with pytest.raises(vsinv.InvalidInput, match=r"invalid parameter `sigma`: must be > 0 \(smallest eigenvalue of A \+ A\^T; Prop\. 2 fails"):
            vsinv.laws.tracking_bound(1.0, sigma, 1.0)
    report = vsinv.laws.check_stability(lens(600.0), -np.diag([600.0, 600.0, -1.0]), kappa=1.0)
    assert not report.prop2 and report.sigma <= 0
    with pytest.raises(vsinv.InvalidInput, match=r"invalid parameter `sigma`: must be > 0 \(smallest eigenvalue of A \+ A\^T; Prop\. 2 fails"):
        report.tracking_bound(0.1)


def test_issue16_invariant_path_sample_refuses_nan():
    obj = object_points()
    ref, _ = view(obj, np.eye(4), lens(1200.0))
    from conftest import pose
    cur, _ = view(obj, pose((0.08, -0.05, -0.15), (0.1, -0.15, 0.4)), lens(700.0))
    path = vsinv.laws.InvariantPath(cur, ref, duration=2.0)
    for t in (np.nan, np.inf):
        with pytest.raises(vsinv.InvalidInput, match="t must be finite"):
            path.sample(t)
    q, r = path.sample(-1.0)
    assert np.isfinite(q).all() and np.isfinite(r).all()


def test_issue16_messages_print_short_numbers():
    """Issue 16, item 6: `{}` of 1e-320 or 1e300 printed 300+ digits in messages."""
    calls = [
        lambda: vsinv.Intrinsics(1e-320, 800.0, 0.0, 0.0),
        lambda: vsinv.Intrinsics(-1e300, 800.0, 0.0, 0.0),
        lambda: vsinv.Intrinsics(800.0, 800.0, 0.0, 0.0, skew=1e-320),
        lambda: vsinv.laws.tracking_bound(1.0, -1e-320, 1.0),
        lambda: vsinv.laws.tracking_bound(-1e300, 1.0, 1.0),
        lambda: vsinv.laws.check_stability(lens(600.0), lens(600.0), kappa=-1e300),
        lambda: vsinv.laws.InvariantController(view(object_points(), np.eye(4), lens(800.0))[0], lens(800.0), gain=-1e300),
    ]
    texts = []
    for f in calls:
        with pytest.raises(vsinv.InvalidInput) as info:
            f()
        texts.append(str(info.value))
        assert not re.search(r"\d{21,}", texts[-1]), texts[-1]
    assert any("1.0e-320" in t for t in texts) and any("1.0e300" in t for t in texts), texts


# Issue 17, item 6: exceptions carry the error's fields as attributes ------------------------

ATTRIBUTES = ("kind", "argument", "index", "row", "column", "expected", "got", "needed", "count", "reason", "basis",
              "image", "ratio", "threshold", "depth", "estimate", "hint", "key", "file", "field", "a_hat", "residual")


def raised(f):
    """The VsinvError `f` raises."""
    with pytest.raises(vsinv.VsinvError) as info:
        f()
    return info.value


def fields(err):
    """The attributes that apply (not None)."""
    return {name: getattr(err, name) for name in ATTRIBUTES if getattr(err, name) is not None}


def test_every_attribute_is_declared_and_none_by_default():
    for cls in (vsinv.VsinvError, vsinv.InvalidInput, vsinv.DegenerateGeometry, vsinv.NotReady):
        assert fields(cls("raised by Python code")) == {}
    for name in ATTRIBUTES:
        assert name in vsinv.VsinvError.__doc__


def test_attributes_of_bad_arrays(scene):
    ctl = vsinv.laws.InvariantController(scene["ref"], scene["k"])
    cur = scene["cur"].copy()
    cur[5, 1] = np.nan
    err = raised(lambda: ctl.step(cur, scene["z"]))
    assert isinstance(err, vsinv.InvalidInput)
    assert fields(err) == {"kind": "non_finite_point", "argument": "pixels", "row": 5, "column": 1}
    assert str(err) == "pixels: non-finite value at row 5, column 1"
    z = np.where(np.arange(12) == 3, np.nan, 1.0)
    err = raised(lambda: vsinv.laws.IbvsController(scene["ref"], scene["k"], reference_depths=z))
    assert fields(err) == {"kind": "non_finite", "argument": "reference_depths", "index": 3}
    err = raised(lambda: ctl.step(scene["cur"][:10], scene["z"][:10]))
    assert (err.kind, err.argument, err.got) == ("shape", "pixels", "10 points")
    assert err.expected.startswith("12 points")
    err = raised(lambda: ctl.step(np.zeros((12, 3)), scene["z"]))  # read by the bindings
    assert fields(err) == {"kind": "shape", "argument": "pixels", "expected": "shape (n, 2)", "got": "[12, 3]"}
    assert str(err) == "pixels: expected shape (n, 2), got [12, 3]"
    err = raised(lambda: ctl.step(np.zeros((12, 2), complex), scene["z"]))
    assert (err.kind, err.argument) == ("invalid_argument", "pixels")
    k = np.stack([scene["k"].matrix, np.full((3, 3), np.nan)])
    err = raised(lambda: vsinv.laws.check_stability(k, scene["k"]))
    assert fields(err) == {"kind": "non_finite_point", "argument": "K", "row": 0, "column": 0}


def test_attributes_of_bad_parameters(scene):
    err = raised(lambda: vsinv.laws.InvariantController(scene["ref"], scene["k"], gain=0.0))
    assert fields(err) == {"kind": "invalid_parameter", "argument": "gain", "reason": "must be finite and > 0, got 0"}
    err = raised(lambda: vsinv.Intrinsics(-1.0, 1.0, 0.0, 0.0))
    assert err.kind == "invalid_intrinsics" and "focal" in err.reason and err.argument is None
    err = raised(lambda: vsinv.laws.check_stability([scene["k"], np.ones((3, 3))], scene["k"]))
    assert (err.kind, err.argument) == ("invalid_intrinsics", "K") and str(err).startswith("K: matrix 1: ")
    for f, argument in [(lambda: vsinv.laws.InvariantController(scene["ref"], scene["k"], basis="widest"), "basis"),
                        (lambda: vsinv.vision.detect_dots(np.zeros((4, 4), np.uint8), threshold=300), "threshold"),
                        (lambda: vsinv.sim.run_batch([], threads=-1), "threads"),
                        (lambda: vsinv.load_scenario("/nonexistent.toml"), "scenario")]:
        err = raised(f)
        assert (type(err), err.kind, err.argument) == (vsinv.InvalidInput, "invalid_argument", argument)
    err = raised(lambda: vsinv.laws.InvariantController(scene["ref"], scene["k"]).eps)
    assert isinstance(err, vsinv.NotReady) and fields(err) == {"kind": "not_ready"}


def test_attributes_of_degenerate_geometry(scene):
    px = scene["ref"]
    err = raised(lambda: vsinv.laws.InvariantController(px[:5], scene["k"]))
    assert isinstance(err, vsinv.DegenerateGeometry)
    assert (err.kind, err.needed, err.count) == ("too_few_points", 6, 5) and "five dof" in err.reason
    line = px.copy()
    line[2] = (line[0] + line[1]) / 2
    err = raised(lambda: vsinv.laws.InvariantController(line, scene["k"], basis=(0, 1, 2)))
    assert fields(err) == {"kind": "collinear_basis", "basis": (0, 1, 2), "image": "reference", "ratio": 0.0}
    ctl = vsinv.laws.InvariantController(px, scene["k"])
    bad = scene["z"].copy()
    bad[7] = -0.5
    err = raised(lambda: ctl.step(scene["cur"], bad))
    assert fields(err) == {"kind": "point_behind_camera", "index": 7, "depth": -0.5}
    err = raised(lambda: ctl.step(scene["cur"], np.full(12, 0.6)))
    assert err.kind == "degenerate_structure" and err.ratio < err.threshold == 1e-3
    err = raised(lambda: vsinv.calibration.depths_from_translation(px, px))
    assert err.kind == "degenerate_estimate" and "epipole" in err.estimate and "did not move" in err.hint


def test_attributes_of_scenario_errors(tmp_path):
    d = vsinv.load_scenario("lens-12-12").to_dict()
    d["control"]["gain"] = -1.0
    err = raised(lambda: vsinv.sim.Scenario.from_dict(d))
    assert fields(err) == {"kind": "scenario", "key": "control.gain", "reason": "must be finite and > 0, got -1"}
    assert str(err) == "scenario: control.gain: must be finite and > 0, got -1"
    err = raised(lambda: vsinv.sim.run_batch([d]))
    assert (err.kind, err.key) == ("scenario", "[0].control.gain")
    err = raised(lambda: vsinv.sim.run_batch(["lens-12-12", 5]))  # re-raised with the item's index
    assert (err.kind, err.argument) == ("invalid_argument", "scenario") and str(err).startswith("scenario 1: ")
    arm = vsinv.load_scenario("arm-ur5-12-6").to_dict()
    arm["robot"]["end_effector"] = "nolink"
    err = raised(lambda: vsinv.run_scenario(arm))
    assert (err.kind, err.key) == ("scenario", "robot.end_effector") and "no link `nolink`" in err.reason
    path = tmp_path / "bad.toml"
    path.write_text(vsinv.load_scenario("lens-12-12").to_toml().replace("gain = ", "gain = -", 1))
    err = raised(lambda: vsinv.load_scenario(path))
    assert (err.kind, err.file, err.key) == ("scenario", str(path), "control.gain")
    assert str(err).startswith(f"{path}: scenario: control.gain: ")


def test_attributes_of_file_image_and_lens_errors(tmp_path):
    from test_distortion import ROS

    err = raised(lambda: vsinv.calibration.load_calibration("/nonexistent/cal.yaml"))
    assert (err.kind, err.file, err.field) == ("calibration", "/nonexistent/cal.yaml", None)
    assert err.reason.startswith("cannot read")
    path = tmp_path / "bad.yaml"
    path.write_text(ROS.replace("data: [812.25, 0.0, 323.5", "data: [812.25, 0.0, abc", 1))
    err = raised(lambda: vsinv.calibration.load_calibration(path))
    assert (err.kind, err.file, err.field) == ("calibration", str(path), "camera_matrix.data[2]")
    err = raised(lambda: vsinv.vision.detect_dots(np.zeros((4, 4, 2), np.uint8)))
    assert (err.kind, err.argument) == ("invalid_image", "image") and "grey" in err.reason and "(4, 4, 2)" in err.reason
    k = vsinv.Intrinsics(500.0, 500.0, 320.0, 240.0)
    px = np.array([[320.0, 240.0], [570.0, 240.0], [670.0, 240.0]])
    err = raised(lambda: vsinv.vision.undistort_points(px, k, [-0.4, 0.0, 0.0, 0.0]))
    assert (err.kind, err.index) == ("distortion", 2) and "folds" in err.reason


def test_attributes_survive_pickling(scene):
    import pickle

    ctl = vsinv.laws.InvariantController(scene["ref"], scene["k"])
    cur = scene["cur"].copy()
    cur[5, 1] = np.nan
    err = raised(lambda: ctl.step(cur, scene["z"]))
    back = pickle.loads(pickle.dumps(err))
    assert type(back) is vsinv.InvalidInput and str(back) == str(err) and fields(back) == fields(err)
