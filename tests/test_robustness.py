"""Robustness of every public name of ``vsinv`` (and ``vsinv.sweep``) under hypothesis.

The promise checked here: a call returns a correct result, or raises the package's own
exception (a ``vsinv.VsinvError`` subclass) whose message names the argument at fault and,
for a non-finite value in an array, its position ("row R, column C" for 2-d arrays). Never a
``PanicException``, another exception class, a crash, a hang (each call is timed) or NaN/inf
in an output without an exception. A wrong Python type for a scalar argument (a str where a
float is expected) may raise ``TypeError`` naming the argument (PyO3's convention: the
argument is named in the exception's notes).

One harness, :func:`call`, runs every call and keeps a census (calls tried, returned, raised
by class, per API). With ``VSINV_CENSUS=path`` the census is merged into the JSON file
``path`` at the end of the module and printed at the end of the session; ``python
tests/test_robustness.py path`` prints a census file as a table.

Each argument's strategy draws valid values, layout variants that must give the same answer
(lists, Fortran order, strided views, read-only arrays), NaN/inf at a drawn position, zeros,
negatives, huge values, wrong shapes and dtypes, and degenerate geometry; one argument is
corrupted per call, so the exception must name that argument.
"""

from __future__ import annotations

import functools
import json
import math
import os
import re
import sys
import time
from collections import Counter, defaultdict
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Optional

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import vsinv
import vsinv.plots
import vsinv.sweep
from conftest import lens, object_points, pose, view

cv2 = pytest.importorskip("cv2")

# ---------------------------------------------------------------------------------------------
# settings: bounded time per call and per example, small inputs

DEADLINE_MS = 2000
CALL_LIMIT_S = 2.0


def fuzz_settings(n: int) -> settings:
    return settings(
        max_examples=n,
        deadline=DEADLINE_MS,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture, HealthCheck.data_too_large],
        database=None,
    )


# ---------------------------------------------------------------------------------------------
# the census

CENSUS: dict[str, Counter[str]] = defaultdict(Counter)


def census_table(census: dict[str, Any]) -> str:
    classes = sorted({k for c in census.values() for k in c if k not in ("tried", "returned")})
    head = ["API", "tried", "returned", *classes]
    rows = [[api, *(str(c.get(k, 0)) for k in ("tried", "returned", *classes))] for api, c in sorted(census.items())]
    total = ["TOTAL", *(str(sum(c.get(k, 0) for c in census.values())) for k in ("tried", "returned", *classes))]
    rows.append(total)
    widths = [max(len(r[i]) for r in [head, *rows]) for i in range(len(head))]
    line = lambda r: "  ".join(x.ljust(w) if i == 0 else x.rjust(w) for i, (x, w) in enumerate(zip(r, widths)))  # noqa: E731
    return "\n".join([line(head), line(["-" * w for w in widths]), *(line(r) for r in rows)])


@pytest.fixture(scope="module", autouse=True)
def _census_dump():
    yield
    path = os.environ.get("VSINV_CENSUS")
    if not path:
        return
    merged: dict[str, Counter[str]] = defaultdict(Counter)
    if os.path.exists(path):
        try:
            for api, counts in json.loads(Path(path).read_text()).items():
                merged[api].update(counts)
        except (OSError, ValueError):
            pass
    for api, counts in CENSUS.items():
        merged[api].update(counts)
    Path(path).write_text(json.dumps({k: dict(v) for k, v in sorted(merged.items())}, indent=1))


# ---------------------------------------------------------------------------------------------
# the harness

SAME = "same"  # must return, equal to the answer for the canonical arguments
ANY = "any"  # return (finite) or a package exception naming the argument
INVALID = "invalid"  # must raise InvalidInput naming the argument
RAISE = "raise"  # must raise a package exception (naming the argument, for InvalidInput)
NONFINITE = "nonfinite"  # InvalidInput naming the argument and the position
TYPE = "type"  # TypeError or InvalidInput naming the argument
RETURN = "return"  # must return


class _Unset:
    pass


UNSET: Any = _Unset()


def _api_name(fn: Any) -> str:
    owner = getattr(fn, "__self__", None)
    name = getattr(fn, "__name__", repr(fn))
    if isinstance(owner, type):
        return f"{owner.__name__}.{name}" if name != "__new__" else owner.__name__
    if owner is not None and not isinstance(owner, type(sys)):
        return f"{type(owner).__name__}.{name}"
    return name


def _text(exc: BaseException) -> str:
    return " ".join([str(exc), *getattr(exc, "__notes__", [])])


def assert_finite(out: Any, where: str = "output") -> None:
    """Floats and float/complex arrays in the output (tuples, lists, dicts) are finite."""
    if isinstance(out, np.ndarray):
        if out.dtype.kind in "fc":
            assert np.isfinite(out).all(), f"{where}: non-finite output without an exception: {out!r}"
    elif isinstance(out, float):
        assert math.isfinite(out), f"{where}: non-finite output {out!r}"
    elif isinstance(out, (tuple, list)):
        for i, x in enumerate(out):
            assert_finite(x, f"{where}[{i}]")
    elif isinstance(out, dict):
        for k, x in out.items():
            assert_finite(x, f"{where}[{k!r}]")


def position_pattern(where: tuple[int, ...]) -> str:
    if len(where) == 1:
        return rf"\b{where[0]}\b"
    if len(where) == 2:
        return rf"row {where[0]}, column {where[1]}\b"
    return rf"\b{where[0]}\b.*row {where[1]}, column {where[2]}\b"


def call(fn: Callable[..., Any], *args: Any, _api: Optional[str] = None, _expect: str = ANY,
         _names: tuple[str, ...] = (), _where: Optional[tuple[int, ...]] = None,
         _finite: bool = True, _check: Optional[Callable[[Any], None]] = None, **kwargs: Any) -> Any:
    """Call ``fn``: it returns (outputs finite, ``_check`` passes) or raises a package
    exception whose message names one of ``_names``. Returns the output or the exception."""
    api = _api or _api_name(fn)
    CENSUS[api]["tried"] += 1
    t0 = time.perf_counter()
    try:
        out = fn(*args, **kwargs)
    except vsinv.VsinvError as exc:
        elapsed = time.perf_counter() - t0
        CENSUS[api][type(exc).__name__] += 1
        assert elapsed < CALL_LIMIT_S, f"{api} took {elapsed:.2f} s to raise"
        msg = str(exc)
        assert msg.strip(), f"{api}: {type(exc).__name__} with an empty message"
        # Numbers in messages are short (issue 16): {} of 1e-320 or 1e300 printed 300+ digits.
        # An integer the caller passed may be echoed as given.
        echoed = [str(abs(a)) for a in (*args, *kwargs.values()) if isinstance(a, int) and abs(a) >= 10**20]
        short = msg
        for text in echoed:
            short = short.replace(text, "")
        assert not re.search(r"\d{21,}", short), f"{api}: a number with more than 20 digits in {msg!r}"
        assert _expect not in (SAME, RETURN), f"{api}: raised {type(exc).__name__}: {msg}"
        if _expect in (INVALID, NONFINITE):
            assert isinstance(exc, vsinv.InvalidInput), f"{api}: expected InvalidInput, got {type(exc).__name__}: {msg}"
        if _names and (isinstance(exc, vsinv.InvalidInput) or _expect in (INVALID, NONFINITE, TYPE)):
            assert any(n.lower() in msg.lower() for n in _names), f"{api}: message {msg!r} names none of {_names}"
        if _expect == NONFINITE and _where is not None:
            assert re.search(position_pattern(_where), msg), f"{api}: message {msg!r} does not give the position {_where}"
            assert not re.search(r"index \d+", msg) or len(_where) == 1, f"{api}: flat index in {msg!r}"
        return exc
    except TypeError as exc:
        CENSUS[api]["TypeError"] += 1
        assert _expect == TYPE, f"{api}: TypeError outside the hierarchy: {_text(exc)}"
        assert any(n in _text(exc) for n in _names), f"{api}: TypeError {_text(exc)!r} names none of {_names}"
        return exc
    except BaseException as exc:  # PanicException, ValueError, OverflowError, ...
        if isinstance(exc, KeyboardInterrupt):
            raise
        CENSUS[api][type(exc).__name__] += 1
        pytest.fail(f"{api}: {type(exc).__module__}.{type(exc).__name__} outside the hierarchy: {_text(exc)}")
    elapsed = time.perf_counter() - t0
    CENSUS[api]["returned"] += 1
    assert elapsed < CALL_LIMIT_S, f"{api} took {elapsed:.2f} s"
    assert _expect not in (INVALID, NONFINITE, RAISE, TYPE), f"{api}: returned {out!r:.200} where an exception was due"
    if _finite:
        assert_finite(out, api)
    if _check is not None:
        _check(out)
    return out


def returned(out: Any) -> bool:
    return not isinstance(out, BaseException)


def assert_same(a: Any, b: Any, rtol: float = 0.0, where: str = "output") -> None:
    if isinstance(a, (tuple, list)):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, rtol, f"{where}[{i}]")
    elif isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for k in a:
            assert_same(a[k], b[k], rtol, f"{where}[{k!r}]")
    elif isinstance(a, (np.ndarray, float, int)):
        a, b = np.asarray(a), np.asarray(b)
        assert a.shape == b.shape, f"{where}: {a.shape} != {b.shape}"
        if a.dtype.kind in "fc":
            np.testing.assert_allclose(a, b, rtol=rtol, atol=0, equal_nan=True, err_msg=where)
        else:
            assert np.array_equal(a, b), where
    else:
        assert a == b, f"{where}: {a!r} != {b!r}"


# ---------------------------------------------------------------------------------------------
# argument variants


@dataclass
class V:
    """A drawn argument: its value, what the call must do, and where a non-finite value is."""

    value: Any
    expect: str
    label: str
    where: Optional[tuple[int, ...]] = None

    def __repr__(self) -> str:
        return f"V({self.label}, expect={self.expect}, where={self.where}, value={self.value!r:.300})"


ARRAY_KINDS = (
    "valid", "list", "fortran", "strided", "readonly", "float32", "int", "nan", "posinf", "neginf",
    "zero", "negative", "huge", "tiny", "fewer", "empty", "extra_axis", "flat", "lead_axis",
    "object_str", "object_float", "str", "none", "complex", "ragged", "scalar", "bool",
)


@st.composite
def arrays(draw: Any, valid: Any, overrides: Optional[dict[str, str]] = None, skip: tuple[str, ...] = ()) -> V:
    """Variants of a valid float array argument; ``overrides`` changes an expectation by
    kind, ``skip`` leaves kinds out."""
    valid = np.asarray(valid, dtype=np.float64)
    kinds = [k for k in ARRAY_KINDS if k not in skip]
    kind = draw(st.sampled_from(kinds), label="kind")
    expect = ANY
    where = None
    if kind == "valid":
        value, expect = valid.copy(), SAME
    elif kind == "list":
        value, expect = valid.tolist(), SAME
    elif kind == "fortran":
        value, expect = np.asfortranarray(valid), SAME
    elif kind == "strided":
        value, expect = np.repeat(valid, 2, axis=-1)[..., ::2], SAME
        assert valid.size <= 1 or not value.flags.c_contiguous or valid.ndim == 0
    elif kind == "readonly":
        value = valid.copy()
        value.flags.writeable = False
        expect = SAME
    elif kind == "float32":
        value = valid.astype(np.float32)
    elif kind == "int":
        value = valid.astype(np.int64)
        expect = SAME if np.array_equal(value, valid) else ANY
    elif kind in ("nan", "posinf", "neginf"):
        if valid.size == 0:
            value = valid.copy()
        else:
            idx = tuple(draw(st.integers(0, s - 1), label=f"axis{i}") for i, s in enumerate(valid.shape))
            value = valid.copy()
            value[idx] = {"nan": np.nan, "posinf": np.inf, "neginf": -np.inf}[kind]
            expect, where = NONFINITE, idx
    elif kind == "zero":
        value = np.zeros_like(valid)
    elif kind == "negative":
        value = -valid
    elif kind == "huge":
        value = valid * 1e300 + draw(st.sampled_from([0.0, 1e300]))
    elif kind == "tiny":
        value = valid * 1e-300
    elif kind == "fewer":
        k = draw(st.integers(0, max(len(valid) - 1, 0))) if valid.ndim else 0
        value = valid[:k] if valid.ndim else valid
    elif kind == "empty":
        value = np.empty((0, *valid.shape[1:]))
    elif kind == "extra_axis":
        value, expect = (np.concatenate([valid, valid[..., :1]], axis=-1) if valid.ndim >= 2 else valid[:, None]), INVALID
    elif kind == "flat":
        value, expect = valid.ravel(), (INVALID if valid.ndim >= 2 else SAME)
    elif kind == "lead_axis":
        value, expect = valid[None], INVALID
    elif kind == "object_str":
        value = valid.astype(object)
        if value.size:
            value.flat[draw(st.integers(0, value.size - 1))] = "x"
        expect = INVALID if value.size else ANY
    elif kind == "object_float":
        value, expect = valid.astype(object), INVALID
    elif kind == "str":
        value, expect = draw(st.sampled_from(["abc", "", "1.0"])), INVALID
    elif kind == "none":
        value, expect = None, INVALID
    elif kind == "complex":
        value, expect = valid.astype(complex), INVALID
    elif kind == "ragged":
        value, expect = [[1.0, 2.0], [3.0]], INVALID
    elif kind == "scalar":
        value, expect = 1.0, INVALID
    elif kind == "bool":
        value = valid.astype(bool)
    else:  # pragma: no cover
        raise AssertionError(kind)
    expect = (overrides or {}).get(kind, expect)
    return V(value, expect, kind, where)


SCALAR_KINDS = ("valid", "int", "npfloat", "nan", "posinf", "neginf", "zero", "negative", "huge", "neghuge", "tiny", "str", "none", "list")


@st.composite
def floats(draw: Any, valid: float, overrides: Optional[dict[str, str]] = None, skip: tuple[str, ...] = ()) -> V:
    """Variants of a float argument: NaN must be refused; inf, 0, negatives and huge values
    either work or are refused; wrong Python types raise TypeError (or InvalidInput)."""
    kind = draw(st.sampled_from([k for k in SCALAR_KINDS if k not in skip]), label="kind")
    table: dict[str, tuple[Any, str]] = {
        "valid": (valid, SAME),
        "int": (int(valid), SAME if int(valid) == valid else ANY),
        "npfloat": (np.float64(valid), SAME),
        "nan": (math.nan, RAISE),
        "posinf": (math.inf, ANY),
        "neginf": (-math.inf, ANY),
        "zero": (0.0, ANY),
        "negative": (-abs(valid) - 1.0, ANY),
        "huge": (1e300, ANY),
        "neghuge": (-1e300, ANY),
        "tiny": (1e-300, ANY),
        "str": ("abc", TYPE),
        "none": (None, TYPE),
        "list": ([valid], TYPE),
    }
    value, expect = table[kind]
    if kind == "valid" and draw(st.booleans()):  # a nearby valid value
        value, expect = valid * draw(st.floats(0.5, 2.0)), ANY
    return V(value, (overrides or {}).get(kind, expect), kind)


INT_KINDS = ("valid", "npint", "zero", "negative", "huge", "float", "str", "none", "bool")


@st.composite
def ints(draw: Any, valid: int, overrides: Optional[dict[str, str]] = None) -> V:
    """Variants of an integer argument: negative and out-of-range integers must be refused
    with InvalidInput (not OverflowError), wrong types with TypeError or InvalidInput."""
    kind = draw(st.sampled_from(INT_KINDS), label="kind")
    table: dict[str, tuple[Any, str]] = {
        "valid": (valid, SAME),
        "npint": (np.int64(valid), SAME),
        "zero": (0, ANY),
        "negative": (draw(st.sampled_from([-1, -(2**70)])), INVALID),
        "huge": (draw(st.sampled_from([2**31, 2**64, 2**70])), ANY),
        "float": (valid + 0.5, TYPE),
        "str": ("3", TYPE),
        "none": (None, TYPE),
        "bool": (True, ANY),
    }
    value, expect = table[kind]
    return V(value, (overrides or {}).get(kind, expect), kind)


@st.composite
def choices(draw: Any, good: list[Any], bad: list[Any], bad_expect: str = INVALID) -> V:
    if draw(st.booleans()):
        return V(draw(st.sampled_from(good)), RETURN, "good")
    return V(draw(st.sampled_from(bad)), bad_expect, "bad")


def basis_variants(n: int) -> st.SearchStrategy[V]:
    good = [(0, 1, 2), [0, 1, 2], np.array([0, 1, 2]), "auto", (2, 5, 9)]
    bad = [(0, 1), (0, 0, 1), (0, 1, n), (0, -1, 2), "widest", None, (0.5, 1, 2), (0, 1, 2, 3), 7, (0, 1, 2**70)]
    return choices(good, bad).map(lambda v: V(v.value, ANY if v.expect == RETURN else v.expect, v.label))


# ---------------------------------------------------------------------------------------------
# the fuzz driver: corrupt one argument per call


def fuzz(data: Any, fn: Callable[..., Any], args: dict[str, Any], strategies: dict[str, st.SearchStrategy[V]], *,
         api: Optional[str] = None, names: Optional[dict[str, tuple[str, ...]]] = None,
         digest: Callable[[Any], Any] = lambda x: x, ref: Any = UNSET, rtol: float = 0.0,
         check: Optional[Callable[[Any], None]] = None, finite: bool = True) -> tuple[str, V, Any]:
    """Draw one argument of ``strategies``, draw its variant and call ``fn(**args)`` with it.
    A SAME variant's output must match ``ref`` (the canonical call) through ``digest``."""
    name = data.draw(st.sampled_from(sorted(strategies)), label="argument")
    v = data.draw(strategies[name], label=name)
    kwargs = dict(args)
    kwargs[name] = v.value
    own = (names or {}).get(name, (name, "points") if "pixels" in name else (name,))
    if v.expect == ANY:  # a consequence may be reported on another argument (a dot too small to find...)
        own = (*own, *args, *(n for ns in (names or {}).values() for n in ns))
    out = call(fn, _api=api, _expect=v.expect, _names=own, _where=v.where,
               _finite=finite, _check=check, **kwargs)
    if v.expect == SAME and ref is not UNSET:
        assert_same(digest(out), digest(ref), rtol, f"{api or _api_name(fn)} with {name}={v.label}")
    return name, v, out


# ---------------------------------------------------------------------------------------------
# the scene: twelve non-coplanar points, a reference view with K* and a current view with K

OBJ = object_points()
K = lens(600.0)
KSTAR = lens(1200.0)
REF_PX, REF_Z = view(OBJ, np.eye(4), KSTAR)
CUR_POSE = pose((0.05, -0.03, -0.08), (0.1, -0.2, 0.3))
CUR_PX, CUR_Z = view(OBJ, CUR_POSE, K)
TRANS_PX, TRANS_Z = view(OBJ, pose((0.06, 0.02, -0.05)), K)  # pure translation from F*
FIRST_PX, FIRST_Z = view(OBJ, np.eye(4), K)
N = len(OBJ)

#: Registry: public name -> the tests that cover it (filled by @covers).
REGISTRY: dict[str, list[str]] = defaultdict(list)


def covers(*names: str) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    def mark(fn: Callable[..., Any]) -> Callable[..., Any]:
        for n in names:
            REGISTRY[n].append(fn.__name__)
        return fn

    return mark


def k_variants(valid: Any = K) -> st.SearchStrategy[V]:
    """An Intrinsics, its matrix in every layout, and bad matrices."""
    bad = [
        V(np.ones((3, 3)), INVALID, "not triangular"),
        V(np.eye(4), INVALID, "4x4"),
        V(np.diag([-600.0, 600.0, 1.0]), INVALID, "negative focal"),
        V(np.diag([600.0, 0.0, 1.0]), INVALID, "zero focal"),
        V(np.zeros((3, 3)), INVALID, "zeros"),
        V(valid.matrix * np.array([[1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [0.0, 0.0, 2.0]]), INVALID, "K[2,2] = 2"),
    ]
    m = valid.matrix
    return st.one_of(
        st.just(V(valid, SAME, "Intrinsics")),
        arrays(m, overrides={"zero": INVALID, "negative": INVALID, "fewer": INVALID, "empty": INVALID, "flat": INVALID,
                             "bool": ANY, "tiny": ANY}),
        st.sampled_from(bad),
    )


# ---------------------------------------------------------------------------------------------
# geometry: project, invariant points, Jacobians


def manual_project(points: np.ndarray, k: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    h = points @ k.T
    return h[:, :2] / h[:, 2:], points[:, 2]


@covers("project")
@fuzz_settings(120)
@given(st.data())
def test_project(data: Any) -> None:
    ref = vsinv.project(OBJ, K)
    np.testing.assert_allclose(ref[0], manual_project(OBJ, K.matrix)[0], rtol=1e-14)

    def check(out: Any) -> None:
        px, z = out
        assert px.dtype == np.float64 and z.dtype == np.float64
        assert px.shape == (len(z), 2) and z.ndim == 1
        assert (z > 0).all()

    name, v, out = fuzz(data, vsinv.project, {"points": OBJ, "K": K},
                        {"points": arrays(OBJ, overrides={"negative": RAISE}), "K": k_variants()}, ref=ref, check=check)
    if returned(out) and name == "points" and v.expect != SAME:
        pts = np.asarray(v.value, dtype=float)
        mpx, mz = manual_project(pts, K.matrix)
        np.testing.assert_allclose(out[0], mpx, rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(out[1], mz, rtol=0)


@covers("project")
@fuzz_settings(60)
@given(st.lists(st.tuples(st.floats(-5, 5), st.floats(-5, 5), st.floats(-2, 5)), min_size=0, max_size=8),
       st.floats(10, 5000), st.floats(10, 5000), st.floats(-500, 500), st.floats(-500, 500))
def test_project_against_numpy_and_opencv(pts: list[tuple[float, float, float]], fu: float, fv: float, u0: float, v0: float) -> None:
    k = vsinv.Intrinsics(fu, fv, u0, v0)
    p = np.array(pts, dtype=float).reshape(-1, 3)
    out = call(vsinv.project, p, k, _names=("point", "behind"))
    if (p[:, 2] <= 1e-9).any():
        # A point at or behind the camera, or (checked first if it comes first) one so close
        # to the camera plane that its pixel overflows.
        overflow = isinstance(out, vsinv.InvalidInput) and "out of range" in str(out)
        assert isinstance(out, vsinv.DegenerateGeometry) or overflow or (p[:, 2] > 0).all(), out
        return
    assert returned(out)
    np.testing.assert_allclose(out[0], manual_project(p, k.matrix)[0], rtol=1e-12, atol=1e-6)
    if len(p):
        cv, _ = cv2.projectPoints(p, np.zeros(3), np.zeros(3), k.matrix, None)
        np.testing.assert_allclose(out[0], cv.reshape(-1, 2), rtol=1e-9, atol=1e-6)


def manual_invariants(px: np.ndarray, basis: tuple[int, int, int]) -> np.ndarray:
    h = np.column_stack([px, np.ones(len(px))])
    q = np.linalg.solve(h[list(basis)].T, h.T).T
    return q


def pixel_variants(valid: np.ndarray, degenerate_expect: str = RAISE, **kw: Any) -> st.SearchStrategy[V]:
    """Pixels: fewer than needed or degenerate values may be refused as geometry; a collinear
    or duplicated basis (points 0, 1, 2) is refused where the basis is used (``RAISE``)."""
    over = {"zero": RAISE, "empty": RAISE, "lead_axis": INVALID, "bool": RAISE}
    over.update(kw.pop("overrides", {}))
    degenerate = valid.copy()
    degenerate[2] = 0.5 * (degenerate[0] + degenerate[1])  # collinear basis
    dup = valid.copy()
    dup[1] = dup[0]  # duplicate basis point
    return st.one_of(arrays(valid, overrides=over, **kw),
                     st.sampled_from([V(degenerate, degenerate_expect, "collinear basis"),
                                      V(dup, degenerate_expect, "duplicate point")]))


@covers("invariant_points")
@fuzz_settings(100)
@given(st.data())
def test_invariant_points(data: Any) -> None:
    ref = vsinv.invariant_points(CUR_PX)
    np.testing.assert_allclose(ref, manual_invariants(CUR_PX, (0, 1, 2)), atol=1e-10)

    def check(q: np.ndarray) -> None:
        assert q.dtype == np.float64 and q.ndim == 2 and q.shape[1] == 3
        np.testing.assert_allclose(q.sum(axis=1), 1.0, atol=1e-6)

    name, v, out = fuzz(data, vsinv.invariant_points, {"pixels": CUR_PX, "basis": (0, 1, 2)},
                        {"pixels": pixel_variants(CUR_PX), "basis": basis_variants(N)}, ref=ref, rtol=1e-12, check=check)
    if returned(out) and name == "basis" and not isinstance(v.value, str):
        b = tuple(int(i) for i in v.value)
        np.testing.assert_allclose(out, manual_invariants(CUR_PX, b), atol=1e-8)


def interaction_numpy(px: np.ndarray, z: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Espiau's point interaction matrix in pixels: K[:2,:2] L(x, y, Z)."""
    h = np.linalg.solve(k, np.column_stack([px, np.ones(len(px))]).T).T
    out = []
    for (x, y, _), zz in zip(h, z):
        ln = np.array([[-1 / zz, 0, x / zz, x * y, -(1 + x * x), y], [0, -1 / zz, y / zz, 1 + y * y, -x * y, -x]])
        out.append(k[:2, :2] @ ln)
    return np.array(out)


def depth_variants(valid: np.ndarray, extra: Optional[dict[str, str]] = None) -> st.SearchStrategy[V]:
    return arrays(valid, overrides={"zero": RAISE, "negative": RAISE, "empty": RAISE, "bool": ANY, "flat": SAME,
                                    "strided": SAME, "fewer": RAISE, **(extra or {})}, skip=("fortran",))


@covers("interaction_matrix")
@fuzz_settings(100)
@given(st.data())
def test_interaction_matrix(data: Any) -> None:
    ref = vsinv.interaction_matrix(CUR_PX, CUR_Z, K)
    np.testing.assert_allclose(ref, interaction_numpy(CUR_PX, CUR_Z, K.matrix), rtol=1e-9, atol=1e-9)
    fuzz(data, vsinv.interaction_matrix, {"pixels": CUR_PX, "depths": CUR_Z, "K": K},
         {"pixels": pixel_variants(CUR_PX, ANY, overrides={"zero": ANY, "empty": ANY, "bool": ANY}),
          "depths": depth_variants(CUR_Z), "K": k_variants()},
         ref=ref, check=lambda L: L.shape[1:] == (2, 6) or pytest.fail(f"shape {L.shape}"))


@covers("invariant_jacobian", "jacobian_factors", "structure_ratio")
@fuzz_settings(150)
@given(st.data())
def test_jacobians(data: Any) -> None:
    which = data.draw(st.sampled_from(["invariant_jacobian", "jacobian_factors", "structure_ratio"]))
    fn = getattr(vsinv, which)
    args: dict[str, Any] = {"pixels": CUR_PX, "depths": CUR_Z, "basis": (0, 1, 2)}
    strategies = {"pixels": pixel_variants(CUR_PX), "depths": depth_variants(CUR_Z), "basis": basis_variants(N)}
    if which != "jacobian_factors":
        args["K"] = K
        strategies["K"] = k_variants()
    ref = fn(**args)

    def check(out: Any) -> None:
        if which == "invariant_jacobian":
            assert out.shape[1] == 5 and out.shape[0] % 3 == 0
        elif which == "jacobian_factors":
            assert out[0].shape[1] == 3 and out[1].shape[1] == 2 and out[0].shape[0] == out[1].shape[0]
        else:
            assert 0.0 <= out <= 1.0 + 1e-12

    fuzz(data, fn, args, strategies, ref=ref, rtol=1e-12, check=check)
    if which == "invariant_jacobian":  # J = [Phi K, Psi F(K)]: the first three columns
        phi, _ = vsinv.jacobian_factors(CUR_PX, CUR_Z)
        np.testing.assert_allclose(ref[:, :3], phi @ K.matrix, rtol=1e-9, atol=1e-9)


@covers("rz_coefficients")
@fuzz_settings(100)
@given(st.data())
def test_rz_coefficients(data: Any) -> None:
    args = {"pixels": CUR_PX, "depths": CUR_Z, "reference_pixels": REF_PX, "K": K, "basis": (0, 1, 2)}
    ref = vsinv.rz_coefficients(**args)

    def check(out: Any) -> None:
        a, c = out
        assert isinstance(a, float) and c.shape == (5,)

    fuzz(data, vsinv.rz_coefficients, args,
         {"pixels": pixel_variants(CUR_PX, ANY, overrides={"zero": ANY, "bool": ANY}), "depths": depth_variants(CUR_Z),
          "reference_pixels": pixel_variants(REF_PX),
          "K": k_variants(), "basis": basis_variants(N)}, ref=ref, rtol=1e-12, check=check)


@covers("choose_basis")
@fuzz_settings(80)
@given(st.data())
def test_choose_basis(data: Any) -> None:
    ref = vsinv.choose_basis(REF_PX)

    def check(b: tuple[int, int, int]) -> None:
        assert isinstance(b, tuple) and len(b) == 3 and list(b) == sorted(set(b))

    name, v, out = fuzz(data, vsinv.choose_basis, {"pixels": REF_PX}, {"pixels": pixel_variants(REF_PX, ANY)}, ref=ref, check=check)
    if returned(out):
        px = np.asarray(v.value, dtype=float)
        assert max(out) < len(px)
        # the widest triangle: no other triple is wider (brute force, n <= 12)
        h = np.column_stack([px, np.ones(len(px))])
        with np.errstate(all="ignore"):  # huge pixels overflow the determinant
            area = abs(np.linalg.det(h[list(out)]))
            best = max(abs(np.linalg.det(h[[i, j, k]])) for i in range(len(px)) for j in range(i) for k in range(j))
        assert area >= best * (1 - 1e-9) - 1e-12 or not np.isfinite(best)


@covers("choose_basis", "invariant_points")
@fuzz_settings(60)
@given(st.lists(st.tuples(st.floats(-1e4, 1e4), st.floats(-1e4, 1e4)), min_size=0, max_size=9))
def test_arbitrary_pixel_clouds(pts: list[tuple[float, float]]) -> None:
    px = np.array(pts, dtype=float).reshape(-1, 2)
    call(vsinv.choose_basis, px, _names=("pixels", "points", "collinear"))
    out = call(vsinv.invariant_points, px, basis="auto", _names=("pixels", "points", "collinear", "basis"))
    if returned(out):
        b = vsinv.choose_basis(px)
        np.testing.assert_allclose(out, manual_invariants(px, b), rtol=1e-6, atol=1e-6)


# ---------------------------------------------------------------------------------------------
# Intrinsics, Distortion and lenses


@covers("Intrinsics", "Intrinsics.from_matrix", "Intrinsics.fku", "Intrinsics.fkv", "Intrinsics.u0", "Intrinsics.v0",
        "Intrinsics.skew", "Intrinsics.matrix")
@fuzz_settings(150)
@given(st.data())
def test_intrinsics(data: Any) -> None:
    args = {"fku": 600.0, "fkv": 580.0, "u0": 384.0, "v0": 288.0, "skew": 1.5}
    ref = vsinv.Intrinsics(**args)
    strategies = {k: floats(v) for k, v in args.items()}
    name, v, out = fuzz(data, vsinv.Intrinsics, args, strategies, api="Intrinsics",
                        digest=lambda k: (k.fku, k.fkv, k.u0, k.v0, k.skew))
    if returned(out):
        k = out
        vals = [call(getattr, k, p, _api=f"Intrinsics.{p}") for p in ("fku", "fkv", "u0", "v0", "skew")]
        m = call(getattr, k, "matrix", _api="Intrinsics.matrix")
        fku, fkv, u0, v0, th = vals
        expect = np.array([[fku, -fku / math.tan(th), u0], [0, fkv / math.sin(th), v0], [0, 0, 1]])
        np.testing.assert_allclose(m, expect, rtol=1e-9, atol=1e-9 * max(1.0, abs(fku)))
        back = call(vsinv.Intrinsics.from_matrix, m, _api="Intrinsics.from_matrix", _names=("K",))
        if returned(back):
            np.testing.assert_allclose(back.matrix, m, rtol=1e-9, atol=1e-9 * abs(m).max())
        assert k == vsinv.Intrinsics(fku, fkv, u0, v0, th)
    # from_matrix on every variant of K
    kv = data.draw(k_variants(ref), label="from_matrix")
    if not isinstance(kv.value, vsinv.Intrinsics):
        out = call(vsinv.Intrinsics.from_matrix, kv.value, _api="Intrinsics.from_matrix", _expect=kv.expect,
                   _names=("K",), _where=kv.where)
        if kv.expect == SAME:
            assert out == ref


DIST = np.array([-0.3125, 0.109375, 0.00125, -0.0009765625, -0.015625])
DIST8 = np.array([0.1, -0.05, 0.001, -0.002, 0.01, 0.05, -0.01, 0.002])


def dist_variants() -> st.SearchStrategy[V]:
    bad_lengths = [V(np.zeros(3), INVALID, "3 coefficients"), V(np.zeros(6), INVALID, "6"), V(np.zeros(14), INVALID, "14")]
    return st.one_of(
        st.just(V(vsinv.Distortion(DIST), SAME, "Distortion")),
        arrays(DIST, overrides={"lead_axis": SAME, "extra_axis": SAME, "fewer": ANY, "empty": INVALID, "bool": ANY},
               skip=("object_float",)),
        st.sampled_from(bad_lengths),
    )


@covers("Distortion", "Distortion.model", "Distortion.coefficients")
@fuzz_settings(120)
@given(st.data())
def test_distortion(data: Any) -> None:
    ref = vsinv.Distortion(DIST)
    coeff = data.draw(st.sampled_from([DIST, DIST8, DIST[:4]]))
    model = data.draw(st.sampled_from([None, "plumb_bob", "rational_polynomial", "fisheye", "", 3]))
    strategies = {"coefficients": arrays(coeff, overrides={"lead_axis": ANY, "extra_axis": ANY, "empty": INVALID,
                                                            "fewer": ANY, "bool": ANY, "object_float": INVALID})}
    mexpect = TYPE if model == 3 else (ANY if model in (None, "plumb_bob", "rational_polynomial") else INVALID)
    name, v, out = fuzz(data, vsinv.Distortion, {"coefficients": coeff, "model": None}, strategies, api="Distortion",
                        names={"coefficients": ("coefficients",)})
    out2 = call(vsinv.Distortion, coeff, model, _api="Distortion", _expect=mexpect, _names=("model",))
    for d in (out, out2):
        if returned(d):
            m = call(getattr, d, "model", _api="Distortion.model")
            c = call(getattr, d, "coefficients", _api="Distortion.coefficients")
            assert m in ("plumb_bob", "rational_polynomial") and c.shape == ((5,) if m == "plumb_bob" else (8,))
            assert d == vsinv.Distortion(c, m)
    assert ref == vsinv.Distortion(DIST.tolist())


def cv_distort(px: np.ndarray, k: np.ndarray, d: np.ndarray) -> np.ndarray:
    norm = np.linalg.solve(k, np.column_stack([px, np.ones(len(px))]).T).T
    out, _ = cv2.projectPoints(norm, np.zeros(3), np.zeros(3), k, d)
    return out.reshape(-1, 2)


@covers("distort_points", "undistort_points")
@fuzz_settings(150)
@given(st.data())
def test_distort_undistort(data: Any) -> None:
    px = CUR_PX * 0.5 + 100.0  # inside the calibrated field
    which = data.draw(st.sampled_from(["distort_points", "undistort_points"]))
    fn = getattr(vsinv, which)
    args: dict[str, Any] = {"pixels": px, "K": K, "distortion": vsinv.Distortion(DIST)}
    strategies: dict[str, Any] = {"pixels": arrays(px, overrides={"lead_axis": INVALID}), "K": k_variants(),
                                  "distortion": dist_variants()}
    if which == "undistort_points":
        args.update(tol=1e-10, max_iter=50)
        strategies.update(tol=floats(1e-10, overrides={"negative": INVALID, "neginf": INVALID}), max_iter=ints(50))
    ref = fn(**args)
    if which == "distort_points":
        np.testing.assert_allclose(ref, cv_distort(px, K.matrix, DIST), rtol=1e-9, atol=1e-6)
    else:
        np.testing.assert_allclose(vsinv.distort_points(ref, K, DIST), px, atol=1e-6)
    fuzz(data, fn, args, strategies, names={"distortion": ("distortion", "coefficients")}, ref=ref, rtol=1e-12,
         check=lambda out: out.shape[1:] == (2,) or pytest.fail(str(out.shape)))


@covers("distort_points", "undistort_points")
@fuzz_settings(60)
@given(st.lists(st.tuples(st.floats(0, 640), st.floats(0, 480)), min_size=1, max_size=6),
       st.lists(st.floats(-0.2, 0.2), min_size=5, max_size=5))
def test_distortion_round_trip_against_opencv(pts: list[tuple[float, float]], coeffs: list[float]) -> None:
    px = np.array(pts)
    k = vsinv.Intrinsics(800.0, 790.0, 320.0, 240.0)
    d = np.array(coeffs) * np.array([1.0, 1.0, 0.05, 0.05, 1.0])
    dist = call(vsinv.distort_points, px, k, d, _names=("point", "distortion"))
    if not returned(dist):
        assert "point" in str(dist)
        return
    np.testing.assert_allclose(dist, cv_distort(px, k.matrix, d), rtol=1e-9, atol=1e-6)
    back = call(vsinv.undistort_points, dist, k, d, _names=("point", "distortion"))
    if returned(back):
        np.testing.assert_allclose(back, px, atol=1e-6)


CAL_FIXTURES = Path(__file__).parent / "fixtures" / "calibration"
CAL_FILES = sorted(p for p in CAL_FIXTURES.iterdir() if p.suffix in (".yaml", ".xml"))
CAL_TOKENS = ["nan", ".nan", "-1", "0", "1e300", "abc", "", "[]", "[1, 2]", "-.inf", "!!binary", "<", "]", ":", "\x00"]


@st.composite
def mutated_text(draw: Any, text: str) -> tuple[str, str]:
    kind = draw(st.sampled_from(["same", "number", "delete_line", "truncate", "token", "garbage", "empty", "dup_line"]))
    lines = text.splitlines(keepends=True)
    if kind == "same":
        return kind, text
    if kind == "number":
        nums = list(re.finditer(r"-?\d+(\.\d*)?(e-?\d+)?", text))
        m = draw(st.sampled_from(nums))
        return kind, text[: m.start()] + draw(st.sampled_from(CAL_TOKENS)) + text[m.end():]
    if kind == "delete_line":
        i = draw(st.integers(0, len(lines) - 1))
        return kind, "".join(lines[:i] + lines[i + 1:])
    if kind == "dup_line":
        i = draw(st.integers(0, len(lines) - 1))
        return kind, "".join(lines[: i + 1] + lines[i:])
    if kind == "truncate":
        return kind, text[: draw(st.integers(0, len(text)))]
    if kind == "token":
        i = draw(st.integers(0, len(text)))
        return kind, text[:i] + draw(st.sampled_from(CAL_TOKENS)) + text[i:]
    if kind == "garbage":
        return kind, draw(st.text(max_size=60))
    return kind, ""


@covers("load_calibration", "Calibration", "Calibration.intrinsics", "Calibration.distortion", "Calibration.image_size")
@fuzz_settings(150)
@given(data=st.data())
def test_load_calibration(tmp_path_factory: Any, data: Any) -> None:
    src = data.draw(st.sampled_from(CAL_FILES), label="file")
    kind, text = data.draw(mutated_text(src.read_text()), label="mutation")
    path = tmp_path_factory.mktemp("cal") / src.name
    path.write_text(text, encoding="utf-8", errors="surrogateescape")
    as_type = data.draw(st.sampled_from([str, Path]))
    out = call(vsinv.load_calibration, as_type(path), _expect=RETURN if kind == "same" else ANY,
               _names=(src.name, "calibration"))
    if returned(out):
        assert isinstance(out, vsinv.Calibration)
        k = call(getattr, out, "intrinsics", _api="Calibration.intrinsics")
        d = call(getattr, out, "distortion", _api="Calibration.distortion")
        w, h = call(getattr, out, "image_size", _api="Calibration.image_size")
        assert isinstance(k, vsinv.Intrinsics) and isinstance(d, vsinv.Distortion)
        assert w > 0 and h > 0 and k.fku > 0 and k.fkv > 0
    for bad, expect in [(tmp_path_factory.getbasetemp(), ANY), ("/nonexistent/cal.yaml", RAISE), (None, TYPE), (3, TYPE),
                        ("", RAISE)]:
        call(vsinv.load_calibration, bad, _expect=expect, _names=("calibration", "path", str(bad)))


# ---------------------------------------------------------------------------------------------
# SE(3) helpers


def rodrigues(tu: np.ndarray) -> np.ndarray:
    r, _ = cv2.Rodrigues(np.asarray(tu, dtype=float).reshape(3, 1))
    return r


@covers("exp_twist", "pose_from_position_thetau", "thetau_from_pose")
@fuzz_settings(150)
@given(st.data())
def test_se3_round_trips(data: Any) -> None:
    which = data.draw(st.sampled_from(["exp_twist", "pose_from_position_thetau", "thetau_from_pose"]))
    twist = np.array([0.1, -0.2, 0.05, 0.3, -0.1, 0.2])
    position, thetau = np.array([0.2, -0.1, 0.5]), np.array([0.3, -0.4, 1.2])
    p0 = vsinv.pose_from_position_thetau(position, thetau)
    if which == "exp_twist":
        args: dict[str, Any] = {"twist": twist, "dt": 0.5}
        strategies = {"twist": arrays(twist, overrides={"flat": SAME}), "dt": floats(0.5)}
    elif which == "pose_from_position_thetau":
        args = {"position": position, "thetau": thetau}
        strategies = {"position": arrays(position), "thetau": arrays(thetau)}
    else:
        args = {"pose": p0}
        bad_rot = p0.copy()
        bad_rot[:3, :3] *= 2.0
        bad_row = p0.copy()
        bad_row[3] = [0.0, 0.0, 1.0, 1.0]
        strategies = {"pose": st.one_of(arrays(p0, overrides={"zero": INVALID, "negative": INVALID, "fewer": INVALID,
                                                                  "empty": INVALID, "flat": INVALID, "huge": INVALID,
                                                                  "bool": INVALID, "tiny": INVALID, "float32": ANY}),
                                        st.sampled_from([V(bad_rot, INVALID, "scaled rotation"), V(bad_row, INVALID, "last row")]))}
    fn = getattr(vsinv, which)
    ref = fn(**args)
    name, v, out = fuzz(data, fn, args, strategies, ref=ref, rtol=1e-12)
    if not returned(out):
        return
    if which == "exp_twist":
        assert out.shape == (4, 4) and np.allclose(out[3], [0, 0, 0, 1])
        r = out[:3, :3]
        np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-9)
        tw = np.asarray(v.value if name == "twist" else twist, dtype=float).ravel()
        dt = float(v.value) if name == "dt" else 0.5
        if np.abs(tw * dt).max() < 1e3:
            np.testing.assert_allclose(r, rodrigues(tw[3:] * dt), atol=1e-9)
    elif which == "pose_from_position_thetau":
        pos = np.asarray(v.value if name == "position" else position, dtype=float)
        tu = np.asarray(v.value if name == "thetau" else thetau, dtype=float)
        np.testing.assert_allclose(out[:3, 3], pos, rtol=1e-15)
        if np.linalg.norm(tu) < 1e6:
            np.testing.assert_allclose(out[:3, :3], rodrigues(tu), atol=1e-9)
        if 1e-6 < np.linalg.norm(tu) < math.pi - 1e-6 and np.abs(pos).max() < 1e100:
            p, t = vsinv.thetau_from_pose(out)
            np.testing.assert_allclose(t, tu, atol=1e-9)
    else:
        p, t = out
        assert p.shape == (3,) and t.shape == (3,) and np.linalg.norm(t) <= math.pi + 1e-12


@covers("exp_twist", "thetau_from_pose", "pose_from_position_thetau")
@fuzz_settings(80)
@given(st.lists(st.floats(-3, 3), min_size=6, max_size=6), st.floats(-2, 2))
def test_exp_twist_composes(tw: list[float], dt: float) -> None:
    t = np.array(tw)
    a = call(vsinv.exp_twist, t, dt)
    b = call(vsinv.exp_twist, t, -dt)
    np.testing.assert_allclose(a @ b, np.eye(4), atol=1e-9)
    p, tu = call(vsinv.thetau_from_pose, a)
    back = call(vsinv.pose_from_position_thetau, p, tu)
    np.testing.assert_allclose(back, a, atol=1e-9)


# ---------------------------------------------------------------------------------------------
# controllers


def controller_kwargs(cls: type) -> tuple[dict[str, Any], dict[str, st.SearchStrategy[V]]]:
    speed = floats(0.25, overrides={"none": SAME, "nan": RAISE, "negative": INVALID, "zero": INVALID, "neghuge": INVALID,
                                    "neginf": INVALID})
    adaptive_bad = [((1.0, 2.0), INVALID), ((1.0, 2.0, 3.0, 4.0), INVALID), (("a", 1.0, 1.0), TYPE), ((np.nan, 1.0, 1.0), INVALID),
                    ((0.4, 4.0, 30.0), ANY), ((-1.0, 0.4, 30.0), INVALID), ("abc", TYPE), (1.0, TYPE)]
    adaptive = st.one_of(st.just(V((4.0, 0.4, 30.0), RETURN, "good")), st.just(V(None, RETURN, "none")),
                         st.sampled_from([V(x, e, repr(x)) for x, e in adaptive_bad]))
    common = {
        "reference_pixels": pixel_variants(REF_PX, overrides={"fewer": ANY, "empty": RAISE, "negative": ANY}),
        "K_hat": k_variants(KSTAR),
        "gain": floats(1.0, overrides={"zero": INVALID, "negative": INVALID, "neghuge": INVALID, "neginf": INVALID}),
        "adaptive_gain": adaptive,
        "max_linear_speed": speed,
        "max_angular_speed": speed,
    }
    args = {"reference_pixels": REF_PX, "K_hat": KSTAR, "gain": 1.0, "adaptive_gain": None, "max_linear_speed": None,
            "max_angular_speed": None}
    if cls is vsinv.InvariantController:
        args.update(gain_rz=1.0, basis=(0, 1, 2), feedforward=True, min_structure_ratio=1e-3, rz_task="angle")
        common.update(gain_rz=common["gain"], basis=basis_variants(N),
                      feedforward=choices([True, False, np.bool_(True)], ["yes", None, 2.5, 1, 0], TYPE),
                      min_structure_ratio=floats(1e-3, overrides={"none": TYPE}),
                      rz_task=choices(["angle", "tau21"], ["tau", "", "ANGLE"]) )
    else:
        args.update(interaction="current", reference_depths=None)
        common.update(interaction=st.one_of(choices(["current"], ["sideways", "", "Current"]),
                                            st.sampled_from([V("desired", RAISE, "desired without depths"),
                                                             V("mean", RAISE, "mean without depths")])),
                      reference_pixels=pixel_variants(REF_PX, ANY, overrides={"fewer": ANY, "empty": RAISE, "negative": ANY,
                                                                              "zero": ANY, "bool": ANY}),
                      reference_depths=depth_variants(REF_Z, {k: ANY for k in ("none", "valid", "list", "strided", "readonly", "flat")}))
    return args, common


@covers("InvariantController", "IbvsController")
@fuzz_settings(200)
@given(st.data())
def test_controller_constructors(data: Any) -> None:
    cls = data.draw(st.sampled_from([vsinv.InvariantController, vsinv.IbvsController]))
    args, strategies = controller_kwargs(cls)
    name, v, out = fuzz(data, cls, args, strategies, api=cls.__name__,
                        names={"K_hat": ("K_hat", "intrinsics"), "adaptive_gain": ("adaptive_gain", "at_zero", "at_infinity", "slope")})
    if returned(out):
        tw = call(out.step, CUR_PX, CUR_Z, _api=f"{cls.__name__}.step", _names=("pixels", "depths"))
        if returned(tw):
            assert tw.shape == (6,)


def step_args(visible: bool, degenerate_expect: str) -> tuple[dict[str, Any], dict[str, st.SearchStrategy[V]]]:
    args: dict[str, Any] = {"pixels": CUR_PX, "depths": CUR_Z}
    strategies: dict[str, Any] = {
        "pixels": pixel_variants(CUR_PX, degenerate_expect,
                                 overrides={"fewer": INVALID, "empty": INVALID, "zero": degenerate_expect, "bool": degenerate_expect}),
        "depths": depth_variants(CUR_Z),
    }
    if visible:
        ones = np.ones(N, bool)
        args["visible"] = ones
        strategies["visible"] = st.one_of(
            st.sampled_from([V(ones, SAME, "all"), V(ones.tolist(), SAME, "list"), V(np.ones(2 * N, bool)[::2], SAME, "strided")]),
            st.sampled_from([V(np.ones(N, int), INVALID, "int"), V(np.ones(N - 1, bool), INVALID, "short"),
                             V(np.ones((N, 1), bool), INVALID, "2-d"), V(None, INVALID, "none"), V("abc", INVALID, "str"),
                             V(np.zeros(N, bool), RAISE, "none visible"), V(np.arange(N) > 8, RAISE, "three visible")]),
        )
    return args, strategies


def controller(cls: type) -> Any:
    if cls is vsinv.InvariantController:
        return vsinv.InvariantController(REF_PX, KSTAR)
    return vsinv.IbvsController(REF_PX, KSTAR)


@covers("InvariantController.step", "InvariantController.step_visible", "IbvsController.step", "IbvsController.step_visible")
@fuzz_settings(250)
@given(st.data())
def test_controller_steps(data: Any) -> None:
    cls = data.draw(st.sampled_from([vsinv.InvariantController, vsinv.IbvsController]))
    visible = data.draw(st.booleans())
    ctl = controller(cls)
    fn = ctl.step_visible if visible else ctl.step
    args, strategies = step_args(visible, RAISE if cls is vsinv.InvariantController else ANY)
    ref = fn(**args)
    if visible:
        assert_same(ref, ctl.step(CUR_PX, CUR_Z), rtol=1e-12)
    fuzz(data, fn, args, strategies, ref=ref, rtol=1e-12, check=lambda tw: tw.shape == (6,) or pytest.fail(str(tw.shape)),
         names={"pixels": ("pixels", "points", "visible")})


@covers("InvariantController.step_visible", "IbvsController.step_visible")
@fuzz_settings(60)
@given(st.data())
def test_hidden_points_may_be_nan(data: Any) -> None:
    cls = data.draw(st.sampled_from([vsinv.InvariantController, vsinv.IbvsController]))
    ctl = controller(cls)
    hidden = data.draw(st.lists(st.sampled_from([3, 4, 5, 6, 7, 8, 9, 10, 11]), max_size=3, unique=True))
    vis = np.ones(N, bool)
    vis[hidden] = False
    px, z = CUR_PX.copy(), CUR_Z.copy()
    px[hidden] = data.draw(st.sampled_from([np.nan, np.inf, -1e300]))
    z[hidden] = data.draw(st.sampled_from([np.nan, -1.0, 0.0]))
    tw = call(ctl.step_visible, px, z, vis)  # fewer points may leave a degenerate structure
    assert returned(tw) or isinstance(tw, vsinv.DegenerateGeometry), tw
    if returned(tw):
        assert tw.shape == (6,)


@covers("InvariantController.set_k_hat", "InvariantController.set_reference", "InvariantController.converged",
        "InvariantController.k_hat", "InvariantController.basis", "InvariantController.reference_invariants",
        "InvariantController.eps", "InvariantController.eps_z", "InvariantController.invariant_error",
        "InvariantController.tau_11", "InvariantController.tau_21", "InvariantController.tau_22",
        "InvariantController.t_matrix", "InvariantController.last_gain", "InvariantController.saturation",
        "IbvsController.pixel_error", "IbvsController.last_gain", "IbvsController.saturation")
@fuzz_settings(150)
@given(st.data())
def test_controller_state(data: Any) -> None:
    inv = controller(vsinv.InvariantController)
    ibvs = controller(vsinv.IbvsController)
    state = ["eps", "eps_z", "invariant_error", "tau_11", "tau_21", "tau_22", "t_matrix", "last_gain", "saturation"]
    # before a step: NotReady (invariant law) or None (IBVS)
    for p in state:
        call(getattr, inv, p, _api=f"InvariantController.{p}", _expect=RAISE)
        assert isinstance(getattr_or_exc(inv, p), vsinv.NotReady)
    for p in ("pixel_error", "last_gain", "saturation"):
        assert call(getattr, ibvs, p, _api=f"IbvsController.{p}", _expect=RETURN) is None
    assert call(inv.converged, _expect=RETURN) is False
    assert call(getattr, inv, "basis", _api="InvariantController.basis") == (0, 1, 2)
    s_star = call(getattr, inv, "reference_invariants", _api="InvariantController.reference_invariants")
    assert s_star.shape == (N - 3, 3)
    np.testing.assert_allclose(s_star, np.delete(manual_invariants(REF_PX, (0, 1, 2)), [0, 1, 2], axis=0), atol=1e-9)
    assert call(getattr, inv, "k_hat", _api="InvariantController.k_hat") == KSTAR
    # set_k_hat and set_reference with corrupted arguments
    what = data.draw(st.sampled_from(["set_k_hat", "set_reference", "converged"]))
    if what == "set_k_hat":
        fuzz(data, inv.set_k_hat, {"K_hat": K}, {"K_hat": k_variants(K)}, names={"K_hat": ("K_hat", "intrinsics")})
    elif what == "set_reference":
        rate = np.zeros_like(s_star)
        fuzz(data, inv.set_reference, {"s_star": s_star, "rate": rate},
             {"s_star": arrays(s_star, overrides={"zero": INVALID, "negative": INVALID, "fewer": INVALID, "empty": INVALID,
                                                  "huge": INVALID, "tiny": INVALID, "bool": INVALID, "float32": ANY}),
              "rate": st.one_of(arrays(rate, overrides={"fewer": INVALID, "empty": INVALID, "none": SAME, "bool": ANY}),
                                st.just(V(None, SAME, "none")))})
    else:
        fuzz(data, inv.converged, {"invariant_tol": 1e-4, "tau21_tol": 1e-4},
             {"invariant_tol": floats(1e-4, overrides={"nan": ANY}), "tau21_tol": floats(1e-4, overrides={"nan": ANY})})
    # after a step: every state property is finite
    tw = call(inv.step, CUR_PX, CUR_Z, _expect=ANY)
    if returned(tw):
        for p in state:
            call(getattr, inv, p, _api=f"InvariantController.{p}", _expect=RETURN)
        t = inv.t_matrix
        assert t.shape == (3, 3) and inv.eps.shape == (5,)
        assert math.isclose(inv.tau_11, t[0, 0]) and math.isclose(inv.tau_21, t[1, 0]) and math.isclose(inv.tau_22, t[1, 1])
    call(ibvs.step, CUR_PX, CUR_Z, _expect=RETURN)
    for p in ("pixel_error", "last_gain", "saturation"):
        x = call(getattr, ibvs, p, _api=f"IbvsController.{p}", _expect=RETURN)
        assert isinstance(x, float)
    rms = math.sqrt(np.mean(np.sum((CUR_PX - REF_PX) ** 2, axis=1)))
    assert math.isclose(ibvs.pixel_error, rms, rel_tol=1e-9) or math.isclose(ibvs.pixel_error, np.sqrt(np.mean((CUR_PX - REF_PX) ** 2)), rel_tol=1e-9)


def getattr_or_exc(obj: Any, name: str) -> Any:
    try:
        return getattr(obj, name)
    except Exception as exc:  # noqa: BLE001
        return exc


@covers("InvariantController", "IbvsController")
def test_controllers_pickle() -> None:
    import pickle

    for cls in (vsinv.InvariantController, vsinv.IbvsController):
        ctl = controller(cls)
        copy = call(pickle.loads, pickle.dumps(ctl), _api=f"{cls.__name__}.__reduce__", _expect=RETURN)
        assert_same(copy.step(CUR_PX, CUR_Z), ctl.step(CUR_PX, CUR_Z))


# ---------------------------------------------------------------------------------------------
# stability


@covers("check_stability", "StabilityReport", "StabilityReport.prop1", "StabilityReport.prop2", "StabilityReport.sigma",
        "StabilityReport.eigenvalues", "StabilityReport.tracking_bound", "tracking_bound")
@fuzz_settings(150)
@given(st.data())
def test_stability(data: Any) -> None:
    which = data.draw(st.sampled_from(["check_stability", "tracking_bound", "report"]))
    if which == "check_stability":
        sched = np.stack([K.matrix, lens(500.0).matrix])
        khat = st.one_of(k_variants(KSTAR).filter(lambda v: v.label not in ("negative focal", "negative")),
                         st.just(V(np.diag([-600.0, 600.0, 1.0]), RETURN, "negative focal: any signs")))
        one = k_variants(K).map(lambda v: V(v.value, ANY, v.label) if v.label == "lead_axis" else v)  # (1, 3, 3): a schedule
        kvar = st.one_of(one, arrays(sched, overrides={"zero": INVALID, "negative": INVALID, "fewer": ANY, "empty": ANY,
                                                                   "flat": INVALID, "bool": ANY, "tiny": ANY, "lead_axis": INVALID}),
                         st.just(V([K, lens(500.0)], RETURN, "list of Intrinsics")))
        fuzz(data, vsinv.check_stability, {"K": K, "K_hat": KSTAR, "kappa": 1.0, "gain": 1.0},
             {"K": kvar, "K_hat": khat, "kappa": floats(1.0), "gain": floats(1.0)},
             names={"K": ("K", "intrinsics"), "K_hat": ("K_hat", "intrinsics")},
             check=lambda r: isinstance(r, vsinv.StabilityReport) or pytest.fail(repr(r)))
    elif which == "tracking_bound":
        ref = vsinv.tracking_bound(1.0, 0.5, 0.1)
        assert math.isclose(ref, 2 * 0.1 / (1.0 * 0.5))
        args = {"gain": 1.0, "sigma": 0.5, "max_b": 0.1}
        name, v, out = fuzz(data, vsinv.tracking_bound, args,
                            {"gain": floats(1.0), "sigma": floats(0.5), "max_b": floats(0.1)}, ref=ref, rtol=1e-15, finite=False)
        if returned(out):  # documented: +inf when sigma <= 0 (no bound), else 2 max_b / (gain sigma)
            kw = {**args, name: float(v.value)}
            assert out >= 0 and not math.isnan(out)
            if kw["sigma"] <= 0:
                assert out == math.inf
            else:
                with np.errstate(all="ignore"):
                    expect = np.float64(2.0) * kw["max_b"] / (np.float64(kw["gain"]) * kw["sigma"])
                assert math.isclose(out, expect, rel_tol=1e-12) or (math.isinf(out) and not np.isfinite(expect))
    else:
        same = vsinv.check_stability(K, K)
        assert call(getattr, same, "prop1", _api="StabilityReport.prop1") is True
        assert call(getattr, same, "prop2", _api="StabilityReport.prop2") is True
        sigma = call(getattr, same, "sigma", _api="StabilityReport.sigma")
        eig = call(getattr, same, "eigenvalues", _api="StabilityReport.eigenvalues")
        assert eig.shape == (5,) and eig.dtype == np.complex128 and (eig.real > 0).all()
        sched = vsinv.check_stability([K, lens(500.0)], KSTAR)
        assert call(getattr, sched, "eigenvalues", _api="StabilityReport.eigenvalues").shape == (2, 5)
        v = data.draw(floats(0.1, overrides={"nan": RAISE}), label="max_b")
        out = call(same.tracking_bound, v.value, _expect=v.expect, _names=("max_b",))
        if returned(out) and v.expect == SAME:
            assert math.isclose(out, 2 * 0.1 / sigma)


# ---------------------------------------------------------------------------------------------
# planning and depths


@covers("estimate_plane_parallax", "PlaneParallax", "PlaneParallax.gamma", "PlaneParallax.epipole", "PlaneParallax.mu_e",
        "PlaneParallax.gamma_k", "PlaneParallax.residual", "PlaneParallax.candidates")
@fuzz_settings(120)
@given(st.data())
def test_plane_parallax(data: Any) -> None:
    args = {"current_pixels": CUR_PX, "reference_pixels": REF_PX, "basis": (0, 1, 2)}
    over = {"fewer": RAISE, "negative": ANY}
    digest = lambda p: (p.gamma, p.epipole, p.mu_e, p.gamma_k, p.residual)  # noqa: E731
    ref = vsinv.estimate_plane_parallax(**args)
    name, v, out = fuzz(data, vsinv.estimate_plane_parallax, args,
                        {"current_pixels": pixel_variants(CUR_PX, overrides=over),
                         "reference_pixels": pixel_variants(REF_PX, overrides=over), "basis": basis_variants(N)},
                        digest=digest, ref=ref, rtol=1e-9)
    if returned(out):
        for p in ("gamma", "epipole", "mu_e", "gamma_k", "residual", "candidates"):
            call(getattr, out, p, _api=f"PlaneParallax.{p}", _expect=RETURN)
        m = len(out.gamma_k)
        assert out.gamma.shape == (3,) and out.mu_e.shape == (m, 3) and out.candidates >= 1
        assert math.isclose(np.linalg.norm(out.epipole), 1.0, rel_tol=1e-9)


@covers("InvariantPath", "InvariantPath.duration", "InvariantPath.plane_parallax", "InvariantPath.sample")
@fuzz_settings(120)
@given(st.data())
def test_invariant_path(data: Any) -> None:
    args = {"current_pixels": CUR_PX, "reference_pixels": REF_PX, "duration": 10.0, "basis": (0, 1, 2)}
    over = {"fewer": RAISE, "negative": ANY}
    name, v, out = fuzz(data, vsinv.InvariantPath, args,
                        {"current_pixels": pixel_variants(CUR_PX, overrides=over),
                         "reference_pixels": pixel_variants(REF_PX, overrides=over), "basis": basis_variants(N),
                         "duration": floats(10.0, overrides={"zero": INVALID, "negative": INVALID, "neghuge": INVALID,
                                                             "neginf": INVALID, "posinf": INVALID})},
                        api="InvariantPath", digest=lambda p: p.duration)
    path = out if returned(out) else vsinv.InvariantPath(**args)
    assert call(getattr, path, "duration", _api="InvariantPath.duration") > 0
    assert isinstance(call(getattr, path, "plane_parallax", _api="InvariantPath.plane_parallax"), vsinv.PlaneParallax)
    t = data.draw(floats(5.0, overrides={"posinf": INVALID, "neginf": INVALID, "huge": ANY}), label="t")
    res = call(path.sample, t.value, _expect=RETURN if t.expect == SAME else t.expect, _names=("t",))
    if returned(res):
        q, dq = res
        assert q.shape == dq.shape == (N - 3, 3)
    if returned(out) and v.expect == SAME:  # the end of the path is the reference image
        q, _ = path.sample(path.duration)
        np.testing.assert_allclose(q, np.delete(manual_invariants(REF_PX, (0, 1, 2)), [0, 1, 2], axis=0), atol=1e-8)


@covers("depths_from_translation")
@fuzz_settings(120)
@given(st.data())
def test_depths_from_translation(data: Any) -> None:
    args = {"first_pixels": FIRST_PX, "second_pixels": TRANS_PX}
    ref = vsinv.depths_from_translation(**args)
    z, e, res = ref
    np.testing.assert_allclose(z / z.mean(), FIRST_Z / FIRST_Z.mean(), rtol=1e-6)
    over = {"fewer": RAISE, "negative": ANY, "zero": ANY, "bool": ANY}

    def check(out: Any) -> None:
        z, e, r = out
        assert z.shape == (len(z),) and e.shape == (3,) and (z > 0).all() and r >= 0

    fuzz(data, vsinv.depths_from_translation, args,
         {"first_pixels": pixel_variants(FIRST_PX, ANY, overrides=over), "second_pixels": pixel_variants(TRANS_PX, ANY, overrides=over)},
         ref=ref, rtol=1e-9, check=check)


@covers("ResectionDepths", "ResectionDepths.estimate")
@fuzz_settings(150)
@given(st.data())
def test_resection_depths(data: Any) -> None:
    rz = FIRST_Z / FIRST_Z.mean()
    args = {"first_pixels": FIRST_PX, "first_depths": rz, "reference_pixels": REF_PX, "reference_mean_depth": 1.0}
    over = {"fewer": RAISE, "negative": ANY}
    name, v, out = fuzz(data, vsinv.ResectionDepths, args,
                        {"first_pixels": pixel_variants(FIRST_PX, ANY, overrides=over), "first_depths": depth_variants(rz),
                         "reference_pixels": pixel_variants(REF_PX, ANY, overrides=over),
                         "reference_mean_depth": floats(1.0, overrides={"zero": INVALID, "negative": INVALID,
                                                                        "neghuge": INVALID, "neginf": INVALID,
                                                                        "posinf": INVALID})},
                        api="ResectionDepths", names={"first_depths": ("first_depths", "depths", "point")})
    est = vsinv.ResectionDepths(**args)
    ref = est.estimate(CUR_PX)
    np.testing.assert_allclose(ref / ref.mean(), CUR_Z / CUR_Z.mean(), rtol=1e-6)
    ones = np.ones(N, bool)
    fuzz(data, est.estimate, {"pixels": CUR_PX, "visible": None},
         {"pixels": pixel_variants(CUR_PX, ANY, overrides={"fewer": INVALID, "empty": INVALID}),
          "visible": st.sampled_from([V(None, SAME, "none"), V(ones.tolist(), SAME, "list"), V(ones, SAME, "array"),
                                      V(np.ones(2 * N, bool)[::2], SAME, "strided"), V(ones[:5], INVALID, "short"),
                                      V(np.arange(N) < 3, RAISE, "three"), V("abc", INVALID, "str"),
                                      V(np.ones(N, int), INVALID, "int")])},
         ref=ref, rtol=1e-6, check=lambda z: z.shape == (N,) or pytest.fail(str(z.shape)))


# ---------------------------------------------------------------------------------------------
# scenarios and runs

BASE = vsinv.load_scenario("lens-12-12").to_dict()
BASE["stop"]["max_iterations"] = 4
VISION = vsinv.load_scenario("vision-12-12").to_dict()
VISION["stop"]["max_iterations"] = 2
BUILTINS = [n for n, _ in vsinv.list_scenarios()]
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


@covers("Scenario", "Scenario.from_dict", "Scenario.from_toml", "Scenario.name", "Scenario.description", "Scenario.to_dict",
        "Scenario.to_toml", "load_scenario", "list_scenarios")
@fuzz_settings(200)
@given(st.data())
def test_scenarios(data: Any) -> None:
    names = call(vsinv.list_scenarios, _expect=RETURN)
    assert names and all(isinstance(n, str) and isinstance(t, str) for n, t in names)
    d, path = data.draw(mutated_scenario(BASE), label="mutation")
    # which names may the message give: the mutated key's segments (the last one, usually)
    s = call(vsinv.Scenario.from_dict, d, _api="Scenario.from_dict", _names=scenario_names(path),
             _expect=RETURN if path is None else ANY)
    how = data.draw(st.sampled_from(["dict", "toml", "load", "file", "name"]))
    if how == "toml" and returned(s):
        text = call(s.to_toml, _api="Scenario.to_toml", _expect=RETURN)
        back = call(vsinv.Scenario.from_toml, text, _api="Scenario.from_toml", _expect=RETURN)
        assert back.to_dict() == s.to_dict()
        # and mutated TOML text
        _, bad = data.draw(mutated_text(text), label="toml mutation")
        call(vsinv.Scenario.from_toml, bad, _api="Scenario.from_toml", _names=("scenario",))
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
    call(vsinv.Scenario.from_toml, 3, _api="Scenario.from_toml", _expect=TYPE, _names=("text",))
    call(vsinv.Scenario.from_dict, "abc", _api="Scenario.from_dict", _expect=ANY, _names=("scenario",))
    if returned(s):
        assert isinstance(call(getattr, s, "name", _api="Scenario.name"), str)
        assert isinstance(call(getattr, s, "description", _api="Scenario.description"), str)
        dd = call(s.to_dict, _api="Scenario.to_dict", _finite=False)
        again = vsinv.Scenario.from_dict(dd).to_dict()
        assert again == dd, [(k, dd[k], again.get(k)) for k in dd if dd[k] != again.get(k)]


# The columns every run records, from their declaration.
RUN_ARRAYS = tuple(c["name"] for c in vsinv.recorded_columns() if c["recorded"] == "always")


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
    assert isinstance(call(getattr, r, "scenario", _api="RunResult.scenario"), vsinv.Scenario)
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


@covers("recorded_columns", "summary_fields", "RunResult.columns", "RunResult.plot")
@fuzz_settings(10)
@given(kind=st.sampled_from([*vsinv.plots.PLOTS, "nope", "", None, 3, b"errors"]),
       ax=st.sampled_from([None, "axes", "two", "three", 3]))
def test_run_result_schema_and_plot(kind: Any, ax: Any) -> None:
    vsinv.plots._use_agg()
    import matplotlib.pyplot as plt

    run = lens_run()
    columns = call(vsinv.recorded_columns, _finite=False)
    assert tuple(columns) == call(getattr, vsinv.RunResult, "columns", _api="RunResult.columns", _finite=False)
    assert {f["name"] for f in call(vsinv.summary_fields, _finite=False)} <= set(run.summary)
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
            batch.append(vsinv.Scenario.from_dict(BASE))
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
    out = call(vsinv.run_batch, batch, threads=threads.value, _expect=expect, _names=names, _finite=False)
    if returned(out):
        assert all(len(c) == len(batch) for c in out.values())
        ok = out["status"] != "error"
        for k in ("final_translation_error_mm", "final_rotation_error_deg"):
            assert np.isfinite(out[k][ok]).all()
    call(vsinv.run_batch, 3, _expect=TYPE, _names=("scenarios", "iterable"))


# ---------------------------------------------------------------------------------------------
# images


def image_variants(valid: np.ndarray) -> st.SearchStrategy[V]:
    h, w = valid.shape
    return st.sampled_from([
        V(valid, SAME, "valid"),
        V(np.asfortranarray(valid), SAME, "fortran"),
        V(np.repeat(valid, 2, axis=1)[:, ::2], SAME, "strided"),
        V(valid.astype(np.int64), INVALID, "int64"),
        V(valid.astype(np.float64), INVALID, "float64"),
        V(valid.astype(np.uint16), INVALID, "uint16"),
        V(np.stack([valid] * 3, axis=-1), INVALID, "colour"),
        V(valid.ravel(), INVALID, "1-d"),
        V(valid.tolist(), INVALID, "list"),
        V(None, INVALID, "none"),
        V("abc", INVALID, "str"),
        V(np.zeros((0, w), np.uint8), INVALID, "empty"),
        V(np.zeros((h, 0), np.uint8), INVALID, "no columns"),
        V(np.zeros((1, 1), np.uint8), ANY, "1x1"),
        V(np.zeros_like(valid), ANY, "black"),
        V(np.full_like(valid, 255), ANY, "white"),
        V(valid[: h // 2], ANY, "half"),
        V(valid.astype(object), INVALID, "object"),
        V(valid.view(np.int8), INVALID, "int8"),
    ])


IMG_LOCK: dict[str, Any] = {}


def rendered() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if "view" not in IMG_LOCK:
        IMG_LOCK["view"] = vsinv.render_view(VISION)
    return IMG_LOCK["view"]


@covers("render", "render_view")
@fuzz_settings(40)
@given(st.data())
def test_render(data: Any) -> None:
    fn = data.draw(st.sampled_from([vsinv.render, vsinv.render_view]))
    p0 = vsinv.pose_from_position_thetau([0.02, -0.01, -0.05], [0.05, -0.02, 0.1])
    scen = dict(VISION)
    size = data.draw(st.sampled_from([None, (64, 48), (1, 1), (0, 48), (-5, 48), (70000, 10), (12.5, 48), ("a", 48)]))
    if size is not None:
        scen = json.loads(json.dumps(VISION))
        for cam in ("reference_camera", "camera"):
            if scen.get(cam):
                scen[cam]["width"], scen[cam]["height"] = size
    valid_size = size is None or (isinstance(size[0], (int, float)) and 1 <= size[0] <= 65536)  # sizes are real numbers
    args = {"scenario": scen, "pose": p0, "time": 0.0, "reference": False}
    pose_over = {"zero": INVALID, "negative": INVALID, "fewer": INVALID, "empty": INVALID, "flat": INVALID, "huge": INVALID,
                 "bool": INVALID, "tiny": INVALID, "none": ANY, "float32": ANY}  # None: the start pose
    strategies = {"pose": arrays(p0, overrides=pose_over),
                  "time": floats(0.0, overrides={"negative": INVALID, "neghuge": INVALID, "neginf": INVALID, "posinf": INVALID}),
                  "reference": choices([True, False, np.bool_(True)], ["yes", None, 0], TYPE),
                  "scenario": st.sampled_from([V(scen, SAME, "dict"), V("vision-12-12", ANY, "name"), V("lens-12-12", ANY, "no vision"),
                                               V("nope", INVALID, "unknown"), V(None, INVALID, "none"), V(3, INVALID, "int")])}

    def check(out: Any) -> None:
        image = out[0] if isinstance(out, tuple) else out
        assert image.dtype == np.uint8 and image.ndim == 2 and image.flags.c_contiguous
        if isinstance(out, tuple):
            _, px, vis = out
            assert px.shape == (len(vis), 2) and vis.dtype == np.bool_

    if not valid_size:
        call(fn, **args, _expect=INVALID, _names=("width", "height", "camera"))
        return
    ref = fn(**args)
    fuzz(data, fn, args, strategies, ref=ref, check=check, finite=False,
         digest=lambda o: o if isinstance(o, np.ndarray) else o[0])
    if size is None and fn is vsinv.render_view:
        image, px, vis = ref
        h, w = image.shape
        inside = (px[:, 0] >= 0) & (px[:, 0] < w) & (px[:, 1] >= 0) & (px[:, 1] < h)
        assert (vis <= inside).all()


@covers("detect_dots", "Dots", "Dots.centroids", "Dots.areas", "Dots.bboxes")
@fuzz_settings(100)
@given(st.data())
def test_detect_dots(data: Any) -> None:
    image, px, vis = rendered()
    ref = vsinv.detect_dots(image)
    assert len(ref) == int(vis.sum())
    args = {"image": image, "threshold": None, "min_area": 4, "max_area": None}
    digest = lambda d: (d.centroids, d.areas, d.bboxes)  # noqa: E731
    name, v, out = fuzz(data, vsinv.detect_dots, args,
                        {"image": image_variants(image),
                         "threshold": ints(128, overrides={"huge": INVALID, "none": SAME, "valid": ANY, "npint": ANY}),
                         "min_area": ints(4),
                         "max_area": ints(10_000, overrides={"none": SAME})},
                        digest=digest, ref=ref)
    if returned(out):
        c = call(getattr, out, "centroids", _api="Dots.centroids")
        a = call(getattr, out, "areas", _api="Dots.areas")
        b = call(getattr, out, "bboxes", _api="Dots.bboxes")
        m = len(out)
        assert c.shape == (m, 2) and a.shape == (m,) and b.shape == (m, 4) and b.dtype == np.int64
        assert (b[:, 0] <= c[:, 0]).all() and (c[:, 0] <= b[:, 2]).all()


@covers("DotTracker", "DotTracker.track", "DotTracker.positions")
@fuzz_settings(100)
@given(st.data())
def test_dot_tracker(data: Any) -> None:
    image, px, vis = rendered()
    clicks = px[vis] + 1.0
    args = {"image": image, "initial_pixels": clicks, "search_radius": 20.0, "max_search_radius": 80.0, "min_area": 4}
    ref = vsinv.DotTracker(**args)
    digest = lambda t: t.positions  # noqa: E731
    over = {"fewer": ANY, "empty": ANY, "huge": ANY, "zero": ANY}
    name, v, out = fuzz(data, vsinv.DotTracker, args,
                        {"image": image_variants(image), "initial_pixels": arrays(clicks, overrides=over),
                         "search_radius": floats(20.0, overrides={"nan": INVALID}),
                         "max_search_radius": floats(80.0, overrides={"nan": INVALID}), "min_area": ints(4)},
                        api="DotTracker", digest=digest, ref=ref)
    tracker = out if returned(out) else ref
    pos = call(getattr, tracker, "positions", _api="DotTracker.positions")
    assert pos.shape == (len(tracker), 2)
    nxt = data.draw(image_variants(image), label="track image")
    res = call(tracker.track, nxt.value, _expect=nxt.expect if nxt.expect != SAME else RETURN, _names=("image",))
    if returned(res):
        p, found = res
        assert p.shape == (len(tracker), 2) and found.shape == (len(tracker),) and found.dtype == np.bool_
        if nxt.expect == SAME and tracker is ref:
            np.testing.assert_allclose(p[found], px[vis][found], atol=0.5)


@covers("load_image", "save_image")
@fuzz_settings(60)
@given(data=st.data())
def test_images_on_disk(tmp_path_factory: Any, data: Any) -> None:
    image = rendered()[0][:40, :50].copy()
    folder = tmp_path_factory.mktemp("img")
    v = data.draw(image_variants(image), label="image")
    target = data.draw(st.sampled_from(["ok.png", "dir", "missing/x.png", "noext", "ok.gif"]), label="path")
    path = folder / target if target != "dir" else folder
    expect = v.expect
    if expect in (SAME, ANY) and target in ("dir", "missing/x.png"):
        expect = RAISE
    out = call(vsinv.save_image, v.value, path, _expect=expect, _names=("image", str(path), "path"))
    if returned(out) and v.expect == SAME and target == "ok.png":
        back = call(vsinv.load_image, path, _expect=RETURN)
        assert np.array_equal(back, image)
        assert np.array_equal(cv2.imread(str(path), cv2.IMREAD_UNCHANGED), image)
    # bad files
    garbage = folder / "bad.png"
    kind = data.draw(st.sampled_from(["truncated", "text", "empty", "colour", "gif"]), label="file")
    if kind == "truncated":
        cv2.imwrite(str(garbage), image)
        blob = garbage.read_bytes()
        garbage.write_bytes(blob[: data.draw(st.integers(0, len(blob) - 1))])
        expect = ANY  # a PNG cut after its image data still decodes
    elif kind == "text":
        garbage.write_text("not a png")
        expect = RAISE
    elif kind == "empty":
        garbage.write_bytes(b"")
        expect = RAISE
    elif kind == "colour":
        cv2.imwrite(str(garbage), np.stack([image, image // 2, image // 3], axis=-1))
        expect = RETURN
    else:
        garbage = folder / "bad.gif"
        garbage.write_bytes(b"GIF89a" + bytes(20))
        expect = RAISE
    out = call(vsinv.load_image, garbage, _expect=expect, _names=(str(garbage), "image"))
    if returned(out):
        assert out.dtype == np.uint8 and out.shape == image.shape
    for bad, e in ((folder / "nothing.png", RAISE), (folder, RAISE), (None, TYPE), (3, TYPE)):
        call(vsinv.load_image, bad, _expect=e, _names=(str(bad), "path", "image"))


# ---------------------------------------------------------------------------------------------
# sweeps (vsinv.sweep and its names in vsinv)

SWEEP_BASE = json.loads(json.dumps(BASE))
SWEEP_BASE["stop"]["max_iterations"] = 3


@covers("run_sweep", "SweepResult", "sweep", "sweep.run_sweep", "sweep.SweepResult", "sweep.build_scenarios")
@fuzz_settings(40)
@given(data=st.data())
def test_run_sweep(tmp_path_factory: Any, data: Any) -> None:
    good_vary = [{"control.gain": [0.5, 1.0]}, {"focal_error": 0.1}, {"roll_deg": vsinv.Uniform(-10, 10)},
                 {"noise.pixel_sigma": vsinv.LogUniform(0.01, 0.1), "control.gain": [1.0]}, {"start.position.2": [-0.1]},
                 {"lens_ratio": vsinv.Choice([0.5, 1.0])}, {}]
    bad_vary = [{"nope": [1]}, {"control.gain": []}, {"control.gain": "abc"}, {"control.gain": [-1.0]},
                {"control.gain": [math.nan]}, {"focal_error": [math.inf]}, {"start.position.7": [1.0]}, {"": [1]},
                {"control..gain": [1]}, {"roll_deg": ["a"]}, {3: [1]}, [("control.gain", [1.0])], None,
                {"stop.max_iterations": [10**9]}, {"control.gain": {"a": 1}}, {"control.gain": vsinv.Uniform(-1, 1)}]
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
    res = call(vsinv.run_sweep, base, vary.value, progress=False, **kw, _expect=expect, _names=names, _finite=False)
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
    cls = data.draw(st.sampled_from([vsinv.Uniform, vsinv.LogUniform, vsinv.Choice]))
    if cls is vsinv.Choice:
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
        s = call(d.sample, rng, 5, _api=f"{cls.__name__}.sample", _finite=cls is not vsinv.Choice)
        b = call(d.bounds, _api=f"{cls.__name__}.bounds", _finite=False)
        if returned(s) and cls is not vsinv.Choice:
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


# ---------------------------------------------------------------------------------------------
# pose uncertainty and the noise meter


@covers("InvariantController.pose_uncertainty", "IbvsController.pose_uncertainty", "PoseUncertainty",
        "PoseUncertainty.covariance", "PoseUncertainty.offset", "PoseUncertainty.translation_sigma",
        "PoseUncertainty.rotation_sigma", "PoseUncertainty.translation_bound", "PoseUncertainty.rotation_bound")
@fuzz_settings(150)
@given(st.data())
def test_pose_uncertainty(data: Any) -> None:
    cls = data.draw(st.sampled_from([vsinv.InvariantController, vsinv.IbvsController]))
    ctl = controller(cls)
    args, strategies = step_args(True, RAISE if cls is vsinv.InvariantController else ANY)
    args.update(pixel_sigma=0.5, reference_sigma=0.25, averaged_images=4)
    strategies.update(
        pixel_sigma=floats(0.5, overrides={"zero": ANY, "negative": INVALID, "neghuge": INVALID, "neginf": INVALID,
                                           "huge": INVALID, "inf": INVALID}),
        reference_sigma=floats(0.25, overrides={"none": ANY, "zero": ANY, "negative": INVALID, "neghuge": INVALID,
                                                "neginf": INVALID, "huge": INVALID, "inf": INVALID}),
        averaged_images=ints(4, overrides={"zero": INVALID}),
    )
    ref = ctl.pose_uncertainty(**args)
    digest = lambda u: u.covariance if isinstance(u, vsinv.PoseUncertainty) else u  # noqa: E731
    fuzz(data, ctl.pose_uncertainty, args, strategies, ref=ref, rtol=1e-12, digest=digest,
         api=f"{cls.__name__}.pose_uncertainty", names={"pixels": ("pixels", "points", "visible")}, finite=False)
    # the properties of the result, against NumPy
    cov = call(getattr, ref, "covariance", _api="PoseUncertainty.covariance")
    assert cov.shape == (6, 6) and np.allclose(cov, cov.T, rtol=1e-9, atol=0) and np.all(np.linalg.eigvalsh(cov) > -1e-18)
    offset = call(getattr, ref, "offset", _api="PoseUncertainty.offset")
    t_sigma = call(getattr, ref, "translation_sigma", _api="PoseUncertainty.translation_sigma")
    r_sigma = call(getattr, ref, "rotation_sigma", _api="PoseUncertainty.rotation_sigma")
    assert t_sigma == pytest.approx(np.sqrt(np.trace(cov[:3, :3])), rel=1e-12)
    assert r_sigma == pytest.approx(np.sqrt(np.trace(cov[3:, 3:])), rel=1e-12)
    sigmas = data.draw(floats(3.0, overrides={"zero": INVALID, "negative": INVALID, "neghuge": INVALID, "neginf": INVALID,
                                              "huge": ANY, "inf": INVALID, "none": TYPE}), label="sigmas")
    for name, sigma, part in (("translation_bound", t_sigma, offset[:3]), ("rotation_bound", r_sigma, offset[3:])):
        out = call(getattr(ref, name), sigmas.value, _api=f"PoseUncertainty.{name}", _expect=sigmas.expect,
                   _names=("sigmas",), _finite=False)
        if sigmas.expect == SAME:
            assert out == pytest.approx(3.0 * sigma + np.linalg.norm(part), rel=1e-12)


@covers("PixelNoiseMeter", "PixelNoiseMeter.push", "PixelNoiseMeter.sigma", "PixelNoiseMeter.clear")
@fuzz_settings(100)
@given(st.data())
def test_pixel_noise_meter(data: Any) -> None:
    capacity = data.draw(ints(8, overrides={"zero": INVALID}), label="capacity")
    meter = call(vsinv.PixelNoiseMeter, capacity.value, _api="PixelNoiseMeter", _expect=capacity.expect,
                 _names=("capacity",))
    if not isinstance(meter, vsinv.PixelNoiseMeter):
        return
    rng = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1), label="seed"))
    frames = [CUR_PX + rng.normal(0, 0.3, CUR_PX.shape) for _ in range(3)]
    ones = np.ones(N, bool)
    args, strategies = {"pixels": frames[0], "visible": ones}, step_args(True, ANY)[1]
    visible = st.sampled_from([V(ones, SAME, "all"), V(None, SAME, "none"), V(np.zeros(N, bool), RETURN, "none visible"),
                               V(np.ones(N, int), INVALID, "int"), V(np.ones(N - 1, bool), INVALID, "short"),
                               V("abc", INVALID, "str")])
    fuzz(data, meter.push, args, {"pixels": strategies["pixels"], "visible": visible},
         api="PixelNoiseMeter.push", names={"pixels": ("pixels", "points", "visible")}, finite=False)
    meter.clear()
    call(meter.clear, _api="PixelNoiseMeter.clear", _expect=RETURN)
    for f in frames:
        meter.push(f)
    # against NumPy: the second difference of the three frames
    d = frames[0] - 2 * frames[1] + frames[2]
    sigma = call(getattr, meter, "sigma", _api="PixelNoiseMeter.sigma")
    assert sigma == pytest.approx(np.sqrt(np.mean(d**2) / 6), rel=1e-12)


# ---------------------------------------------------------------------------------------------
# exceptions, version, and the registry itself


@covers("VsinvError", "InvalidInput", "DegenerateGeometry", "NotReady", "__version__")
def test_exception_classes_and_version() -> None:
    for cls in (vsinv.InvalidInput, vsinv.DegenerateGeometry, vsinv.NotReady):
        assert issubclass(cls, vsinv.VsinvError) and cls.__module__ == "vsinv"
        e = cls("msg")
        assert str(e) == "msg" and isinstance(e, Exception)
    assert isinstance(vsinv.__version__, str) and re.fullmatch(r"\d+\.\d+\.\d+.*", vsinv.__version__)


def public_members(cls: type) -> list[str]:
    out = []
    for name in dir(cls):
        if name.startswith("_"):
            continue
        attr = getattr(cls, name)
        if isinstance(attr, type) and issubclass(attr, BaseException):
            continue
        out.append(f"{cls.__name__}.{name}")
    return out


def test_every_public_name_has_a_robustness_test() -> None:
    """New API cannot slip through: every name of vsinv.__all__ and vsinv.sweep.__all__, and
    every public method and property of the public classes, is covered by a test above."""
    names = set(vsinv.__all__) | {f"sweep.{n}" for n in vsinv.sweep.__all__}
    classes = [getattr(vsinv, n) for n in vsinv.__all__ if isinstance(getattr(vsinv, n), type)]
    for cls in classes:
        if issubclass(cls, BaseException) or cls.__module__.startswith("vsinv.sweep"):
            continue
        names.update(public_members(cls))
    missing = sorted(n for n in names if not REGISTRY.get(n))
    assert not missing, f"public names without a robustness test: {missing}"
    tests = {t for ts in REGISTRY.values() for t in ts}
    module = sys.modules[__name__]
    assert all(callable(getattr(module, t, None)) for t in tests)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: python tests/test_robustness.py CENSUS.json")
    print(census_table(json.loads(Path(sys.argv[1]).read_text())))
