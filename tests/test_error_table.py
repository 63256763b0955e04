"""The exception classes, their kinds and attributes are declared once (``src/python/errors.rs``:
``CLASSES``, ``KINDS``, ``ATTRIBUTES``; ``vsinv._core.ERROR_CLASSES``, ``ERROR_KINDS``,
``ERROR_ATTRIBUTES``): the module's classes are built from the table, and these tests check the
stub's classes, docstrings and attributes against it, and that every kind the bindings raise is in
it with its class."""

from __future__ import annotations

import ast
import builtins
import inspect
import re
from pathlib import Path

import numpy as np
import pytest

import vsinv
from vsinv import _core

pytestmark = pytest.mark.robustness

STUB = Path(vsinv.__file__).with_name("_core.pyi")
ERRORS_RS = Path(__file__).resolve().parents[1] / "src" / "python" / "errors.rs"
CLASSES = {c["name"]: c for c in _core.ERROR_CLASSES}
KINDS = {k["kind"]: k for k in _core.ERROR_KINDS}


def _paragraphs(text: str) -> list[str]:
    """The paragraphs of a docstring, each on one line (the stub wraps its lines)."""
    return [" ".join(p.split()) for p in inspect.cleandoc(text).split("\n\n")]


def _stub_classes() -> dict[str, ast.ClassDef]:
    tree = ast.parse(STUB.read_text())
    return {n.name: n for n in tree.body if isinstance(n, ast.ClassDef)}


@pytest.mark.parametrize("name", list(CLASSES))
def test_each_class_is_built_from_the_table(name):
    spec, cls = CLASSES[name], getattr(_core, name)
    parent = getattr(_core, spec["parent"]) if spec["parent"] else None
    builtin = getattr(builtins, spec["builtin"])
    assert cls.__bases__ == ((parent, builtin) if parent else (builtin,))
    runtime, table = _paragraphs(cls.__doc__), _paragraphs(spec["doc"])
    assert runtime[: len(table) - 1] == table[:-1] and runtime[len(table) - 1].startswith(table[-1])


@pytest.mark.parametrize("name", list(CLASSES))
def test_the_stub_declares_each_class_as_the_table(name):
    spec, stub = CLASSES[name], _stub_classes().get(name)
    assert stub is not None, f"{name} is not in _core.pyi"
    bases = [ast.unparse(b) for b in stub.bases]
    assert bases == ([spec["parent"], spec["builtin"]] if spec["parent"] else [spec["builtin"]]), bases
    stub_doc = _paragraphs(ast.get_docstring(stub) or "")
    assert stub_doc == _paragraphs(spec["doc"]), f"{name}: the stub's docstring is not the table's"


def test_the_stub_has_no_other_exception_class():
    exceptions = {n for n, c in _stub_classes().items() if any(ast.unparse(b) in CLASSES for b in c.bases)}
    exceptions |= {n for n, c in _stub_classes().items() if [ast.unparse(b) for b in c.bases] == ["Exception"]}
    assert exceptions == set(CLASSES)


def _stub_attributes() -> dict[str, tuple[str, str]]:
    """Each annotated attribute of VsinvError in the stub: (annotation, docstring)."""
    body = _stub_classes()["VsinvError"].body
    out = {}
    for node, after in zip(body, body[1:] + [None]):
        if isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            doc = after.value.value if isinstance(after, ast.Expr) and isinstance(after.value, ast.Constant) else ""
            out[node.target.id] = (ast.unparse(node.annotation), " ".join(str(doc).split()))
    return out


def test_the_stub_declares_each_attribute_as_the_table():
    stub = _stub_attributes()
    assert list(stub) == [a["name"] for a in _core.ERROR_ATTRIBUTES]
    for a in _core.ERROR_ATTRIBUTES:
        annotation, doc = stub[a["name"]]
        assert annotation == f"{a['type']} | None", a["name"]
        assert doc == " ".join(a["doc"].split()), a["name"]
        assert getattr(_core.VsinvError, a["name"]) is None
    assert all(f"'{k}'" in stub["kind"][1] for k in KINDS)


def test_each_kind_the_bindings_name_is_in_the_table_with_its_class():
    source = ERRORS_RS.read_text()
    describe = source[source.index("fn describe("):source.index("impl From<&Error> for PyError")]
    named = set(re.findall(r'\(\s*"([a-z_]+)",\s*(?:vec!|opt\(|\[)', describe))
    named |= set(re.findall(r'\.kind\("([a-z_]+)"\)', source)) | set(re.findall(r'kind: Some\("([a-z_]+)"\)', source))
    assert len(named) >= 20 and named <= set(KINDS), named - set(KINDS)
    assert set(KINDS) - named == set(), set(KINDS) - named
    for spec in KINDS.values():
        assert spec["class"] in CLASSES and spec["doc"], spec


@pytest.mark.parametrize(
    ("call", "kind"),
    [
        (lambda: vsinv.geometry.project(np.full((3, 3), np.nan), _core.Intrinsics(500, 500, 320, 240)), "non_finite_point"),
        (lambda: _core.ImageServo(np.zeros((8, 8), np.uint8), "rings", _core.Intrinsics(500, 500, 4, 4)), "invalid_argument"),
        (lambda: vsinv.load_scenario({"name": "x"}), "scenario"),
    ],
)
def test_a_raised_kind_comes_with_the_tables_class(call, kind):
    with pytest.raises(_core.VsinvError) as err:
        call()
    assert err.value.kind == kind
    assert type(err.value) is getattr(_core, KINDS[kind]["class"])
