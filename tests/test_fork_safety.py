"""Fork safety (issue 19, item 3): batches, sweeps and dot detection keep working in a process
forked after they ran (a ``ProcessPoolExecutor`` with the ``fork`` start method).

POSIX ``fork`` copies only the calling thread, so a worker pool started before the fork has no
workers in the child: before the fix the sweep guide's sweep (docs/guides/sweeps.md) on a ``ProcessPoolExecutor(2)`` waited
forever at 0 % CPU when a sweep or batch had run before in the same process. vsinv now keeps
its own pools and rebuilds them in a forked child (``src/parallel.rs``).

Every scenario runs in its own interpreter, in a session of its own, under a time limit: a hang
fails the test (and the whole process group, the forked workers included, is killed) instead
of hanging the suite.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap

import pytest

pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="needs os.fork (POSIX)")

# Each script finishes in about a second here; a hang is what the limit catches.
TIME_LIMIT_S = 120


# Defined in every script: the parent's side of a fork, waiting up to a minute for the child and
# printing its exit code, or "child hung" (and killing it).
WAIT_FOR_CHILD = """
import os as _os, time as _time
def wait_for(pid):
    for _ in range(1200):
        done, status = _os.waitpid(pid, _os.WNOHANG)
        if done == pid:
            print("child exit", _os.waitstatus_to_exitcode(status))
            return
        _time.sleep(0.05)
    _os.kill(pid, 9)
    print("child hung")
"""


def run_script(code: str) -> str:
    """Run ``code`` in a fresh interpreter; its stdout. Fails on a hang or a non-zero exit."""
    proc = subprocess.Popen(
        [sys.executable, "-c", WAIT_FOR_CHILD + textwrap.dedent(code)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        out, err = proc.communicate(timeout=TIME_LIMIT_S)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)  # the script and the children it forked
        out, err = proc.communicate()
        pytest.fail(f"hung for {TIME_LIMIT_S} s (a fork after a started pool?); output so far:\n{out}\n{err}")
    assert proc.returncode == 0, f"exit {proc.returncode}:\n{out}\n{err}"
    return out


def test_the_readme_sweep_on_a_process_pool_after_earlier_sweeps_and_batches() -> None:
    """The "Batches and sweeps" guide's block (docs/guides/sweeps.md) in order: a batch, a sweep in this process, then
    the sweep on ``ProcessPoolExecutor(2)`` (fork, Linux's default before Python 3.14)."""
    out = run_script(
        """
        import concurrent.futures, multiprocessing
        import numpy as np
        import vsinv

        scenario_a, scenario_b = "lens-12-6", "planar"
        table = vsinv.sim.run_batch([scenario_a, scenario_b], threads=2)
        table = vsinv.sim.run_batch([scenario_a, scenario_b])          # the pool of all cores too
        res = vsinv.sim.run_sweep("lens-12-6", {"focal_error": np.linspace(-0.9, 3.0, 4),
                                            "roll_deg": vsinv.sweep.Uniform(-120, 120)}, draws=2, seed=1)
        res.summary_by("focal_error")
        res = vsinv.sim.run_sweep("noise-12-6", {"noise.pixel_sigma": [0.25, 0.5, 1.0]}, repeats=20,
                              executor=concurrent.futures.ProcessPoolExecutor(2))
        print("readme", len(res.columns["status"]))
        fork = multiprocessing.get_context("fork")   # explicit: the default start method may change
        with concurrent.futures.ProcessPoolExecutor(2, mp_context=fork) as pool:
            res = vsinv.sim.run_sweep("noise-12-6", {"noise.pixel_sigma": [0.25, 0.5]}, repeats=4, executor=pool)
            print("fork", len(res.columns["status"]), sorted(set(res.columns["status"].tolist())))
            table = pool.submit(vsinv.sim.run_batch, ["lens-12-6"] * 3).result()
            print("batch in a worker", table["status"].tolist())
        """
    )
    assert "readme 60" in out
    assert "fork 8 ['converged']" in out
    assert "batch in a worker ['converged', 'converged', 'converged']" in out


def test_fork_after_dot_detection_on_a_large_image() -> None:
    """``detect_dots`` on a large image runs rows and tiles in parallel; a child forked after it
    detects the same dots (before the fix it used rayon's global pool and hung in the child)."""
    out = run_script(
        """
        import os, time
        import numpy as np
        import vsinv

        image = np.full((3000, 4000), 40, np.uint8)
        v, u = np.mgrid[0:3000, 0:4000]
        for k in range(48):
            cu, cv = 200 + (k % 8) * 470, 200 + (k // 8) * 480
            image[(u - cu) ** 2 + (v - cv) ** 2 <= 30 ** 2] = 220
        parent = vsinv.vision.detect_dots(image)
        assert len(parent) == 48, len(parent)
        pid = os.fork()
        if pid == 0:
            child = vsinv.vision.detect_dots(image)
            same = np.array_equal(child.centroids, parent.centroids)
            os._exit(0 if same else 3)
        wait_for(pid)
        """
    )
    assert "child exit 0" in out, out


def test_fork_while_another_thread_runs_a_batch() -> None:
    """Forks taken while a batch runs on another thread (its pool busy, the pool registry in
    use): every child runs its own batch; the parent's batch finishes."""
    out = run_script(
        """
        import os, threading, time
        import vsinv

        vsinv.sim.run_batch(["lens-12-6"] * 2)
        result = {}
        worker = threading.Thread(target=lambda: result.update(vsinv.sim.run_batch(["noise-12-6"] * 40, threads=2)))
        worker.start()
        codes = []
        for _ in range(5):
            pid = os.fork()
            if pid == 0:
                table = vsinv.sim.run_batch(["lens-12-6"] * 2, threads=2)
                os._exit(0 if list(table["status"]) == ["converged"] * 2 else 3)
            for _ in range(1200):
                done, status = os.waitpid(pid, os.WNOHANG)
                if done == pid:
                    codes.append(os.waitstatus_to_exitcode(status))
                    break
                time.sleep(0.05)
            else:
                os.kill(pid, 9)
                codes.append("hung")
        worker.join()
        print("children", codes, "parent", len(result["status"]))
        """
    )
    assert "children [0, 0, 0, 0, 0] parent 40" in out, out


def test_fork_after_tag_detection() -> None:
    """AprilTag decoding (kornia, rayon inside) runs on vsinv's pools too: a child forked after
    ``detect_tags`` decodes the same tags."""
    pytest.importorskip("cv2")
    out = run_script(
        """
        import os, time
        import cv2
        import numpy as np
        import vsinv

        dictionary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11)
        image = np.full((1200, 1600), 220, np.uint8)
        for k, tag in enumerate((0, 5, 9)):
            marker = cv2.aruco.generateImageMarker(dictionary, tag, 240, borderBits=1)
            image[300:540, 100 + 500 * k : 340 + 500 * k] = np.where(marker > 0, 220, 30)
        parent = vsinv.vision.detect_tags(image)
        assert sorted(parent.ids.tolist()) == [0, 5, 9], parent.ids
        pid = os.fork()
        if pid == 0:
            child = vsinv.vision.detect_tags(image)
            os._exit(0 if np.array_equal(child.corners, parent.corners) else 3)
        wait_for(pid)
        """
    )
    assert "child exit 0" in out, out
