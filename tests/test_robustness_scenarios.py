"""Robustness of the public Python API under hypothesis, scenarios, runs (run_scenario, run_batch)
and sweeps (vsinv.sweep).

The promise and the harness are described in tests/robustness_harness.py.
"""

from __future__ import annotations

import functools
import json
import math
import os
from pathlib import Path
from typing import Any, Optional

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

import vsinv
import vsinv.plots
import vsinv.sweep
from robustness_harness import (
    ANY, INVALID, RETURN, SAME, TYPE, VISION, arrays, call, choices, covers, floats, fuzz, fuzz_settings, ints,
    mutated_text, returned, rodrigues,
)


# ---------------------------------------------------------------------------------------------
# scenarios and runs

BASE = vsinv.load_scenario("lens-12-12").to_dict()
BASE["stop"]["max_iterations"] = 4
BUILTINS = [n for n, _ in vsinv.sim.list_scenarios()]
MUTANTS = [None, math.nan, -1, 0, 1e300, -1e300, "abc", "", [], {}, True, [1.0, 2.0], {"x": 1}, 2**70]


def leaves(d: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    out = [prefix] if prefix else []
    if isinstance(d, dict):
        for k, v in d.items():
            out += leaves(v, (*prefix, k))
    elif isinstance(d, list) and len(d) <= 16:
        for i, v in enumerate(d):
            out += leaves(v, (*prefix, i))
    return out


@st.composite
def mutated_scenario(draw: Any, base: dict[str, Any], keep_stop: bool = False) -> tuple[dict[str, Any], Optional[tuple[Any, ...]]]:
    """A deep copy of ``base`` with one entry replaced or deleted (or none); with
    ``keep_stop``, [stop] is left alone (a run must stay short)."""
    d = json.loads(json.dumps(base))
    if draw(st.integers(0, 5)) == 0:
        return d, None
    path = draw(st.sampled_from([p for p in leaves(d) if not (keep_stop and p[0] == "stop")]))
    node = d
    for k in path[:-1]:
        node = node[k]
    if isinstance(node, dict) and draw(st.booleans()):
        del node[path[-1]]
    else:
        node[path[-1]] = draw(st.sampled_from(MUTANTS))
    # a run must stay short whatever was mutated
    if isinstance(d.get("stop"), dict) and isinstance(d["stop"].get("max_iterations"), int):
        d["stop"]["max_iterations"] = min(d["stop"]["max_iterations"], 4)
    if isinstance(d.get("path"), dict) and isinstance(d["path"].get("samples"), int):
        d["path"]["samples"] = min(d["path"]["samples"], 50)
    return d, path


def scenario_names(path: Optional[tuple[Any, ...]]) -> tuple[str, ...]:
    if not path:
        return ("scenario",)
    return tuple(str(p) for p in path if isinstance(p, str)) + ("scenario",)


@covers("Scenario", "Scenario.engine", "Scenario.from_dict", "Scenario.from_toml", "Scenario.name", "Scenario.description", "Scenario.to_dict",
        "Scenario.to_toml", "load_scenario", "list_scenarios")
@fuzz_settings(200)
@given(st.data())
def test_scenarios(data: Any) -> None:
    names = call(vsinv.sim.list_scenarios, _expect=RETURN)
    assert names and all(isinstance(n, str) and isinstance(t, str) for n, t in names)
    d, path = data.draw(mutated_scenario(BASE), label="mutation")
    # which names may the message give: the mutated key's segments (the last one, usually)
    s = call(vsinv.sim.Scenario.from_dict, d, _api="Scenario.from_dict", _names=scenario_names(path),
             _expect=RETURN if path is None else ANY)
    how = data.draw(st.sampled_from(["dict", "toml", "load", "file", "name"]))
    if how == "toml" and returned(s):
        text = call(s.to_toml, _api="Scenario.to_toml", _expect=RETURN)
        back = call(vsinv.sim.Scenario.from_toml, text, _api="Scenario.from_toml", _expect=RETURN)
        assert back.to_dict() == s.to_dict()
        # and mutated TOML text
        _, bad = data.draw(mutated_text(text), label="toml mutation")
        call(vsinv.sim.Scenario.from_toml, bad, _api="Scenario.from_toml", _names=("scenario",))
    elif how == "load":
        call(vsinv.load_scenario, d, _names=scenario_names(path), _expect=RETURN if path is None else ANY)
    elif how == "file":
        tmp = Path(os.environ.get("TMPDIR", "/tmp")) / f"vsinv-robustness-{os.getpid()}.toml"
        if returned(s):
            tmp.write_text(s.to_toml())
            call(vsinv.load_scenario, tmp, _expect=RETURN)
        call(vsinv.load_scenario, str(tmp) + ".missing", _expect=INVALID, _names=("missing", "scenario"))
    elif how == "name":
        n = data.draw(st.sampled_from([*BUILTINS, "nope", "", "lens-12-12 "]))
        call(vsinv.load_scenario, n, _expect=RETURN if n in BUILTINS else INVALID, _names=(repr(n)[1:-1] or "scenario", "scenario"))
    for bad, expect in ((None, INVALID), (3, INVALID), ([], INVALID), ({}, INVALID), (b"abc", INVALID)):
        call(vsinv.load_scenario, bad, _expect=expect, _names=("scenario",))
    call(vsinv.sim.Scenario.from_toml, 3, _api="Scenario.from_toml", _expect=TYPE, _names=("text",))
    call(vsinv.sim.Scenario.from_dict, "abc", _api="Scenario.from_dict", _expect=ANY, _names=("scenario",))
    if returned(s):
        assert isinstance(call(getattr, s, "name", _api="Scenario.name"), str)
        assert isinstance(call(getattr, s, "description", _api="Scenario.description"), str)
        assert call(getattr, s, "engine", _api="Scenario.engine") in ("kinematic", "mujoco")
        dd = call(s.to_dict, _api="Scenario.to_dict", _finite=False)
        again = vsinv.sim.Scenario.from_dict(dd).to_dict()
        assert again == dd, [(k, dd[k], again.get(k)) for k in dd if dd[k] != again.get(k)]


# The columns every run records, from their declaration.
RUN_ARRAYS = tuple(c["name"] for c in vsinv.sim.recorded_columns() if c["recorded"] == "always")


@covers("run_scenario", "RunResult", "RunResult.summary", "RunResult.scenario", "RunResult.arrays", "RunResult.time",
        "RunResult.pose", "RunResult.twist", "RunResult.joints", "RunResult.pixels", "RunResult.visible",
        "RunResult.invariant_error", "RunResult.tracking_error", "RunResult.eps", "RunResult.eps_z",
        "RunResult.image_error", "RunResult.translation_error", "RunResult.rotation_error", "RunResult.reference_pixels",
        "RunResult.detection_error", "RunResult.joint_velocities", "RunResult.joint_limits")
@fuzz_settings(80)
@given(st.data())
def test_run_scenario(data: Any) -> None:
    base = data.draw(st.sampled_from([BASE, BASE, VISION]), label="base")
    d, path = data.draw(mutated_scenario(base, keep_stop=True), label="mutation")
    record = data.draw(choices([True, False, np.bool_(False)], ["yes", None, 1], TYPE), label="record")
    progress_calls: list[tuple[int, int]] = []
    progress = data.draw(st.sampled_from([None, lambda i, n: progress_calls.append((i, n)), "abc"]), label="progress")
    expect = record.expect if record.expect == TYPE else ANY
    names = ("record",) if record.expect == TYPE else scenario_names(path)
    if base is VISION:  # a moved point may leave its dot undetectable: reported on [vision]
        names = (*names, "vision")
    if progress == "abc":
        expect, names = TYPE, (*names, "progress")
    r = call(vsinv.run_scenario, d, record=record.value, progress=progress, _expect=expect, _names=names, _finite=False)
    if not returned(r):
        return
    s = call(getattr, r, "summary", _api="RunResult.summary", _finite=False)
    assert s["status"] in ("converged", "max_iterations", "lost_features", "diverged", "degenerate", "rz_trap", "joint_limit",
                           "singular", "settled", "observed", "error"), s["status"]
    assert 0 <= s["iterations"] <= 4
    assert isinstance(call(getattr, r, "scenario", _api="RunResult.scenario"), vsinv.sim.Scenario)
    arrs = call(getattr, r, "arrays", _api="RunResult.arrays", _finite=False)
    rows = len(r.time)
    for name in RUN_ARRAYS:
        a = call(getattr, r, name, _api=f"RunResult.{name}", _finite=False)
        assert a is arrs[name] or np.array_equal(a, arrs[name], equal_nan=True)
        assert a.shape[:1] == (rows,) or name == "reference_pixels"
    assert np.isfinite(r.time).all() and np.isfinite(r.pose).all()
    if rows > 1:
        assert np.isfinite(r.twist[:-1]).all()
    for name in ("detection_error", "joint_velocities", "joint_limits"):
        call(getattr, r, name, _api=f"RunResult.{name}", _finite=False)
    assert (r.detection_error is None) == ("vision" not in r.scenario.to_dict() or r.scenario.to_dict().get("vision") is None)


@covers("RunResult.from_recording")
@fuzz_settings(40)
@given(st.data())
def test_run_result_from_recording(data: Any) -> None:
    """A kinematic run's summary and columns with one part replaced by a mutant: the same
    RunResult back, or InvalidInput naming the summary or arrays (never another exception)."""
    r = lens_run()
    summary, arrays = dict(r.summary), dict(r.arrays)
    part = data.draw(st.sampled_from(["summary", "arrays", "none"]), label="part")
    target = summary if part == "summary" else arrays
    key = data.draw(st.sampled_from([*target, "extra"]), label="key") if part != "none" else None
    if key is not None:
        how = data.draw(st.sampled_from(["drop", "replace"]), label="how")
        if how == "drop":
            target.pop(key, None)
        else:
            target[key] = data.draw(st.sampled_from([*MUTANTS, np.zeros((2, 2)), np.array([True])]), label="value")
    out = call(vsinv.RunResult.from_recording, r.scenario, summary, arrays, _api="RunResult.from_recording",
               _expect=ANY, _names=("summary", "arrays"), _finite=False)
    if returned(out):
        assert list(out.summary) == list(r.summary)
        assert set(out.arrays) <= set(vsinv.RunResult.from_recording(r.scenario, dict(r.summary), dict(r.arrays)).arrays)
    for bad in (None, 3, "abc"):
        call(vsinv.RunResult.from_recording, r.scenario, bad, arrays, _api="RunResult.from_recording", _expect=TYPE,
             _names=("summary",), _finite=False)


@covers("recorded_columns", "summary_fields", "RunResult.columns", "RunResult.plot")
@fuzz_settings(10)
@given(kind=st.sampled_from([*vsinv.plots.PLOTS, "nope", "", None, 3, b"errors"]),
       ax=st.sampled_from([None, "axes", "two", "three", 3]))
def test_run_result_schema_and_plot(kind: Any, ax: Any) -> None:
    vsinv.plots._use_agg()
    import matplotlib.pyplot as plt

    run = lens_run()
    columns = call(vsinv.sim.recorded_columns, _finite=False)
    assert tuple(columns) == call(getattr, vsinv.RunResult, "columns", _api="RunResult.columns", _finite=False)
    assert {f["name"] for f in call(vsinv.sim.summary_fields, _finite=False)} <= set(run.summary)
    fig, axes = plt.subplots(1, 3)
    where = {"axes": axes[0], "two": [axes[0], axes[1]], "three": list(axes)}.get(ax, ax) if isinstance(ax, str) else ax
    if not isinstance(kind, str):
        expect = TYPE
    elif kind not in vsinv.plots.PLOTS or kind in ("joints", "joint_velocities"):  # not an arm
        expect = INVALID
    else:
        expect = TYPE if ax == 3 else ANY
    try:
        out = call(run.plot, kind, ax=where, _api="RunResult.plot", _expect=expect, _names=("kind", "ax"), _finite=False)
        if returned(out) and where is None:
            plt.close(out)
    finally:
        plt.close(fig)


@functools.cache
def lens_run() -> vsinv.RunResult:
    return vsinv.run_scenario("lens-12-6")


@covers("run_batch")
@fuzz_settings(50)
@given(st.data())
def test_run_batch(data: Any) -> None:
    items = data.draw(st.lists(st.sampled_from(["base", "json", "scenario", "mutant", "bad"]), min_size=0, max_size=3), label="items")
    batch: list[Any] = []
    bad_index = None
    for i, kind in enumerate(items):
        if kind == "base":
            batch.append(BASE)
        elif kind == "json":
            batch.append(json.dumps(BASE))
        elif kind == "scenario":
            batch.append(vsinv.sim.Scenario.from_dict(BASE))
        elif kind == "mutant":
            batch.append(data.draw(mutated_scenario(BASE, keep_stop=True))[0])
        else:
            batch.append(data.draw(st.sampled_from([None, 3, "nope", b"x", [1]])))
            bad_index = i if bad_index is None else bad_index
    threads = data.draw(ints(1, overrides={"zero": INVALID, "huge": INVALID, "none": SAME}), label="threads")
    expect = threads.expect if threads.expect in (INVALID, TYPE) else (INVALID if bad_index is not None else ANY)
    names = ("threads",) if threads.expect in (INVALID, TYPE) else (f"scenario {bad_index}",) if bad_index is not None else ("scenario",)
    if threads.expect in (INVALID, TYPE) and bad_index is not None:
        names = (*names, f"scenario {bad_index}")  # either may be reported first
    counts: list[int] = []
    progress = data.draw(st.sampled_from([None, False, lambda done, total: counts.append(done)]), label="progress")
    out = call(vsinv.sim.run_batch, batch, threads=threads.value, progress=progress, _expect=expect, _names=names, _finite=False)
    if returned(out):
        assert all(len(c) == len(batch) for c in out.values())
        assert counts == sorted(set(counts)) and counts[-1:] == ([len(batch)] if callable(progress) and batch else [])
        ok = out["status"] != "error"
        for k in ("final_translation_error", "final_rotation_error"):
            assert np.isfinite(out[k][ok]).all()
    call(vsinv.sim.run_batch, 3, _expect=TYPE, _names=("scenarios", "iterable"))
    call(vsinv.sim.run_batch, [], progress="yes", _expect=TYPE, _names=("progress",))


# The sweep's table converts to pandas and writes parquet with pyarrow when they are installed:
# import them once here, so that the timed calls measure the conversion, not a first import
# (seconds on a loaded machine).
for _module in ("pandas", "pyarrow", "pyarrow.parquet"):
    try:
        __import__(_module)
    except ImportError:
        pass

# ---------------------------------------------------------------------------------------------
# sweeps (vsinv.sweep and its names in vsinv)

SWEEP_BASE = json.loads(json.dumps(BASE))
SWEEP_BASE["stop"]["max_iterations"] = 3


@covers("run_sweep", "SweepResult", "sweep", "sweep.run_sweep", "sweep.SweepResult", "sweep.build_scenarios")
@fuzz_settings(40)
@given(data=st.data())
def test_run_sweep(tmp_path_factory: Any, data: Any) -> None:
    good_vary = [{"control.gain": [0.5, 1.0]}, {"focal_error": 0.1}, {"roll_deg": vsinv.sim.Uniform(-10, 10)},
                 {"noise.pixel_sigma": vsinv.sim.LogUniform(0.01, 0.1), "control.gain": [1.0]}, {"start.position.2": [-0.1]},
                 {"lens_ratio": vsinv.sim.Choice([0.5, 1.0])}, {}]
    bad_vary = [{"nope": [1]}, {"control.gain": []}, {"control.gain": "abc"}, {"control.gain": [-1.0]},
                {"control.gain": [math.nan]}, {"focal_error": [math.inf]}, {"start.position.7": [1.0]}, {"": [1]},
                {"control..gain": [1]}, {"roll_deg": ["a"]}, {3: [1]}, [("control.gain", [1.0])], None,
                {"stop.max_iterations": [10**9]}, {"control.gain": {"a": 1}}, {"control.gain": vsinv.sim.Uniform(-1, 1)}]
    vary = data.draw(choices(good_vary, bad_vary), label="vary")
    kw: dict[str, Any] = {}
    random = isinstance(vary.value, dict) and any(isinstance(x, vsinv.sweep.Distribution) for x in vary.value.values())
    if random:
        kw["draws"] = 2
    extra = data.draw(st.sampled_from(["none", "repeats", "draws", "seed", "chunk_size", "threads", "base"]), label="extra")
    expect, names = (vary.expect if vary.expect == INVALID else ANY), ("vary", "key", "draws")
    base: Any = SWEEP_BASE
    if extra != "none" and vary.expect != INVALID:
        bad = data.draw(st.sampled_from([0, -1, 1.5, "2", True, None, 2**70]), label="bad value")
        if extra == "base":
            base, expect, names = data.draw(st.sampled_from([None, "nope", 3])), INVALID, ("scenario",)
        elif extra == "draws" and bad is None:
            pass
        elif extra == "seed" and bad in (0, 2**70):
            kw["seed"] = bad
        elif extra == "threads" and bad is None:
            kw["threads"] = None
        elif extra == "chunk_size" and bad in (None, 2**70):
            kw["chunk_size"] = bad  # None: the default; a chunk larger than the sweep is fine
        else:  # threads=True too: a bool is not a thread count
            kw[extra] = bad
            expect, names = INVALID, (extra,)
            if extra == "draws" and not random and bad is not None:
                names = ("draws",)
            if extra == "repeats" and bad == 2**70:
                kw[extra] = 2**70
    res = call(vsinv.sim.run_sweep, base, vary.value, progress=False, **kw, _expect=expect, _names=names, _finite=False)
    if not returned(res):
        return
    n = len(res)
    assert n >= 1 and all(len(c) == n for c in res.columns.values())
    for k in res.keys:
        assert k in res.columns
    summary = call(res.summary_by, _api="SweepResult.summary_by", _finite=False)
    assert sum(summary["runs"]) == n
    call(res.summary_by, "nope", _api="SweepResult.summary_by", _expect=INVALID, _names=("nope",))
    call(res.summary_by, (), bins=data.draw(st.sampled_from([None, 1, 3])), _api="SweepResult.summary_by", _finite=False)
    out = call(res.write, tmp_path_factory.mktemp("sweep") / data.draw(st.sampled_from(["r.csv", "r.parquet"])),
               _api="SweepResult.write", _expect=RETURN)
    assert out.exists()
    df = call(res.to_pandas, _api="SweepResult.to_pandas", _expect=RETURN, _finite=False)
    assert len(df) == n
    assert call(res.__getitem__, "seed", _api="SweepResult.__getitem__").shape == (n,)
    scen = call(vsinv.sweep.build_scenarios, SWEEP_BASE, vary.value, **{k: v for k, v in kw.items() if k in ("draws", "seed", "repeats")},
                _api="sweep.build_scenarios", _finite=False)
    if returned(scen):
        assert len(scen) == n


@covers("Uniform", "LogUniform", "Choice", "sweep.Uniform", "sweep.LogUniform", "sweep.Choice", "sweep.Distribution")
@fuzz_settings(150)
@given(st.data())
def test_distributions(data: Any) -> None:
    cls = data.draw(st.sampled_from([vsinv.sim.Uniform, vsinv.sim.LogUniform, vsinv.sim.Choice]))
    if cls is vsinv.sim.Choice:
        values = data.draw(st.sampled_from([[1.0, 2.0], (1,), np.array([0.5, 1.5]), ["a", "b"], [], None, 3, "ab", [[1, 2], [3]]]))
        expect = INVALID if (isinstance(values, (list, str)) and len(values) != 2) or values is None or isinstance(values, int) else ANY
        d = call(cls, values, _api=cls.__name__, _expect=expect, _names=("Choice", "values"), _finite=False)
    else:
        lo = data.draw(floats(0.1, overrides={"nan": INVALID, "posinf": INVALID, "neginf": INVALID, "str": INVALID,
                                              "none": INVALID, "list": INVALID}), label="lo")
        hi = data.draw(floats(2.0, overrides={"nan": INVALID, "posinf": INVALID, "neginf": INVALID, "str": INVALID,
                                              "none": INVALID, "list": INVALID}), label="hi")
        expect = INVALID if INVALID in (lo.expect, hi.expect) else ANY
        d = call(cls, lo.value, hi.value, _api=cls.__name__, _expect=expect, _names=(cls.__name__,))
    if returned(d):
        assert isinstance(d, vsinv.sweep.Distribution)
        rng = np.random.default_rng(0)
        s = call(d.sample, rng, 5, _api=f"{cls.__name__}.sample", _finite=cls is not vsinv.sim.Choice)
        b = call(d.bounds, _api=f"{cls.__name__}.bounds", _finite=False)
        if returned(s) and cls is not vsinv.sim.Choice:
            lo_, hi_ = b
            assert len(s) == 5 and ((s >= lo_) & (s <= hi_)).all()


@covers("sweep.DERIVED_KEYS", "sweep.noise_seeds", "sweep.rotation_from_thetau", "sweep.thetau_from_rotation")
@fuzz_settings(150)
@given(st.data())
def test_sweep_helpers(data: Any) -> None:
    assert set(vsinv.sweep.DERIVED_KEYS) == {"lens_ratio", "focal_error", "principal_point_error", "roll_deg"}
    which = data.draw(st.sampled_from(["noise_seeds", "rotation_from_thetau", "thetau_from_rotation"]))
    tu = np.array([0.3, -0.4, 1.2])
    if which == "noise_seeds":
        args = {"seed": 7, "points": np.arange(4), "repeats": np.zeros(4, int)}
        ref = vsinv.sweep.noise_seeds(**args)
        ints_over = {"float32": ANY, "nan": INVALID, "posinf": INVALID, "neginf": INVALID, "negative": INVALID, "huge": INVALID,
                     "complex": INVALID, "object_str": INVALID, "str": INVALID, "none": INVALID, "ragged": INVALID,
                     "object_float": ANY, "fewer": ANY, "extra_axis": ANY, "flat": SAME, "lead_axis": ANY, "scalar": ANY,
                     "tiny": ANY, "int": SAME}
        name, v, out = fuzz(data, vsinv.sweep.noise_seeds, args,
                            {"seed": ints(7, overrides={"negative": INVALID, "float": INVALID, "str": INVALID, "none": INVALID,
                                                        "huge": ANY}),
                             "points": arrays(np.arange(4.0), overrides=ints_over),
                             "repeats": arrays(np.zeros(4), overrides={**ints_over, "negative": ANY, "huge": ANY})},  # -0.0, 0 * 1e300
                            api="sweep.noise_seeds", ref=ref)
        if returned(out):
            assert out.dtype == np.int64 and (out >= 0).all()
    elif which == "rotation_from_thetau":
        ref = vsinv.sweep.rotation_from_thetau(tu)
        np.testing.assert_allclose(ref, rodrigues(tu), atol=1e-12)
        over = {"flat": SAME, "strided": SAME, "huge": INVALID, "str": INVALID, "none": INVALID, "object_str": INVALID,
                "ragged": INVALID, "complex": INVALID, "scalar": INVALID, "fewer": INVALID, "empty": INVALID, "extra_axis": ANY,
                "lead_axis": ANY, "object_float": ANY}
        name, v, out = fuzz(data, vsinv.sweep.rotation_from_thetau, {"thetau": tu}, {"thetau": arrays(tu, overrides=over)},
                            api="sweep.rotation_from_thetau", ref=ref, rtol=1e-12)
        if returned(out):
            np.testing.assert_allclose(out @ out.T, np.eye(3), atol=1e-9)
    else:
        r = rodrigues(tu)
        ref = vsinv.sweep.thetau_from_rotation(r)
        np.testing.assert_allclose(ref, tu, atol=1e-12)
        over = {"huge": INVALID, "str": INVALID, "none": INVALID, "object_str": INVALID, "ragged": INVALID, "complex": INVALID,
                "scalar": INVALID, "fewer": INVALID, "empty": INVALID, "extra_axis": INVALID, "flat": ANY, "lead_axis": ANY,
                "object_float": ANY, "tiny": ANY}
        name, v, out = fuzz(data, vsinv.sweep.thetau_from_rotation, {"rot": r}, {"rot": arrays(r, overrides=over)},
                            api="sweep.thetau_from_rotation", ref=ref, rtol=1e-12)
        if returned(out):
            assert out.shape == (3,) and np.linalg.norm(out) <= math.pi + 1e-9
