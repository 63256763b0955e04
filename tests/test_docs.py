"""The documentation's code runs and does what its text says (issue 19, item 5).

Each page's ```python and ```console blocks run in order in a fresh interpreter in a temporary
directory (docs/pages.py; its asserts are the claims the text makes). The site itself, with the
Rust API and in mkdocs' strict mode, is built by `make docs`, which `make test` runs.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from doc_pages import pages

ROOT = Path(__file__).resolve().parent.parent

RUNNABLE = [p for p in pages.pages() if pages.runs_as_page(p)]
# Pages of prose and reference only; every other page (the tutorial, the concepts) shows code.
WITHOUT_CODE = ("index.md", "paper-corrections.md", "reference/python.md", "reference/rust.md", "reference/law-options.md")


def _mujoco_missing() -> str | None:
    import vsinv.mujoco

    return vsinv.mujoco.available()


def _textured_box_missing() -> str | None:
    import feature_world

    return feature_world.available()


# Pages whose code needs an optional extra: skipped, saying what to install, without it.
NEEDS = {"guides/mujoco.md": _mujoco_missing, "guides/markerless.md": _textured_box_missing}


def nav_pages() -> list[str]:
    """The pages mkdocs.yml's nav lists (lines `title: page.md`)."""
    nav = (ROOT / "mkdocs.yml").read_text(encoding="utf-8").split("\nnav:\n", 1)[1]
    return re.findall(r"^\s+- [^:]+: (\S+\.md)$", nav, re.M)


@pytest.mark.parametrize("page", RUNNABLE, ids=lambda p: str(p.relative_to(pages.DOCS)))
def test_page_code_runs(page: Path, tmp_path: Path) -> None:
    why_not = NEEDS.get(str(page.relative_to(pages.DOCS)), lambda: None)()
    if why_not is not None:
        pytest.skip(why_not)
    done = pages.run_page(page, tmp_path)
    assert done.returncode == 0, f"{page.name}:\n{done.stdout[-2000:]}\n{done.stderr[-3000:]}"


def test_tutorial_and_concepts_have_code() -> None:
    """The tutorial and every concept page show runnable code, so every one is checked; the
    manual's pages are run block by block by tests/test_readme_blocks.py."""
    for name in nav_pages():
        if name not in WITHOUT_CODE and name not in pages.MANUAL:
            assert pages.DOCS / name in RUNNABLE, f"{name} has no runnable block"


def test_manual_pages_are_on_disk_and_not_run_as_programs() -> None:
    for page in pages.manual_pages():
        assert page.is_file(), page
        assert page not in RUNNABLE, page


def test_nav_lists_every_page() -> None:
    on_disk = sorted(str(p.relative_to(pages.DOCS)) for p in pages.pages())
    assert sorted(nav_pages()) == on_disk


def test_console_blocks_check_quoted_output() -> None:
    """A console block's quoted line that the command does not print fails the page."""
    program = pages.console_as_python("$ echo hello\nhello\n...\n")
    exec(program, {"_subprocess": __import__("subprocess")})
    wrong = pages.console_as_python("$ echo hello\ngoodbye\n")
    with pytest.raises(AssertionError, match="not printed: 'goodbye'"):
        exec(wrong, {"_subprocess": __import__("subprocess")})


def test_the_site_needs_no_network() -> None:
    """Equations become MathML at build time (docs/hooks/mathml.py) and the theme uses the
    system's fonts: no script or font from a CDN, so the site reads offline (issue 29, item 5)."""
    config = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    assert "docs/hooks/mathml.py" in config and "font: false" in config
    assert not re.search(r"^\s*-\s*https?://", config, re.M), "a script from the network"


def test_equations_become_mathml() -> None:
    """The hook's conversion against latex2mathml's own, for the two forms arithmatex writes."""
    pytest.importorskip("latex2mathml")
    import importlib.util

    from latex2mathml.converter import convert

    spec = importlib.util.spec_from_file_location("mathml_hook", ROOT / "docs/hooks/mathml.py")
    assert spec is not None and spec.loader is not None
    hook = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(hook)
    page = ('<p>so <span class="arithmatex">\\(q = Q^{-1} p\\)</span> and</p>\n'
            '<div class="arithmatex">\\[a &lt; b\\]</div>')
    out = hook.to_mathml(page)
    assert convert("q = Q^{-1} p", display="inline") in out
    assert convert("a < b", display="block") in out
    assert "arithmatex" not in out and "\\(" not in out
