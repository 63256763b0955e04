"""The command-line interface (`vsinv list`, `vsinv run`) and the figures/archive it writes."""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import vsinv
from vsinv.cli import first_sentence, main

pytest.importorskip("matplotlib")

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
FIGURES = [
    "image_trajectories.png",
    "errors.png",
    "task_functions.png",
    "velocities.png",
    "pose_errors.png",
    "path3d.png",
]
REQUIRED = [
    "status",
    "iterations",
    "final_translation_error",
    "final_rotation_error",
    "final_image_error",
    "final_invariant_error",
]


def run_cli(capsys, *args):
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def bad_scenario(tmp_path: Path, old: str, new: str) -> Path:
    text = vsinv.load_scenario("lens-12-6").to_toml()
    assert old in text
    path = tmp_path / "bad.toml"
    path.write_text(text.replace(old, new, 1))
    return path


def test_list(capsys):
    code, out, err = run_cli(capsys, "list")
    assert code == 0
    assert "lens-12-6" in out
    names = [n for n, _ in vsinv.sim.list_scenarios()]
    lines = out.splitlines()
    for name in names:
        assert any(line.split()[0] == name for line in lines if line.strip())
    assert all(len(line) <= 200 for line in lines)
    assert err == ""


def test_first_sentence_skips_abbreviations():
    assert first_sentence("Sec. 5.2, experiment 2: a lens change. The rest.") == "Sec. 5.2, experiment 2: a lens change."
    assert first_sentence("See Prop. 1 and Fig. 3. Then more.") == "See Prop. 1 and Fig. 3."
    assert first_sentence("No full stop") == "No full stop"


def test_version(capsys):
    code, out, _ = run_cli(capsys, "--version")
    assert code == 0
    assert vsinv.__version__ in out


def test_run_human_summary(capsys):
    code, out, err = run_cli(capsys, "run", "lens-12-6", "--no-progress")
    assert code == 0
    assert "converged" in out
    for word in ("mm", "deg", "px", "tau_11", "tau_22", "invariant", "Prop. 1", "Prop. 2", "basis"):
        assert word in out
    assert "Traceback" not in out + err


def test_run_json(capsys):
    code, out, err = run_cli(capsys, "run", "lens-12-6", "--json", "--no-progress")
    assert code == 0
    summary = json.loads(out)  # exactly one JSON object, nothing else on stdout
    assert isinstance(summary, dict)
    for key in REQUIRED:
        assert key in summary, key
    assert summary["status"] == "converged"
    assert summary["name"] == "lens-12-6"
    assert isinstance(summary["iterations"], int) and summary["iterations"] > 0
    assert summary["final_translation_error"] < 1e-3
    assert summary["final_rotation_error"] < np.radians(0.1)
    assert "final_translation_error_mm" not in summary  # the older names are gone (issue 29)
    assert "NaN" not in out and "Infinity" not in out


def test_json_writes_nan_as_null_and_plots_a_lost_run(capsys, tmp_path):
    # Turned 60 degrees away, the camera sees no point: the run ends at once with status
    # lost_features (exit code 1: not converged) and NaN invariant error and tau values.
    d = vsinv.load_scenario("lens-12-6").to_dict()
    d["name"] = "lost-at-start"
    d["start"]["rotation_deg"] = [0.0, 60.0, 0.0]
    path = tmp_path / "lost.toml"
    path.write_text(vsinv.sim.Scenario.from_dict(d).to_toml())
    code, out, err = run_cli(capsys, "run", str(path), "--json", "--out", str(tmp_path / "out"), "--no-progress")
    assert code == 1, err
    assert "NaN" not in out
    summary = json.loads(out)
    assert summary["status"] == "lost_features"
    assert summary["final_invariant_error"] is None
    assert summary["final_tau_11"] is None
    for name in FIGURES:
        assert (tmp_path / "out" / name).read_bytes().startswith(PNG_MAGIC), name

    from vsinv.plots import summary_json

    text = summary_json({"a": float("nan"), "b": [1.0, float("-inf")], "c": np.float64(2.0)})
    assert json.loads(text) == {"a": None, "b": [1.0, None], "c": 2.0}


def test_run_out_writes_npz_and_figures(capsys, tmp_path):
    out_dir = tmp_path / "nested" / "out"
    code, out, err = run_cli(capsys, "run", "lens-12-6", "--json", "--out", str(out_dir), "--no-progress")
    assert code == 0
    summary = json.loads(out)  # the file listing goes to stderr with --json
    assert "trajectory.npz" in err
    for name in FIGURES:
        path = out_dir / name
        assert path.is_file(), name
        data = path.read_bytes()
        assert len(data) > 1000 and data.startswith(PNG_MAGIC), name
        assert name in err
    with np.load(out_dir / "trajectory.npz") as npz:
        n = summary["iterations"]
        rows = npz["time"].shape[0]
        assert rows >= n >= 1
        assert npz["pose"].shape == (rows, 4, 4)
        assert npz["pixels"].shape == (rows, 12, 2)
        assert npz["reference_pixels"].shape == (12, 2)
        for key in ("twist", "joints", "visible", "invariant_error", "eps", "eps_z", "image_error",
                    "translation_error", "rotation_error"):
            assert npz[key].shape[0] == rows, key
        np.testing.assert_allclose(np.linalg.norm(npz["pose"][-1, :3, 3]), npz["translation_error"][-1])
        stored = json.loads(str(npz["summary_json"]))
    assert stored["status"] == "converged"
    assert stored["iterations"] == summary["iterations"]


def test_run_out_lists_files_on_stdout_without_json(capsys, tmp_path):
    code, out, _ = run_cli(capsys, "run", "lens-12-6", "--out", str(tmp_path), "--no-progress")
    assert code == 0
    assert "trajectory.npz" in out and "path3d.png" in out


def test_save_figures_and_npz_api(tmp_path):
    import matplotlib.pyplot as plt

    from vsinv.plots import save_figures, save_npz

    open_before = plt.get_fignums()  # figures other tests of the session left open
    result = vsinv.run_scenario("lens-12-6")
    paths = save_figures(result, tmp_path / "figs")
    assert [p.name for p in paths] == FIGURES
    assert all(p.read_bytes().startswith(PNG_MAGIC) for p in paths)
    npz_path = save_npz(result, tmp_path / "run")
    assert npz_path.name == "run.npz" and npz_path.is_file()
    assert plt.get_fignums() == open_before  # every figure it made closed after saving
    with pytest.raises(ValueError, match=r"the run was not recorded \(run_scenario\(\.\.\., record=False\)\): nothing to plot"):
        save_figures(vsinv.run_scenario("lens-12-6", record=False), tmp_path / "none")


@pytest.mark.parametrize(
    "old, new, key",
    [
        ("[robot]", "[robot]\nfrobnicate = 1", "robot.frobnicate"),
        ("max_iterations = 1500", 'max_iterations = "many"', "stop.max_iterations"),
        ("gain = 1.0", 'gain = "fast"', "control.gain"),
    ],
)
def test_bad_scenario_file(capsys, tmp_path, old, new, key):
    path = bad_scenario(tmp_path, old, new)
    code, out, err = run_cli(capsys, "run", str(path), "--no-progress")
    assert code == 2
    assert err.startswith("vsinv: error: ")
    assert key in err
    assert "Traceback" not in err
    assert out == ""


def test_unknown_name(capsys):
    code, out, err = run_cli(capsys, "run", "no-such-scenario", "--json")
    assert code == 2
    assert out == ""
    assert "vsinv: error:" in err and "no-such-scenario" in err
    assert "Traceback" not in err


def test_usage_errors(capsys):
    assert run_cli(capsys, "frobnicate")[0] == 2
    assert run_cli(capsys)[0] == 2
    assert run_cli(capsys, "run")[0] == 2


def test_unwritable_out_dir(capsys, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    code, _, err = run_cli(capsys, "run", "lens-12-6", "--out", str(blocker / "sub"), "--no-progress")
    assert code == 2
    assert err.startswith("vsinv: error: ")


def _console_command():
    exe = shutil.which("vsinv", path=os.path.dirname(sys.executable) + os.pathsep + os.environ.get("PATH", ""))
    return [exe] if exe else [sys.executable, "-m", "vsinv"]


def test_console_script(tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg")
    ok = subprocess.run(
        [*_console_command(), "run", "lens-12-6", "--json"],
        capture_output=True, text=True, timeout=120, env=env,
    )
    assert ok.returncode == 0, ok.stderr
    assert json.loads(ok.stdout)["status"] == "converged"
    assert ok.stderr == ""  # no progress bar when stderr is not a terminal

    bad = bad_scenario(tmp_path, "[robot]", "[robot]\nfrobnicate = 1")
    fail = subprocess.run([*_console_command(), "run", str(bad)], capture_output=True, text=True, timeout=120, env=env)
    assert fail.returncode == 2
    assert "robot.frobnicate" in fail.stderr
    assert "Traceback" not in fail.stderr
    assert fail.stdout == ""


def test_python_dash_m(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "vsinv", "list"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0
    assert "lens-12-6" in proc.stdout


@pytest.mark.parametrize(
    "observed, bound, printed",
    [
        (0.163, 0.1022, "max ||eps|| 0.163 > psi/phi 0.1022"),
        (0.05, 0.1022, "max ||eps|| 0.05 <= psi/phi 0.1022"),
        (0.1022, 0.1022, "max ||eps|| 0.1022 <= psi/phi 0.1022"),
        (None, 0.1022, "max ||eps|| n/a vs psi/phi 0.1022"),
        (float("nan"), 0.1022, "max ||eps|| n/a vs psi/phi 0.1022"),
    ],
)
def test_prop3_line_prints_the_comparison_that_holds(observed, bound, printed):
    # Issue 19: the summary printed "0.163 <= psi/phi 0.1022" whatever the numbers were.
    from vsinv.cli import format_summary

    summary = {"name": "x", "path_duration": 1.0, "observed_max_eps": observed, "tracking_bound": bound}
    line = next(line for line in format_summary(summary).splitlines() if "Prop. 3" in line)
    assert printed in line
