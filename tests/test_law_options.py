"""The laws' options are declared once (Rust ``servo::law::options``, ``vsinv._core.LAW_OPTIONS``)
and every layer reads the table: the scenario keys, ``Servo``'s keyword arguments, the ROS
parameters, the ``vsinv replay`` flags and the stub. Nothing here lists the options: each test
goes through the table, so a new entry is tested in every layer as it is added."""

from __future__ import annotations

import argparse
import ast
import inspect
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import vsinv
from vsinv import _core
from vsinv import cli_replay
from vsinv.ros import params

OPTIONS = _core.LAW_OPTIONS
STUB = Path(vsinv.__file__).with_name("_core.pyi")
PAIRS = [(o, law) for o in OPTIONS for law in o["laws"]]
IDS = [f"{o['name']}-{law}" for o, law in PAIRS]

RELIEF = [0.0, 0.06, -0.04, 0.03, -0.06, 0.05, 0.02, -0.03]
POINTS = np.array([[-0.15 + 0.1 * (i % 4), -0.12 + 0.2 * (i // 4), 0.6 + RELIEF[i]] for i in range(8)])
K_HAT = vsinv.Intrinsics(650, 570, 395, 280)


def valid(o: dict[str, Any]) -> Any:
    """A value in the option's range, in its own unit."""
    kind = o["kind"]
    if kind == "number" and o["default"] is not None:
        return o["default"] * 1.5
    if kind == "number":
        return (o["min"] if math.isfinite(o["min"]) else 0.0) + 0.75
    if kind == "flag":
        return not o["default"]
    if kind == "choice":
        return o["choices"][-1]
    return (4.0, 0.4, 30.0)


def invalid(o: dict[str, Any]) -> Any:
    """A value the option refuses."""
    kind = o["kind"]
    if kind == "number":
        return o["min"] if o["min_open"] else o["min"] - 1.0
    if kind == "flag":
        return "yes"
    if kind == "choice":
        return "bogus"
    return (1.0, 2.0, 3.0)


def test_the_table_is_whole():
    names = [o["name"] for o in OPTIONS]
    assert len(names) == len(set(names))
    for o in OPTIONS:
        assert o["laws"] and set(o["laws"]) <= {"invariant", "ibvs", "none"}, o
        assert (o["range"] is not None) == (o["kind"] == "number"), o
        assert o["doc"], o
        if o["default"] is not None:
            _core.check_law_option(o["name"], o["default"])  # each default is a valid value
    table = _core.law_options_markdown()
    assert len(table.splitlines()) == len(OPTIONS) + 2
    assert all(f"| `{n}` |" in table for n in names)


def _stub_new(cls: str) -> ast.FunctionDef:
    tree = ast.parse(STUB.read_text())
    for node in tree.body:
        if isinstance(node, ast.ClassDef) and node.name == cls:
            for item in node.body:
                if isinstance(item, ast.FunctionDef) and item.name == "__new__":
                    return item
    raise AssertionError(f"{cls}.__new__ not in the stub")


def _stub_args(fn: ast.FunctionDef) -> dict[str, tuple[ast.arg, Any]]:
    """Each argument of a stub function with its default (a literal, or ... when none)."""
    a = fn.args
    positional = a.posonlyargs + a.args
    defaults = [...] * (len(positional) - len(a.defaults)) + [ast.literal_eval(d) for d in a.defaults]
    out = {arg.arg: (arg, d) for arg, d in zip(positional, defaults)}
    for arg, d in zip(a.kwonlyargs, a.kw_defaults):
        out[arg.arg] = (arg, ... if d is None else ast.literal_eval(d))
    return out


def _check_declared(cls: str, o: dict[str, Any], unset_only: bool) -> None:
    args = _stub_args(_stub_new(cls))
    assert o["name"] in args, f"{cls} in _core.pyi does not declare the law option {o['name']}"
    arg, default = args[o["name"]]
    allowed = (None,) if unset_only else (o["default"],)
    assert default in allowed or default == o["default"], f"{cls}.{o['name']}: default {default!r}"
    annotation = ast.unparse(arg.annotation) if arg.annotation else ""
    for choice in o["choices"]:
        assert repr(choice) in annotation, f"{cls}.{o['name']}: {annotation}"


@pytest.mark.parametrize("o", OPTIONS, ids=[o["name"] for o in OPTIONS])
def test_the_stub_declares_every_option(o):
    # Servo (and so ImageServo): every option, None for "the law's default".
    _check_declared("Servo", o, unset_only=True)
    # The controllers: their law's options, with the table's defaults, as at run time.
    for cls, law in (("InvariantController", "invariant"), ("IbvsController", "ibvs")):
        if law in o["laws"]:
            _check_declared(cls, o, unset_only=False)
            runtime = inspect.signature(getattr(vsinv.laws, cls)).parameters[o["name"]].default
            assert runtime == o["default"] or (runtime is None and o["default"] is None), (cls, runtime)


def _reference() -> tuple[np.ndarray, np.ndarray]:
    return vsinv.geometry.project(POINTS, vsinv.Intrinsics(1200, 1200, 384, 288))


@pytest.mark.parametrize(("o", "law"), PAIRS, ids=IDS)
def test_servo_keywords_take_the_range(o, law):
    px, z = _reference()
    vsinv.Servo(px, K_HAT, law, reference_depths=z, **{o["name"]: valid(o)})
    with pytest.raises(vsinv.InvalidInput) as err:
        vsinv.Servo(px, K_HAT, law, reference_depths=z, **{o["name"]: invalid(o)})
    assert err.value.argument.startswith(o["name"]), err.value
    others = [other for other in ("invariant", "ibvs", "none") if other not in o["laws"]]
    for other in others:
        with pytest.raises(vsinv.InvalidInput, match=f'^{o["name"]}: not an argument of the "{other}" law'):
            vsinv.Servo(px, K_HAT, other, reference_depths=z, **{o["name"]: valid(o)})


def _scenario_value(o: dict[str, Any], value: Any) -> Any:
    if o["kind"] == "adaptive_gain" and isinstance(value, tuple):
        return dict(zip(("at_zero", "at_infinity", "slope_at_zero"), value))
    if o["scenario_unit"] != o["unit"] and isinstance(value, float):
        return math.degrees(value)  # a _deg key: degrees where the option is in radians
    return value


@pytest.mark.parametrize(("o", "law"), [p for p in PAIRS if p[0]["scenario_key"]], ids=[
    i for p, i in zip(PAIRS, IDS) if p[0]["scenario_key"]
])
def test_scenario_keys_take_the_range(o, law):
    d = vsinv.load_scenario("lens-12-6").to_dict()
    key = o["scenario_key"]
    d["control"] = {"law": law, "dt": 0.04, key: _scenario_value(o, valid(o))}
    vsinv.sim.Scenario.from_dict(d)
    d["control"][key] = _scenario_value(o, invalid(o))
    with pytest.raises(vsinv.InvalidInput) as err:
        vsinv.sim.Scenario.from_dict(d)
    assert err.value.key.startswith(f"control.{key}"), err.value


@pytest.fixture(scope="module")
def reference_image(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("ros") / "reference.png"
    vsinv.vision.save_image(np.full((48, 64), 128, np.uint8), path)
    return path


def _ros_value(o: dict[str, Any], value: Any) -> Any:
    return list(value) if o["kind"] == "adaptive_gain" else value


@pytest.mark.parametrize(("o", "law"), PAIRS, ids=IDS)
def test_ros_parameters_take_the_range(o, law, reference_image):
    assert params._BY_NAME[o["name"]].kind == params._ROS_KINDS[o["kind"]]
    base = {"reference_image": str(reference_image), "law": law, "camera_frame": "camera"}
    config = params.parse_parameters({**base, o["name"]: _ros_value(o, valid(o))})
    assert config.servo_options[o["name"]] == valid(o)
    with pytest.raises(vsinv.InvalidInput, match=f"^parameter {o['name']}:"):
        params.parse_parameters({**base, o["name"]: _ros_value(o, invalid(o))})


def _replay_args(*extra: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    cli_replay.add_replay_command(parser.add_subparsers())
    return parser.parse_args(["replay", "ref.png", "frames", "--K-hat", "600,600,320,240", *extra])


def _flag_args(o: dict[str, Any], value: Any) -> list[str]:
    flag = "--" + o["name"].replace("_", "-")
    if o["kind"] == "flag":
        return [flag if value else "--no-" + flag[2:]]
    if o["kind"] == "adaptive_gain":
        return [flag, ",".join(str(v) for v in value)]
    return [flag, str(value)]


@pytest.mark.parametrize(("o", "law"), PAIRS, ids=IDS)
def test_replay_flags_take_the_range(o, law):
    args = _replay_args("--law", law, *_flag_args(o, valid(o)))
    assert cli_replay._law_options(args)[o["name"]] == valid(o)
    if o["kind"] == "flag":
        return  # --x / --no-x: nothing out of range to give
    if o["kind"] == "choice":
        with pytest.raises(SystemExit):  # argparse refuses a name not among the choices
            _replay_args("--law", law, *_flag_args(o, invalid(o)))
        return
    flag = "--" + o["name"].replace("_", "-")
    with pytest.raises(vsinv.InvalidInput, match=f"^{flag}:"):
        cli_replay._law_options(_replay_args("--law", law, *_flag_args(o, invalid(o))))


def test_replay_keeps_its_gentler_gain_for_the_laws_that_read_it():
    assert cli_replay._law_options(_replay_args("--law", "invariant")) == {"gain": 0.5}
    assert cli_replay._law_options(_replay_args("--law", "none")) == {}


def test_the_docs_table_is_the_declaration() -> None:
    """docs/reference/law-options.md shows the table the servo layer declares, as generated."""
    from pathlib import Path

    page = (Path(__file__).resolve().parent.parent / "docs/reference/law-options.md").read_text(encoding="utf-8")
    table = vsinv._core.law_options_markdown().strip()
    assert table in page, "docs/reference/law-options.md: paste vsinv._core.law_options_markdown() again"


def of_another_kind(o: dict[str, Any]) -> Any:
    """A value of another kind than the option's (a string for a number, a number for a choice,
    a flag for the adaptive gain's triple)."""
    return {"number": "fast", "flag": "yes", "choice": 3, "adaptive_gain": True}[o["kind"]]


@pytest.mark.parametrize("o", OPTIONS, ids=[o["name"] for o in OPTIONS])
def test_a_value_of_another_kind_is_invalid_input_naming_the_option(o):
    """Issue 29, item 1: ``check_law_option("adaptive_gain", True)`` raised a bare TypeError that
    did not name the option."""
    with pytest.raises(vsinv.InvalidInput) as info:
        _core.check_law_option(o["name"], of_another_kind(o))
    err = info.value
    assert (err.kind, err.argument, err.location) == ("invalid_argument", o["name"], (o["name"],)), str(err)
    assert str(err).startswith(f"{o['name']}: "), str(err)
