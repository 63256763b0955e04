"""The site's equations as MathML, written at build time (issue 29, item 5: a site readable
offline, with no script from a CDN).

pymdownx.arithmatex (generic mode) leaves each equation as LaTeX in a `span` (inline, between
`\\(` and `\\)`) or a `div` (display, between `\\[` and `\\]`) of class `arithmatex`; this mkdocs
hook replaces each with the MathML that latex2mathml writes, which browsers render natively.
An equation it cannot convert fails the build, naming the page.
"""

from __future__ import annotations

import html
import re
from typing import Any

from latex2mathml.converter import convert

_MATH = re.compile(
    r'<(?P<tag>span|div) class="arithmatex">\s*(?:\\\((?P<inline>.*?)\\\)|\\\[(?P<block>.*?)\\\])\s*</(?P=tag)>',
    re.S,
)


def to_mathml(page_html: str) -> str:
    """`page_html` with every arithmatex equation as MathML."""

    def replace(m: re.Match[str]) -> str:
        inline = m.group("inline") is not None
        latex = html.unescape(m.group("inline") if inline else m.group("block"))
        return convert(latex.strip(), display="inline" if inline else "block")

    return _MATH.sub(replace, page_html)


def on_page_content(page_html: str, page: Any, **_: Any) -> str:
    try:
        return to_mathml(page_html)
    except Exception as error:  # latex2mathml raises its own types: name the page
        raise RuntimeError(f"{page.file.src_path}: an equation latex2mathml cannot convert: {error}") from error
