"""Every fenced code block of README.md and of the manual's pages, executed (issue 19, item 2:
a README that is true; issue 29: the manual moved from the README to the docs site's guides,
references and results, `MANUAL` in docs/pages.py, and its blocks kept running here).

`tests/readme.rs` checks the README's scenario block against the schema (it parses and names
every key); this file runs the blocks as a reader would and checks what the text says of them.

Each block is matched to one entry of `BLOCKS` by its language and a piece of its code that
no other block of its language holds (so the pages need no markers, and a block can move). An
entry says how the block is taken:

- `RUN`: executed exactly as written (issue 29, item 5: every block runs as pasted), in a
  temporary working directory, in a fresh interpreter (Python) or bash (shell; there `vsinv`
  and `python` stand for `python -m vsinv` and the interpreter running the tests, as they do
  where the package is installed). Nothing is defined for a block: it makes or loads its own
  inputs (a built-in scenario, a rendering, generated arrays). A `check` runs after it (Python,
  in the same interpreter) or is applied to its output (shell): the outcome or the figures the
  page states next to the block.
- `SLOW`: runs only when `VSINV_README_SLOW=1` (minutes); counted otherwise.
- `NOT_RUN`: cannot run here (a real robot, a crate registry, a whole build); the reason is
  written down and counted.
- `needs_visp`: runs when ViSP's image dataset is installed, else reported skipped with why.

Every block must match exactly one entry and every entry one block: a new block without an
entry fails `test_every_block_has_an_entry`, so no block is silently skipped. The counts are
printed by `test_block_counts` (`pytest -s`).

Below the blocks, the README's figures are checked against the runs that make them: the tables
of built-in results (main, sec. 5.3, through images, lens distortion), the speed-limit figures
and the core's crate count. Default run: about 35 s; `VSINV_README_SLOW=1` adds the runs
through images (about 2.5 minutes more).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import textwrap
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import pytest
from doc_pages import pages

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
# The README (the landing page) and the manual's pages of the docs site, whose blocks run here.
MANUAL = [README, *pages.manual_pages()]
VISP = Path("/usr/share/visp-images-data/ViSP-images")
TIME_LIMIT_S = 300

RUN, SLOW, NOT_RUN = "run", "slow", "not run"


Block = pages.Block  # a fenced block: lang, code, line of its opening fence


def placed_blocks() -> list[tuple[Path, Block]]:
    """Every block of the README and the manual's pages, with its page."""
    return [(page, block) for page in MANUAL for block in pages.blocks(page)]


def readme_blocks() -> list[Block]:
    return [block for _, block in placed_blocks()]


def readme_text() -> str:
    """The README and the manual's pages, one text (the figures are found wherever they moved)."""
    return "\n".join(page.read_text(encoding="utf-8") for page in MANUAL)


@dataclass(frozen=True)
class Entry:
    lang: str
    holds: str  # a piece of the block's code that no other block of its language holds
    mode: str
    reason: str = ""
    check: str | Callable[[str], None] = ""  # Python after the block, or a check of a shell block's output
    output: str = ""  # text the README quotes as the block's output (stdout or stderr)
    needs_visp: bool = False


# --- checks: what the page states of a block, run after it (Python) ----------------------------


CALIBRATION_CHECK = """
assert np.allclose(vsinv.vision.distort_points(ideal, K, [k1, k2, p1, p2, k3]), distorted, atol=1e-9)
assert np.allclose(ideal, pixels, atol=1e-6) and not np.allclose(distorted, pixels, atol=1.0)
"""


HAND_EYE_CHECK = """
assert np.abs(cal.matrix - X).max() < 1e-9
assert cal.rms_rotation_deg < 1e-6 and 20 < cal.axis_spread_deg <= 90
assert agreement.max_rotation_deg < 1e-6 and agreement.max_translation_m < 1e-9
"""


EYE_TO_HAND_CHECK = """
assert cal.setup == "eye_to_hand" and np.abs(cal.matrix - Y).max() < 1e-9
assert cal.rms_rotation_deg < 1e-6 and cal.rms_translation_m < 1e-9 and 20 < cal.axis_spread_deg <= 90
wrong = vsinv.calibration.calibrate_hand_eye(gripper_poses, target_poses, method="park")
assert wrong.setup == "eye_in_hand" and wrong.rms_rotation_deg > 1.0
"""


def check_replay(out: str) -> None:
    """Every dot in every frame (the block's recording: three copies of vision-12-6's start
    view), and the table and figure written."""
    assert "3 frames, 12 points; 0 point-frames not found" in out, out
    assert Path("replay/replay.csv").is_file() and Path("replay/replay.png").is_file(), out


# The figures the README states under the block: the noisy copy with its loosened rule, and
# the same copy with the default rule.
SIMULATOR_CHECK = f"""
import re
text = open({str(ROOT / "docs/guides/simulator.md")!r}).read()
m = re.search(r"with the default\\s+`\\[stop\\]` the noisy copy above ends `(\\w+)` after (\\d+) iterations \\(([\\d.]+) mm", text)
plain = dict(d, stop=vsinv.load_scenario("lens-12-6").to_dict()["stop"])
s = vsinv.run_scenario(plain).summary
assert (s["status"], str(s["iterations"]), f"{{s['final_translation_error'] * 1e3:.2f}}") == m.groups(), (s, m.groups())
m = re.search(r"the copy then meets its rule after (\\d+) iterations,\\s+([\\d.]+) mm from the goal, and ends `(\\w+)`: "
              r"with `lens-12-6`'s object the images still allow\\s+([\\d.]+) mm", text)
s = noisy.summary
assert (str(s["iterations"]), f"{{s['final_translation_error'] * 1e3:.2f}}", s["status"]) == m.groups()[:3], (s, m.groups())
assert f"{{s['translation_uncertainty'] * 1e3:.1f}}" == m.group(4), s["translation_uncertainty"]
"""


RENDER_CHECK = """
assert found.all() and pixels.shape == (12, 2), found
assert (vsinv.vision.load_image("view.png") == image).all()
"""


IMAGE_SERVO_CHECK = """
assert len(sent) == 3 and step.found.all(), (len(sent), step.found)
"""


TAGS_SERVO_CHECK = """
step = pipeline.step(vsinv.vision.render("tags-12-6"))
assert step.found.sum() == 12, step.found
"""

# The depths the reference-depths block prints are those of the scenario's reference view (its
# ground truth: the points' z in the reference camera's frame) within 1 %, though the photo's
# camera was resected from dots found in a rendered image and the model moved to its own frame.
REFERENCE_DEPTHS_CHECK = """
_rc = vsinv.load_scenario("vision-12-6").to_dict()["reference_camera"]
_, _z = vsinv.geometry.project(points, vsinv.Intrinsics(_rc["fku"], _rc["fkv"], _rc["u0"], _rc["v0"]))
assert z_star.shape == (12,) and np.allclose(z_star, _z, rtol=0.01), (z_star, _z)
print("largest error", np.abs(z_star / _z - 1).max())
"""


def check_mire2_replay(out: str) -> None:
    """IBVS follows mire-2's five dots through the first 100 real frames."""
    assert "100 frames, 5 points; 0 point-frames not found" in out, out[-500:]



BATCH_CHECK = """
assert list(table["status"][:2]) == ["converged", "max_iterations"] or len(table["status"]) == 4
import os
assert os.path.exists("sweep.parquet") or os.path.exists("sweep.csv")
"""

LOGGING_OUTPUT = "vsinv run_scenario lens-12-6: converged after 213 iterations in"


SERVO_CHECK = """
assert str(step.verdict) == "converged", (step.verdict, step.reason)
assert np.linalg.norm(pose[:3, 3]) < 1e-3, pose
"""


# --- checks of shell output: the figures the README quotes next to the block ------------------


def _number_after(pattern: str, text: str) -> float:
    m = re.search(pattern, text)
    assert m, f"README no longer says {pattern!r}"
    return float(m.group(1))


def check_zoom_invariance(out: str) -> None:
    """'prints image errors growing to 120.5 px at 1550 px while every invariant error stays at
    or below 6.36e-4'."""
    text = readme_text()
    quoted_image = _number_after(r"prints image errors growing to ([\d.]+) px", text)
    quoted_invariant = _number_after(r"every invariant error stays at or below\s+([\d.e-]+)", text)
    m = re.search(r"max image error ([\d.]+) px .*max invariant error ([\d.e+-]+) over", out)
    assert m, out
    assert round(float(m.group(1)), 1) == quoted_image, (m.group(1), quoted_image)
    assert float(f"{float(m.group(2)):.3g}") == quoted_invariant, (m.group(2), quoted_invariant)
    assert "0 of 96 dots not found" in out, out


def check_lens_invariance(out: str) -> None:
    """'finds all 12 dots (image errors 82.8 to 379.2 px; invariant errors up to 0.146 ...)'."""
    text = readme_text()
    m = re.search(r"finds all (\d+) dots \(image errors ([\d.]+) to ([\d.]+) px; invariant errors up to ([\d.]+)", text)
    assert m, "README no longer states the lens-change invariance figures"
    dots, low, high, invariant = int(m.group(1)), float(m.group(2)), float(m.group(3)), float(m.group(4))
    rows = re.findall(r"^\s*\d+\s+([\d.]+) / ([\d.e+-]+)\s*$", out, re.M)
    assert len(rows) == dots, out
    errors = [float(r[0]) for r in rows]
    assert (round(min(errors), 1), round(max(errors), 1)) == (low, high), errors
    worst = re.search(r"max invariant error ([\d.e+-]+) over", out)
    assert worst and round(float(worst.group(1)), 3) == invariant, out
    assert f"0 of {dots} dots not found" in out, out


def check_exit_only(out: str) -> None:
    """The block's commands all exit 0 (checked by the runner); nothing is quoted."""


def check_sweeps(out: str) -> None:
    assert Path("sweeps").is_dir()


# --- the registry: one entry per README block --------------------------------------------------

BLOCKS: list[Entry] = [
    Entry("sh", "make run", NOT_RUN, "the whole install and test suite (make run compiles for several minutes, "
          "make test about 15 minutes on 2 cores): CI and the lead run it, and this file is part of it"),
    Entry("sh", "python -m pip install .", NOT_RUN, "compiles the extension from source (5-15 minutes); make wheels "
          "and tests/test_wheels.py (VSINV_WHEELS=1) run the same install in a fresh venv"),
    Entry("python", "# The paper's lens change (sec. 5.2)", RUN, output="converged after 212 steps, 0.09 mm from the reference pose"),
    Entry("sh", "python3 -m venv --system-site-packages .venv", NOT_RUN, "needs a ROS 2 installation, a camera "
          "driver and MoveIt Servo; tests/test_ros_loop.py runs the node over ROS 2 topics with simulated ones"),
    Entry("python", "ctl = vsinv.laws.InvariantController(", RUN, check="assert twist.shape == (6,) and report.prop1, report"),
    Entry("python", "try:\n    vsinv.run_scenario(d)", RUN, check="print('no exception escaped')", output="fix the gain:"),
    Entry("python", "cal = vsinv.calibration.load_calibration", RUN, check=CALIBRATION_CHECK),
    Entry("python", "cal = vsinv.calibration.calibrate_hand_eye(gripper_poses, target_poses, method=\"park\")", RUN,
          check=HAND_EYE_CHECK),
    Entry("python", "setup=\"eye_to_hand\")", RUN, check=EYE_TO_HAND_CHECK),
    Entry("sh", "vsinv list", RUN, check=check_exit_only),
    Entry("python", "result = vsinv.run_scenario", RUN, check=SIMULATOR_CHECK),
    Entry("toml", 'name = "my-run"', RUN, "loaded and run: the outcome stated under the block"),
    Entry("python", "ref = vsinv.vision.render(\"vision-12-6\", reference=True)", RUN, check=RENDER_CHECK),
    Entry("sh", "vsinv render vision-zoom", RUN, check=check_zoom_invariance),
    Entry("sh", "vsinv render vision-12-6 --out lens/", RUN, check=check_lens_invariance),
    Entry("python", 'image = vsinv.vision.load_image("/usr/share/visp-images-data', RUN, needs_visp=True,
          check="assert len(dots.centroids) == 36, len(dots.centroids)"),
    Entry("python", "tags = vsinv.vision.detect_tags", RUN, needs_visp=True,
          check="assert tags.ids[0] == 8 and tags.ids[1] == 9 and tags.ids[-1] == 19, tags.ids\n"
          "assert tags.corners[0].shape == (4, 2)"),
    Entry("python", "pipeline = vsinv.ImageServo(reference_image, \"dots\"", RUN, check=IMAGE_SERVO_CHECK),
    Entry("python", "pipeline = vsinv.ImageServo(reference_image, \"tags\"", RUN, check=TAGS_SERVO_CHECK),
    Entry("sh", "vsinv replay rec/reference.png frames/", RUN, check=check_replay),
    Entry("python", "import contextlib", NOT_RUN, "needs a camera: tests/test_camera_source.py runs "
          "vsinv.frames(0) through a stand-in VideoCapture and OpenCV's own reading a video file"),
    Entry("python", "# The object's model, in its own frame", RUN, check=REFERENCE_DEPTHS_CHECK),
    Entry("sh", "VISP=/usr/share/visp-images-data/ViSP-images", RUN, needs_visp=True, check=check_mire2_replay),
    Entry("python", "table = vsinv.sim.run_batch(", RUN, check=BATCH_CHECK),
    Entry("sh", "vsinv sweep lens-12-6", RUN, check=check_sweeps),
    Entry("python", "import logging", RUN, output=LOGGING_OUTPUT),
    Entry("python", 'stop={"window": 10})', RUN, check=SERVO_CHECK),
    Entry("yaml", "vsinv_ros:", NOT_RUN, "a ROS 2 parameters file for a real camera and arm: "
          "tests/test_ros_bridge.py parses it with the bridge's parser (with files of its own), and "
          "tests/test_ros_loop.py runs the bridge from such a file over ROS 2 topics"),
    Entry("sh", "vsinv-ros --lifecycle", NOT_RUN, "needs ROS 2's command line (ros2 lifecycle): "
          "tests/test_ros_lifecycle.py drives the same transitions over the node's lifecycle services"),
    Entry("sh", "colcon build --base-paths ros", NOT_RUN, "needs a ROS 2 installation with colcon, launch and launch_ros (not on "
          "PyPI); tests/test_ros_package.py builds the package with colcon when it is installed"),
    Entry("sh", "ros2 service call /servo_node/switch_command_type", NOT_RUN, "needs ROS 2, a camera driver and MoveIt Servo; "
          "tests/test_ros_loop.py runs the same command against a simulated camera and robot"),
    Entry("python", "q = [0.1, -1.2, 1.0, -0.5, 1.4, 0.3]", RUN,
          check="assert solution.position_residual < 1e-10 and solution.rotation_residual < 1e-10\n"
          "assert np.allclose(vsinv.kinematics.fk('ur5', solution.joints), pose, atol=1e-9)\n"
          "assert list(sweep['status']) == ['converged'] * 3, list(sweep['status'])"),
    Entry("toml", "[dependencies]", RUN, "a Cargo manifest: parsed, its version checked against Cargo.toml "
          "(not built: the crate is not on crates.io yet)"),
    Entry("rust", "use vsinv::{Intrinsics", NOT_RUN, "a fragment (reference_pixels, pixels, depths undefined); "
          "examples/control_loop.rs is the compiled loop with the same calls (make test-examples)"),
    Entry("", "src/", NOT_RUN, "not code: the source tree (checked: every top-level entry exists)"),
    Entry("sh", "make bench", NOT_RUN, "the benchmarks: tens of minutes, timing only (make bench)"),
]


def entry_for(block: Block) -> Entry:
    matches = [e for e in BLOCKS if e.lang == block.lang and e.holds in block.code]
    assert len(matches) == 1, f"manual block at line {block.line} ({block.lang!r}: {block.first_line!r}) matches {len(matches)} entries"
    return matches[0]


def test_every_block_has_an_entry() -> None:
    blocks = readme_blocks()
    used = [entry_for(b) for b in blocks]
    unused = [e for e in BLOCKS if e not in used]
    assert not unused, f"entries that match no README block (a block changed its first line?): {unused}"


def test_block_counts() -> None:
    """How the blocks are taken; printed with `pytest -s`."""
    counts: dict[str, int] = {}
    for block in readme_blocks():
        entry = entry_for(block)
        mode = entry.mode
        if entry.needs_visp and not VISP.is_dir():
            mode = "skipped: no visp-images-data"
        counts[mode] = counts.get(mode, 0) + 1
    print(f"README blocks: {sum(counts.values())}; " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
    assert sum(counts.values()) == len(BLOCKS)


def run_python(code: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    script = cwd / "block.py"
    script.write_text(code, encoding="utf-8")
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.run([sys.executable, str(script)], cwd=cwd, capture_output=True, text=True,
                          timeout=TIME_LIMIT_S, env=env, check=False)


def run_shell(code: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    shell = f'set -e\nvsinv() {{ "{sys.executable}" -m vsinv "$@"; }}\npython() {{ "{sys.executable}" "$@"; }}\n{code}'
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.run(["bash", "-c", shell], cwd=cwd, capture_output=True, text=True,
                          timeout=TIME_LIMIT_S, env=env, check=False)


def _ids() -> list[str]:
    return [f"{page.relative_to(ROOT)}:{b.line}-{b.lang or 'text'}" for page, b in placed_blocks()]


@pytest.mark.parametrize("block", readme_blocks(), ids=_ids())
def test_readme_block(block: Block, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    entry = entry_for(block)
    if entry.mode == NOT_RUN:
        check_not_run(block, entry)
        return
    if entry.mode == SLOW and os.environ.get("VSINV_README_SLOW") != "1":
        pytest.skip(f"slow: {entry.reason} (VSINV_README_SLOW=1 runs it)")
    if entry.needs_visp and not VISP.is_dir():
        pytest.skip("ViSP's image dataset is not installed: apt-get install visp-images-data")
    monkeypatch.chdir(tmp_path)
    if block.lang == "python":
        run_python_block(block, entry, tmp_path)
    elif block.lang == "sh":
        run_shell_block(block, entry, tmp_path)
    elif block.lang == "toml":
        run_toml_block(block, entry)
    else:
        raise AssertionError(f"no runner for {block.lang!r}")


def check_not_run(block: Block, entry: Entry) -> None:
    assert entry.reason, f"block at line {block.line} is not run without a reason"
    if block.lang == "":
        for line in block.code.splitlines():
            m = re.match(r"^(\S+/|\S+\.rs)\s", line + " ")
            if m and not line.startswith(" "):
                assert (ROOT / m.group(1)).exists() or (ROOT / "src" / m.group(1)).exists(), line
    if block.lang == "rust":
        example = (ROOT / "examples/control_loop.rs").read_text(encoding="utf-8")
        assert "InvariantController::new(" in example and "InvariantControllerConfig::default()" in example


def run_python_block(block: Block, entry: Entry, cwd: Path) -> None:
    assert isinstance(entry.check, str)
    # The check is the test's code (it imports what it uses), run after the block as written.
    code = "\n".join([block.code, "# --- check ---", "import numpy as np, vsinv", textwrap.dedent(entry.check)])
    proc = run_python(code, cwd)
    assert proc.returncode == 0, f"manual block at line {block.line} ({block.first_line!r}) failed:\n{proc.stdout}\n{proc.stderr}"
    assert entry.output in proc.stderr + proc.stdout, proc.stderr


def run_shell_block(block: Block, entry: Entry, cwd: Path) -> None:
    proc = run_shell(block.code, cwd)
    assert proc.returncode == 0, f"manual block at line {block.line} ({block.first_line!r}) failed:\n{proc.stdout}\n{proc.stderr}"
    assert callable(entry.check)
    entry.check(proc.stdout)


def run_toml_block(block: Block, entry: Entry) -> None:
    if block.code.startswith("[dependencies]"):
        # tomllib is Python 3.11+: the two version strings are read by pattern.
        wanted = re.search(r'^vsinv = \{ version = "([\d.]+)"', block.code, re.M)
        crate = re.search(r'^\[package\][^\[]*?^version = "([\d.]+)"', (ROOT / "Cargo.toml").read_text(encoding="utf-8"), re.M | re.S)
        assert wanted and crate and crate.group(1).startswith(wanted.group(1) + "."), (wanted, crate)
        return
    check_full_scenario(block)


def check_full_scenario(block: Block) -> None:
    """The scenario block runs to the outcome the README states under it."""
    import vsinv

    text = readme_text()
    after = text.split(block.code, 1)[1]
    m = re.search(r"This scenario, as written, ends `(\w+)` after (\d+) iterations, ([\d.]+) mm and "
                  r"([\d.]+) degrees from the goal", after)
    assert m, "the README no longer states the outcome of its scenario block"
    result = vsinv.run_scenario(vsinv.sim.Scenario.from_toml(block.code))
    s = result.summary
    assert s["status"] == m.group(1), s["message"]
    assert s["iterations"] == int(m.group(2)), s["iterations"]
    assert f"{s['final_translation_error'] * 1e3:.2f}" == m.group(3), s["final_translation_error"]
    assert f"{s['final_rotation_error'] * 180 / 3.141592653589793:.3f}" == m.group(4), s["final_rotation_error"]


def test_long_compiles_show_progress() -> None:
    """`make run` and `make test` install first, which compiles the extension for minutes: the
    install targets must not silence it (`-q`), `make run` builds with maturin itself (pip
    would hold cargo's progress back) in the lighter profile `light` and installs no extra,
    and the README says how long to expect."""
    makefile = (ROOT / "Makefile").read_text(encoding="utf-8")
    recipes = {}
    for target in ("install:", "install-run:"):
        recipe = makefile.split("\n" + target, 1)[1].split("\n\n", 1)[0]
        assert "pip" in recipe.lower() or "$(PIP)" in recipe, recipe
        assert " -q" not in recipe, f"{target} silences the compile: {recipe!r}"
        recipes[target] = recipe
    run = recipes["install-run:"]
    assert "MATURIN) build --profile light" in run and "[" not in run, run  # "[": an extra
    cargo = (ROOT / "Cargo.toml").read_text(encoding="utf-8")
    profile = re.search(r"^\[profile\.light\]\n((?:[^\[\n].*\n)+)", cargo, re.M)
    assert profile and 'inherits = "release"' in profile.group(1) and "lto = false" in profile.group(1), profile
    assert re.search(r"first `make run`.*compiles.*took \d+ min( \d+ s)? on 2 idle cores", readme_text(), re.S)


# --- the tables of built-in results: each figure is what `vsinv run NAME --json` prints ----------


def readme_table(header_start: str) -> list[list[str]]:
    """The rows of the README table whose header line starts with `header_start`."""
    lines = readme_text().split("\n")
    start = next(i for i, line in enumerate(lines) if line.startswith(header_start))
    rows = []
    for line in lines[start + 2:]:
        if not line.startswith("|"):
            break
        rows.append([cell.strip() for cell in line.strip().strip("|").split("|")])
    return rows


def agrees(quoted: str, value: float | None) -> bool:
    """`value` rounds to the README's figure at the README's precision (`n/a`: no value)."""
    quoted = quoted.split(" ")[0]
    if quoted == "n/a":
        return value is None or value != value  # None or NaN
    decimals = len(quoted.split(".")[1]) if "." in quoted else 0
    return value is not None and round(value, decimals) == float(quoted)


DEG = 180.0 / 3.141592653589793


def test_builtin_table_is_what_the_runs_print() -> None:
    """The README's table of built-in scenarios ("Measured with `vsinv run NAME --json`")."""
    import vsinv

    rows = readme_table("| scenario | status | iterations | final translation error (mm) | final rotation error (deg) | final image")
    assert len(rows) >= 17
    for name, status, iterations, *figures in rows:
        s = vsinv.run_scenario(name).summary
        got = [s["final_translation_error"] * 1e3, s["final_rotation_error"] * DEG, s["final_image_error"],
               s["final_invariant_error"], s["peak_linear_speed"], s["peak_angular_speed"] * DEG]
        assert status.split(" ")[0] == s["status"] and int(iterations) == s["iterations"], (name, s["status"], s["iterations"])
        wrong = [(q, g) for q, g in zip(figures, got) if not agrees(q, g)]
        assert not wrong, f"{name}: README figure vs run: {wrong}"


def test_path_table_is_what_the_runs_print() -> None:
    """The README's sec. 5.3 table (Prop. 3's figures along the planned path)."""
    import vsinv

    rows = readme_table("| scenario | status | iterations | final translation error (mm) | final rotation error (deg) | max line")
    assert [r[0] for r in rows] == ["path-500", "path-3000", "path-500-feedforward"]
    for name, status, iterations, *figures in rows:
        s = vsinv.run_scenario(name).summary
        got = [s["final_translation_error"] * 1e3, s["final_rotation_error"] * DEG, s["max_line_deviation"] * 1e3,
               s["tracking_sigma"], s["tracking_psi"], s["tracking_bound"], s["observed_max_eps"]]
        assert (status, int(iterations)) == (s["status"], s["iterations"]), (name, s["status"], s["iterations"])
        wrong = [(q, g) for q, g in zip(figures, got) if not agrees(q, g)]
        assert not wrong, f"{name}: README figure vs run: {wrong}"


VISION_TABLE = "| scenario | status | iterations | final translation error (mm) | final rotation error (deg) | detection"


def test_vision_table_status_is_the_recorded_one() -> None:
    """Status and iterations of the vision table against tests/fixtures/builtin_results.txt
    (which tests/builtin_results.rs keeps bit-identical to the runs); the other figures are
    checked by the slow test below."""
    recorded = {}
    for line in (ROOT / "tests/fixtures/builtin_results.txt").read_text(encoding="utf-8").splitlines():
        name, status, iterations, _digest = line.split()
        recorded[name] = (status, int(iterations))
    for name, status, iterations, *_ in readme_table(VISION_TABLE):
        assert recorded[name] == (status.split(" ")[0], int(iterations)), (name, recorded[name])


@pytest.mark.skipif(os.environ.get("VSINV_README_SLOW") != "1", reason="slow (about 2 minutes): VSINV_README_SLOW=1 runs it")
def test_vision_table_is_what_the_runs_print() -> None:
    """The README's table of the built-ins through images (also printed by
    `cargo test --release --test integration vision_loop:: -- --nocapture`)."""
    import vsinv

    rows = readme_table(VISION_TABLE)
    assert len(rows) >= 6
    for name, status, iterations, translation, rotation, detection in rows:
        s = vsinv.run_scenario(name).summary
        assert (status.split(" ")[0], int(iterations)) == (s["status"], s["iterations"]), (name, s["status"], s["iterations"])
        median, worst = detection.split(" / ")
        got = [s["final_translation_error"] * 1e3, s["final_rotation_error"] * DEG, s["detection_error_median"], s["detection_error_max"]]
        wrong = [(q, g) for q, g in zip([translation, rotation, median, worst], got) if not agrees(q, g)]
        assert not wrong, f"{name}: README figure vs run: {wrong}"


def test_speed_limit_figures() -> None:
    """'Without limits the first step of `lens-12-6` asks for 82 deg/s (422 deg/s with the
    paper's `rz_task = "tau21"`) ... (lens-12-6: 212 iterations without the limits, 213 with them'."""
    import math

    import vsinv

    m = re.search(r"Without limits the first step of `lens-12-6` asks for\s+(\d+) deg/s \((\d+) deg/s with the paper's "
                  r"`rz_task = \"tau21\"`\).*?lens-12-6: (\d+)\s+iterations without the limits, (\d+) with them", readme_text(), re.S)
    assert m, "the README no longer states the speed-limit figures"
    free = vsinv.load_scenario("lens-12-6").to_dict()
    for key in ("max_linear_speed", "max_angular_speed_deg"):
        free["control"].pop(key)
    first_steps = []
    for rz_task in ("angle", "tau21"):
        run = vsinv.run_scenario(dict(free, control=dict(free["control"], rz_task=rz_task)))
        first_steps.append(round(math.degrees(float(sum(w * w for w in run.twist[0][3:]) ** 0.5))))
        if rz_task == "angle":
            unlimited = run.summary["iterations"]
    limited = vsinv.run_scenario("lens-12-6").summary["iterations"]
    assert [str(x) for x in (*first_steps, unlimited, limited)] == list(m.groups()), (first_steps, unlimited, limited)


@pytest.mark.skipif(shutil.which("cargo") is None, reason="needs cargo")
def test_core_crate_count() -> None:
    """'nalgebra and thiserror as its only dependencies (16 crates in all, vsinv included'."""
    m = re.search(r"as its only dependencies \((\d+) crates in all, vsinv included", readme_text())
    assert m, "the README no longer states the core's crate count"
    tree = subprocess.run(["cargo", "tree", "--offline", "--no-default-features", "-e", "normal", "--prefix", "none"],
                          cwd=ROOT, capture_output=True, text=True, timeout=120, check=False)
    if tree.returncode != 0:
        pytest.skip(f"cargo tree failed (offline, no registry cache?): {tree.stderr[-300:]}")
    crates = {line.replace(" (*)", "").strip() for line in tree.stdout.splitlines() if line.strip()}
    assert len(crates) == int(m.group(1)), sorted(crates)


def _barrel_runs(slow: bool) -> dict[str, dict]:
    """The runs behind the README's "Distortion in the loop" figures (as tests/distortion_loop.rs)."""
    import vsinv

    runs = {"known (default)": vsinv.load_scenario("lens-12-6-barrel").to_dict()}
    unknown = vsinv.load_scenario("lens-12-6-barrel").to_dict()
    unknown["estimate"] = {"fku": 600.0, "fkv": 600.0, "u0": 416.0, "v0": 312.0, "distortion": [0.0] * 5}
    runs["unknown (`[estimate] distortion = [0, 0, 0, 0, 0]`)"] = unknown
    if slow:
        through_images = vsinv.load_scenario("vision-12-6").to_dict()
        through_images["camera"]["distortion"] = [-0.30, 0.10, 0.0005, -0.0008, -0.02]
        runs["wrong K_hat"] = dict(through_images)
        through_images = dict(through_images)
        through_images.pop("estimate")
        runs["known, through images (`vision-12-6` with this lens)"] = through_images
    return {key: vsinv.run_scenario(d).summary for key, d in runs.items()}


def check_barrel_figures(slow: bool) -> None:
    rows = {r[0]: r for r in readme_table("| distortion | K_hat | status | iterations |")}
    summaries = _barrel_runs(slow)
    for key, s in summaries.items():
        if key == "wrong K_hat":
            continue
        _, _, status, iterations, translation, rotation = rows[key]
        assert (status, int(iterations)) == (s["status"], s["iterations"]), (key, s["status"], s["iterations"])
        got = [s["final_translation_error"] * 1e3, s["final_rotation_error"] * DEG]
        assert all(agrees(q, g) for q, g in zip([translation, rotation], got)), (key, got, translation, rotation)
    text = readme_text()
    unknown = summaries["unknown (`[estimate] distortion = [0, 0, 0, 0, 0]`)"]
    m = re.search(r"the invariant error stays at\s+([\d.]+)\)", text)
    assert m and agrees(m.group(1), unknown["final_invariant_error"]), (m, unknown["final_invariant_error"])
    if slow:
        wrong = summaries["wrong K_hat"]
        m = re.search(r"that run stops ([\d.]+) mm and ([\d.]+) degrees away", text)
        assert m and agrees(m.group(1), wrong["final_translation_error"] * 1e3), (m, wrong)
        assert agrees(m.group(2), wrong["final_rotation_error"] * DEG), (m, wrong)


def test_barrel_table_is_what_the_runs_print() -> None:
    """The README's "Distortion in the loop" table, its first two rows (the third is slow)."""
    check_barrel_figures(slow=False)


@pytest.mark.skipif(os.environ.get("VSINV_README_SLOW") != "1", reason="slow (about 40 s): VSINV_README_SLOW=1 runs it")
def test_barrel_figures_through_images() -> None:
    """The third row (through images) and the run with vision-12-6's wrong K_hat: 1.0 mm, 0.91 degrees."""
    check_barrel_figures(slow=True)
