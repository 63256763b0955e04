"""Scenario-file mutation fuzzer: every key of a built-in scenario deleted, given the wrong
type, or given NaN, infinities, zero, negative and huge values, one mutation at a time.

The only outcomes allowed for ``vsinv.run_scenario`` (and for ``Scenario.from_toml`` of the
mutated file) are

- a result whose status is one of the documented statuses and whose pose errors are finite, or
- ``vsinv.InvalidInput`` (a ``ValueError`` of the package's own hierarchy) whose message names
  the mutated key (its dotted path, or its parent's path and its own name);

never another exception, a crash (the fuzzer runs in a subprocess in the tests), a run
longer than ``TIMEOUT_S`` seconds, or a non-finite result without an exception.

Usage::

    python tests/scenario_fuzz.py [--quick] [--scenario NAME ...]

``--quick`` (the CI part) fuzzes a few built-ins covering every table; without it every
built-in is fuzzed (``make fuzz``). Prints the counts per scenario and every failure; exit
code 1 on any failure.
"""

from __future__ import annotations

import argparse
import copy
import math
import os
import re
import signal
import sys
import time
from collections import Counter
from typing import Any, Iterator

import vsinv

STATUSES = {"converged", "max_iterations", "lost_features", "diverged", "degenerate", "rz_trap", "observed", "joint_limit", "singular", "settled"}
TIMEOUT_S = 30
QUICK = ["lens-12-6", "lens-12-6-barrel", "cartesian-12-6", "occlusion", "zoom-servo", "path-500", "vision-12-6"]
# Runs through images are slow: a few iterations are enough to exercise every key.
SHORT_RUNS = {"vision-12-6": 15, "vision-12-12": 15, "vision-25-12": 15, "path-3000": 400}

Path = tuple[Any, ...]
MISSING = object()
TRACE = bool(os.environ.get("VSINV_FUZZ_TRACE"))


def leaves(node: Any, path: Path = ()) -> Iterator[tuple[Path, Any]]:
    """Every key and every first list element, depth first (a list's first element stands
    for its siblings)."""
    if path:
        yield path, node
    if isinstance(node, dict):
        for k, v in node.items():
            yield from leaves(v, (*path, k))
    elif isinstance(node, list) and node:
        yield from leaves(node[0], (*path, 0))


def replacements(value: Any) -> list[Any]:
    """The values tried in place of ``value`` (MISSING: the key deleted)."""
    if isinstance(value, bool):
        return [MISSING, 1.0, "yes", None]
    if isinstance(value, (int, float)):
        return [MISSING, math.nan, math.inf, -math.inf, 0, -1, -1e300, 1e300, 10**12, "x", [1.0], {}, True]
    if isinstance(value, str):
        return [MISSING, "bogus", 1.0, [], ""]
    if isinstance(value, list):
        return [MISSING, [], [[]], "x", 1.0, [math.nan] * max(len(value), 1)]
    if isinstance(value, dict):
        return [MISSING, "x", [], {"bogus": 1}]
    return [MISSING]


def mutated(base: dict[str, Any], path: Path, new: Any) -> dict[str, Any]:
    d = copy.deepcopy(base)
    node = d
    for k in path[:-1]:
        node = node[k]
    if new is MISSING:
        if isinstance(node, list):
            del node[path[-1]]
        else:
            del node[path[-1]]
    else:
        node[path[-1]] = new
    return d


def dotted(path: Path) -> str:
    out = ""
    for k in path:
        out += f"[{k}]" if isinstance(k, int) else (f".{k}" if out else str(k))
    return out


def names_the_key(message: str, path: Path) -> bool:
    """The message names the key (its dotted path) or, for a value that is valid alone but
    not with the rest (a camera that does not see the object), the key's table."""
    keys = [k for k in path if isinstance(k, str)]
    return dotted(path) in message or ".".join(keys) in message or re.search(rf"\b{keys[0]}\b", message) is not None


class Timeout(Exception):
    pass


def on_alarm(signum: int, frame: Any) -> None:
    raise Timeout()


def outcome(d: dict[str, Any], path: Path) -> tuple[str, str]:
    """('ok' | 'invalid' | 'FAIL', detail) for one mutated scenario."""
    signal.alarm(TIMEOUT_S)
    try:
        result = vsinv.run_scenario(d, record=False)
    except vsinv.InvalidInput as e:
        message = str(e)
        if not isinstance(e, ValueError) or not names_the_key(message, path):
            return "FAIL", f"InvalidInput without the key {dotted(path)!r}: {message}"
        return "invalid", message
    except Timeout:
        return "FAIL", f"longer than {TIMEOUT_S} s"
    except BaseException as e:  # PanicException is a BaseException
        return "FAIL", f"{type(e).__module__}.{type(e).__name__}: {e}"
    finally:
        signal.alarm(0)
    s = result.summary
    if s["status"] not in STATUSES:
        return "FAIL", f"unknown status {s['status']!r}"
    finite = all(math.isfinite(s[k]) for k in ("final_translation_error", "final_rotation_error"))
    if not finite:
        return "FAIL", f"non-finite pose error with status {s['status']}"
    if s["status"] == "converged" and not all(math.isfinite(s[k]) for k in ("final_invariant_error", "final_image_error")):
        return "FAIL", "converged with a non-finite error"
    return "ok", s["status"]


def fuzz(name: str, failures: list[str]) -> Counter[str]:
    base = vsinv.load_scenario(name).to_dict()
    if name in SHORT_RUNS:
        base["stop"]["max_iterations"] = SHORT_RUNS[name]
    counts: Counter[str] = Counter()
    for path, value in list(leaves(base)):
        if path == ("name",) or path[0] == "description":
            continue
        for new in replacements(value):
            if TRACE:
                print(f"  {name}: {dotted(path)} = {'<deleted>' if new is MISSING else repr(new)}", file=sys.stderr, flush=True)
            kind, detail = outcome(mutated(base, path, new), path)
            counts[kind] += 1
            if kind == "FAIL":
                shown = "<deleted>" if new is MISSING else repr(new)
                failures.append(f"{name}: {dotted(path)} = {shown}: {detail}")
    return counts


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="the CI subset: " + ", ".join(QUICK))
    parser.add_argument("--scenario", action="append", default=[], help="fuzz this built-in (repeatable)")
    args = parser.parse_args()
    signal.signal(signal.SIGALRM, on_alarm)
    # The mujoco-* built-ins (`[world] engine = "mujoco"`) are left out by default: each mutated
    # run renders hundreds of MuJoCo frames (6-30 s) and needs the mujoco extra; their keys other
    # than [world] are those of the kinematic built-ins fuzzed here. --scenario NAME fuzzes one.
    names = args.scenario or (QUICK if args.quick else [
        n for n, _ in vsinv.sim.list_scenarios() if vsinv.load_scenario(n).engine == "kinematic"])
    failures: list[str] = []
    total: Counter[str] = Counter()
    start = time.perf_counter()
    for name in names:
        counts = fuzz(name, failures)
        total += counts
        print(f"{name:<22} {sum(counts.values()):5d} mutations: {counts['ok']:4d} ran, "
              f"{counts['invalid']:4d} InvalidInput naming the key, {counts['FAIL']:3d} failures", flush=True)
    print(f"total {sum(total.values())} mutations in {time.perf_counter() - start:.1f} s: {total['ok']} ran, "
          f"{total['invalid']} InvalidInput, {total['FAIL']} failures")
    for f in failures:
        print("FAIL", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
