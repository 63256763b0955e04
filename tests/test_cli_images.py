"""The image commands: `vsinv render`, `vsinv invariance`, and the views a `[vision]` run writes."""

import csv
from pathlib import Path

import numpy as np
import pytest

import vsinv
from vsinv.cli import main

pytest.importorskip("matplotlib")


def run_cli(capsys, *args):
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def test_render_then_invariance_reproduces_fig_3(capsys, tmp_path: Path) -> None:
    # Sec. 5.1: six images of a stationary zooming camera, written as files, tracked back.
    code, out, _ = run_cli(capsys, "render", "vision-zoom", "--out", tmp_path / "img")
    assert code == 0, out
    images = [tmp_path / "img" / f"image-{k}.png" for k in range(1, 6)]
    assert all(p.exists() for p in images) and (tmp_path / "img" / "start.png").exists()
    code, out, err = run_cli(
        capsys,
        "invariance",
        tmp_path / "img" / "reference.png",
        tmp_path / "img" / "start.png",
        *images,
        "--points",
        tmp_path / "img" / "reference.csv",
        "--basis",
        "0,7,10",
        "--out",
        tmp_path / "inv",
    )
    assert code == 0, err
    assert "basis [0, 7, 10]" in out and "0 of 96 dots not found" in out
    with open(tmp_path / "inv" / "invariance.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 6 * 16
    image_error = np.array([float(r["image_error_px"]) for r in rows]).reshape(6, 16)
    invariant_error = np.array([float(r["invariant_error"]) for r in rows]).reshape(6, 16)
    # The image error grows with the zoom; the invariant error stays at the detection noise.
    assert image_error[0].max() < 0.2 and image_error[-1].max() > 100.0
    assert np.all(np.diff(image_error.max(axis=1)) > 10.0)
    assert invariant_error.max() < 1e-3
    assert (tmp_path / "inv" / "invariance.png").read_bytes()[:4] == b"\x89PNG"


def test_invariance_reports_missing_measurements_and_fails(capsys, tmp_path: Path) -> None:
    # The 6 mm start image of vision-12-6 tracked from the 12 mm reference positions: no dot is
    # found, so nothing was measured; the command says so and fails instead of printing 0.00.
    run_cli(capsys, "render", "vision-12-6", "--out", tmp_path)
    code, out, err = run_cli(
        capsys, "invariance", tmp_path / "reference.png", tmp_path / "start.png", "--points", tmp_path / "reference.csv"
    )
    assert code == 1, out
    assert "no measurement: 12 of 12 dots not found in any image" in out
    assert "max image error" not in out and "0.00" not in out.splitlines()[-1]
    assert "not every dot was found" in err


def test_invariance_summary_counts_partial_measurements() -> None:
    from vsinv.cli_images import complete, measurement_summary
    from vsinv.images import InvarianceResult

    found = np.array([[True, True, True, True], [True, False, True, True]])
    image_error = np.where(found, [[0.1, 0.2, 0.3, 0.4], [1.5, 9.0, 0.5, 0.25]], np.nan)
    invariant_error = np.full((2, 4), np.nan)
    invariant_error[0] = [0.0, 0.0, 0.0, 2e-4]
    result = InvarianceResult(
        names=["a", "b"], reference_pixels=np.zeros((4, 2)), basis=(0, 1, 2), pixels=np.zeros((2, 4, 2)), found=found,
        image_error=image_error, invariant_error=invariant_error,
    )
    text = measurement_summary(result)
    assert text.startswith("max image error 1.50 px over 7 of 8 dot images")
    assert "max invariant error 2.00e-04 over 4 of 8" in text and text.endswith("1 of 8 dots not found")
    assert not complete(result)
    full = InvarianceResult(
        names=["a"], reference_pixels=np.zeros((4, 2)), basis=(0, 1, 2), pixels=np.zeros((1, 4, 2)), found=found[:1],
        image_error=image_error[:1], invariant_error=invariant_error[:1],
    )
    assert complete(full)


def test_render_writes_true_dot_positions(capsys, tmp_path: Path) -> None:
    code, _, _ = run_cli(capsys, "render", "vision-12-6", "--out", tmp_path)
    assert code == 0
    assert not (tmp_path / "image-1.png").exists()  # a moving camera: reference and start only
    image = vsinv.load_image(tmp_path / "start.png")
    _, pixels, _ = vsinv.render_view("vision-12-6")
    assert np.array_equal(image, vsinv.render("vision-12-6"))
    from vsinv.images import read_points

    assert np.allclose(read_points(tmp_path / "start.csv"), pixels, atol=1e-6)


def test_invariance_reports_bad_files(capsys, tmp_path: Path) -> None:
    run_cli(capsys, "render", "vision-12-12", "--out", tmp_path)
    bad = tmp_path / "bad.csv"
    bad.write_text("point,u,v\n0,12.0,oops\n")
    code, _, err = run_cli(capsys, "invariance", tmp_path / "reference.png", tmp_path / "start.png", "--points", bad)
    assert code == 2 and "row 2, column v" in err
    code, _, err = run_cli(
        capsys, "invariance", tmp_path / "missing.png", tmp_path / "start.png", "--points", tmp_path / "reference.csv"
    )
    assert code == 2 and "missing.png" in err
    code, _, err = run_cli(
        capsys,
        "invariance",
        tmp_path / "reference.png",
        tmp_path / "start.png",
        "--points",
        tmp_path / "reference.csv",
        "--basis",
        "1,2",
    )
    assert code == 2 and "--basis" in err


def test_vision_run_writes_views_and_gif(capsys, tmp_path: Path) -> None:
    code, out, _ = run_cli(capsys, "run", "vision-zoom", "--out", tmp_path, "--no-progress")
    assert code == 1 and "observed" in out  # a stationary camera: no control, not converged
    for name in ("view_reference.png", "view_first.png", "view_last.png"):
        assert (tmp_path / name).read_bytes()[:4] == b"\x89PNG"
    from PIL import Image

    gif = Image.open(tmp_path / "camera.gif")
    assert getattr(gif, "n_frames") == 6 and gif.size == (384, 288)
    npz = np.load(tmp_path / "trajectory.npz")
    assert "detection_error" in npz.files and npz["detection_error"].shape == (6, 16)
