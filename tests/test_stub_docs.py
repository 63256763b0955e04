"""The stub's docstrings are the extension's (the Rust `///` comments of `src/python/`), whole.

``tools/stub_docs.py`` (``make stubs``) writes every docstring of ``_core.pyi`` from the built
extension: module, classes, functions, methods, properties, and the attributes of
``VsinvError`` (from ``ERROR_ATTRIBUTES``; an exception class's docstring is its
``ERROR_CLASSES`` doc). Here, for every one of them, the stub's text (``ast``,
``inspect.cleandoc``) equals the extension's: a Rust doc comment changed without the stub
regenerated fails, and so does a docstring written in the stub only. The script itself is
checked on altered copies of the stub: its check names each difference, regenerating restores
the stub byte for byte, and an item of the extension the stub lacks (a new class) is named."""

from __future__ import annotations

import ast
import importlib.util
import inspect
import os
import sys
import types
from pathlib import Path

import pytest

import vsinv
from vsinv import _core

pytestmark = pytest.mark.package

STUB = Path(vsinv.__file__).with_name("_core.pyi")
_TOOL = Path(__file__).resolve().parent.parent / "tools" / "stub_docs.py"
_spec = importlib.util.spec_from_file_location("stub_docs", _TOOL)
assert _spec is not None and _spec.loader is not None
stub_docs = importlib.util.module_from_spec(_spec)
sys.modules["stub_docs"] = stub_docs
_spec.loader.exec_module(stub_docs)

SOURCE = STUB.read_text()
ITEMS, PROBLEMS = stub_docs.stub_items(ast.parse(SOURCE), _core)
#: Docstrings of the stub with no text at run time to come from: a class attribute the
#: extension makes with `#[classattr]` is a plain tuple, without a `__doc__` of its own.
STUB_ONLY = {"RunResult.columns"}


def test_the_items_are_read():
    names = {i.name for i in ITEMS}
    assert len(ITEMS) > 250
    assert {"module", "project", "Intrinsics", "Intrinsics.fku", "Intrinsics.from_matrix", "Servo.step"} <= names
    assert {"Intrinsics.__reduce__", "VsinvError.kind", "InvalidInput"} <= names
    public = {n for n, o in vars(_core).items() if not n.startswith("_") and (inspect.isclass(o) or callable(o))}
    assert public <= names


@pytest.mark.parametrize("item", ITEMS, ids=[i.name for i in ITEMS])
def test_the_stub_docstring_is_the_extensions(item):
    """Whole texts: a Rust doc comment changed and the stub not regenerated fails here."""
    if item.runtime is None:
        assert item.stub is None, f"{item.name}: a docstring in the stub only; its text belongs in the Rust `///` comment"
        return
    assert item.stub is not None, f"{item.name}: no docstring in _core.pyi; run `make stubs`"
    assert item.stub == item.runtime, f"{item.name}: the stub's docstring is not the extension's; run `make stubs`"


def test_spot_checks_read_the_runtime_directly():
    """The items' texts are the objects' own ``__doc__``, as Python shows them."""
    by_name = {i.name: i for i in ITEMS}
    assert by_name["project"].stub == inspect.cleandoc(_core.project.__doc__)
    assert by_name["Intrinsics.fku"].stub == inspect.cleandoc(_core.Intrinsics.fku.__doc__)
    assert by_name["Intrinsics.from_matrix"].stub == inspect.cleandoc(_core.Intrinsics.from_matrix.__doc__)
    assert by_name["module"].stub == inspect.cleandoc(_core.__doc__)
    assert _core.__doc__ and "compiled core" in _core.__doc__


def test_every_docstring_of_the_stub_is_an_item():
    """No docstring of the stub escapes the comparison (nested or not)."""
    names = {i.name for i in ITEMS}
    tree = ast.parse(SOURCE)
    for node in tree.body:
        if not isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            continue
        if node.name.startswith("_") and not hasattr(_core, node.name):
            continue  # a type of the stub only (a TypedDict)
        assert node.name in names
        if isinstance(node, ast.FunctionDef):
            continue
        for m, after in zip(node.body, node.body[1:] + [None]):
            assert not isinstance(m, ast.ClassDef), f"a nested class in the stub: {node.name}.{m.name}"
            if isinstance(m, ast.FunctionDef) and ast.get_docstring(m) is not None:
                assert f"{node.name}.{m.name}" in names, m.name
            if isinstance(m, ast.AnnAssign) and isinstance(after, ast.Expr) and isinstance(m.target, ast.Name):
                name = f"{node.name}.{m.target.id}"
                assert name in names or name in STUB_ONLY, name


def test_nothing_is_declared_on_one_side_only():
    assert PROBLEMS == []


def test_regenerating_the_stub_changes_nothing():
    """The stub is what `make stubs` writes: every docstring, and the rest of the file as is."""
    out, changed, problems = stub_docs.generate(SOURCE, _core)
    assert (changed, problems) == ([], [])
    assert out == SOURCE


def _replace_once(text: str, old: str, new: str) -> str:
    assert text.count(old) == 1, old
    return text.replace(old, new)


def test_the_check_names_each_difference_and_regenerating_restores_the_stub(tmp_path, capsys):
    fku = '        """' + inspect.cleandoc(_core.Intrinsics.fku.__doc__) + '"""'
    stale = _replace_once(SOURCE, "(eqs. 1-3)", "(eqs. 1-4)")  # project's docstring
    stale = _replace_once(stale, "    def fku(self) -> float:\n" + fku + "\n", "    def fku(self) -> float: ...\n")
    stale = _replace_once(stale, "class Intrinsics:\n", "class Intrinsics:\n    # a comment kept\n")
    path = tmp_path / "_core.pyi"
    path.write_text(stale)
    assert stub_docs.main(["--check", "--stub", str(path)]) == 1
    out = capsys.readouterr().out
    assert "project: differs" in out and "Intrinsics.fku: differs (no docstring in the stub)" in out
    assert path.read_text() == stale
    assert stub_docs.main(["--stub", str(path)]) == 0
    assert path.read_text() == _replace_once(SOURCE, "class Intrinsics:\n", "class Intrinsics:\n    # a comment kept\n")
    assert stub_docs.main(["--check", "--stub", str(path)]) == 0


def test_a_docstring_in_the_stub_only_is_reported_not_removed(tmp_path, capsys):
    eq = "    def __eq__(self, other: object, /) -> bool: ..."
    stale = _replace_once(SOURCE, eq + "\n    def __reduce__(self) -> tuple[type[Intrinsics]", (
        eq[:-4] + '\n        """Written in the stub only."""\n    def __reduce__(self) -> tuple[type[Intrinsics]'
    ))
    path = tmp_path / "_core.pyi"
    path.write_text(stale)
    assert stub_docs.main(["--stub", str(path)]) == 1
    assert "Intrinsics.__eq__: the stub has a docstring the extension lacks" in capsys.readouterr().err
    assert path.read_text() == stale


def test_a_new_item_of_the_extension_is_named_and_its_docstring_filled_in():
    """As when a binding adds a class: the check names it until the stub declares it, and then
    regenerating writes its docstrings (non-ASCII text and names too: ast counts columns in
    bytes)."""
    core = types.ModuleType("vsinv._core", _core.__doc__)
    vars(core).update({k: v for k, v in vars(_core).items() if k != "__doc__"})

    class Fisheye:
        """A lens model: r = f θ.

        Its second paragraph, with a backslash \\ and "quotes"."""

        @property
        def θ(self) -> float:
            """An angle."""
            return 0.0

    core.Fisheye = Fisheye
    _, problems = stub_docs.stub_items(ast.parse(SOURCE), core)
    assert problems == ["Fisheye: in the extension, not declared in the stub"]
    declared = SOURCE + "\nclass Fisheye:\n    @property\n    def θ(self) -> float: ...\n"
    out, changed, problems = stub_docs.generate(declared, core)
    assert ([i.name for i in changed], problems) == (["Fisheye", "Fisheye.θ"], [])
    assert out == SOURCE + (
        '\nclass Fisheye:\n    """A lens model: r = f θ.\n\n    Its second paragraph, with a backslash \\\\ and "quotes"."""\n'
        '    @property\n    def θ(self) -> float:\n        """An angle."""\n'
    )
    assert ast.get_docstring(ast.parse(out).body[-1]) == inspect.cleandoc(Fisheye.__doc__)
    stale = out.replace('"""An angle."""', '"""An angle, old."""')
    assert stub_docs.generate(stale, core)[0] == out


@pytest.mark.parametrize(
    "text", ["One line.", "Two\n\nparagraphs.", 'Ends with a quote "x"', 'Has """ inside', "A \\ backslash\n    indented\nand not"]
)
def test_a_docstring_literal_reads_back_as_its_text(text):
    literal = stub_docs.literal(text, "    ")
    assert inspect.cleandoc(ast.literal_eval(literal)) == text
    assert "\n" not in text or "\n    " in literal


def test_an_extension_older_than_the_rust_sources_is_warned_of(tmp_path):
    """Regenerating from an extension built before the last Rust edit would write its old texts."""
    built = tmp_path / "_core.abi3.so"
    built.write_bytes(b"")
    os.utime(built, (0, 0))
    core = types.ModuleType("vsinv._core")
    core.__file__ = str(built)
    assert "rebuild the extension first" in (stub_docs.stale_warning(core) or "")
    os.utime(built, None)
    assert stub_docs.stale_warning(core) is None
