"""The package's logger (issue 19, item 5): ``logging.getLogger("vsinv")``, quiet by default
(a NullHandler), INFO at the start and end of run_scenario, run_batch, run_sweep and replay,
DEBUG for details; the package never prints."""

from __future__ import annotations

import logging
import subprocess
import sys

import numpy as np
import pytest

import vsinv


def messages(caplog: pytest.LogCaptureFixture, level: int) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.name == "vsinv" and r.levelno == level]


def test_the_logger_is_quiet_by_default() -> None:
    assert any(isinstance(h, logging.NullHandler) for h in logging.getLogger("vsinv").handlers)
    code = (
        "import logging, vsinv\n"
        "logging.getLogger('vsinv').setLevel(logging.DEBUG)\n"  # enabled, but no handler configured
        "vsinv.run_scenario('lens-12-6', record=False)\n"
        "vsinv.sim.run_batch(['lens-12-6'])\n"
        "vsinv.sim.run_sweep('lens-12-6', {'focal_error': [0.0]})\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout == "" and done.stderr == ""


def test_run_scenario_logs_its_start_and_end(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.DEBUG, logger="vsinv")
    vsinv.run_scenario("lens-12-6", record=False)
    info = messages(caplog, logging.INFO)
    assert info[0] == "run_scenario lens-12-6: start (record=False)"
    assert info[-1].startswith("run_scenario lens-12-6: converged after ") and " iterations in " in info[-1]
    assert any(m == "run_scenario lens-12-6: 12 points, dt 0.04 s, no images" for m in messages(caplog, logging.DEBUG))


def test_info_hides_the_details(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO, logger="vsinv")
    vsinv.run_scenario("lens-12-6", record=False)
    assert len(messages(caplog, logging.INFO)) == 2 and not messages(caplog, logging.DEBUG)


def test_run_batch_logs_its_start_and_end(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO, logger="vsinv")
    vsinv.sim.run_batch(["lens-12-6", "lens-12-6"], threads=2)
    assert messages(caplog, logging.INFO)[0] == "run_batch: 2 scenarios on 2 threads"
    assert messages(caplog, logging.INFO)[-1].startswith("run_batch: 2 runs in ")
    assert messages(caplog, logging.INFO)[-1].endswith(": 2 converged, 0 errors")


def test_run_sweep_logs_its_start_end_and_chunks(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.DEBUG, logger="vsinv")
    vsinv.sim.run_sweep("lens-12-6", {"focal_error": [0.0, 0.5, 1.0]}, chunk_size=2)
    sweep = [m for m in messages(caplog, logging.INFO) if m.startswith("run_sweep")]
    assert sweep[0] == "run_sweep lens-12-6: 3 runs in chunks of 2 on this process"
    assert sweep[-1].startswith("run_sweep lens-12-6: 3 runs in ") and sweep[-1].endswith(": 3 converged")
    chunks = [m for m in messages(caplog, logging.DEBUG) if m.startswith("run_sweep: runs")]
    assert chunks == ["run_sweep: runs 0 to 1 done", "run_sweep: runs 2 to 2 done"]


def test_replay_logs_its_start_end_and_frames(caplog: pytest.LogCaptureFixture) -> None:
    scenario = vsinv.load_scenario("vision-12-12").to_dict()
    ref, ref_px, _ = vsinv.vision.render_view(scenario, reference=True)
    image, px, _ = vsinv.vision.render_view(scenario)
    caplog.set_level(logging.DEBUG, logger="vsinv")
    vsinv.replay(ref, [image, image], np.diag([600.0, 600.0, 1.0]), "dots", reference_points=ref_px,
                 first_points=px, law="ibvs", depths=0.6)
    info = messages(caplog, logging.INFO)
    assert info[0] == "replay: start (dots target)" and info[-1].startswith("replay: 2 frames in ")
    frames = [m for m in messages(caplog, logging.DEBUG) if m.startswith("replay: frame")]
    assert len(frames) == 2 and all("12 points found" in m for m in frames)
