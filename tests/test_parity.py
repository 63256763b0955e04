"""Python parity with the Rust API: masked steps, K_hat updates, repr, pickling, docstrings."""

import inspect
import pickle

import numpy as np
import pytest

import vsinv
import vsinv._core
from conftest import lens


def hide(pixels, depths, hidden):
    """Pixels and depths with the hidden points set to NaN (they must be ignored) and the mask."""
    visible = np.ones(len(pixels), dtype=bool)
    visible[list(hidden)] = False
    px, z = pixels.copy(), depths.copy()
    px[~visible] = np.nan
    z[~visible] = np.nan
    return px, z, visible


# --- step with visible -------------------------------------------------------------------


@pytest.mark.parametrize("hidden", [[5], [4, 10], [1, 6, 11]])
def test_ibvs_step_visible_against_numpy(scene, hidden):
    k = scene["k"]
    ctl = vsinv.laws.IbvsController(scene["ref"], k, gain=0.5)
    px, z, visible = hide(scene["cur"], scene["z"], hidden)
    tw = ctl.step(px, z, visible)
    km = k.matrix
    rows = []
    for (u, v), zz in zip(scene["cur"][visible], scene["z"][visible]):
        x, y, _ = np.linalg.solve(km, [u, v, 1.0])
        lx = np.array([[-1 / zz, 0, x / zz, x * y, -(1 + x * x), y], [0, -1 / zz, y / zz, 1 + y * y, -x * y, -x]])
        rows.append(km[:2, :2] @ lx)
    err = (scene["cur"] - scene["ref"])[visible].ravel()
    expected = -0.5 * np.linalg.pinv(np.vstack(rows)) @ err
    np.testing.assert_allclose(tw, expected, rtol=1e-7, atol=1e-10)
    rms = np.sqrt(((scene["cur"] - scene["ref"])[visible] ** 2).sum(axis=1).mean())
    assert ctl.pixel_error == pytest.approx(rms)


@pytest.mark.parametrize(("basis", "hidden"), [((0, 3, 8), [5]), ((0, 3, 8), [1, 11]), ((2, 6, 9), [0, 4, 10])])
def test_invariant_step_visible_equals_the_reduced_controller(scene, basis, hidden):
    k_hat = vsinv.Intrinsics(650.0, 570.0, 395.0, 280.0)
    ctl = vsinv.laws.InvariantController(scene["ref"], k_hat, gain=0.7, gain_rz=1.3, basis=basis)
    px, z, visible = hide(scene["cur"], scene["z"], hidden)
    tw = ctl.step(px, z, visible)
    keep = np.flatnonzero(visible)
    reduced_basis = tuple(int(np.searchsorted(keep, b)) for b in basis)
    reduced = vsinv.laws.InvariantController(scene["ref"][keep], k_hat, gain=0.7, gain_rz=1.3, basis=reduced_basis)
    expected = reduced.step(scene["cur"][keep], scene["z"][keep])
    np.testing.assert_allclose(tw, expected, rtol=1e-12, atol=1e-15)
    assert ctl.invariant_error == pytest.approx(reduced.invariant_error, rel=1e-12)


def test_step_visible_all_visible_equals_step(scene):
    for make in (vsinv.laws.InvariantController, vsinv.laws.IbvsController):
        a, b = make(scene["ref"], scene["k"]), make(scene["ref"], scene["k"])
        mask = np.ones(12, dtype=bool)
        np.testing.assert_array_equal(a.step(scene["cur"], scene["z"], mask), b.step(scene["cur"], scene["z"]))
        # a list of bools is converted; a strided bool array is read
        np.testing.assert_array_equal(a.step(scene["cur"], scene["z"], [True] * 12), b.step(scene["cur"], scene["z"]))
        strided = np.ones(24, dtype=bool)[::2]
        np.testing.assert_array_equal(a.step(scene["cur"], scene["z"], strided), b.step(scene["cur"], scene["z"]))
        # visible=None is every point
        np.testing.assert_array_equal(a.step(scene["cur"], scene["z"], visible=None), b.step(scene["cur"], scene["z"]))


def test_too_few_visible_points(scene):
    ctl = vsinv.laws.InvariantController(scene["ref"], scene["k"], basis=(0, 1, 2))
    px, z, visible = hide(scene["cur"], scene["z"], [1])  # a basis point
    with pytest.raises(vsinv.DegenerateGeometry, match="too few points"):
        ctl.step(px, z, visible)
    px, z, visible = hide(scene["cur"], scene["z"], range(5, 12))  # 2 non-basis points left
    with pytest.raises(vsinv.DegenerateGeometry, match="too few points"):
        ctl.step(px, z, visible)
    ibvs = vsinv.laws.IbvsController(scene["ref"], scene["k"])
    px, z, visible = hide(scene["cur"], scene["z"], range(3, 12))
    with pytest.raises(vsinv.DegenerateGeometry, match="too few points"):
        ibvs.step(px, z, visible)


@pytest.mark.parametrize(
    "mask",
    [
        np.ones(11, dtype=bool),
        np.ones(13, dtype=bool),
        np.ones(12, dtype=int),
        np.ones(12, dtype=float),
        [1] * 12,
        np.ones((12, 1), dtype=bool),
        np.ones((3, 4), dtype=bool),
        "abc",
    ],
)
def test_bad_visible(scene, mask):
    for make in (vsinv.laws.InvariantController, vsinv.laws.IbvsController):
        ctl = make(scene["ref"], scene["k"])
        with pytest.raises(vsinv.InvalidInput, match=r"visible: expected (a bool array, got dtype|shape \(12,\), got)"):
            ctl.step(scene["cur"], scene["z"], mask)


# --- set_k_hat ----------------------------------------------------------------------------


def test_set_k_hat_acts_as_a_controller_built_with_it(scene):
    k1, k2 = vsinv.Intrinsics(650.0, 570.0, 395.0, 280.0), vsinv.Intrinsics(900.0, 880.0, 380.0, 300.0, skew=1.5)
    ctl = vsinv.laws.InvariantController(scene["ref"], k1, gain=0.7, basis=(0, 3, 8))
    before = ctl.step(scene["cur"], scene["z"])
    assert ctl.k_hat == k1
    ctl.set_k_hat(k2)
    assert ctl.k_hat == k2
    fresh = vsinv.laws.InvariantController(scene["ref"], k2, gain=0.7, basis=(0, 3, 8))
    after = ctl.step(scene["cur"], scene["z"])
    np.testing.assert_array_equal(after, fresh.step(scene["cur"], scene["z"]))
    assert not np.allclose(before, after)
    # a 3x3 matrix works as elsewhere
    ctl.set_k_hat(k1.matrix)
    np.testing.assert_allclose(ctl.k_hat.matrix, k1.matrix, rtol=1e-14, atol=1e-12)
    np.testing.assert_allclose(ctl.step(scene["cur"], scene["z"]), before, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize(
    ("k_hat", "match"),
    [
        (np.diag([np.nan, 600.0, 1.0]), "K_hat: non-finite value at row 0, column 0"),
        (np.array([[600.0, 0.0, np.inf], [0.0, 600.0, 200.0], [0.0, 0.0, 1.0]]), "K_hat: non-finite value at row 0, column 2"),
        (np.eye(4), r"K_hat: expected shape \(3, 3\), got \[4, 4\]"),
        ("abc", "K_hat: expected a real numeric array, got dtype <U3"),
        (np.diag([-600.0, 600.0, 1.0]), r"invalid intrinsics: K\[0,0\] and K\[1,1\] must be > 0, got -600 and 600"),
    ],
)
def test_bad_k_hat(scene, k_hat, match):
    ctl = vsinv.laws.InvariantController(scene["ref"], scene["k"])
    with pytest.raises(vsinv.InvalidInput, match=match):
        ctl.set_k_hat(k_hat)
    assert ctl.k_hat == scene["k"]
    with pytest.raises(vsinv.InvalidInput, match=match):
        vsinv.laws.InvariantController(scene["ref"], k_hat)
    with pytest.raises(vsinv.InvalidInput, match=match):
        vsinv.laws.IbvsController(scene["ref"], k_hat)


# --- repr ---------------------------------------------------------------------------------


def test_intrinsics_repr_round_trips():
    k = vsinv.Intrinsics(1200.5, 1100.0, 390.25, 280.0, skew=1.4)
    assert repr(k) == "Intrinsics(fku=1200.5, fkv=1100.0, u0=390.25, v0=280.0, skew=1.4)"
    assert eval(repr(k), {"Intrinsics": vsinv.Intrinsics}) == k
    assert k == vsinv.Intrinsics(1200.5, 1100.0, 390.25, 280.0, skew=1.4)
    assert k != vsinv.Intrinsics(1200.5, 1100.0, 390.25, 280.0)
    assert k != "Intrinsics"


def test_controller_reprs(scene):
    ctl = vsinv.laws.InvariantController(
        scene["ref"], lens(600.0), gain=0.7, gain_rz=1.3, basis=(0, 3, 8), feedforward=False,
        min_structure_ratio=1e-4, rz_task="tau21", adaptive_gain=(4.0, 0.4, 30.0), max_linear_speed=0.25,
    )
    r = repr(ctl)
    assert r.startswith("InvariantController(")
    for part in (
        "n_points=12", "K_hat=Intrinsics(fku=600.0, fkv=600.0, u0=384.0, v0=288.0", "gain=0.7", "gain_rz=1.3",
        "basis=(0, 3, 8)", "feedforward=False", "min_structure_ratio=0.0001", "rz_task='tau21'",
        "adaptive_gain=(4.0, 0.4, 30.0)", "max_linear_speed=0.25", "max_angular_speed=None",
    ):
        assert part in r, (part, r)
    assert "feedforward=True" in repr(vsinv.laws.InvariantController(scene["ref"], lens(600.0)))
    ibvs = vsinv.laws.IbvsController(
        scene["ref"], lens(600.0), gain=0.5, interaction="mean", reference_depths=scene["z_star"],
        max_angular_speed=1.0,
    )
    r = repr(ibvs)
    assert r.startswith("IbvsController(")
    for part in (
        "n_points=12", "K_hat=Intrinsics(fku=600.0", "gain=0.5", "interaction='mean'", "reference_depths=given",
        "adaptive_gain=None", "max_linear_speed=None", "max_angular_speed=1.0",
    ):
        assert part in r, (part, r)


# --- pickling -----------------------------------------------------------------------------


def round_trip(obj):
    return pickle.loads(pickle.dumps(obj))


def test_intrinsics_pickle():
    for k in (vsinv.Intrinsics(1200.0, 1100.0, 390.0, 280.0, skew=1.4), vsinv.Intrinsics.from_matrix(np.diag([5.0, 7.0, 1.0]))):
        back = round_trip(k)
        assert back == k and type(back) is vsinv.Intrinsics
        np.testing.assert_array_equal(back.matrix, k.matrix)


INVARIANT_CONFIGS = [
    {},
    {"gain": 0.7, "gain_rz": 1.3, "basis": (0, 3, 8), "feedforward": False, "min_structure_ratio": 1e-4,
     "rz_task": "tau21"},
    {"basis": "auto", "adaptive_gain": (4.0, 0.4, 30.0), "max_linear_speed": 0.01, "max_angular_speed": 0.02},
    {"max_angular_speed": 0.05},
]


@pytest.mark.parametrize("config", INVARIANT_CONFIGS)
def test_invariant_controller_pickle(scene, config):
    k_hat = vsinv.Intrinsics(650.0, 570.0, 395.0, 280.0, skew=1.5)
    ctl = vsinv.laws.InvariantController(scene["ref"], k_hat, **config)
    copy = round_trip(ctl)
    assert type(copy) is vsinv.laws.InvariantController
    assert repr(copy) == repr(ctl) and copy.k_hat == k_hat and copy.basis == ctl.basis
    fresh = vsinv.laws.InvariantController(scene["ref"], k_hat, **config)
    np.testing.assert_array_equal(copy.step(scene["cur"], scene["z"]), fresh.step(scene["cur"], scene["z"]))
    # after steps, a K_hat change and a moving reference: the next twist is the original's
    ctl.step(scene["cur"], scene["z"])
    ctl.set_k_hat(lens(700.0))
    s = ctl.reference_invariants
    d = np.zeros_like(s)
    d[:, 0], d[:, 1] = 0.01, -0.01
    ctl.set_reference(s + d, rate=0.1 * d)
    copy = round_trip(ctl)
    assert copy.k_hat == lens(700.0)
    np.testing.assert_array_equal(copy.reference_invariants, ctl.reference_invariants)
    np.testing.assert_array_equal(copy.step(scene["cur"], scene["z"]), ctl.step(scene["cur"], scene["z"]))
    # the state of the last step is not kept
    with pytest.raises(RuntimeError, match="no control step"):
        _ = round_trip(ctl).eps


IBVS_CONFIGS = [
    {},
    {"gain": 0.5, "interaction": "desired", "reference_depths": "z_star"},
    {"interaction": "mean", "reference_depths": "z_star", "adaptive_gain": (2.0, 0.5, 0.01), "max_linear_speed": 0.01},
    {"max_angular_speed": 0.02},
]


@pytest.mark.parametrize("config", IBVS_CONFIGS)
def test_ibvs_controller_pickle(scene, config):
    config = {k: scene[v] if k == "reference_depths" else v for k, v in config.items()}
    ctl = vsinv.laws.IbvsController(scene["ref"], scene["k"], **config)
    copy = round_trip(ctl)
    assert type(copy) is vsinv.laws.IbvsController and repr(copy) == repr(ctl)
    fresh = vsinv.laws.IbvsController(scene["ref"], scene["k"], **config)
    np.testing.assert_array_equal(copy.step(scene["cur"], scene["z"]), fresh.step(scene["cur"], scene["z"]))
    ctl.step(scene["cur"], scene["z"])
    copy = round_trip(ctl)
    assert copy.pixel_error is None
    np.testing.assert_array_equal(copy.step(scene["cur"], scene["z"]), ctl.step(scene["cur"], scene["z"]))


# --- docstrings ---------------------------------------------------------------------------


def core_classes():
    return [
        obj for _, obj in inspect.getmembers(vsinv._core, inspect.isclass) if obj.__module__ == "vsinv._core"
    ]


def test_core_classes_are_found():
    names = {c.__name__ for c in core_classes()}
    assert {"Intrinsics", "InvariantController", "IbvsController", "StabilityReport", "Scenario"} <= names


@pytest.mark.parametrize("cls", core_classes(), ids=lambda c: c.__name__)
def test_every_public_attribute_has_a_docstring(cls):
    assert (cls.__doc__ or "").strip(), f"{cls.__name__} has no docstring"
    missing = [
        name for name, attr in vars(cls).items() if not name.startswith("_") and not (attr.__doc__ or "").strip()
    ]
    assert not missing, f"{cls.__name__}: no docstring on {missing}"
