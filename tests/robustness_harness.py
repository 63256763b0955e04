"""Robustness of every public name of ``vsinv`` (and ``vsinv.sweep``) under hypothesis.

The promise checked here: a call returns a correct result, or raises the package's own
exception (a ``vsinv.VsinvError`` subclass) whose message names the argument at fault and,
for a non-finite value in an array, its position ("row R, column C" for 2-d arrays). Never a
``PanicException``, another exception class, a crash, a hang (each call is timed) or NaN/inf
in an output without an exception. A wrong Python type for a scalar argument (a str where a
float is expected) may raise ``TypeError`` naming the argument (PyO3's convention: the
argument is named in the exception's notes).

The tests are split by API area (``tests/test_robustness_<area>.py``); this module is their
shared harness. One function, :func:`call`, runs every call and keeps a census (calls tried, returned, raised
by class, per API). With ``VSINV_CENSUS=path`` the census is merged into the JSON file
``path`` at the end of the session (tests/conftest.py) and printed then; ``python
tests/robustness_harness.py path`` prints a census file as a table.

Each argument's strategy draws valid values, layout variants that must give the same answer
(lists, Fortran order, strided views, read-only arrays), NaN/inf at a drawn position, zeros,
negatives, huge values, wrong shapes and dtypes, and degenerate geometry; one argument is
corrupted per call, so the exception must name that argument.
"""

from __future__ import annotations

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
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

import vsinv
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


def dump_census() -> None:
    """With ``VSINV_CENSUS=path``, merges this session's census into the JSON file ``path``
    (tests/conftest.py calls it at the end of the session)."""
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
# shared by several areas: pixel and depth variants, text mutations, Rodrigues, the vision scenario


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


def depth_variants(valid: np.ndarray, extra: Optional[dict[str, str]] = None) -> st.SearchStrategy[V]:
    return arrays(valid, overrides={"zero": RAISE, "negative": RAISE, "empty": RAISE, "bool": ANY, "flat": SAME,
                                    "strided": SAME, "fewer": RAISE, **(extra or {})}, skip=("fortran",))


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


def rodrigues(tu: np.ndarray) -> np.ndarray:
    r, _ = cv2.Rodrigues(np.asarray(tu, dtype=float).reshape(3, 1))
    return r


VISION = vsinv.load_scenario("vision-12-12").to_dict()
VISION["stop"]["max_iterations"] = 2


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: python tests/robustness_harness.py CENSUS.json")
    print(census_table(json.loads(Path(sys.argv[1]).read_text())))
