"""The documentation's code, run as a reader runs it (issue 19, item 5).

Every ```python block of a page under docs/ runs, in order, in one fresh interpreter per page
(a page's later blocks see the names its earlier blocks defined). Blocks write their figures
under ``figures/`` of the working directory: `make docs` runs the pages in docs/ itself, so
the site shows the figures the tutorial's own code draws; tests/test_docs.py runs them in a
temporary directory, so a page whose code fails, or stops doing what its text says (its
asserts), fails the tests.

A ```console block lists commands, one per line after ``$ ``; ``vsinv`` stands for
``python -m vsinv``. A block whose first line is ``# not run: <reason>`` is shown, not run
(installation commands).

The manual's pages (`MANUAL`: the guides, references and results that were the README's
sections) are the exception: tests/test_readme_blocks.py runs their blocks one by one, each
exactly as written in a fresh interpreter (a block makes or loads its own inputs, so it runs
when pasted), with a check of what the text says of it; they are not run here as one program.
Usage:

    python docs/pages.py run [PAGE ...] [--cwd DIR]   # every page by default, cwd docs/
    python docs/pages.py rust                         # cargo doc into docs/rust/ (the Rust API)
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
NOT_RUN = "# not run:"
TIME_LIMIT_S = 600


@dataclass(frozen=True)
class Block:
    lang: str
    code: str
    line: int  # of the opening fence, 1-based

    @property
    def first_line(self) -> str:
        return self.code.split("\n", 1)[0]

    @property
    def runs(self) -> bool:
        return self.lang in ("python", "console") and not self.code.startswith(NOT_RUN)


# The manual: pages whose blocks tests/test_readme_blocks.py runs one by one (with the README).
MANUAL = (
    "install.md",
    "guides/python.md",
    "guides/simulator.md",
    "guides/images.md",
    "guides/real-camera.md",
    "guides/tags.md",
    "guides/sweeps.md",
    "guides/real-robot.md",
    "guides/ros2.md",
    "guides/hand-eye.md",
    "guides/rust.md",
    "reference/conventions.md",
    "reference/scenario-files.md",
    "reference/files-and-limits.md",
    "results/built-in-scenarios.md",
    "results/noise.md",
    "results/performance.md",
    "development.md",
)


def manual_pages() -> list[Path]:
    return [DOCS / name for name in MANUAL]


def runs_as_page(page: Path) -> bool:
    """Whether the page's blocks run here, as one program (the manual's run block by block)."""
    return page.resolve() not in {p.resolve() for p in manual_pages()} and any(b.runs for b in blocks(page))


def pages() -> list[Path]:
    """Every Markdown page of the site, in a stable order."""
    return sorted(p for p in DOCS.rglob("*.md") if "rust" not in p.relative_to(DOCS).parts)


def blocks(page: Path) -> list[Block]:
    text = page.read_text(encoding="utf-8")
    return [
        Block(m.group(1), m.group(2), text.count("\n", 0, m.start()) + 1)
        for m in re.finditer(r"^```(\w*)\n(.*?)^```", text, re.M | re.S)
    ]


def console_as_python(code: str) -> str:
    """A console block's commands as Python: each must exit 0 and print the lines quoted under
    it (``...`` stands for lines left out)."""
    commands: list[tuple[str, list[str]]] = []
    for raw in code.splitlines():
        if raw.startswith("$ "):
            cmd = raw[2:].strip()
            if cmd.startswith("vsinv "):
                cmd = f"{sys.executable} -m vsinv {cmd[len('vsinv '):]}"
            commands.append((cmd, []))
        elif commands and raw.strip() not in ("", "..."):
            commands[-1][1].append(raw.rstrip())
    return "\n".join(
        f"_out = _subprocess.run({cmd!r}, shell=True, check=True, capture_output=True, text=True).stdout\n"
        f"print(_out)\n"
        f"for _line in {quoted!r}:\n"
        f"    assert _line in _out.splitlines(), f'not printed: {{_line!r}}'"
        for cmd, quoted in commands
    )


def page_program(page: Path) -> str:
    """The page's runnable blocks as one program, each tagged with its place in the page."""
    parts = ["import subprocess as _subprocess", "import matplotlib", "matplotlib.use('Agg')"]
    for block in (b for b in blocks(page) if b.runs):
        code = block.code if block.lang == "python" else console_as_python(block.code)
        parts.append(f"# {page.name}:{block.line}\n{code}")
    return "\n".join(parts) + "\n"


def run_page(page: Path, cwd: Path) -> subprocess.CompletedProcess[str]:
    """Runs the page's blocks in a fresh interpreter in `cwd` (figures go to cwd/figures)."""
    (cwd / "figures").mkdir(parents=True, exist_ok=True)
    return subprocess.run(
        [sys.executable, "-c", page_program(page)],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=TIME_LIMIT_S,
    )


def build_rust_docs() -> None:
    """The Rust API (cargo doc, warnings are errors) copied to docs/rust/ for the site."""
    env = {**os.environ, "RUSTDOCFLAGS": "-D warnings"}
    subprocess.run(["cargo", "doc", "--no-deps", "-q"], cwd=ROOT, check=True, env=env)
    shutil.rmtree(DOCS / "rust", ignore_errors=True)
    target = Path(os.environ.get("CARGO_TARGET_DIR") or ROOT / "target")  # where cargo wrote it
    shutil.copytree(ROOT / target / "doc", DOCS / "rust")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run the pages' code blocks")
    run.add_argument("pages", nargs="*", type=Path)
    run.add_argument("--cwd", type=Path, default=DOCS)
    sub.add_parser("rust", help="cargo doc into docs/rust/")
    args = parser.parse_args()
    if args.command == "rust":
        build_rust_docs()
        return 0
    failed = 0
    for page in [p.resolve() for p in args.pages] or [p for p in pages() if runs_as_page(p)]:
        done = run_page(page, args.cwd)
        print(f"{page.relative_to(DOCS)}: {'ok' if done.returncode == 0 else 'FAILED'}")
        if done.returncode != 0:
            failed += 1
            print(done.stdout[-3000:], done.stderr[-3000:], sep="\n", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
