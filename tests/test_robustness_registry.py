"""Robustness of the public Python API under hypothesis, the exception classes, the version, and
the registry: every public name is covered by a robustness test of one of the
tests/test_robustness_*.py modules.

The promise and the harness are described in tests/robustness_harness.py.
"""

from __future__ import annotations

import importlib
import re
import sys
import types

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import vsinv
import vsinv.sweep
from robustness_harness import REGISTRY, covers


# The modules whose tests fill the registry (@covers), imported here so that this module alone
# checks the whole API.
AREAS = (
    "test_robustness_geometry",
    "test_robustness_camera",
    "test_robustness_se3",
    "test_robustness_kinematics",
    "test_robustness_control",
    "test_robustness_planning",
    "test_robustness_scenarios",
    "test_robustness_vision",
)
for _name in AREAS:
    importlib.import_module(_name)

# The levels below the session (issue 29, item 3).
LEVELS = ("laws", "vision", "sim", "calibration", "kinematics", "geometry", "errors")


# ---------------------------------------------------------------------------------------------
# exceptions, version, and the registry itself


@covers("VsinvError", "InvalidInput", "DegenerateGeometry", "NotReady", "__version__")
def test_exception_classes_and_version() -> None:
    for cls in (vsinv.InvalidInput, vsinv.DegenerateGeometry, vsinv.NotReady):
        assert issubclass(cls, vsinv.VsinvError) and cls.__module__ == "vsinv"
        e = cls("msg")
        assert str(e) == "msg" and isinstance(e, Exception)
    assert isinstance(vsinv.__version__, str) and re.fullmatch(r"\d+\.\d+\.\d+.*", vsinv.__version__)


@covers("TARGETS", "ERROR_CLASSES", "ERROR_KINDS", "ERROR_ATTRIBUTES")
@settings(max_examples=60, deadline=None)
@given(st.text(max_size=24))
def test_the_tables_describe_what_the_package_raises(name: str) -> None:
    """Any target name outside ``vsinv.vision.TARGETS`` is refused by ``ImageServo`` with an
    error that the error tables describe: its class, its kind and every attribute."""
    if name in {t["name"] for t in vsinv.vision.TARGETS}:
        return
    image = np.zeros((48, 64), np.uint8)
    with pytest.raises(vsinv.InvalidInput) as err:
        vsinv.ImageServo(image, name, vsinv.Intrinsics(600.0, 600.0, 32.0, 24.0), law="none", depths=0.5)
    e = err.value
    assert e.argument == "target" and str(e).startswith("target: expected one of")
    assert type(e).__name__ in {c["name"] for c in vsinv.errors.ERROR_CLASSES}
    assert (e.kind, "InvalidInput") in {(k["kind"], k["class"]) for k in vsinv.errors.ERROR_KINDS}
    assert all(hasattr(e, a["name"]) for a in vsinv.errors.ERROR_ATTRIBUTES)


_TRACKER_IMAGE = np.zeros((48, 64), np.uint8)
_TRACKER_IMAGE[20:28, 28:36] = 255


@covers("TRACKER_SETTINGS")
@settings(max_examples=60, deadline=None)
@given(st.text(max_size=24), st.one_of(st.text(max_size=8), st.floats(), st.integers(-5, 200), st.none()))
def test_the_tracker_settings_describe_what_image_servo_takes(key: str, value: object) -> None:
    """Any key of ``ImageServo``'s ``tracker`` outside ``vsinv.vision.TRACKER_SETTINGS`` is refused
    naming it and listing the table; a key of the table takes any value without an exception
    other than ``InvalidInput`` naming it."""
    settings_ = {s["name"]: s for s in vsinv.vision.TRACKER_SETTINGS}
    args = {"reference_points": [[32.0, 24.0]], "law": "none", "depths": 0.5}
    k = vsinv.Intrinsics(600.0, 600.0, 32.0, 24.0)
    try:
        vsinv.ImageServo(_TRACKER_IMAGE, "dots", k, tracker={key: value}, **args)
    except vsinv.InvalidInput as e:
        if key not in settings_:
            assert str(e) == f"tracker.{key}: unknown key; known: {', '.join(settings_)}"
        else:
            assert key in str(e) or "tracker" in str(e), str(e)
    else:
        assert key in settings_


def public_members(cls: type) -> list[str]:
    out = []
    for name in dir(cls):
        if name.startswith("_"):
            continue
        attr = getattr(cls, name)
        if isinstance(attr, type) and issubclass(attr, BaseException):
            continue
        out.append(f"{cls.__name__}.{name}")
    return out


def public_names() -> dict[str, object]:
    """The public names: the top level's (but its submodules) and every level's, as name -> object."""
    out = {n: getattr(vsinv, n) for n in vsinv.__all__ if not isinstance(getattr(vsinv, n), types.ModuleType)}
    for level in LEVELS:
        module = importlib.import_module(f"vsinv.{level}")
        out.update({n: getattr(module, n) for n in module.__all__})
    return out


def test_every_public_name_has_a_robustness_test() -> None:
    """New API cannot slip through: every name of vsinv.__all__, of its levels' __all__ and of
    vsinv.sweep.__all__, and every public method and property of the public classes, is covered
    by a test above."""
    public = public_names()
    names = set(public) | {f"sweep.{n}" for n in vsinv.sweep.__all__}
    classes = [obj for obj in public.values() if isinstance(obj, type)]
    for cls in classes:
        if issubclass(cls, BaseException) or cls.__module__.startswith("vsinv.sweep"):
            continue
        names.update(public_members(cls))
    missing = sorted(n for n in names if not REGISTRY.get(n))
    assert not missing, f"public names without a robustness test: {missing}"
    tests = {t for ts in REGISTRY.values() for t in ts}
    modules = [sys.modules[name] for name in (*AREAS, __name__)]
    assert all(any(callable(getattr(module, t, None)) for module in modules) for t in tests)
