"""Command-line interface: ``vsinv list``, ``vsinv run NAME|FILE [--json] [--out DIR]``,
``vsinv sweep NAME|FILE --vary KEY=START:STOP:COUNT [...] [--out DIR]``,
``vsinv render NAME|FILE --out DIR``, ``vsinv invariance REF.png IMG.png ... --points CSV``
(the image commands, in :mod:`vsinv.cli_images`) and ``vsinv replay REF FRAMES --target dots``
(:mod:`vsinv.cli_replay`).

Exit codes: ``vsinv run`` returns 0 when the run's status is ``converged`` and 1 for every
other status (``max_iterations``, ``lost_features``, ``diverged``, ``degenerate``, ``rz_trap``,
``observed``, ``joint_limit``, ``singular``, ``settled``), which it reports; ``sweep`` and ``render``
return 0 when they finish (a sweep's statuses are in its table); ``invariance`` returns 0 when
every dot was found in every image and 1 when a measurement is missing, and so does ``replay``
(1 when a point was not found in some frame); every command
returns 2 for bad input (unknown scenario, invalid scenario file, bad --vary/--random,
unwritable output directory) and 130 on Ctrl-C.
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

import numpy as np

from . import VsinvError, __version__, load_scenario, run_scenario
from .sim import list_scenarios
from .cli_images import add_allow_outside_files, add_image_commands, cmd_invariance, cmd_render
from .cli_replay import add_replay_command, cmd_replay

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


def _mm(s: dict[str, Any], key: str, spec: str = ".4g") -> str:
    """A summary length (metres) in millimetres."""
    v = s.get(key)
    return _fmt(v * 1e3 if isinstance(v, (int, float)) else v, spec, " mm")


def _deg(s: dict[str, Any], key: str, spec: str = ".4g") -> str:
    """A summary angle (radians) in degrees."""
    v = s.get(key)
    return _fmt(math.degrees(v) if isinstance(v, (int, float)) and math.isfinite(v) else v, spec, " deg")


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
            f"{_mm(s, 'final_translation_error')} translation, "
            f"{_deg(s, 'final_rotation_error')} rotation",
        ),
        (
            "final image error",
            f"{_fmt(s.get('final_image_error'), '.4g', ' px')} (largest distance to p*), "
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
            f"{_mm(s, 'start_translation_error')}, "
            f"{_deg(s, 'start_rotation_error')}",
        ),
        ("basis", _fmt_basis(s.get("basis"))),
        ("line deviation", f"{_mm(s, 'max_line_deviation')} (largest, camera centre path)"),
    ]
    if s.get("path_duration") is not None:
        rows += [
            (
                "path (sec. 3)",
                f"T = {_fmt(s.get('path_duration'), '.4g', ' s')}, plane + parallax residual "
                f"{_fmt(s.get('plane_parallax_residual'), '.2e')}",
            ),
            (
                "Prop. 3",
                f"max ||eps|| {_fmt(s.get('observed_max_eps'), '.4g')} {_compare(s.get('observed_max_eps'), s.get('tracking_bound'))} psi/phi "
                f"{_fmt(s.get('tracking_bound'), '.4g')} (sigma {_fmt(s.get('tracking_sigma'), '.4g')}, "
                f"psi {_fmt(s.get('tracking_psi'), '.4g')}, phi {_fmt(s.get('tracking_phi'), '.4g')})",
            ),
        ]
    if s.get("min_manipulability") is not None:
        rows.append(("arm", f"smallest manipulability {_fmt(s.get('min_manipulability'), '.4g')}"))
    rows.append(("pose uncertainty", _uncertainty(s)))
    rows.append(("message", str(s.get("message", ""))))
    width = max(len(k) for k, _ in rows)
    lines = [f"scenario {s.get('name', '?')}"]
    lines += [f"  {k:<{width}}  {v}" for k, v in rows]
    return "\n".join(lines)


def _compare(a: Any, b: Any) -> str:
    """The comparison that holds between two numbers (``vs`` when either is missing)."""
    if not all(isinstance(x, (int, float)) and math.isfinite(x) for x in (a, b)):
        return "vs"
    return "<=" if a <= b else ">"


def _uncertainty(s: dict[str, Any]) -> str:
    """What the final images allow about the pose, and the ground truth against the tolerance."""
    truth = "final pose within the tolerance" if s.get("within_tolerance") else "final pose NOT within the tolerance"
    if s.get("translation_uncertainty") is None:
        return f"not measured (too few points in view or too few images); {truth} (ground truth)"
    return (
        f"{_mm(s, 'translation_uncertainty', '.3g')}, {_deg(s, 'rotation_uncertainty', '.3g')} "
        f"(3 sigma + offset; pixel noise {_fmt(s.get('pixel_sigma'), '.3g', ' px')} measured, reference "
        f"{_fmt(s.get('reference_pixel_sigma'), '.3g', ' px')}); {truth} (ground truth)"
    )


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
        description="Run a built-in scenario or a scenario TOML file and print its summary. Scenario angles "
        "are degrees, in keys that say so (rotation_deg, skew_deg, max_angular_speed_deg; the older key "
        "rotation is read as degrees).",
    )
    run.add_argument("scenario", metavar="NAME|FILE", help="a built-in scenario name (see `vsinv list`) or a TOML file")
    run.add_argument("--json", action="store_true", help="print the summary as one JSON object (NaN as null)")
    run.add_argument("--out", metavar="DIR", type=Path, help="write trajectory.npz and the figures (PNG) to DIR")
    run.add_argument(
        "--record",
        metavar="FILE",
        type=Path,
        help="write a recording to FILE (MCAP: images with detections, poses, twist, errors, verdict per "
        "iteration; opens in Foxglove; needs the record extra: pip install 'vsinv[record]')",
    )
    run.add_argument("--no-progress", action="store_true", help="do not show a progress bar")
    add_allow_outside_files(run)

    sw = sub.add_parser(
        "sweep",
        help="run a scenario over a grid / random draws of parameters",
        description="Run a scenario for every combination of the varied parameters (vsinv.sim.run_sweep) and print the "
        "convergence rate and median final errors per grid point. Keys: any dotted scenario key "
        "(noise.pixel_sigma, control.gain, start.position.2, ...) or a derived key: "
        "focal_error, principal_point_error, roll_deg, lens_ratio.",
    )
    sw.add_argument("scenario", metavar="NAME|FILE", help="a built-in scenario name (see `vsinv list`) or a TOML file")
    sw.add_argument(
        "--vary",
        metavar="KEY=START:STOP:COUNT",
        action="append",
        default=[],
        help="a grid axis: COUNT values from START to STOP (linspace), or KEY=V1,V2,... (repeatable)",
    )
    sw.add_argument(
        "--random",
        metavar="KEY=LO:HI[:log]",
        action="append",
        default=[],
        help="a random key, uniform on [LO, HI) (log-uniform with :log), sampled --draws times (repeatable)",
    )
    sw.add_argument("--draws", metavar="N", type=int, help="random samples when --random is given (default 100)")
    sw.add_argument("--repeats", metavar="N", type=int, default=1, help="runs per point, each with its own noise seed")
    sw.add_argument("--seed", metavar="S", type=int, default=0, help="seed of the draws and the noise seeds (default 0)")
    sw.add_argument(
        "--workers", metavar="N", type=int, default=1, help="worker processes (ProcessPoolExecutor when > 1)"
    )
    sw.add_argument("--out", metavar="DIR", type=Path, help="write sweep.parquet (or sweep.csv) and stability_map.png")
    sw.add_argument("--no-progress", action="store_true", help="do not show a progress bar")
    add_allow_outside_files(sw)
    add_image_commands(sub)
    add_replay_command(sub)
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

    scenario = load_scenario(args.scenario, allow_outside_files=args.allow_outside_files)
    out_dir: Optional[Path] = args.out
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)  # fail before a long run, not after

    progress: Optional[_Progress] = None
    if not args.no_progress and sys.stderr.isatty():
        stop = scenario.to_dict().get("stop") or {}
        progress = _Progress(int(stop.get("max_iterations") or 0), scenario.name)
    callback: Optional[Callable[[int, int], object]] = progress
    try:
        result = run_scenario(scenario, record=out_dir is not None or args.record is not None, progress=callback)
    finally:
        if progress is not None:
            progress.close()
    summary = result.summary

    written: list[Path] = []
    if out_dir is not None:
        written.append(save_npz(result, out_dir / "trajectory.npz"))
        written.extend(save_figures(result, out_dir))
        if result.detection_error is not None:
            from .view_plots import save_view_figures

            written.extend(save_view_figures(result, out_dir))
    if args.record is not None:
        from .recording import write_recording

        write_recording(result, args.record)
        written.append(args.record)

    if args.json:
        print(summary_json(summary))
    else:
        print(format_summary(summary))
    if written:
        listing = sys.stderr if args.json else sys.stdout
        print(f"wrote {len(written)} files" + (f" to {out_dir}:" if out_dir is not None else ":"), file=listing)
        for path in written:
            print(f"  {path}", file=listing)
    return 0 if summary.get("status") == "converged" else 1


class UsageError(ValueError):
    """A bad command-line value (exit code 2)."""


def _parse_scalar(text: str) -> Any:
    t = text.strip()
    low = t.lower()
    if low in ("true", "false"):
        return low == "true"
    for conv in (int, float):
        try:
            return conv(t)
        except ValueError:
            pass
    return t


def _parse_number(text: str, what: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise UsageError(f"{what}: {text!r} is not a number") from None
    if not math.isfinite(v):
        raise UsageError(f"{what}: {text!r} is not a finite number")
    return v


def _split_assignment(text: str, option: str, form: str) -> tuple[str, str]:
    key, sep, spec = text.partition("=")
    if not sep or not key.strip() or not spec.strip():
        raise UsageError(f"{option} {text!r}: expected {form}")
    return key.strip(), spec.strip()


def parse_vary(text: str) -> tuple[str, list[Any]]:
    """``KEY=START:STOP:COUNT`` (COUNT values, like numpy.linspace; integers when START, STOP
    and the step are integers) or ``KEY=V1,V2,...``."""
    form = "KEY=START:STOP:COUNT or KEY=V1,V2,..."
    key, spec = _split_assignment(text, "--vary", form)
    if ":" in spec:
        parts = spec.split(":")
        if len(parts) != 3:
            raise UsageError(f"--vary {text!r}: expected {form}")
        start = _parse_number(parts[0], f"--vary {key} START")
        stop = _parse_number(parts[1], f"--vary {key} STOP")
        try:
            count = int(parts[2])
        except ValueError:
            raise UsageError(f"--vary {text!r}: COUNT {parts[2]!r} is not an integer") from None
        if count < 1:
            raise UsageError(f"--vary {text!r}: COUNT must be >= 1")
        if count == 1:
            values: list[Any] = [start]
        else:
            values = [float(v) for v in np.linspace(start, stop, count)]
        is_int = [re.fullmatch(r"[+-]?\d+", p.strip()) is not None for p in parts[:2]]
        if all(is_int) and all(float(v).is_integer() for v in values):
            values = [int(v) for v in values]
        return key, values
    values = [_parse_scalar(v) for v in spec.split(",") if v.strip()]
    if not values:
        raise UsageError(f"--vary {text!r}: expected {form}")
    return key, values


def parse_random(text: str) -> tuple[str, Any]:
    """``KEY=LO:HI`` (uniform) or ``KEY=LO:HI:log`` (log-uniform)."""
    from .sweep import LogUniform, Uniform

    form = "KEY=LO:HI or KEY=LO:HI:log"
    key, spec = _split_assignment(text, "--random", form)
    parts = spec.split(":")
    if len(parts) not in (2, 3) or (len(parts) == 3 and parts[2].strip().lower() != "log"):
        raise UsageError(f"--random {text!r}: expected {form}")
    lo = _parse_number(parts[0], f"--random {key} LO")
    hi = _parse_number(parts[1], f"--random {key} HI")
    try:
        return key, (LogUniform(lo, hi) if len(parts) == 3 else Uniform(lo, hi))
    except ValueError as exc:
        raise UsageError(f"--random {text!r}: {exc}") from None


def format_sweep_table(result: Any, keys: Sequence[str], bins: Optional[int] = None) -> str:
    """Per group of ``keys``: runs, converged %, median final errors, Prop. 1/2 %."""
    s = result.summary_by(list(keys), bins=bins)
    head = [*keys, "runs", "converged", "median err (mm)", "median err (deg)", "Prop. 1", "Prop. 2"]
    rows = []
    for i in range(len(s["runs"])):
        rows.append(
            [
                *(_fmt(_native_value(s[k][i]), ".6g") for k in keys),
                str(int(s["runs"][i])),
                f"{100 * float(s['convergence_rate'][i]):.0f}%",
                _fmt(1e3 * float(s["median_translation_error"][i]), ".3g"),
                _fmt(math.degrees(float(s["median_rotation_error"][i])), ".3g"),
                f"{100 * float(s['prop1_rate'][i]):.0f}%",
                f"{100 * float(s['prop2_rate'][i]):.0f}%",
            ]
        )
    widths = [max(len(h), *(len(r[j]) for r in rows)) if rows else len(h) for j, h in enumerate(head)]
    nk = len(keys)
    lines = ["  ".join(h.ljust(w) if j < nk else h.rjust(w) for j, (h, w) in enumerate(zip(head, widths)))]
    for r in rows:
        lines.append("  ".join(c.ljust(w) if j < nk else c.rjust(w) for j, (c, w) in enumerate(zip(r, widths))))
    return "\n".join(lines)


def _native_value(v: Any) -> Any:
    return v.item() if isinstance(v, np.generic) else v


def _cmd_sweep(args: argparse.Namespace) -> int:
    import os

    from .sweep import run_sweep

    vary: dict[str, Any] = {}
    for text in args.vary:
        key, values = parse_vary(text)
        if key in vary:
            raise UsageError(f"--vary {key}: given twice")
        vary[key] = values
    for text in args.random:
        key, dist = parse_random(text)
        if key in vary:
            raise UsageError(f"--random {key}: given twice")
        vary[key] = dist
    if not vary:
        raise UsageError("sweep: give at least one --vary or --random")
    randoms = [k for k in vary if not isinstance(vary[k], list)]
    draws = args.draws
    if randoms and draws is None:
        draws = 100
    if draws is not None and not randoms:
        raise UsageError("--draws: needs a --random key")
    if draws is not None and draws < 1:
        raise UsageError("--draws: must be >= 1")
    if args.repeats < 1:
        raise UsageError("--repeats: must be >= 1")
    if args.workers < 1:
        raise UsageError("--workers: must be >= 1")
    if args.seed < 0:
        raise UsageError("--seed: must be >= 0")
    out_dir: Optional[Path] = args.out
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)  # fail before a long sweep, not after

    progress = False if args.no_progress else None
    if args.workers > 1:
        import concurrent.futures
        import multiprocessing

        method = "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else "spawn"
        threads = max(1, (os.cpu_count() or 1) // args.workers)
        with concurrent.futures.ProcessPoolExecutor(args.workers, mp_context=multiprocessing.get_context(method)) as ex:
            result = run_sweep(
                args.scenario, vary, repeats=args.repeats, draws=draws, seed=args.seed,
                executor=ex, threads=threads, progress=progress, allow_outside_files=args.allow_outside_files,
            )
    else:
        result = run_sweep(
            args.scenario, vary, repeats=args.repeats, draws=draws, seed=args.seed, progress=progress,
            allow_outside_files=args.allow_outside_files,
        )

    grid = list(result.grid_keys)
    details = [f"{len(result.summary_by(grid)['runs'])} grid points"] if grid else []
    details += [f"{draws} draws"] if draws else []
    details += [f"{args.repeats} repeats"] if args.repeats > 1 else []
    print(f"sweep {result.base_name}: {len(result)} runs ({', '.join(details)}) in {result.elapsed_s:.1f} s")
    if grid:
        print(format_sweep_table(result, grid))
    else:
        print(format_sweep_table(result, list(result.random_keys), bins=10))

    if out_dir is not None:
        from .sweep.plots import plot_stability_map

        written = [result.write(out_dir / "sweep.parquet")]
        plot_keys = grid[:2] if len(grid) >= 2 else list(result.keys)[:2]
        written.append(plot_stability_map(result, out_dir / "stability_map.png", keys=plot_keys))
        print(f"wrote {len(written)} files to {out_dir}:")
        for path in written:
            print(f"  {path}")
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
        if args.command == "sweep":
            return _cmd_sweep(args)
        if args.command == "render":
            return cmd_render(args)
        if args.command == "invariance":
            return cmd_invariance(args)
        if args.command == "replay":
            return cmd_replay(args)
        return _cmd_run(args)
    except (VsinvError, ValueError, OSError) as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
