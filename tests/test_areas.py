"""Every test file has an area (a marker per layer, tests/conftest.py's AREAS or the file's own
``pytestmark``), and every area is a registered marker, so ``pytest -m vision`` misses no test."""

import re
import tomllib
from pathlib import Path

from conftest import AREA_OF, AREAS, SLOW

TESTS = Path(__file__).parent
OWN_MARK = re.compile(r"^pytestmark\s*=\s*\[?\s*pytest\.mark\.(\w+)", re.MULTILINE)


def registered_markers() -> set[str]:
    config = tomllib.loads((TESTS.parent / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]
    assert "--strict-markers" in config["addopts"]
    return {line.split(":")[0].strip() for line in config["markers"]}


def area_of(path: Path) -> str | None:
    own = [m for m in OWN_MARK.findall(path.read_text(encoding="utf-8")) if m in AREAS]
    return own[0] if own else AREA_OF.get(path.name)


def test_every_test_file_has_an_area():
    missing = [p.name for p in sorted(TESTS.glob("test_*.py")) if area_of(p) is None]
    assert not missing, f"test files without an area (add them to AREAS in tests/conftest.py): {missing}"


def test_the_table_names_existing_files_once():
    names = [n for names in AREAS.values() for n in names]
    assert len(names) == len(set(names)), "a file is in two areas"
    stale = [n for n in names if not (TESTS / n).is_file()]
    assert not stale, f"AREAS names files that do not exist: {stale}"


def test_every_area_and_slow_are_registered():
    assert set(AREAS) | {"slow"} <= registered_markers()


def test_own_marker_is_found(tmp_path):
    own = tmp_path / "test_x.py"
    own.write_text("import pytest\n\npytestmark = pytest.mark.ros\n")
    assert area_of(own) == "ros"
    none = tmp_path / "test_y.py"
    none.write_text("import pytest\n")
    assert area_of(none) is None


def test_the_area_marker_is_given(request):
    assert request.node.get_closest_marker("package") is not None
    assert request.node.get_closest_marker("vision") is None


def test_slow_cases_name_existing_tests():
    """Each case of conftest's SLOW names a test function of an existing file (the case's
    parameters are checked by the marker taking effect: test_slow_cases_are_marked)."""
    for case in SLOW:
        file, function = case.split("[")[0].split("::")
        assert f"def {function}(" in (TESTS / file).read_text(encoding="utf-8"), case


def test_slow_cases_are_marked(pytestconfig):
    """Collects the SLOW cases on their own: every one is found and carries `slow`."""
    import subprocess
    import sys

    ids = sorted(f"tests/{case}" for case in SLOW)
    done = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q", "-m", "slow", "-p", "no:cacheprovider", *ids],
                          cwd=TESTS.parent, capture_output=True, text=True)
    collected = sorted(line for line in done.stdout.splitlines() if "::" in line)
    assert collected == ids, done.stdout[-2000:] + done.stderr[-2000:]
