"""Installs a built wheel in a fresh virtual environment and runs the main job from it.

Usage: python tests/wheel_smoke.py WHEEL_DIR [PYTHON ...]

For every interpreter given (default: the one running this script) it makes a new virtual
environment without the system's site-packages, installs the one wheel of WHEEL_DIR with its
dependencies from the package index (no editable install), and, from a working directory outside
the source tree (so `python/vsinv` cannot shadow the installed package), runs what `make run`
runs: `vsinv run lens-12-6` (converges, exit 0) and `vsinv run ibvs-12-6` (IBVS does not converge
on a lens change, exit 1). It also checks the sdist of WHEEL_DIR holds what a source build needs.
Exits non-zero on the first failure.
"""

from __future__ import annotations

import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

# What `make run` runs, with the exit code each gives (see the Makefile's `run` target).
MAIN_JOB = [("lens-12-6", 0), ("ibvs-12-6", 1)]
# Files an sdist must hold for `pip install vsinv-*.tar.gz` to compile (relative to its root).
SDIST_NEEDS = ["pyproject.toml", "Cargo.toml", "Cargo.lock", "src/lib.rs", "python/vsinv/__init__.py",
               "scenarios/lens-12-6.toml", "README.md", "LICENSE-MIT", "LICENSE-APACHE"]


def run(cmd: list[str], cwd: Path, expect: int = 0) -> str:
    done = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    if done.returncode != expect:
        sys.exit(f"{' '.join(cmd)}: exit {done.returncode}, expected {expect}\n{done.stdout}\n{done.stderr}")
    return done.stdout


def check_wheel(wheel: Path, python: str) -> None:
    start = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="vsinv-wheel-") as tmp:
        work = Path(tmp)
        venv = work / "venv"
        run([python, "-m", "venv", str(venv)], work)
        bin_dir = venv / "bin"
        run([str(bin_dir / "python"), "-m", "pip", "install", "-q", str(wheel)], work)
        where = run([str(bin_dir / "python"), "-c", "import sys, vsinv; print(vsinv.__file__, sys.version.split()[0])"], work)
        if not where.startswith(str(venv)):
            sys.exit(f"vsinv imported from outside the fresh environment: {where}")
        for scenario, code in MAIN_JOB:
            run([str(bin_dir / "vsinv"), "run", scenario, "--out", str(work / "results" / scenario)], work, code)
        print(f"{wheel.name} on Python {where.split()[-1]}: installed and ran {', '.join(s for s, _ in MAIN_JOB)} "
              f"in {time.monotonic() - start:.0f} s")


def check_sdist(sdist: Path) -> None:
    with tarfile.open(sdist) as tar:
        names = {n.split("/", 1)[1] for n in tar.getnames() if "/" in n}
    missing = [n for n in SDIST_NEEDS if n not in names]
    if missing:
        sys.exit(f"{sdist.name} lacks {missing}")
    print(f"{sdist.name}: {len(names)} files, holds {', '.join(SDIST_NEEDS)}")


def main() -> None:
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = Path(sys.argv[1]).resolve()
    wheels = sorted(out.glob("vsinv-*.whl"))
    if len(wheels) != 1:
        sys.exit(f"expected one wheel in {out}, found {[w.name for w in wheels]}")
    for sdist in sorted(out.glob("vsinv-*.tar.gz")):
        check_sdist(sdist)
    for python in sys.argv[2:] or [sys.executable]:
        check_wheel(wheels[0], python)


if __name__ == "__main__":
    main()
