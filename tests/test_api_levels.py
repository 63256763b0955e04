"""One Python API per level (issue 29, item 3): the session at the top of ``vsinv``, and below
it the levels ``laws``, ``vision``, ``sim``, ``calibration``, ``kinematics``, ``geometry``,
``errors``;
every public name of ``vsinv._core`` in exactly one of them (or the session), one step order
``step(pixels, depths, visible=None)`` and one default basis ``"auto"``."""

from __future__ import annotations

import ast
import importlib
import inspect
import types
from pathlib import Path

import numpy as np
import pytest

import vsinv
from vsinv import _core

LEVELS = ("laws", "vision", "sim", "calibration", "kinematics", "geometry", "errors")
STUB = Path(vsinv.__file__).with_name("_core.pyi")

# The session level: what an application that servoes needs, and nothing else.
SESSION = {
    "__version__",
    "Servo",
    "ServoStep",
    "ImageServo",
    "ImageStep",
    "Intrinsics",
    "replay",
    "ReplayResult",
    "frames",
    "run_scenario",
    "load_scenario",
    "RunResult",
    "VsinvError",
    "InvalidInput",
    "DegenerateGeometry",
    "NotReady",
}
# Re-exported at the top from their level: the main job (a simulated session) and frame sources.
FROM_A_LEVEL = {
    "run_scenario": "sim",
    "load_scenario": "sim",
    "RunResult": "sim",
    "frames": "vision",
    **{name: "errors" for name in ("VsinvError", "InvalidInput", "DegenerateGeometry", "NotReady")},
}


def levels() -> dict[str, types.ModuleType]:
    return {name: importlib.import_module(f"vsinv.{name}") for name in LEVELS}


def test_the_top_level_is_the_session() -> None:
    assert set(vsinv.__all__) == SESSION | set(LEVELS)
    assert len(vsinv.__all__) == len(set(vsinv.__all__))
    for name in LEVELS:
        assert getattr(vsinv, name) is levels()[name]
    for name, level in FROM_A_LEVEL.items():
        assert getattr(vsinv, name) is getattr(levels()[level], name)
    # The flat names of before are gone (0.1.0 was never published): one way in.
    for gone in ("InvariantController", "detect_dots", "run_batch", "fk", "exp_twist", "calibrate_hand_eye", "run_sweep"):
        assert not hasattr(vsinv, gone), gone


def test_every_level_all_resolves_and_is_sorted_out() -> None:
    for name, module in levels().items():
        assert len(module.__all__) == len(set(module.__all__)), name
        for member in module.__all__:
            assert hasattr(module, member), f"vsinv.{name}.{member}"
        # Nothing public beyond __all__ (but imported modules and annotations).
        public = {n for n, v in vars(module).items() if not n.startswith("_") and not isinstance(v, types.ModuleType)}
        assert public - {"annotations"} == set(module.__all__), (name, sorted(public ^ set(module.__all__)))


def test_each_name_lives_in_exactly_one_level() -> None:
    homes: dict[str, list[str]] = {}
    for name, module in levels().items():
        for member in module.__all__:
            homes.setdefault(member, []).append(name)
    twice = {n: h for n, h in homes.items() if len(h) > 1}
    assert not twice, twice
    # Only the re-exports are both at the top and in a level.
    assert set(homes) & SESSION == set(FROM_A_LEVEL)
    assert all(homes[n] == [level] for n, level in FROM_A_LEVEL.items())


def test_every_name_of_the_core_has_a_home() -> None:
    """A new binding cannot be forgotten: every public name of ``vsinv._core`` is at the top or
    in one level."""
    core = {n for n in dir(_core) if not n.startswith("_")}
    placed = (SESSION | {n for m in levels().values() for n in m.__all__}) - {"replay", "ReplayResult", "frames"}
    placed |= {"run_batch"}  # vsinv.sim.run_batch wraps the core's with progress bars
    placed |= {"run_sweep_runs", "sweep_scenarios", "SWEEP_DERIVED_KEYS"}  # vsinv.sweep's engine (run_sweep, DERIVED_KEYS)
    assert core - placed == set(), sorted(core - placed)
    assert vsinv.sim.run_batch is not _core.run_batch and vsinv.sim.run_batch.__module__ == "vsinv._batch"


def stub_signature(cls: str, method: str) -> list[tuple[str, str | None]]:
    """The parameters (name, default as source text) of ``cls.method`` in the stub."""
    tree = ast.parse(STUB.read_text(encoding="utf-8"))
    node = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == cls)
    fn = next(n for n in node.body if isinstance(n, ast.FunctionDef) and n.name == method)
    args = fn.args.args
    defaults = [None] * (len(args) - len(fn.args.defaults)) + [ast.unparse(d) for d in fn.args.defaults]
    return [(a.arg, d) for a, d in zip(args, defaults)]


def runtime_signature(cls: type, method: str) -> list[tuple[str, object]]:
    sig = inspect.signature(getattr(cls, method))
    return [(p.name, None if p.default is inspect.Parameter.empty else p.default) for p in sig.parameters.values()]


@pytest.mark.parametrize("cls", ["Servo", "InvariantController", "IbvsController"])
def test_one_step_order(cls: str) -> None:
    """``step(pixels, depths, visible=None)`` everywhere: in the stub and at run time (the
    session's ``depths`` defaults to None, its depths being fixed unless ``depths="per_step"``)."""
    depths_default = "None" if cls == "Servo" else None
    assert stub_signature(cls, "step") == [("self", None), ("pixels", None), ("depths", depths_default), ("visible", "None")]
    runtime = runtime_signature(getattr(_core, cls), "step")
    assert [n for n, _ in runtime] == ["self", "pixels", "depths", "visible"]
    assert runtime[2][1] is None and runtime[3][1] is None
    assert not hasattr(getattr(_core, cls), "step_visible")  # one way to step


def test_one_default_basis() -> None:
    for cls in ("InvariantController",):
        assert dict(stub_signature(cls, "__new__"))["basis"] == "'auto'"
        assert inspect.signature(getattr(_core, cls)).parameters["basis"].default == "auto"
    # The controllers and Servo choose the same basis when none is given: the widest triangle.
    points = np.array(vsinv.load_scenario("lens-12-6").to_dict()["object"]["points"])
    k = vsinv.Intrinsics(1200.0, 1200.0, 416.0, 312.0)
    px, z = vsinv.geometry.project(points, k)
    chosen = vsinv.laws.choose_basis(px)
    assert chosen != (0, 1, 2)  # else the test could not tell "auto" from the old default
    assert vsinv.laws.InvariantController(px, k).basis == chosen
    assert vsinv.Servo(px, k, reference_depths=z).basis == chosen


def test_steps_agree_by_position_and_keyword() -> None:
    points = np.array(vsinv.load_scenario("lens-12-6").to_dict()["object"]["points"])
    k = vsinv.Intrinsics(1200.0, 1200.0, 416.0, 312.0)
    ref, z_star = vsinv.geometry.project(points, k)
    px, z = vsinv.geometry.project(points + [0.01, -0.02, 0.05], k)
    hidden = np.ones(len(px), bool)
    hidden[-1] = False
    for make in (vsinv.laws.InvariantController, vsinv.laws.IbvsController):
        a, b = make(ref, k), make(ref, k)
        np.testing.assert_array_equal(a.step(px, z, hidden), b.step(pixels=px, depths=z, visible=hidden))
    a = vsinv.Servo(ref, k, depths="per_step")
    b = vsinv.Servo(ref, k, depths="per_step")
    np.testing.assert_array_equal(a.step(px, z, hidden).twist, b.step(px, depths=z, visible=hidden).twist)
