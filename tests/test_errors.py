"""Bad input raises the package's own exceptions, never a panic or a silent answer."""

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
    with pytest.raises(vsinv.InvalidInput, match="upper triangular"):
        vsinv.Intrinsics.from_matrix(np.ones((3, 3)))
    with pytest.raises(vsinv.InvalidInput, match="shape"):
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
    return [vsinv.InvariantController(px, lens(1200.0)), vsinv.IbvsController(px, lens(1200.0))]


def test_nan_and_inf_pixels_and_depths(ref):
    px, z = ref
    for ctl in controllers(px):
        bad = px.copy()
        bad[4, 1] = np.nan
        with pytest.raises(vsinv.InvalidInput, match="non-finite"):
            ctl.step(bad, z)
        badz = z.copy()
        badz[5] = np.inf
        with pytest.raises(vsinv.InvalidInput, match="non-finite"):
            ctl.step(px, badz)
    with pytest.raises(vsinv.InvalidInput):
        vsinv.invariant_points(np.full((6, 2), np.nan))
    with pytest.raises(vsinv.InvalidInput):
        vsinv.project(np.array([[0.0, np.nan, 1.0]]), lens(100.0))


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
        with pytest.raises(vsinv.InvalidInput, match="12 points"):
            ctl.step(px[:10], z[:10])
        with pytest.raises(vsinv.InvalidInput, match="depths"):
            ctl.step(px, z[:5])
        with pytest.raises(vsinv.InvalidInput):
            ctl.step(px, z.reshape(3, 4))


def test_too_few_points(ref):
    px, z = ref
    with pytest.raises(vsinv.DegenerateGeometry, match="too few points"):
        vsinv.InvariantController(px[:5], lens(1200.0))
    with pytest.raises(vsinv.DegenerateGeometry, match="too few points"):
        vsinv.IbvsController(px[:3], lens(1200.0))


def test_collinear_basis(ref):
    px, z = ref
    line = px.copy()
    line[2] = (line[0] + line[1]) / 2
    with pytest.raises(vsinv.DegenerateGeometry, match="collinear"):
        vsinv.InvariantController(line, lens(1200.0))
    with pytest.raises(vsinv.DegenerateGeometry, match="collinear"):
        vsinv.invariant_points(line)
    ctl = vsinv.InvariantController(px, lens(1200.0))
    with pytest.raises(vsinv.DegenerateGeometry, match="collinear.*current"):
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
        vsinv.project(np.array([[0.0, 0.0, 1.0], [0.1, 0.1, -1.0]]), lens(100.0))


def test_planar_object_and_equal_depths(ref):
    px, z = ref
    planar = object_points()
    planar[:, 2] = 0.6 + 0.2 * planar[:, 0]
    ppx, pz = view(planar, np.eye(4), lens(1200.0))
    ctl = vsinv.InvariantController(ppx, lens(1200.0), basis=(0, 3, 8))
    with pytest.raises(vsinv.DegenerateGeometry, match="planar"):
        ctl.step(ppx + 3.0, pz)
    ctl = vsinv.InvariantController(px, lens(1200.0))
    with pytest.raises(vsinv.DegenerateGeometry, match="equal"):
        ctl.step(px + 3.0, np.full(12, 0.6))
    assert vsinv.structure_ratio(ppx, pz, lens(1200.0), basis=(0, 3, 8)) < 1e-6


@pytest.mark.parametrize("k_hat", [np.diag([-1200.0, 1200.0, 1.0]), np.diag([1200.0, 0.0, 1.0])])
def test_non_positive_focal_estimate(ref, k_hat):
    with pytest.raises(vsinv.InvalidInput, match="> 0"):
        vsinv.InvariantController(ref[0], k_hat)
    with pytest.raises(vsinv.InvalidInput):
        vsinv.IbvsController(ref[0], k_hat)


def test_bad_parameters(ref):
    px, z = ref
    with pytest.raises(vsinv.InvalidInput, match="gain"):
        vsinv.InvariantController(px, lens(1200.0), gain=0.0)
    with pytest.raises(vsinv.InvalidInput, match="gain_rz"):
        vsinv.InvariantController(px, lens(1200.0), gain_rz=np.nan)
    with pytest.raises(vsinv.InvalidInput, match="basis"):
        vsinv.InvariantController(px, lens(1200.0), basis=(0, 1, 12))
    with pytest.raises(vsinv.InvalidInput, match="basis"):
        vsinv.InvariantController(px, lens(1200.0), basis=(0, 0, 1))
    with pytest.raises(vsinv.InvalidInput, match="basis"):
        vsinv.InvariantController(px, lens(1200.0), basis=(0, -1, 2))
    with pytest.raises(vsinv.InvalidInput, match="basis"):
        vsinv.InvariantController(px, lens(1200.0), basis="widest")
    with pytest.raises(vsinv.InvalidInput, match="interaction"):
        vsinv.IbvsController(px, lens(1200.0), interaction="sideways")
    with pytest.raises(vsinv.InvalidInput, match="reference_depths"):
        vsinv.IbvsController(px, lens(1200.0), interaction="desired")
    ctl = vsinv.InvariantController(px, lens(1200.0))
    with pytest.raises(vsinv.InvalidInput, match="sum to 1"):
        ctl.set_reference(np.zeros((9, 3)))
    with pytest.raises(vsinv.InvalidInput, match="s_star"):
        ctl.set_reference(np.zeros((8, 3)))
    with pytest.raises(vsinv.NotReady, match="no control step"):
        _ = ctl.eps
    assert issubclass(vsinv.NotReady, vsinv.VsinvError) and issubclass(vsinv.NotReady, RuntimeError)
    with pytest.raises(vsinv.InvalidInput):
        vsinv.check_stability(np.ones((3, 3)), lens(1.0))
    with pytest.raises(vsinv.InvalidInput):
        vsinv.check_stability(lens(1.0), np.diag([0.0, 1.0, 1.0]))
    with pytest.raises(vsinv.InvalidInput):
        vsinv.tracking_bound(-1.0, 1.0, 1.0)


def test_no_panic_ever_reaches_python(ref):
    """Fuzz the step with junk: only package exceptions come out."""
    rng = np.random.default_rng(0)
    px, z = ref
    ctl = vsinv.InvariantController(px, lens(1200.0))
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
    ctl = vsinv.InvariantController(scene["ref"], scene["k"])
    with pytest.raises(vsinv.InvalidInput, match=r"pixels: non-finite value at row 5, column 1"):
        ctl.step(cur, scene["z_star"])
    ref = scene["ref"].copy()
    ref[4, 0] = np.inf
    with pytest.raises(vsinv.InvalidInput, match=r"reference_pixels: non-finite value at row 4, column 0"):
        vsinv.IbvsController(ref, scene["k"])


def test_equal_depths_are_refused_with_what_to_do_instead(scene):
    ctl = vsinv.InvariantController(scene["ref"], scene["k"])
    with pytest.raises(vsinv.DegenerateGeometry, match="reference depths") as info:
        ctl.step(scene["cur"], np.full(len(scene["cur"]), 0.6))
    assert "estimated" in str(info.value)
