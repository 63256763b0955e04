"""Scene helpers for the Python tests: a non-planar object, poses and a pinhole view."""

import os

import numpy as np
import pytest
from hypothesis import settings

import vsinv

# CI runs the property tests on a fixed sequence of examples (a red CI must mean a bug, not a
# draw); `make fuzz` explores new ones with VSINV_HYPOTHESIS=explore.
settings.register_profile("ci", derandomize=True)
settings.register_profile("explore", derandomize=False, max_examples=500)
settings.load_profile(os.environ.get("VSINV_HYPOTHESIS", "ci"))


def object_points() -> np.ndarray:
    """Twelve points in a 300 x 240 mm area about 600 mm in front of F*, +-60 mm relief."""
    xs = [-0.15, -0.05, 0.05, 0.15]
    ys = [-0.12, 0.0, 0.12]
    relief = [0.0, 0.06, -0.04, 0.03, -0.06, 0.05, 0.02, -0.03, 0.04, -0.05, 0.01, 0.06]
    pts = np.array([[x, y, 0.6] for y in ys for x in xs])
    pts[:, 2] += relief
    return pts


def rotation(thetau) -> np.ndarray:
    """Rodrigues' formula for a theta-u vector."""
    r = np.asarray(thetau, dtype=float)
    th = np.linalg.norm(r)
    if th < 1e-15:
        return np.eye(3)
    k = r / th
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(th) * kx + (1 - np.cos(th)) * kx @ kx


def pose(position=(0.0, 0.0, 0.0), thetau=(0.0, 0.0, 0.0)) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = rotation(thetau)
    m[:3, 3] = position
    return m


def view(points: np.ndarray, camera_pose: np.ndarray, k):
    """Pixels and depths of points (in F*) seen from a camera at camera_pose (camera in F*)."""
    inv = np.linalg.inv(camera_pose)
    cam = points @ inv[:3, :3].T + inv[:3, 3]
    return vsinv.project(cam, k)


def lens(f: float) -> "vsinv.Intrinsics":
    return vsinv.Intrinsics(f, f, 384.0, 288.0)


@pytest.fixture
def scene():
    """Reference image with a 12 mm lens and a current image from a displaced pose."""
    obj = object_points()
    k_star = lens(1200.0)
    k = lens(600.0)
    ref, z_star = view(obj, np.eye(4), k_star)
    cur, z = view(obj, pose((0.05, -0.03, -0.08), (0.1, -0.2, 0.3)), k)
    return {"object": obj, "k_star": k_star, "k": k, "ref": ref, "z_star": z_star, "cur": cur, "z": z}


@pytest.fixture(scope="session", autouse=True)
def _robustness_census_dump():
    """With VSINV_CENSUS=path, merges the robustness census of this session (the
    tests/test_robustness_*.py modules) into the JSON file path."""
    yield
    import sys

    module = sys.modules.get("robustness_harness")
    if module is not None:
        module.dump_census()


def pytest_terminal_summary(terminalreporter):
    """With VSINV_CENSUS=path, the robustness census (calls tried, returned, raised by class,
    per API) of this session, as written by tests/robustness_harness.py."""
    import json
    import os
    import sys

    path = os.environ.get("VSINV_CENSUS")
    module = sys.modules.get("robustness_harness")
    if not path or module is None or not module.CENSUS:
        return
    terminalreporter.section("vsinv robustness census (this session)")
    terminalreporter.write_line(module.census_table({k: dict(v) for k, v in module.CENSUS.items()}))
    terminalreporter.write_line(f"(merged into {path}; print it with: python tests/robustness_harness.py {path})")
    del json
