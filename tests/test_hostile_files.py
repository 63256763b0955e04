"""Hostile files (issue 16): every file the package reads (calibration YAML and XML, URDF,
scenario TOML, PNG, points CSV) given as a bomb, a device, a FIFO, a huge sparse file, a path
out of the scenario's folder, binary garbage or another encoding, with a planted marker.

Each case group runs in one subprocess with an address-space limit (RLIMIT_AS, 1.5 GiB over
the interpreter's baseline) and a timeout; inside it every case is guarded and must end in the
package's error (InvalidInput / VsinvError), within a generous hang bound, and its message must
not contain the marker (the file's contents). Through the Python API and the ``vsinv`` CLI.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import pytest

MARKER = "SECRETMARKER0123456789"
TIMEOUT_S = 60
MEMORY_OVER_BASELINE = 1536 << 20

pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="RLIMIT_AS, FIFOs and /dev/zero: Linux")

# Runs in the subprocess: limits memory, then runs `cases` (name -> code) and prints one JSON
# line per case: the exception class, the message, the seconds taken.
HARNESS = """
import json, os, resource, sys, time
import vsinv
rss = int(open("/proc/self/statm").read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
limit = rss + {over}
resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
for name, code in json.loads(sys.argv[1]).items():
    t = time.perf_counter()
    try:
        exec(code, {{"vsinv": vsinv}})
        kind, message = "returned", ""
    except BaseException as e:
        kind, message = type(e).__name__, str(e)
    print(json.dumps({{"case": name, "kind": kind, "message": message, "s": time.perf_counter() - t}}), flush=True)
"""


def run_cases(cases: dict[str, str], cwd: Path) -> dict[str, dict[str, Any]]:
    """Runs the cases in one limited subprocess; returns the outcome of each."""
    harness = HARNESS.format(over=MEMORY_OVER_BASELINE)
    proc = subprocess.run(
        [sys.executable, "-c", harness, json.dumps(cases)],
        cwd=cwd, capture_output=True, text=True, timeout=TIMEOUT_S,
    )
    assert proc.returncode == 0, f"the subprocess died ({proc.returncode}): {proc.stderr[-2000:]}"
    out = {}
    for line in proc.stdout.splitlines():
        row = json.loads(line)
        out[row["case"]] = row
    assert set(out) == set(cases), f"cases without an outcome: {set(cases) - set(out)}; {proc.stderr[-2000:]}"
    return out


def check(outcomes: dict[str, dict[str, Any]], kinds: tuple[str, ...] = ("InvalidInput",)) -> None:
    for name, row in outcomes.items():
        assert row["kind"] in kinds, f"{name}: {row['kind']}: {row['message'][:500]}"
        assert MARKER not in row["message"], f"{name}: the error quotes the file: {row['message'][:500]}"
        assert row["s"] < 5.0, f"{name}: {row['s']:.1f} s (hang bound 5 s)"


# ---------------------------------------------------------------------------------------------
# The hostile files


def alias_bomb(levels: int = 9, width: int = 9) -> str:
    lines = [f"a0: &a0 [{', '.join(['1'] * width)}]"]
    for i in range(1, levels):
        lines.append(f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * width)}]")
    return "\n".join(lines) + "\nimage_width: 640\n"


MATRIX_BOMB = (
    "image_width: 640\nimage_height: 480\nb0: &b0 [0, 0, 0, 0, 0, 0, 0, 0, 0]\n"
    + "".join(f"b{i}: &b{i} [{', '.join([f'*b{i - 1}'] * 9)}]\n" for i in range(1, 8))
    + "camera_matrix:\n  rows: 3\n  cols: 3\n  data: [*b7, *b7, *b7, *b7, *b7, *b7, *b7, *b7, *b7]\n"
)

XML_BOMB = (
    '<?xml version="1.0"?>\n<!DOCTYPE lolz [\n <!ENTITY lol "lol">\n'
    + "".join(f' <!ENTITY lol{i} "{("&lol" + (str(i - 1) if i > 1 else "") + ";") * 10}">\n' for i in range(1, 10))
    + "]>\n<opencv_storage><image_width>&lol9;</image_width></opencv_storage>\n"
)

ROS_YAML = """image_width: 640
image_height: 480
camera_matrix:
  rows: 3
  cols: 3
  data: [800.0, 0, 320.0, 0, 800.0, 240.0, 0, 0, 1]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [-0.1, 0.01, 0, 0, 0]
"""

SECRET_YAML = f"image_width: {MARKER}\nimage_height: 480\n"
SECRET_MODEL = ROS_YAML.replace("plumb_bob", MARKER)
SECRET_XML = f"<opencv_storage><image_width>{MARKER}</image_width></opencv_storage>"
SECRET_PASSWD = f"root:x:0:0:root:/root:/bin/bash {MARKER}\ndaemon:x:1:1::/usr/sbin:/usr/sbin/nologin\n"
GARBAGE = bytes(range(256)) * 8 + MARKER.encode()


def write_files(d: Path) -> None:
    """The hostile files, in `d` (the scenario's folder) and in `d`/../outside."""
    (d / "bomb.yaml").write_text(alias_bomb())
    (d / "matrix_bomb.yaml").write_text(MATRIX_BOMB)
    (d / "bomb.xml").write_text(XML_BOMB)
    (d / "secret.yaml").write_text(SECRET_YAML)
    (d / "secret_model.yaml").write_text(SECRET_MODEL)
    (d / "secret.xml").write_text(SECRET_XML)
    (d / "passwd.yaml").write_text(SECRET_PASSWD)
    (d / "garbage.bin").write_bytes(GARBAGE)
    (d / "utf16.yaml").write_text(ROS_YAML + f"# {MARKER}\n", encoding="utf-16")
    (d / "latin1.yaml").write_bytes((ROS_YAML + f"# caf\xe9 {MARKER}\n").encode("latin-1"))
    with open(d / "huge.bin", "wb") as f:  # sparse: takes no disk
        f.truncate(8 << 30)
    os.mkfifo(d / "fifo")
    (d / "good.yaml").write_text(ROS_YAML)
    outside = d.parent / "outside"
    outside.mkdir(exist_ok=True)
    (outside / "good.yaml").write_text(ROS_YAML)
    (d / "link_out.yaml").symlink_to(outside / "good.yaml")
    (d / "link_zero").symlink_to("/dev/zero")


HOSTILE = ["bomb.yaml", "matrix_bomb.yaml", "bomb.xml", "secret.yaml", "secret_model.yaml", "secret.xml",
           "passwd.yaml", "garbage.bin", "utf16.yaml", "latin1.yaml", "huge.bin", "fifo", "link_zero",
           "/dev/zero", "/dev/urandom", "/proc/self/environ", "."]


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    d = tmp_path_factory.mktemp("hostile") / "scenario"
    d.mkdir()
    write_files(d)
    return d


def scenario_toml(camera: str) -> str:
    return textwrap.dedent(f"""\
        name = "hostile"
        [object]
        points = [[-0.1, -0.1, 1.0], [0.1, -0.1, 1.1], [0.1, 0.1, 1.0], [-0.1, 0.1, 1.2],
                  [0.0, 0.0, 1.3], [0.05, -0.05, 0.9]]
        [reference_camera]
        fku = 800.0
        fkv = 800.0
        u0 = 320.0
        v0 = 240.0
        [camera]
        {camera}
        [start]
        position = [0.02, 0.0, -0.05]
        """)


# ---------------------------------------------------------------------------------------------
# load_calibration, URDF, scenario TOML, PNG, CSV through the Python API


def test_calibration_files(folder: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("VSINV_TEST_SECRET", MARKER)  # /proc/self/environ of the subprocess holds it
    cases = {f: f"vsinv.calibration.load_calibration({f!r})" for f in HOSTILE}
    check(run_cases(cases, folder))


def test_image_and_csv_files(folder: Path) -> None:
    (folder / "bomb.png").write_bytes(_png_header(1 << 30, 1 << 30))
    cases = {f"png {f}": f"vsinv.vision.load_image({f!r})" for f in HOSTILE + ["bomb.png"]}
    cases.update({f"csv {f}": f"import vsinv.images; vsinv.images.read_points({f!r})" for f in HOSTILE})
    check(run_cases(cases, folder))


def test_urdf_and_scenario_files(folder: Path) -> None:
    base = "import json; d = vsinv.load_scenario('arm-ur5-12-6').to_dict(); d['robot']['end_effector'] = 'tool0'\n"
    cases = {}
    for f in HOSTILE + ["../outside/good.yaml", "link_out.yaml", "/etc/passwd"]:
        cases[f"urdf {f}"] = base + f"d['robot']['urdf'] = {f!r}; vsinv.load_scenario(d)"
        cases[f"urdf allowed {f}"] = base + f"d['robot']['urdf'] = {f!r}; vsinv.load_scenario(d, allow_outside_files=True)"
        cases[f"toml {f}"] = f"vsinv.load_scenario({f!r})"
    check(run_cases(cases, folder))


def test_scenario_calibration_files(folder: Path) -> None:
    names = HOSTILE + ["../outside/good.yaml", "link_out.yaml", "/etc/passwd", os.fspath(folder.parent / "outside/good.yaml")]
    numbers = "fku = 800.0\nfkv = 800.0\nu0 = 320.0\nv0 = 240.0"
    (folder / "numbers.toml").write_text(scenario_toml(numbers))
    cases = {}
    for i, f in enumerate(names):
        toml = folder / f"cal{i}.toml"
        toml.write_text(scenario_toml(f"calibration = {json.dumps(f)}"))
        cases[f"file {f}"] = f"vsinv.load_scenario({os.fspath(toml)!r})"
        cases[f"run {f}"] = f"vsinv.run_scenario({os.fspath(toml)!r})"
        as_dict = f"d = vsinv.load_scenario({os.fspath(folder / 'numbers.toml')!r}).to_dict()\n"
        cases[f"dict {f}"] = as_dict + f"d['camera'] = {{'calibration': {f!r}}}; vsinv.load_scenario(d)"
    check(run_cases(cases, folder))


def test_outside_files_need_the_opt_in(folder: Path) -> None:
    """The same good file: refused out of the folder, read with allow_outside_files=True."""
    outside = folder.parent / "outside" / "good.yaml"
    cases = {}
    for name, path in [("dotdot", "../outside/good.yaml"), ("link", "link_out.yaml"), ("absolute", os.fspath(outside))]:
        toml = folder / f"out_{name}.toml"
        toml.write_text(scenario_toml(f"calibration = {json.dumps(path)}"))
        cases[name] = f"vsinv.load_scenario({os.fspath(toml)!r})"
        cases[f"{name} allowed"] = f"vsinv.load_scenario({os.fspath(toml)!r}, allow_outside_files=True)"
        cases[f"{name} run allowed"] = f"vsinv.run_scenario({os.fspath(toml)!r}, record=False, allow_outside_files=True)"
    out = run_cases(cases, folder)
    for name, row in out.items():
        if name.endswith("allowed"):
            assert row["kind"] == "returned", (name, row)
        else:
            assert row["kind"] == "InvalidInput" and "allow_outside_files" in row["message"], (name, row)
    inside = folder / "in.toml"
    inside.write_text(scenario_toml('calibration = "good.yaml"'))
    check_inside = run_cases({"inside": f"vsinv.load_scenario({os.fspath(inside)!r})"}, folder)
    assert check_inside["inside"]["kind"] == "returned", check_inside


def _png_header(width: int, height: int) -> bytes:
    """A PNG whose IHDR declares width x height (a decompression bomb's header)."""
    import struct
    import zlib

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\0" * 1024)) + chunk(b"IEND", b"")


# ---------------------------------------------------------------------------------------------
# The CLI


# Each command runs in the limited subprocess through the CLI's entry point; its exit code and
# stderr come back as the case's message.
CLI_CASE = """
import contextlib, io
from vsinv.cli import main
err, out = io.StringIO(), io.StringIO()
with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
    rc = main({args!r})
raise SystemExit(f"exit {{rc}}\\n" + err.getvalue() + out.getvalue())
"""


def check_cli(outcomes: dict[str, dict[str, Any]], named: dict[str, str]) -> None:
    for name, row in outcomes.items():
        message = row["message"]
        assert row["kind"] == "SystemExit" and message.startswith("exit 2\n"), (name, message[:1000])
        assert "vsinv: error:" in message and "Traceback" not in message, (name, message[:1000])
        assert MARKER not in message, (name, message[:1000])
        assert named[name] in message, (name, message[:1000])
        assert row["s"] < 5.0, f"{name}: {row['s']:.1f} s (hang bound 5 s)"


def test_cli_run(folder: Path) -> None:
    """`vsinv run file.toml` with a hostile calibration, with and without the opt-in flag."""
    cases, named = {}, {}
    for i, calibration in enumerate(["bomb.yaml", "/etc/passwd", "fifo", "link_zero", "passwd.yaml", "garbage.bin"]):
        toml = folder / f"cli{i}.toml"
        toml.write_text(scenario_toml(f"calibration = {json.dumps(calibration)}"))
        for extra in ([], ["--allow-outside-files"]):
            name = f"{calibration} {extra}"
            cases[name] = CLI_CASE.format(args=["run", os.fspath(toml), "--no-progress", *extra])
            named[name] = "camera.calibration"
    check_cli(run_cases(cases, folder), named)


def test_cli_invariance_points(folder: Path) -> None:
    """`vsinv invariance ... --points CSV` with a hostile CSV: the error names the file."""
    import numpy as np

    import vsinv

    ref = folder / "ref.png"
    vsinv.vision.save_image(np.zeros((32, 32), dtype=np.uint8), ref)
    cases, named = {}, {}
    for points in ["garbage.bin", "utf16.yaml", "latin1.yaml", "fifo", "/dev/zero", "huge.bin", "."]:
        cases[points] = CLI_CASE.format(args=["invariance", os.fspath(ref), os.fspath(ref), "--points", points])
        named[points] = points
    outcomes = run_cases(cases, folder)
    check_cli(outcomes, named)
    for name, row in outcomes.items():
        assert "codec can't decode" not in row["message"], (name, row["message"])


# ---------------------------------------------------------------------------------------------
# Regressions of the smaller items (issue 16)


def test_image_size_is_optional(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import vsinv

    no_size = ROS_YAML.replace("image_width: 640\nimage_height: 480\n", "")
    (tmp_path / "nosize.yaml").write_text(no_size)
    cal = vsinv.calibration.load_calibration(tmp_path / "nosize.yaml")
    assert cal.image_size is None and cal.intrinsics.fku == 800.0
    assert vsinv.calibration.load_calibration(_write(tmp_path, ROS_YAML)).image_size == (640, 480)
    # A camera that needs the size says so by key.
    monkeypatch.chdir(tmp_path)
    d = vsinv.load_scenario("vision-12-6").to_dict()
    d["camera"] = {"calibration": "nosize.yaml"}
    with pytest.raises(vsinv.InvalidInput, match=r"camera\.calibration: the file has no image_width"):
        vsinv.load_scenario(d)
    d["camera"] = {"calibration": "ros.yaml"}
    vsinv.load_scenario(d)  # with the size: accepted


def _write(folder: Path, text: str) -> Path:
    path = folder / "ros.yaml"
    path.write_text(text)
    return path


def test_outputs_do_not_follow_planted_links(tmp_path: Path) -> None:
    """`--out` wrote trajectory.npz through a symbolic link planted at its name."""
    from vsinv.cli import main

    target = tmp_path / "victim.txt"
    target.write_text("keep")
    out = tmp_path / "out"
    out.mkdir()
    (out / "trajectory.npz").symlink_to(target)
    (out / "translation.png").symlink_to(target)
    assert main(["run", "lens-12-6", "--out", os.fspath(out), "--no-progress"]) == 0
    assert target.read_text() == "keep"
    assert not (out / "trajectory.npz").is_symlink() and (out / "trajectory.npz").stat().st_size > 0
    assert sorted(p.name for p in out.iterdir() if p.name.startswith(".")) == []  # no temporary left


# ---------------------------------------------------------------------------------------------
# Deep nesting (issue 28, finding 2): a 140 KB URDF of 20,000 nested elements killed
# `load_scenario` and `vsinv run` (stack overflow, exit 139); 200,000 levels ran past 30 s.


def nested_urdf(levels: int) -> str:
    return (f'<?xml version="1.0"?>\n<robot name="r"><link name="base">{"<x>" * levels}{MARKER}'
            f'{"</x>" * levels}</link></robot>\n')


def test_deeply_nested_urdf(folder: Path) -> None:
    files = {"deep20k.urdf": nested_urdf(20_000), "deep200k.urdf": nested_urdf(200_000),
             "deep65.urdf": nested_urdf(65),
             "wide.urdf": '<robot name="r"><link name="base"/>' + "<x/>" * 250_000 + f"<{MARKER}/></robot>"}
    for name, text in files.items():
        (folder / name).write_text(text)
    assert len(files["deep20k.urdf"]) < 150_000
    base = "d = vsinv.load_scenario('arm-ur5-12-6').to_dict(); d['robot']['end_effector'] = 'tool0'\n"
    cases = {f"dict {f}": base + f"d['robot']['urdf'] = {f!r}; vsinv.load_scenario(d)" for f in files}
    outcomes = run_cases(cases, folder)
    check(outcomes)
    for f in files:
        message = outcomes[f"dict {f}"]["message"]
        assert f in message and "the limit of a URDF's" in message, message
    # The CLI: `vsinv run` of a scenario file naming the URDF.
    import vsinv

    text = vsinv.load_scenario("arm-ur5-12-6").to_toml()
    assert 'urdf = "ur5"' in text
    cli_cases, named = {}, {}
    for f in files:
        toml = folder / f"arm_{f}.toml"
        toml.write_text(text.replace('urdf = "ur5"', f"urdf = {json.dumps(f)}"))
        cli_cases[f] = CLI_CASE.format(args=["run", os.fspath(toml), "--no-progress"])
        named[f] = f
    check_cli(run_cases(cli_cases, folder), named)
