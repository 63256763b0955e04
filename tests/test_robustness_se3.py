"""Robustness of the public Python API under hypothesis, the SE(3) helpers (exponential of a
twist, theta-u poses).

The promise and the harness are described in tests/robustness_harness.py.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

import vsinv
from robustness_harness import (
    ANY, INVALID, SAME, V, arrays, call, covers, floats, fuzz, fuzz_settings, returned, rodrigues,
)


# ---------------------------------------------------------------------------------------------
# SE(3) helpers


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
