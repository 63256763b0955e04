"""The stub's docstrings and the extension's (the Rust `///` comments of `src/python/`) say the same:
for every public function, class, method and property of ``vsinv._core``, the stub
(``_core.pyi``, read with ``ast``) has a docstring whenever the runtime object has one, and the
first sentences of the two are equal (whitespace and reST's double backquotes aside). The rest of
each text may differ: the stub's is often longer (it is what editors and the docs site show). A
docstring changed on one side only fails here."""

from __future__ import annotations

import ast
import inspect
import re
from pathlib import Path
from typing import Any

import pytest

import vsinv
from vsinv import _core

pytestmark = pytest.mark.package

STUB = Path(vsinv.__file__).with_name("_core.pyi")
#: Abbreviations a sentence does not end at ("eq. 4", "e.g. a zoom").
_NOT_AN_END = ("e.g", "i.e", "eq", "eqs", "vs", "sec", "cf", "etc")


def first_sentence(text: str | None) -> str:
    """The first sentence of the first paragraph, on one line, with ``x`` read as `x`: up to the
    first period followed by a space and a capital, a backquote or a parenthesis, abbreviations
    aside."""
    paragraph = inspect.cleandoc(text or "").split("\n\n")[0]
    flat = " ".join(paragraph.replace("``", "`").split())
    for m in re.finditer(r"\.\s+(?=[A-Z`(])", flat):
        if not any(flat[: m.start()].endswith(a) for a in _NOT_AN_END):
            return flat[: m.start() + 1]
    return flat


def _items() -> list[tuple[str, ast.AST, Any]]:
    """(qualified name, stub node, runtime object) of every public item of the stub."""
    tree = ast.parse(STUB.read_text())
    out = []
    for node in tree.body:
        if not isinstance(node, (ast.FunctionDef, ast.ClassDef)) or node.name.startswith("_"):
            continue
        obj = getattr(_core, node.name)
        out.append((node.name, node, obj))
        if isinstance(node, ast.ClassDef):
            for m in node.body:
                if isinstance(m, ast.FunctionDef) and not m.name.startswith("_"):
                    attr = inspect.getattr_static(obj, m.name)
                    out.append((f"{node.name}.{m.name}", m, getattr(attr, "__func__", attr)))
    return out


ITEMS = _items()


def test_the_items_are_read():
    assert len(ITEMS) > 200
    assert first_sentence("Task function eps of eq. (14) at the last step. More.") == "Task function eps of eq. (14) at the last step."
    assert first_sentence("A ``b`` c, e.g. D. E") == "A `b` c, e.g. D."
    assert first_sentence("One.\n\ntwo, in a second paragraph.") == "One."


@pytest.mark.parametrize(("name", "node", "obj"), ITEMS, ids=[i[0] for i in ITEMS])
def test_stub_and_runtime_docstrings_agree(name, node, obj):
    runtime = getattr(obj, "__doc__", None)
    if not runtime or not runtime.strip():
        return
    stub = ast.get_docstring(node)
    assert stub, f"{name}: no docstring in _core.pyi; the extension's: {first_sentence(runtime)!r}"
    assert first_sentence(stub) == first_sentence(runtime), f"{name}: the stub and the extension disagree"
