"""The stub's docstrings generated from the extension's (issue 29, item 1).

The Rust `///` comments of `src/python/` are the one source of the docstrings of
``vsinv._core``: Python sees them as ``__doc__``. This script imports the built extension and
rewrites every docstring of ``python/vsinv/_core.pyi`` (the module, classes, functions,
methods, properties) to the extension's text exactly (``inspect.cleandoc``-normalised, indented
as the stub's body), leaving everything else of the file (signatures, comments, formatting) as
it is: the docstrings are found with ``ast`` and only their spans are replaced.

A stub docstring the extension has no text for (a ``__new__``, a method without a `///`
comment) is not removed: it is reported, and its text belongs in the Rust comment (the class's
for a constructor). An item of the extension the stub does not declare is reported too (its
signature is written by hand, then this script fills in its docstring).

Usage (after the extension is rebuilt: ``pip install -e . --no-deps``):

    python tools/stub_docs.py           # rewrite python/vsinv/_core.pyi (make stubs)
    python tools/stub_docs.py --check   # exit 1 naming each docstring that differs
"""

from __future__ import annotations

import argparse
import ast
import importlib
import inspect
import sys
import types
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Optional, Union

ROOT = Path(__file__).resolve().parent.parent
STUB = ROOT / "python" / "vsinv" / "_core.pyi"
MODULE = "vsinv._core"

_Scope = Union[ast.Module, ast.ClassDef, ast.FunctionDef]


@dataclass
class Item:
    """A docstring's place in the stub and the extension's text for it (None: it has none).

    `node` is the scope the docstring opens (module, class, def) or, for an attribute's
    docstring (the string after ``name: type`` in a class body), the annotated assignment."""

    name: str
    node: Union[_Scope, ast.AnnAssign]
    indent: str
    runtime: Optional[str]
    attribute_doc: Optional[ast.Expr] = None

    @property
    def stub(self) -> Optional[str]:
        if isinstance(self.node, ast.AnnAssign):
            doc = self.attribute_doc
            return None if doc is None else inspect.cleandoc(doc.value.value)  # type: ignore[attr-defined]
        return ast.get_docstring(self.node, clean=True)


def runtime_doc(obj: Any) -> Optional[str]:
    """The object's own docstring, cleandoc-normalised; None for none or an empty one."""
    doc = getattr(obj, "__doc__", None)
    if not isinstance(doc, str) or not doc.strip():
        return None
    return inspect.cleandoc(doc)


def member_doc(cls: type, name: str) -> Optional[str]:
    """The docstring of a class's member as the extension defines it: None for a member it
    inherits (``object``'s, ``Exception``'s) or a slot (``__eq__``, ``__len__``, ``__new__``),
    whose text is Python's generic one and has no `///` comment behind it."""
    if name not in vars(cls):
        return None
    attr = inspect.getattr_static(cls, name)
    if isinstance(attr, (types.WrapperDescriptorType, types.MethodWrapperType)) or name == "__new__":
        return None
    return runtime_doc(getattr(attr, "__func__", attr))


class Source:
    """The extension's texts. The exception classes are the exception (src/python/errors.rs):
    their ``__doc__`` is the table's ``ERROR_CLASSES`` doc followed by a list of the attributes,
    which the stub declares one by one instead; so a class's docstring in the stub is its
    table doc, and each attribute of ``VsinvError`` has its ``ERROR_ATTRIBUTES`` doc."""

    def __init__(self, core: types.ModuleType):
        self.core = core
        self.error_classes = {c["name"]: c["doc"] for c in getattr(core, "ERROR_CLASSES", ())}
        self.error_attributes = {a["name"]: a["doc"] for a in getattr(core, "ERROR_ATTRIBUTES", ())}

    def of(self, name: str) -> Optional[str]:
        if name in self.error_classes:
            return inspect.cleandoc(self.error_classes[name])
        return runtime_doc(getattr(self.core, name))

    def attribute(self, cls_name: str, name: str) -> Optional[str]:
        if cls_name == "VsinvError" and name in self.error_attributes:
            return inspect.cleandoc(self.error_attributes[name])
        return None


def _body_indent(node: ast.AST) -> str:
    return " " * (getattr(node, "col_offset", -4) + 4)


def stub_items(tree: ast.Module, core: types.ModuleType) -> tuple[list[Item], list[str]]:
    """Every docstring place of the stub with the extension's text, and the problems found on
    the way: stub items the extension does not have, extension items the stub does not declare."""
    source = Source(core)
    items = [Item("module", tree, "", runtime_doc(core))]
    problems: list[str] = []
    declared: set[str] = set()
    for node in tree.body:
        if isinstance(node, (ast.AnnAssign, ast.Assign)):
            targets = [node.target] if isinstance(node, ast.AnnAssign) else node.targets
            declared |= {t.id for t in targets if isinstance(t, ast.Name)}
        if not isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            continue
        declared.add(node.name)
        if not hasattr(core, node.name):
            if not node.name.startswith("_"):  # private stub-only types (TypedDicts) aside
                problems.append(f"{node.name}: in the stub, not in the extension")
            continue
        items.append(Item(node.name, node, _body_indent(node), source.of(node.name)))
        if isinstance(node, ast.ClassDef):
            items += _class_items(node, getattr(core, node.name), source, problems)
    for name in sorted(n for n in vars(core) if not n.startswith("_") and n not in declared):
        problems.append(f"{name}: in the extension, not declared in the stub")
    return items, problems


def _class_items(node: ast.ClassDef, cls: type, source: Source, problems: list[str]) -> list[Item]:
    items, declared = [], set()
    for m, after in zip(node.body, node.body[1:] + [None]):
        if isinstance(m, ast.AnnAssign) and isinstance(m.target, ast.Name):
            declared.add(m.target.id)
            text = source.attribute(node.name, m.target.id)
            doc = after if isinstance(after, ast.Expr) and isinstance(getattr(after, "value", None), ast.Constant) else None
            if text is not None:
                items.append(Item(f"{node.name}.{m.target.id}", m, " " * m.col_offset, text, doc))
        if not isinstance(m, ast.FunctionDef) or m.name in declared:
            continue  # a property's setter or an overload: the first definition carries the text
        declared.add(m.name)
        items.append(Item(f"{node.name}.{m.name}", m, _body_indent(m), member_doc(cls, m.name)))
    for name in sorted(vars(cls)):
        if not name.startswith("_") and name not in declared:
            problems.append(f"{node.name}.{name}: in the extension, not declared in the stub")
    return items


def literal(text: str, indent: str) -> str:
    """The docstring literal of `text` as the stub writes it: the first line after the opening
    quotes, the others indented as the body, the closing quotes after the last line."""
    body = text.replace("\\", "\\\\").replace('"""', '\\"\\"\\"')
    if body.endswith('"'):
        body = body[:-1] + '\\"'
    lines = body.split("\n")
    out = '"""' + "\n".join([lines[0]] + [indent + line if line else "" for line in lines[1:]]) + '"""'
    if inspect.cleandoc(ast.literal_eval(out)) != text:
        raise ValueError(f"cannot write {text[:60]!r}... as a docstring")
    return out


Edit = tuple[int, int, str]  # (start offset, end offset, new text) in the file's text


def edit_for(item: Item, lines: Lines, source: str) -> Optional[Edit]:
    """The edit that makes the item's docstring the extension's; None when it already is, or
    when the extension has no text for it (reported instead)."""
    if item.runtime is None or item.stub == item.runtime:
        return None
    new = literal(item.runtime, item.indent)
    if isinstance(item.node, ast.AnnAssign):  # an attribute's docstring: the string after it
        if item.attribute_doc is not None:
            return _span(item.attribute_doc, lines) + (new,)
        end = _span(item.node, lines)[1]
        return (end, end, "\n" + item.indent + new)
    body = item.node.body
    first = body[0] if body else None
    if first is not None and item.stub is not None:  # replace the docstring's span
        return _span(first, lines) + (new,)
    if isinstance(item.node, ast.Module):
        return (0, 0, new + "\n\n")
    assert first is not None  # a def or class always has a body
    start, end = _span(first, lines)
    if _is_ellipsis(first) and len(body) == 1:  # `def f() -> T: ...`: the body becomes the docstring
        if first.lineno == item.node.lineno or source[:start].rstrip(" ").endswith(":"):
            colon = len(source[:start].rstrip(" "))
            return (colon, end, "\n" + item.indent + new)
        return (start, end, new)
    first_line = min([first.lineno] + [d.lineno for d in getattr(first, "decorator_list", [])])
    line_start = lines[first_line - 1]
    return (line_start, line_start, item.indent + new + "\n")


def _is_ellipsis(node: ast.stmt) -> bool:
    return isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) and node.value.value is Ellipsis


class Lines:
    """Offsets in the file's text of ast's positions: a line number and a column counted in
    UTF-8 bytes from the line's start."""

    def __init__(self, source: str):
        self.source = source
        self.starts = [0] + [i + 1 for i, c in enumerate(source) if c == "\n"]

    def __getitem__(self, line_index: int) -> int:
        """The offset of the start of line `line_index + 1`."""
        return self.starts[line_index]

    def offset(self, lineno: int, col: int) -> int:
        start = self.starts[lineno - 1]
        line = self.source[start : start + col]  # at least `col` bytes' worth of characters
        return start + len(line.encode("utf-8")[:col].decode("utf-8"))


def _span(node: ast.stmt, lines: Lines) -> tuple[int, int]:
    assert node.end_lineno is not None and node.end_col_offset is not None
    return lines.offset(node.lineno, node.col_offset), lines.offset(node.end_lineno, node.end_col_offset)


def generate(source: str, core: types.ModuleType) -> tuple[str, list[Item], list[str]]:
    """The stub with every docstring the extension's, the items changed, and the problems (a
    stub docstring without an extension text, items declared on one side only)."""
    tree = ast.parse(source)
    items, problems = stub_items(tree, core)
    lines = Lines(source)
    edits: list[tuple[Edit, Item]] = []
    for item in items:
        if item.runtime is None and item.stub is not None:
            problems.append(
                f"{item.name}: the stub has a docstring the extension lacks: move its text into the Rust `///` "
                "comment (the class's for a constructor), rebuild, delete it from the stub, run make stubs"
            )
        edit = edit_for(item, lines, source)
        if edit is not None:
            edits.append((edit, item))
    out = source
    for (start, end, new), _ in sorted(edits, key=lambda e: e[0][0], reverse=True):
        out = out[:start] + new + out[end:]
    return out, [item for _, item in edits], problems


def first_difference(stub: Optional[str], runtime: str) -> str:
    """Where the two texts part, for the check's report."""
    if stub is None:
        return "no docstring in the stub"
    a, b = stub.split("\n"), runtime.split("\n")
    for i, (x, y) in enumerate(zip(a, b)):
        if x != y:
            return f"line {i + 1}: stub {x!r} / extension {y!r}"
    return f"the stub has {len(a)} lines, the extension {len(b)}"


def stale_warning(core: types.ModuleType) -> Optional[str]:
    """A warning when a Rust source is newer than the built extension (its texts may be old)."""
    built = Path(getattr(core, "__file__", "") or "")
    sources = list((ROOT / "src").rglob("*.rs"))
    if not built.is_file() or not sources:
        return None
    newest = max(sources, key=lambda f: f.stat().st_mtime)
    if newest.stat().st_mtime <= built.stat().st_mtime:
        return None
    return (
        f"warning: {newest.relative_to(ROOT)} is newer than {built.name}: the texts may be the old build's; "
        "rebuild the extension first (`pip install -e . --no-deps`; make stubs does)"
    )


def main(argv: Optional[list[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="change nothing; exit 1 naming each difference")
    parser.add_argument("--stub", type=Path, default=STUB, help="the stub file (default: %(default)s)")
    args = parser.parse_args(argv)
    core = importlib.import_module(MODULE)
    source = args.stub.read_text(encoding="utf-8")
    warning = stale_warning(core)
    if warning:
        print(warning, file=sys.stderr)
    out, changed, problems = generate(source, core)
    for item in changed:
        verb = "differs" if args.check else "regenerated"
        print(f"{item.name}: {verb} ({first_difference(item.stub, item.runtime or '')})")
    for problem in problems:
        print(problem, file=sys.stderr)
    if args.check:
        if changed:
            print(f"{len(changed)} docstring(s) of {args.stub} differ from {MODULE}'s: run `make stubs`", file=sys.stderr)
        return 1 if changed or problems else 0
    if out != source:
        args.stub.write_text(out, encoding="utf-8")
    print(f"{args.stub}: {len(changed)} docstring(s) regenerated from {core.__file__}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
