"""Every Python example script runs and shows what it says (each exits non-zero otherwise)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


@pytest.mark.parametrize(
    ("script", "expected"),
    [
        ("python_controller.py", "converged after"),
        ("python_servo.py", "servo session: converged after"),
        ("python_scenario.py", "lens-12-6: converged"),
        ("python_batch.py", "+200% | converged"),
        ("python_sweep.py", "runs written to"),
        ("python_vision.py", "by hand: after 700 images"),
    ],
)
def test_example_runs(tmp_path, script, expected):
    pytest.importorskip("matplotlib")
    done = subprocess.run(
        [sys.executable, str(EXAMPLES / script), str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert expected in done.stdout, done.stdout


def test_every_python_example_is_tested():
    tested = {"python_controller.py", "python_servo.py", "python_scenario.py", "python_batch.py", "python_sweep.py", "python_vision.py"}
    assert {p.name for p in EXAMPLES.glob("*.py")} == tested
