"""The targets are declared once (Rust ``vision::targets::TARGETS``, ``vsinv._core.TARGETS``) and
every layer reads the table: ``ImageServo``'s ``target`` and keyword arguments, ``vsinv replay
--target``, the ROS parameters and the stub. Nothing here lists the targets: each test goes
through the table, so a new entry is tested in every layer as it is added (tests/targets.rs does
the scenario schema and the image loop)."""

from __future__ import annotations

import argparse
import ast
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import vsinv
from vsinv import _core, cli_images, cli_replay
from vsinv.ros import params

pytestmark = pytest.mark.vision

TARGETS = _core.TARGETS
NAMES = [t["name"] for t in TARGETS]
STUB = Path(vsinv.__file__).with_name("_core.pyi")
K_HAT = _core.Intrinsics(1000.0, 1000.0, 320.0, 240.0)
SESSION = {"law": "none", "depths": 0.5}


def test_the_table_is_whole():
    assert len(NAMES) == len(set(NAMES)) >= 2
    args = [a["name"] for t in TARGETS for a in t["args"]]
    assert len(args) == len(set(args)), "an argument in two targets"
    for t in TARGETS:
        assert t["doc"] and t["detector"]["name"] and t["detector"]["doc"], t
        # A simulated target reads scenario keys; one of real images only reads none.
        assert bool(t["scenario_keys"]) == t["simulated"] and all("." in k for k in t["scenario_keys"]), t
        for a in t["args"]:
            assert a["kind"] in ("points", "choice", "ids", "count", "tracker"), a
            assert a["doc"], a
            assert (a["kind"] == "choice") == bool(a["choices"]), a
            if a["default"] is not None and a["kind"] == "choice":
                assert a["default"] in a["choices"], a
            if a["default"] is not None and a["kind"] == "count":  # an int, as the ROS parameter's type
                assert type(a["default"]) is int and a["min"] <= a["default"] <= a["max"], a
    assert {a["name"]: a["choices"] for t in TARGETS for a in t["args"]}["family"] == _core.TAG_FAMILIES


def _stub_tree() -> ast.Module:
    return ast.parse(STUB.read_text())


def test_the_stub_names_every_target():
    tree = _stub_tree()
    alias = next(
        n for n in tree.body
        if isinstance(n, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "_TargetName" for t in n.targets)
    )
    assert isinstance(alias.value, ast.Subscript)
    names = [e.value for e in ast.walk(alias.value.slice) if isinstance(e, ast.Constant)]
    assert names == NAMES, f"_core.pyi's _TargetName {names} is not TARGETS' {NAMES}"
    assert '"TARGETS"' in STUB.read_text(), "TARGETS is not in the stub's __all__"


def test_the_stub_declares_every_argument():
    cls = next(n for n in _stub_tree().body if isinstance(n, ast.ClassDef) and n.name == "ImageServo")
    new = next(n for n in cls.body if isinstance(n, ast.FunctionDef) and n.name == "__new__")
    declared = {a.arg: d for a, d in zip(new.args.kwonlyargs, new.args.kw_defaults)}
    for t in TARGETS:
        for a in t["args"]:
            assert a["name"] in declared, f"ImageServo in _core.pyi does not declare {t['name']}'s {a['name']}"
            default = declared[a["name"]]
            assert isinstance(default, ast.Constant) and default.value is None, f"{a['name']}: unset is None"
            assert f"`target=\"{t['name']}\"`" in (ast.get_docstring(cls) or ""), t["name"]


def _scene_showing(target: dict[str, Any]) -> str:
    """A built-in scenario with images that shows the target: its first scenario key of
    ``[object]`` is given (the scenario test, tests/targets.rs, checks the schema's side)."""
    table, key = target["scenario_keys"][0].split(".")
    for name, _ in _core.list_scenarios():
        d = _core.load_scenario(name).to_dict()
        if d.get("vision") and d.get(table, {}).get(key):
            return name
    raise AssertionError(f"no built-in scenario with [vision] shows {target['name']}")


def _arguments(target: dict[str, Any], pixels: np.ndarray) -> dict[str, Any]:
    """A value of each argument of the target, by kind (the projected points for points)."""
    values: dict[str, Any] = {}
    for a in target["args"]:
        kind = a["kind"]
        if kind == "points":
            values[a["name"]] = pixels + 1.0
        elif kind == "choice":
            values[a["name"]] = a["default"] or a["choices"][0]
        elif kind == "count":
            values[a["name"]] = a["default"] if a["default"] is not None else a["min"]
        elif kind == "tracker":
            values[a["name"]] = {}
    return values


def _texture() -> np.ndarray:
    """A textured image for a target of real images only (`simulated` false: no scene shows
    it): smoothed random noise, seeded."""
    rng = np.random.default_rng(32)
    noise = rng.random((246, 326))
    smooth = sum(np.roll(np.roll(noise, i, 0), j, 1) for i in range(-2, 3) for j in range(-2, 3)) / 25.0
    return np.ascontiguousarray((255 * (smooth - smooth.min()) / np.ptp(smooth)).astype(np.uint8)[3:243, 3:323])


def _image_showing(target: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """An image that shows the target and its points' pixels (none for real images only)."""
    if not target["simulated"]:
        return _texture(), np.zeros((0, 2))
    image, pixels, visible = _core.render_view(_scene_showing(target), reference=True)
    assert visible.all()
    return image, pixels


@pytest.mark.parametrize("target", TARGETS, ids=NAMES)
def test_image_servo_takes_each_target_and_its_arguments(target):
    image, pixels = _image_showing(target)
    args = _arguments(target, pixels)
    servo = _core.ImageServo(image, target["name"], K_HAT, **args, **SESSION)
    step = servo.step(image)
    if target["simulated"]:
        assert step.found.all(), f"{target['name']}: points not found in the reference image itself"
    else:  # natural keypoints: a point whose match fails a check is not visible (never wrong)
        assert step.found.mean() > 0.8, f"{target['name']}: {step.found.sum()} of {len(step.found)} found"
    found = step.found
    np.testing.assert_allclose(servo.reference_pixels[found], step.pixels[found], atol=0.01)
    for a in target["args"]:
        if a["required"]:
            less = {k: v for k, v in args.items() if k != a["name"]}
            with pytest.raises(_core.InvalidInput, match=f"^{a['name']}: target \"{target['name']}\" needs"):
                _core.ImageServo(image, target["name"], K_HAT, **less, **SESSION)
    for other in TARGETS:
        if other is target:
            continue
        for name, value in _arguments(other, pixels).items():
            with pytest.raises(_core.InvalidInput, match=f"^{name}: not an argument of target \"{target['name']}\""):
                _core.ImageServo(image, target["name"], K_HAT, **args, **{name: value}, **SESSION)


def test_image_servo_refuses_another_name_listing_the_table():
    image = np.zeros((48, 64), np.uint8)
    with pytest.raises(_core.InvalidInput, match="^target: expected one of") as err:
        _core.ImageServo(image, "rings", K_HAT, **SESSION)
    assert all(f'"{n}"' in str(err.value) for n in NAMES)
    assert err.value.argument == "target"


def _replay(*extra: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    cli_replay.add_replay_command(parser.add_subparsers())
    return parser.parse_args(["replay", "ref.png", "frames", "--K-hat", "600,600,320,240", *extra])


@pytest.mark.parametrize("name", NAMES)
def test_replay_takes_each_target(name):
    assert _replay("--target", name).target == name


def test_replay_refuses_another_target():
    with pytest.raises(SystemExit):
        _replay("--target", "rings")


@pytest.fixture(scope="module")
def reference_image(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("ros") / "reference.png"
    vsinv.vision.save_image(np.full((48, 64), 128, np.uint8), path)
    return path


def _ros_values(target: dict[str, Any]) -> dict[str, Any]:
    """A ROS value of each required argument of the target."""
    out: dict[str, Any] = {}
    for a in target["args"]:
        if a["required"]:
            assert a["kind"] == "points", a  # the only kind required today
            out[a["name"]] = [10.0, 20.0, 30.0, 40.0, 50.0, 20.0]
    return out


@pytest.mark.parametrize("target", TARGETS, ids=NAMES)
def test_ros_parameters_take_each_target(target, reference_image):
    assert params._BY_NAME["target"].choices == tuple(NAMES)
    base = {"reference_image": str(reference_image), "camera_frame": "camera", "target": target["name"]}
    config = params.parse_parameters({**base, **_ros_values(target)})
    assert config.target == target["name"]
    for a in target["args"]:
        assert any(p == a["name"] or p.startswith(a["name"] + ".") for p in params._BY_NAME), a["name"]
    for other in TARGETS:
        if other is target:
            continue
        for a in other["args"]:
            name = next(p for p in params._BY_NAME if p == a["name"] or p.startswith(a["name"] + "."))
            value = {"str": "x", "int": 2, "ints": [1], "float": 1.0, "floats": [1.0, 2.0]}[params._BY_NAME[name].kind]
            with pytest.raises(_core.InvalidInput, match=f"^parameter {name}: not a parameter of target"):
                params.parse_parameters({**base, **_ros_values(target), name: value})



def _invariance(*extra: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    cli_images.add_image_commands(parser.add_subparsers())
    return parser.parse_args(["invariance", "ref.png", "a.png", *extra])


@pytest.mark.parametrize("name", NAMES)
def test_invariance_takes_each_target_and_follows_it_with_its_own_code(name):
    """``vsinv invariance --target`` reads the table as ``vsinv replay`` does; every target of the
    table has its way through image files (a new one cannot fall through to the dots' code)."""
    assert _invariance("--target", name).target == name
    assert cli_images.TARGET_NAMES == tuple(NAMES)
    assert set(cli_images.TRACKERS) == set(NAMES)


def test_invariance_refuses_another_target():
    with pytest.raises(SystemExit):
        _invariance("--target", "rings")
