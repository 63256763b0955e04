"""Command-line interface: ``vsinv list``, ``vsinv run NAME|FILE [--json] [--out DIR]``.

Exit codes: 0 when a run ends (whatever its status, which is reported), 2 for bad input
(unknown scenario, invalid scenario file, unwritable output directory), 130 on Ctrl-C.
"""

from __future__ import annotations

import argparse
import math
import re
import shutil
import sys
import textwrap
from pathlib import Path
from typing import Any, Callable, Optional, Sequence, TextIO

from . import VsinvError, __version__, list_scenarios, load_scenario, run_scenario

__all__ = ["main"]

PROG = "vsinv"

# Abbreviations after which a full stop does not end a sentence.
_ABBREVIATIONS = ("sec", "fig", "eq", "eqs", "prop", "props", "ref", "cf", "e.g", "i.e", "vs", "approx", "no")


def first_sentence(text: str) -> str:
    """The first sentence of a description (abbreviations such as "Sec." do not end it)."""
    text = " ".join(text.split())
    for m in re.finditer(r"[.!?](?=\s+[A-Z(\"'])|[.!?]$", text):
        word = re.findall(r"[\w.]+$", text[: m.start()])
        if word and word[0].lower().rstrip(".") in _ABBREVIATIONS:
            continue
        return text[: m.end()]
    return text


def _shorten(text: str, width: int) -> str:
    return textwrap.shorten(text, width=max(width, 20), placeholder=" ...")


def _fmt(value: Any, spec: str = ".4g", unit: str = "") -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "n/a"
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return f"{value:{spec}}{unit}"
    return f"{value}{unit}"


def _verdict(value: Any) -> str:
    if value is None:
        return "n/a"
    return "holds" if value else "does NOT hold"


def format_summary(summary: dict[str, Any]) -> str:
    """A readable multi-line summary of a run."""
    s = summary
    rows = [
        ("status", f"{s.get('status', '?')} after {s.get('iterations', '?')} iterations"),
        (
            "final pose error",
            f"{_fmt(s.get('final_translation_error_mm'), '.4g', ' mm')} translation, "
            f"{_fmt(s.get('final_rotation_error_deg'), '.4g', ' deg')} rotation",
        ),
        (
            "final image error",
            f"{_fmt(s.get('final_image_error_px'), '.4g', ' px')} (largest distance to p*), "
            f"invariant error {_fmt(s.get('final_invariant_error'), '.3e')}",
        ),
        (
            "final tau",
            f"tau_11 {_fmt(s.get('final_tau_11'), '.6g')}, tau_22 {_fmt(s.get('final_tau_22'), '.6g')}, "
            f"tau_21 {_fmt(s.get('final_tau_21'), '.3e')}",
        ),
        ("stop rule", str(s.get("stop_rule", "n/a"))),
        ("stability", f"Prop. 1 {_verdict(s.get('prop1'))}, Prop. 2 {_verdict(s.get('prop2'))}"),
        (
            "start error",
            f"{_fmt(s.get('start_translation_error_mm'), '.4g', ' mm')}, "
            f"{_fmt(s.get('start_rotation_error_deg'), '.4g', ' deg')}",
        ),
        ("basis", _fmt_basis(s.get("basis"))),
        ("line deviation", f"{_fmt(s.get('max_line_deviation_mm'), '.4g', ' mm')} (largest, camera centre path)"),
    ]
    if s.get("path_duration_s") is not None:
        rows += [
            (
                "path (sec. 3)",
                f"T = {_fmt(s.get('path_duration_s'), '.4g', ' s')}, plane + parallax residual "
                f"{_fmt(s.get('plane_parallax_residual'), '.2e')}",
            ),
            (
                "Prop. 3",
                f"max ||eps|| {_fmt(s.get('observed_max_eps'), '.4g')} <= psi/phi "
                f"{_fmt(s.get('tracking_bound'), '.4g')} (sigma {_fmt(s.get('tracking_sigma'), '.4g')}, "
                f"psi {_fmt(s.get('tracking_psi'), '.4g')}, phi {_fmt(s.get('tracking_phi'), '.4g')})",
            ),
        ]
    rows.append(("message", str(s.get("message", ""))))
    width = max(len(k) for k, _ in rows)
    lines = [f"scenario {s.get('name', '?')}"]
    lines += [f"  {k:<{width}}  {v}" for k, v in rows]
    return "\n".join(lines)


def _fmt_basis(basis: Any) -> str:
    if basis is None:
        return "n/a"
    if isinstance(basis, (list, tuple)):
        return "points " + ", ".join(str(b) for b in basis)
    return str(basis)


def _build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=PROG,
        description="Visual servoing invariant to the camera's intrinsic parameters (Malis, INRIA RR-4309).",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    sub.add_parser("list", help="list the built-in scenarios", description="List the built-in scenarios.")
    run = sub.add_parser(
        "run",
        help="run a scenario and print its summary",
        description="Run a built-in scenario or a scenario TOML file and print its summary.",
    )
    run.add_argument("scenario", metavar="NAME|FILE", help="a built-in scenario name (see `vsinv list`) or a TOML file")
    run.add_argument("--json", action="store_true", help="print the summary as one JSON object (NaN as null)")
    run.add_argument("--out", metavar="DIR", type=Path, help="write trajectory.npz and the figures (PNG) to DIR")
    run.add_argument("--no-progress", action="store_true", help="do not show a progress bar")
    return parser


def _cmd_list(out: TextIO) -> int:
    scenarios = list_scenarios()
    if not scenarios:
        print("no built-in scenarios", file=out)
        return 0
    name_w = max(len("NAME"), *(len(n) for n, _ in scenarios))
    cols = shutil.get_terminal_size((100, 24)).columns
    desc_w = max(cols - name_w - 3, 40)
    print(f"{'NAME':<{name_w}}  DESCRIPTION", file=out)
    for name, description in scenarios:
        print(f"{name:<{name_w}}  {_shorten(first_sentence(description), desc_w)}", file=out)
    return 0


class _Progress:
    """A tqdm bar on stderr fed by run_scenario's progress callback."""

    def __init__(self, total: int, desc: str) -> None:
        from tqdm import tqdm  # type: ignore[import-untyped, unused-ignore]

        self.bar: Any = tqdm(total=total, desc=desc, unit="it", file=sys.stderr, leave=False, dynamic_ncols=True)

    def __call__(self, done: int, total: int) -> None:
        if total and total != self.bar.total:
            self.bar.total = total
        self.bar.update(max(done - self.bar.n, 0))

    def close(self) -> None:
        self.bar.close()


def _cmd_run(args: argparse.Namespace) -> int:
    from .plots import save_figures, save_npz, summary_json

    scenario = load_scenario(args.scenario)
    out_dir: Optional[Path] = args.out
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)  # fail before a long run, not after

    progress: Optional[_Progress] = None
    if not args.no_progress and sys.stderr.isatty():
        stop = scenario.to_dict().get("stop") or {}
        progress = _Progress(int(stop.get("max_iterations") or 0), scenario.name)
    callback: Optional[Callable[[int, int], object]] = progress
    try:
        result = run_scenario(scenario, record=out_dir is not None, progress=callback)
    finally:
        if progress is not None:
            progress.close()
    summary = result.summary

    written: list[Path] = []
    if out_dir is not None:
        written.append(save_npz(result, out_dir / "trajectory.npz"))
        written.extend(save_figures(result, out_dir))

    if args.json:
        print(summary_json(summary))
    else:
        print(format_summary(summary))
    if written:
        listing = sys.stderr if args.json else sys.stdout
        print(f"wrote {len(written)} files to {out_dir}:", file=listing)
        for path in written:
            print(f"  {path}", file=listing)
    return 0


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Entry point of the ``vsinv`` console script; returns the exit code."""
    parser = _build_parser()
    try:
        args = parser.parse_args(None if argv is None else list(argv))
    except SystemExit as exc:  # --help, --version and usage errors
        code = exc.code
        return code if isinstance(code, int) else (0 if code is None else 2)
    try:
        if args.command == "list":
            return _cmd_list(sys.stdout)
        return _cmd_run(args)
    except (VsinvError, ValueError, OSError) as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
