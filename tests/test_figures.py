"""Figures that read like the paper's (issue 19, item 6): pose errors per axis beside the norms
(Figs. 5, 7, 9), the image and invariant error per point for a camera that never moves
(Fig. 3) and nothing meaningless for it, arm joints in degrees with their limits, and a
time-stamped GIF small enough to share."""

import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import vsinv  # noqa: E402
from vsinv import plots  # noqa: E402

cv2 = pytest.importorskip("cv2")


@pytest.fixture(scope="module")
def lens() -> vsinv.RunResult:
    return vsinv.run_scenario("lens-12-6")


@pytest.fixture(scope="module")
def zoom() -> vsinv.RunResult:
    return vsinv.run_scenario("zoom-stationary")


@pytest.fixture(scope="module")
def ur5() -> vsinv.RunResult:
    return vsinv.run_scenario("arm-ur5-12-6")


def _lines(ax) -> list:
    """The data lines of an Axes (not the horizontal and vertical reference lines)."""
    return [ln for ln in ax.get_lines() if len(np.unique(np.asarray(ln.get_ydata(), dtype=float))) > 2]


def test_theta_u_is_opencvs_rodrigues_vector() -> None:
    rng = np.random.default_rng(7)
    vectors = [rng.normal(size=3) for _ in range(20)]
    vectors = [v / np.linalg.norm(v) * a for v, a in zip(vectors, np.linspace(0.0, np.pi - 1e-4, 20))]
    rotations = np.array([cv2.Rodrigues(v)[0] for v in vectors])
    np.testing.assert_allclose(plots.theta_u(rotations), np.array(vectors), atol=1e-6)
    # At exactly pi the axis comes from R + I (up to its sign, both are the same rotation).
    half_turn = cv2.Rodrigues(np.array([0.0, 0.6, 0.8]) * np.pi)[0]
    got = plots.theta_u(half_turn[None])[0]
    assert min(np.abs(got - [0.0, 0.6 * np.pi, 0.8 * np.pi]).max(), np.abs(got + [0.0, 0.6 * np.pi, 0.8 * np.pi]).max()) < 1e-6


def test_pose_errors_per_axis_beside_the_norms(lens: vsinv.RunResult) -> None:
    fig = lens.plot("pose_errors")
    try:
        norm_t, axes_t, norm_r, axes_r = fig.axes
        assert "(mm)" in norm_t.get_ylabel() and "(mm)" in axes_t.get_ylabel()
        assert "(deg)" in norm_r.get_ylabel() and "(deg)" in axes_r.get_ylabel()
        assert norm_r.get_xlabel() == axes_r.get_xlabel() == "time (s)"
        assert [t.get_text() for t in axes_t.get_legend().get_texts()] == ["t_x", "t_y", "t_z"]
        assert [t.get_text() for t in axes_r.get_legend().get_texts()] == ["θu_x", "θu_y", "θu_z"]
        # The components are the camera's translation (mm) and theta-u (deg) in F*.
        tx, ty, tz = (np.asarray(ln.get_ydata()) for ln in _lines(axes_t))
        np.testing.assert_allclose(np.c_[tx, ty, tz], lens.pose[:, :3, 3] * 1e3)
        rx, ry, rz = (np.asarray(ln.get_ydata()) for ln in _lines(axes_r))
        rodrigues = np.array([cv2.Rodrigues(p[:3, :3])[0].ravel() for p in lens.pose])
        np.testing.assert_allclose(np.c_[rx, ry, rz], np.degrees(rodrigues), atol=1e-6)
        # ... and their norms are the recorded distance and angle.
        np.testing.assert_allclose(np.linalg.norm(np.c_[rx, ry, rz], axis=1), np.degrees(lens.rotation_error), atol=1e-6)
    finally:
        plt.close(fig)


def test_a_stationary_camera_gets_fig3_and_no_meaningless_figures(zoom: vsinv.RunResult, lens, tmp_path: Path) -> None:
    assert plots.is_stationary(zoom) and not plots.is_stationary(lens)
    assert not plots.is_stationary(vsinv.run_scenario("planar"))  # degenerate at its first iteration
    paths = plots.save_figures(zoom, tmp_path)
    assert [p.name for p in paths] == list(plots.STATIONARY_FIGURES)
    assert {"path3d.png", "velocities.png", "task_functions.png", "pose_errors.png"}.isdisjoint(os.listdir(tmp_path))
    assert "point_errors.png" in os.listdir(tmp_path)


def test_point_errors_are_fig3_with_a_legend_naming_16_distinct_points(zoom: vsinv.RunResult) -> None:
    fig = zoom.plot("point_errors")
    try:
        image_ax, invariant_ax = fig.axes
        assert "(px)" in image_ax.get_ylabel() and "invariant error" in invariant_ax.get_ylabel()
        assert image_ax.get_xlabel() == invariant_ax.get_xlabel() == "image"
        assert list(image_ax.get_xticks()) == [1, 2, 3, 4, 5, 6]
        assert image_ax.get_ylim()[0] == 0.0 and invariant_ax.get_ylim()[0] == 0.0
        assert image_ax.get_xlim() == invariant_ax.get_xlim()
        lines = image_ax.get_lines()
        assert len(lines) == len(invariant_ax.get_lines()) == 16
        styles = {(matplotlib.colors.to_hex(ln.get_color()), ln.get_linestyle()) for ln in lines}
        assert len(styles) == 16  # no two points look alike
        legend = fig.legends[0]
        labels = [t.get_text() for t in legend.get_texts()]
        assert labels[0] == "point 0 (basis)" and labels[15] == "point 15" and len(labels) == 16
        # The values: an independent computation of ||p_i - p_i*|| and zero at the basis points.
        expected = np.linalg.norm(zoom.pixels - zoom.reference_pixels, axis=2)
        np.testing.assert_allclose(np.array([ln.get_ydata() for ln in lines]).T, expected)
        inv = np.array([ln.get_ydata() for ln in invariant_ax.get_lines()]).T
        assert np.abs(inv[:, [0, 7, 10]]).max() < 1e-9
        assert inv.max() < 0.05 < expected.max() / 100  # the invariant error stays near zero
    finally:
        plt.close(fig)


def test_point_errors_draw_into_a_given_axes(zoom: vsinv.RunResult) -> None:
    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 5))
    try:
        assert zoom.plot("point_errors", ax=left) is fig
        assert right in fig.axes
        assert any(a.get_legend() is not None for a in fig.axes)
    finally:
        plt.close(fig)


def test_invariance_figure_has_a_legend_and_shared_image_axis() -> None:
    from vsinv.images import InvarianceResult
    from vsinv.view_plots import plot_invariance

    rng = np.random.default_rng(3)
    image_error = np.cumsum(rng.uniform(0, 20, size=(6, 16)), axis=0)
    invariant_error = rng.uniform(0, 1e-2, size=(6, 16))
    invariant_error[:, [0, 7, 10]] = 0.0
    result = InvarianceResult(
        names=[f"image-{k}.png" for k in range(6)], reference_pixels=np.zeros((16, 2)), basis=(0, 7, 10),
        pixels=np.zeros((6, 16, 2)), found=np.ones((6, 16), dtype=bool), image_error=image_error,
        invariant_error=invariant_error,
    )
    fig = plot_invariance(result)
    try:
        a, b = fig.axes
        assert len(a.get_lines()) == len(b.get_lines()) == 16
        assert a.get_xlabel() == b.get_xlabel() == "image" and a.get_xlim() == b.get_xlim()
        assert "(px)" in a.get_ylabel() and fig.legends and len(fig.legends[0].get_texts()) == 16
        assert "basis [0, 7, 10]" in fig.get_suptitle()
        assert [t.get_text() for t in a.get_xticklabels()] == result.names  # the images named
    finally:
        plt.close(fig)


@pytest.mark.parametrize("kind, unit", [("joints", "deg"), ("joint_velocities", "deg/s")])
def test_arm_joints_in_degrees_with_their_limits(ur5: vsinv.RunResult, kind: str, unit: str) -> None:
    limits = ur5.joint_limits
    fig = ur5.plot(kind)
    try:
        assert len(fig.axes) == len(limits["names"]) == 6
        values = ur5.joints if kind == "joints" else ur5.joint_velocities
        if kind == "joints":
            low, high = np.degrees(limits["lower"]), np.degrees(limits["upper"])
        else:
            high = np.degrees(limits["velocity"])
            low = -high
        for j, ax in enumerate(fig.axes):
            assert ax.get_ylabel() == f"{limits['names'][j]}\n({unit})"
            data = [ln for ln in ax.get_lines() if ln.get_label() == limits["names"][j]]
            assert len(data) == 1
            np.testing.assert_allclose(np.asarray(data[0].get_ydata(), dtype=float), np.degrees(values[:, j]))
            drawn = sorted(float(ln.get_ydata()[0]) for ln in ax.get_lines() if ln.get_linestyle() == "--")
            np.testing.assert_allclose(drawn, [low[j], high[j]])
            assert ax.get_title(loc="right").startswith(f"limits [{low[j]:.4g}, {high[j]:.4g}] {unit};")
        assert fig.axes[-1].get_xlabel() == "time (s)"
    finally:
        plt.close(fig)


def test_a_limit_near_the_motion_is_in_view() -> None:
    r = vsinv.run_scenario("arm-panda-12-6")
    fig = r.plot("joints")
    try:
        lower = np.degrees(r.joint_limits["lower"])
        upper = np.degrees(r.joint_limits["upper"])
        q = np.degrees(r.joints)
        for j, ax in enumerate(fig.axes):
            bottom, top = ax.get_ylim()
            assert bottom <= np.nanmin(q[:, j]) and np.nanmax(q[:, j]) <= top
            span = max(np.nanmax(q[:, j]) - np.nanmin(q[:, j]), 0.05 * (upper[j] - lower[j]))
            if lower[j] >= np.nanmin(q[:, j]) - 1.5 * span:
                assert bottom < lower[j]
            if upper[j] <= np.nanmax(q[:, j]) + 1.5 * span:
                assert top > upper[j]
    finally:
        plt.close(fig)


@pytest.mark.parametrize("name", ["vision-12-6", "tags-12-6"])
def test_gif_is_small_and_time_stamped(name: str, tmp_path: Path) -> None:
    from PIL import Image

    from vsinv.view_plots import GIF_FRAMES, save_servo_gif

    r = vsinv.run_scenario(name)
    path = save_servo_gif(r, tmp_path / "camera.gif")
    assert path.stat().st_size < 1_000_000  # 5.2 MB for vision-12-6 with 32 adaptive colours
    gif = Image.open(path)
    assert getattr(gif, "n_frames") == min(GIF_FRAMES, len(r.time))
    stamps = []
    for k in (0, gif.n_frames - 1):
        gif.seek(k)
        rgb = np.asarray(gif.convert("RGB"))
        corner = rgb[:14, :150]
        assert (corner == 255).all(axis=2).any() and (corner == 0).all(axis=2).any()  # white text on black
        stamps.append(corner)
    assert not np.array_equal(*stamps)  # the stamp changes with time
