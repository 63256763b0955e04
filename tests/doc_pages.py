"""docs/pages.py (the documentation's code blocks: how they are read and run) as a module the
tests import: tests/test_docs.py runs the pages with it, tests/test_readme_blocks.py reads the
README's blocks with it."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

_PATH = Path(__file__).resolve().parent.parent / "docs" / "pages.py"
_spec = importlib.util.spec_from_file_location("docs_pages", _PATH)
assert _spec is not None and _spec.loader is not None
pages = importlib.util.module_from_spec(_spec)
sys.modules["docs_pages"] = pages
_spec.loader.exec_module(pages)
