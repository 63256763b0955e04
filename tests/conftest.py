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


# The area (layer) of each test file: `pytest -m vision` runs the vision tests. Every test file has
# one, from this table or from its own module-level marker (``pytestmark = pytest.mark.vision``,
# which a new file may use instead of a line here); tests/test_areas.py fails on a file with none.
# The areas are registered in pyproject.toml ([tool.pytest.ini_options] markers, --strict-markers).
AREAS = {
    "core": [
        "test_api.py", "test_planning.py", "test_reference_depths.py", "test_robust_depth.py", "test_scaling.py", "test_se3.py",
    ],
    "servo": [
        "test_commands.py", "test_law_options.py", "test_parity.py", "test_servo.py", "test_uncertainty.py",
    ],
    "vision": [
        "test_dot_filters.py", "test_image_formats.py", "test_image_servo.py", "test_polarity.py",
        "test_real_images.py", "test_tag_families.py", "test_tag_options.py", "test_tag_rig.py",
        "test_tag_tracking.py", "test_tags.py", "test_tags_robustness.py", "test_tracker_border.py",
        "test_tracker_lost.py", "test_tracker_shape.py", "test_vision.py", "test_camera_source.py",
        "test_colour_images.py", "test_decode_image.py", "test_dots_upscaled.py", "test_features.py",
        "test_texture_render.py",
    ],
    "sim": [
        "test_arm.py", "test_batch_progress.py", "test_distortion_loop.py", "test_figures.py", "test_ik.py",
        "test_mount_error.py", "test_mujoco_batch.py", "test_mujoco_vision.py", "test_mujoco_world.py", "test_features_mujoco.py", "test_robust_depth_mujoco.py",
        "test_features_estimated_depths.py", "test_mujoco_user_arm.py",
        "test_recording.py", "test_scenarios.py", "test_schema.py", "test_sweep.py",
    ],
    "calibration": ["test_distortion.py", "test_fisheye.py", "test_hand_eye.py", "test_hand_eye_to_hand.py"],
    "ros": [
        "test_ros_bridge.py", "test_ros_compressed.py", "test_ros_gate.py", "test_ros_lifecycle.py", "test_ros_loop.py",
        "test_ros_package.py", "test_ros_features.py",
    ],
    "cli": ["test_cli.py", "test_cli_images.py", "test_examples.py", "test_features_replay.py"],
    "docs": ["test_docs.py", "test_readme_blocks.py"],
    "robustness": [
        "test_error_locations.py", "test_errors.py", "test_fork_safety.py", "test_fuzz_scenarios.py", "test_hostile_files.py",
        "test_hostile_sizes.py", "test_robustness_camera.py", "test_robustness_control.py",
        "test_robustness_geometry.py", "test_robustness_kinematics.py", "test_robustness_limits.py",
        "test_robustness_planning.py", "test_robustness_registry.py", "test_robustness_scenarios.py",
        "test_robustness_se3.py", "test_robustness_threads.py", "test_robustness_vision.py",
    ],
    "package": [
        "test_api_levels.py", "test_areas.py", "test_binding_boundary.py", "test_logging.py", "test_rust_version.py", "test_source_shape.py", "test_wheels.py",
    ],
}
AREA_OF = {name: area for area, names in AREAS.items() for name in names}

# Tests and cases of parametrised tests marked slow here rather than in their file (node ids, as
# pytest prints them, without "tests/"): each took 3 s of CPU or more (30 s and more of wall time at a
# load average of 14 on 2 cores) in one run of the whole suite timed test by test. Other slow
# tests carry @pytest.mark.slow where they are defined. `make test-fast` (-m "not slow") leaves
# both out; `make test` runs them.
SLOW = {
    "test_arm.py::test_arm_figures",
    "test_docs.py::test_page_code_runs[getting-started.md]",
    "test_docs.py::test_page_code_runs[guides/mujoco.md]",
    "test_docs.py::test_page_code_runs[guides/markerless.md]",
    "test_figures.py::test_gif_is_small_and_time_stamped[tags-12-6]",
    "test_fork_safety.py::test_fork_after_dot_detection_on_a_large_image",
    "test_mujoco_api.py::test_the_lens_change_converges_through_mujoco_images",
    "test_mujoco_api.py::test_ibvs_never_claims_converged_on_the_lens_change",
    "test_mujoco_api.py::test_a_zoom_during_the_servo_changes_the_rendered_K",
    "test_mujoco_api.py::test_the_ur5_with_mass_servoes_through_its_wrist_camera",
    "test_robustness_threads.py::test_tag_tracker_from_threads",
    "test_robustness_vision.py::test_to_grey",
    "test_schema.py::test_scenario_is_converted_once_per_figure_set",
    "test_tag_families.py::test_a_tag_standard_41h12_rig_runs_to_converged",
    "test_tag_families.py::test_rendered_tags_of_every_family_decode_at_their_projected_corners[tagCircle49h12-0.0-0.0]",
    "test_tag_families.py::test_rendered_tags_of_every_family_decode_at_their_projected_corners[tagCircle49h12-0.8-1.0]",
    "test_tag_families.py::test_rendered_tags_of_every_family_decode_at_their_projected_corners[tagCustom48h12-0.0-0.0]",
    "test_tag_families.py::test_rendered_tags_of_every_family_decode_at_their_projected_corners[tagCustom48h12-0.8-1.0]",
    "test_tag_families.py::test_rendered_tags_of_every_family_decode_at_their_projected_corners[tagStandard52h13-0.0-0.0]",
    "test_tag_families.py::test_rendered_tags_of_every_family_decode_at_their_projected_corners[tagStandard52h13-0.8-1.0]",
}


def pytest_collection_modifyitems(config, items):
    """Marks each test with its file's area (from AREAS) unless the file declares one itself,
    and the cases of SLOW with `slow`."""
    for item in items:
        area = AREA_OF.get(item.path.name)
        if area is not None and not any(m.name in AREAS for m in item.iter_markers()):
            item.add_marker(getattr(pytest.mark, area))
        if item.nodeid.removeprefix("tests/") in SLOW:
            item.add_marker(pytest.mark.slow)


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
    return vsinv.geometry.project(cam, k)


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
