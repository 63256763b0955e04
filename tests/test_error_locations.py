"""Issue 29, item 4: an error that names a position in its input carries it as data, the
attribute ``location`` (a tuple of keys and indices from the input's root, as pydantic-core's
``loc``; Rust ``vsinv::Location``), and its message names the same position.

Every kind of ``vsinv._core.ERROR_KINDS`` is either raised here with its location, or listed
as having none: a new kind must be sorted into one of the two."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

import numpy as np
import pytest

import vsinv
from vsinv import _core
from conftest import lens, object_points, pose, view

FIXTURES = Path(__file__).parent / "fixtures" / "calibration"

# Kinds whose error is about no one position of an input (the whole scene, a number, a state).
NO_LOCATION = {
    "invalid_intrinsics",
    "too_few_points",
    "collinear_basis",
    "point_behind_camera",
    "degenerate_structure",
    "degenerate_estimate",
    "urdf",
    "rz_singular",
    "unreachable",
    "degenerate_motion",
    "not_ready",
}


def _scene() -> dict[str, Any]:
    k = lens(600.0)
    ref, _ = view(object_points(), np.eye(4), lens(1200.0))
    cur, z = view(object_points(), pose((0.05, -0.03, -0.08), (0.1, -0.2, 0.3)), k)
    return {"k": k, "ref": ref, "cur": cur, "z": z}


def _nan_pixel() -> None:
    s = _scene()
    cur = s["cur"].copy()
    cur[5, 1] = np.nan
    vsinv.laws.InvariantController(s["ref"], s["k"]).step(cur, s["z"])


def _nan_depth() -> None:
    s = _scene()
    vsinv.laws.IbvsController(s["ref"], s["k"], reference_depths=np.where(np.arange(12) == 3, np.nan, 1.0))


def _short_pixels() -> None:
    s = _scene()
    vsinv.laws.InvariantController(s["ref"], s["k"]).step(s["cur"][:10], s["z"][:10])


def _bad_gain() -> None:
    s = _scene()
    vsinv.laws.InvariantController(s["ref"], s["k"], gain=0.0)


def _bad_basis() -> None:
    s = _scene()
    vsinv.laws.InvariantController(s["ref"], s["k"], basis="widest")


def _scenario_key() -> None:
    d = vsinv.load_scenario("lens-12-12").to_dict()
    d["control"]["gain"] = -1.0
    vsinv.sim.Scenario.from_dict(d)


def _uniform_image() -> None:
    vsinv.vision.detect_dots(np.zeros((40, 30), np.uint8))


def _folded_lens() -> None:
    k = vsinv.Intrinsics(500.0, 500.0, 320.0, 240.0)
    px = np.array([[320.0, 240.0], [570.0, 240.0], [670.0, 240.0]])
    vsinv.vision.undistort_points(px, k, [-0.4, 0.0, 0.0, 0.0])


def _calibration_entry(tmp_path: Path) -> None:
    ros = (FIXTURES / "ros_plumb_bob.yaml").read_text()
    path = tmp_path / "bad.yaml"
    path.write_text(ros.replace("data: [812.25, 0.0, 323.5", "data: [812.25, 0.0, abc", 1))
    vsinv.calibration.load_calibration(path)


def _bad_pose() -> None:
    poses = [np.eye(4) for _ in range(3)]
    bad = np.eye(4)
    bad[3, 0] = 1.0
    vsinv.calibration.calibrate_hand_eye([poses[0], bad, poses[2]], poses)


# kind -> (the call, its location, the text of the location in the message)
CASES: dict[str, tuple[Callable[..., None], tuple[Any, ...], str]] = {
    "non_finite_point": (_nan_pixel, ("pixels", 5, 1), "pixels: non-finite value at row 5, column 1"),
    "non_finite": (_nan_depth, ("reference_depths", 3), "reference_depths: non-finite value at index 3"),
    "shape": (_short_pixels, ("pixels",), "pixels: expected 12 points"),
    "invalid_parameter": (_bad_gain, ("gain",), "invalid parameter `gain`"),
    "invalid_argument": (_bad_basis, ("basis",), "basis: "),
    "scenario": (_scenario_key, ("control", "gain"), "scenario: control.gain: "),
    "invalid_image": (_uniform_image, ("image",), "image: uniform image"),
    "distortion": (_folded_lens, (2,), "distortion: point 2: "),
    "calibration": (_calibration_entry, ("camera_matrix", "data", 2), ": camera_matrix.data[2]: "),
    "invalid_pose": (_bad_pose, ("gripper_poses", 1), "gripper_poses[1]: not a rigid transform"),
}


def test_every_kind_is_sorted_into_located_or_not() -> None:
    kinds = {k["kind"] for k in _core.ERROR_KINDS}
    assert set(CASES) | NO_LOCATION == kinds, sorted(kinds ^ (set(CASES) | NO_LOCATION))
    assert not set(CASES) & NO_LOCATION
    assert "location" in {a["name"] for a in _core.ERROR_ATTRIBUTES}


@pytest.mark.parametrize("kind", sorted(CASES))
def test_python_sees_the_location_and_the_message_names_it(kind: str, tmp_path: Path) -> None:
    call, location, text = CASES[kind]
    with pytest.raises(vsinv.VsinvError) as info:
        call(tmp_path) if kind == "calibration" else call()
    err = info.value
    assert err.kind == kind, (err.kind, str(err))
    assert err.location == location, (err.location, str(err))
    assert isinstance(err.location, tuple)
    assert all(type(step) in (str, int) for step in err.location)
    assert text in str(err), str(err)
    # Each step of the location is in the message, in order.
    message, at = str(err), 0
    for step in location:
        found = message.find(str(step), at)
        assert found >= 0, (step, message)
        at = found


def test_a_batch_item_location_starts_with_its_index() -> None:
    d = vsinv.load_scenario("lens-12-12").to_dict()
    d["control"]["gain"] = -1.0
    with pytest.raises(vsinv.InvalidInput) as info:
        vsinv.sim.run_batch(["lens-12-12", d])
    err = info.value
    assert (err.kind, err.key, err.location) == ("scenario", "[1].control.gain", (1, "control", "gain"))
    assert "scenario: [1].control.gain: must be finite and > 0" in str(err)


def test_a_value_deep_in_a_scenario_dict_is_located_to_its_index() -> None:
    d = vsinv.load_scenario("lens-12-12").to_dict()
    d["object"]["points"][2][1] = "x"
    with pytest.raises(vsinv.InvalidInput) as info:
        vsinv.sim.Scenario.from_dict(d)
    err = info.value
    assert err.kind == "scenario"
    assert err.location[:3] == ("object", "points", 2), (err.location, str(err))
    assert err.key.startswith("object.points[2]") and f"scenario: {err.key}: " in str(err)


def test_the_whole_document_is_the_empty_location(tmp_path: Path) -> None:
    path = tmp_path / "big.toml"
    path.write_text("# " + "x" * (17 << 20))
    with pytest.raises(vsinv.InvalidInput) as info:
        vsinv.load_scenario(path)
    err = info.value
    assert err.kind == "scenario" and err.key is None and err.location == (), (err.location, str(err))


def test_a_location_survives_pickling() -> None:
    import pickle

    with pytest.raises(vsinv.InvalidInput) as info:
        _nan_pixel()
    back = pickle.loads(pickle.dumps(info.value))
    assert back.location == ("pixels", 5, 1) and str(back) == str(info.value)
