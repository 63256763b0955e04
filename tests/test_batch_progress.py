"""run_batch's progress report (issue 19, item 5): a tqdm bar as on sweeps, or a callable
``progress(done, total)`` called from the calling thread while the runs go on in Rust."""

from __future__ import annotations

import threading

import numpy as np
import pytest

import vsinv


def test_the_callable_sees_increasing_counts_up_to_the_total_on_the_calling_thread() -> None:
    calls: list[tuple[int, int, int]] = []
    table = vsinv.sim.run_batch(
        ["lens-12-6"] * 7, threads=2, progress=lambda done, total: calls.append((done, total, threading.get_ident()))
    )
    assert list(table["status"]) == ["converged"] * 7
    assert calls, "progress was never called"
    done = [c[0] for c in calls]
    assert done == sorted(set(done)) and 1 <= done[0] and done[-1] == 7
    assert {c[1] for c in calls} == {7}
    assert {c[2] for c in calls} == {threading.get_ident()}


def test_results_do_not_depend_on_the_progress_report() -> None:
    batch = ["lens-12-6", "noise-12-6", "planar"]
    quiet = vsinv.sim.run_batch(batch, progress=False)
    reported = vsinv.sim.run_batch(batch, progress=lambda done, total: None)
    assert quiet.keys() == reported.keys()
    for name, column in quiet.items():
        np.testing.assert_array_equal(column, reported[name], err_msg=name)  # NaN equals NaN here


def test_progress_true_draws_a_tqdm_bar_on_stderr(capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("tqdm")
    vsinv.sim.run_batch(["lens-12-6"] * 3, progress=True)
    err = capsys.readouterr().err
    assert "batch" in err and "3/3" in err
    vsinv.sim.run_batch(["lens-12-6"] * 3, progress=False)
    vsinv.sim.run_batch(["lens-12-6"] * 3)  # None: stderr is not a terminal under pytest
    assert capsys.readouterr().err == ""


def test_a_bad_progress_is_a_type_error_naming_it() -> None:
    with pytest.raises(TypeError, match=r"progress: expected None, True, False or a callable progress\(done, total\)"):
        vsinv.sim.run_batch(["lens-12-6"], progress="yes")  # type: ignore[arg-type]


def test_an_exception_in_progress_stops_the_batch_and_is_raised() -> None:
    calls = []

    def stop(done: int, total: int) -> None:
        calls.append(done)
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="^stop here$"):
        vsinv.sim.run_batch(["noise-12-6"] * 64, threads=1, progress=stop)
    assert len(calls) == 1
    # The pool is still usable afterwards.
    assert list(vsinv.sim.run_batch(["lens-12-6"], progress=False)["status"]) == ["converged"]


def test_a_sweep_passes_no_bar_to_its_chunks(capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("tqdm")
    vsinv.sim.run_sweep("lens-12-6", {"focal_error": [0.0, 0.5]}, progress=True)
    err = capsys.readouterr().err
    assert "sweep lens-12-6" in err and "batch" not in err


def test_ctrl_c_stops_a_long_batch() -> None:
    """SIGINT while a batch runs (20000 runs on one thread) raises KeyboardInterrupt
    within the signal check's 0.1 s plus the run in progress (uninterrupted: about 8 s)."""
    import subprocess
    import sys

    code = (
        "import os, signal, threading, time, vsinv\n"
        # Python's own Ctrl-C handler, whatever the parent left (a process that ignores SIGINT,
        # as some test runners' workers leave it, passes that on and the signal never arrives).
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT)).start()\n"
        "t = time.perf_counter()\n"
        "try:\n"
        "    vsinv.sim.run_batch(['noise-12-6'] * 20000, threads=1, progress=False)\n"
        "    print('finished')\n"
        "except KeyboardInterrupt:\n"
        "    print('interrupted after %.1f s' % (time.perf_counter() - t))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("interrupted after "), done.stdout
    assert float(done.stdout.split()[2]) < 5.0, done.stdout
