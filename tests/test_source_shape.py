"""The shape of the Rust source: no function in src/ is longer than 80 lines.

A function's length counts the lines from its ``fn`` keyword to its closing brace. Its body
is found by brace matching on the tokens of the file, with string literals (plain, byte and
raw), char literals (``'{'``), lifetimes and comments (line, block, nested) left out, so a
brace inside them does not open or close anything. Trait methods without a body are not
functions here; a nested ``fn`` is measured on its own (and counts in its parent's lines).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import NamedTuple

SRC = Path(__file__).resolve().parent.parent / "src"
MAX_LINES = 80


class Token(NamedTuple):
    text: str
    line: int


class Function(NamedTuple):
    name: str
    line: int
    length: int


_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_RAW_STRING = re.compile(r'(?:br|cr|r)(#*)"')


def tokens(text: str) -> list[Token]:
    """Identifiers and punctuation of Rust source, without comments and literals."""
    out: list[Token] = []
    i, line, n = 0, 1, len(text)

    def skip_to(j: int) -> None:
        nonlocal i, line
        line += text.count("\n", i, j)
        i = j

    while i < n:
        c = text[i]
        if c == "\n":
            line += 1
            i += 1
        elif c.isspace():
            i += 1
        elif text.startswith("//", i):
            end = text.find("\n", i)
            skip_to(n if end < 0 else end)
        elif text.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            skip_to(j)
        elif (m := _RAW_STRING.match(text, i)) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            end = text.find('"' + m.group(1), m.end())
            skip_to(n if end < 0 else end + 1 + len(m.group(1)))
        elif c == '"' or (c in "bc" and text.startswith('"', i + 1) and not (i and (text[i - 1].isalnum() or text[i - 1] == "_"))):
            j = i + (1 if c == '"' else 2)
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            skip_to(j + 1)
        elif c == "'":
            if text.startswith("\\", i + 1):  # '\n', '\'', '\u{7b}'
                end = text.find("'", i + 3)
                skip_to(n if end < 0 else end + 1)
            elif i + 2 < n and text[i + 2] == "'" and text[i + 1] != "\n":  # 'x', '{'
                skip_to(i + 3)
            else:  # a lifetime or a label: 'a
                i += 1
        elif m := _IDENT.match(text, i):
            out.append(Token(m.group(), line))
            i = m.end()
        else:
            out.append(Token(c, line))
            i += 1
    return out


def functions(text: str) -> list[Function]:
    """Every ``fn`` item with a body: its name, the line of ``fn`` and its length in lines."""
    toks = tokens(text)
    found: list[Function] = []
    for k, tok in enumerate(toks):
        if tok.text != "fn" or k + 1 >= len(toks) or not _IDENT.fullmatch(toks[k + 1].text):
            continue  # `fn(u32) -> f64`, a function pointer type, is not an item
        depth, j = 0, k + 2
        while j < len(toks):
            t = toks[j].text
            if t in "([":
                depth += 1
            elif t in ")]":
                depth -= 1
            elif depth == 0 and t in "{;":
                break
            j += 1
        if j >= len(toks) or toks[j].text == ";":
            continue  # a declaration without a body
        braces, end = 0, j
        while end < len(toks):
            if toks[end].text == "{":
                braces += 1
            elif toks[end].text == "}":
                braces -= 1
                if braces == 0:
                    break
            end += 1
        last = toks[min(end, len(toks) - 1)].line
        found.append(Function(toks[k + 1].text, tok.line, last - tok.line + 1))
    return found


def too_long(root: Path = SRC, limit: int = MAX_LINES) -> list[str]:
    """``file:line:name:length`` of every function of ``root/**/*.rs`` over ``limit`` lines."""
    out = []
    for path in sorted(root.rglob("*.rs")):
        for f in functions(path.read_text(encoding="utf-8")):
            if f.length > limit:
                out.append(f"{path.relative_to(root.parent)}:{f.line}:{f.name}:{f.length}")
    return out


def test_no_function_in_src_is_longer_than_80_lines() -> None:
    files = sorted(SRC.rglob("*.rs"))
    assert files, f"no Rust source under {SRC}"
    assert sum(len(functions(p.read_text(encoding="utf-8"))) for p in files) > 100  # the scan sees the crate
    long = too_long()
    assert not long, f"functions longer than {MAX_LINES} lines (file:line:name:length):\n" + "\n".join(long)


# The scanner itself, on small samples: it must flag a long function, and braces in literals
# and comments must not move a function's end.


def _body(lines: int) -> str:
    return "".join(f"    let x{i} = {i};\n" for i in range(lines))


def test_scanner_flags_a_long_function(tmp_path: Path) -> None:
    src = tmp_path / "src"
    src.mkdir()
    (src / "lib.rs").write_text(
        "fn short() -> u32 {\n" + _body(10) + "    0\n}\n\n"
        "pub fn long(a: &[f64; 3]) -> [u8; 2] {\n" + _body(85) + "    [0; 2]\n}\n"
    )
    assert functions((src / "lib.rs").read_text()) == [Function("short", 1, 13), Function("long", 15, 88)]
    assert too_long(src) == ["src/lib.rs:15:long:88"]
    assert too_long(src, limit=88) == []


def test_scanner_ignores_braces_in_literals_and_comments() -> None:
    sample = """
fn open_char() -> char {
    '{'
}
fn close_char(c: char) -> bool {
    c == '}' || c == '\\'' || c == '\\u{7b}' || b'{' == 0
}
fn strings<'a>(s: &'a str) -> &'a str {
    let _ = "}}}{ \\" }";
    let _ = r#"{ "}" "#;
    let _ = br"}";
    'outer: loop { break 'outer; }
    s
}
// fn commented() {
/* fn block() { /* nested } */ } */
trait T {
    fn declared(&self) -> [u8; 3];
    fn provided(&self) -> u8 { 1 }
}
fn pointer(f: fn(u32) -> u32, g: &[fn(u32)]) -> u32 {
    f(g.len() as u32)
}
"""
    assert functions(sample) == [
        Function("open_char", 2, 3),
        Function("close_char", 5, 3),
        Function("strings", 8, 7),
        Function("provided", 19, 1),
        Function("pointer", 21, 3),
    ]
