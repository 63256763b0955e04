"""The scenario-file mutation fuzzer's CI part (``make fuzz`` runs every built-in): in a
subprocess, so that a crash is a failure of this test and not of the test run."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

FUZZER = Path(__file__).resolve().parent / "scenario_fuzz.py"


@pytest.mark.slow
def test_every_mutated_key_runs_or_is_refused_by_name():
    env = dict(os.environ, RUST_BACKTRACE="0")
    done = subprocess.run(
        [sys.executable, str(FUZZER), "--quick"], capture_output=True, text=True, timeout=600, env=env
    )
    assert done.returncode == 0, done.stdout[-4000:] + done.stderr[-4000:]
    assert " 0 failures" in done.stdout.splitlines()[-1], done.stdout[-2000:]
