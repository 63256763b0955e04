"""The dot tracker's settings are declared once (Rust ``vision::tracker::TRACKER_SETTINGS``,
``vsinv.vision.TRACKER_SETTINGS``) and every layer reads the table: ``ImageServo``'s ``tracker``
dictionary, the ROS parameters ``tracker.*`` and the command options of ``vsinv invariance`` and
``vsinv replay``. Nothing here lists the settings: each test goes through the table (issue 29,
item 1)."""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np
import pytest

import vsinv
from vsinv import _core, cli_tracker
from vsinv.ros import params

pytestmark = pytest.mark.vision

SETTINGS = vsinv.vision.TRACKER_SETTINGS
NAMES = [s["name"] for s in SETTINGS]
K_HAT = _core.Intrinsics(1000.0, 1000.0, 320.0, 240.0)
SESSION = {"law": "none", "depths": 0.5}


def test_the_table_is_whole():
    assert SETTINGS is _core.TRACKER_SETTINGS
    assert len(NAMES) == len(set(NAMES)) >= 5
    for s in SETTINGS:
        assert s["kind"] in ("number", "count", "choice") and s["doc"], s
        assert (s["kind"] == "choice") == bool(s["choices"]), s
        if s["kind"] == "choice":
            assert s["default"] in s["choices"], s
        else:
            assert s["default"] >= s["min"] and not (s["min_open"] and s["default"] == s["min"]), s
    dots = next(t for t in _core.TARGETS if any(a["kind"] == "tracker" for a in t["args"]))
    tracker = next(a for a in dots["args"] if a["kind"] == "tracker")
    assert all(n in tracker["doc"] for n in NAMES), tracker["doc"]


@pytest.fixture(scope="module")
def reference() -> tuple[np.ndarray, np.ndarray]:
    image, pixels, _ = _core.render_view(vsinv.load_scenario("vision-12-6"), reference=True)
    return image, pixels


def _servo(reference: tuple[np.ndarray, np.ndarray], tracker: dict[str, Any]) -> Any:
    image, pixels = reference
    return _core.ImageServo(image, "dots", K_HAT, reference_points=pixels, tracker=tracker, **SESSION)


def _other_kind(s: dict[str, Any]) -> Any:
    return {"number": "wide", "count": "many", "choice": 3}[s["kind"]]


@pytest.mark.parametrize("s", SETTINGS, ids=NAMES)
def test_image_servo_takes_each_setting_and_refuses_another_kind(s, reference):
    _servo(reference, {s["name"]: s["default"]}).step(reference[0])
    with pytest.raises(vsinv.InvalidInput) as info:
        _servo(reference, {s["name"]: _other_kind(s)})
    assert s["name"] in str(info.value) and s["name"] in info.value.argument, str(info.value)


def test_image_servo_refuses_another_key_listing_the_table(reference):
    with pytest.raises(vsinv.InvalidInput) as info:
        _servo(reference, {"radius": 3.0})
    err = info.value
    assert str(err) == f"tracker.radius: unknown key; known: {', '.join(NAMES)}"
    assert (err.argument, err.location) == ("tracker.radius", ("tracker.radius",))


@pytest.mark.parametrize("s", SETTINGS, ids=NAMES)
def test_ros_parameters_give_each_setting(s, tmp_path):
    name = f"tracker.{s['name']}"
    p = params._BY_NAME[name]
    assert p.kind == {"number": "float", "count": "int", "choice": "str"}[s["kind"]]
    assert s["doc"] in p.doc
    reference = tmp_path / "reference.png"
    vsinv.vision.save_image(np.full((48, 64), 128, np.uint8), reference)
    base = {"reference_image": str(reference), "camera_frame": "camera", "target": "dots",
            "reference_points": [10.0, 20.0, 30.0, 40.0, 50.0, 20.0]}
    config = params.parse_parameters({**base, name: s["default"]})
    assert config.target == "dots"
    tracker_params = {n for n in params._BY_NAME if n.startswith("tracker.")}
    assert tracker_params == {f"tracker.{n}" for n in NAMES}


def _command(*extra: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    cli_tracker.add_tracker_options(parser)
    return parser.parse_args(list(extra))


def test_command_options_default_to_the_table():
    options = cli_tracker.tracker_options(_command())
    assert set(options) == set(NAMES)
    for s in SETTINGS:
        assert options[s["name"]] == s["default"], s["name"]


@pytest.mark.parametrize("s", [s for s in SETTINGS if s["kind"] == "number"], ids=lambda s: s["name"])
def test_command_options_hold_the_tables_bound(s):
    flag = "--" + s["name"].replace("_", "-")
    below = s["min"] if s["min_open"] else s["min"] - 0.5
    with pytest.raises(SystemExit):
        _command(flag, str(below))
    assert _command(flag, str(s["min"] + 0.5)).__dict__[s["name"]] == s["min"] + 0.5
