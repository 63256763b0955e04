"""`vsinv replay --target features` end to end (issue 32): MuJoCo renders the textured box of
`feature_world` (photographs on three faces, no marker), the reference with one lens (f = 1200 px)
and a short closed-loop run of `vsinv.ImageServo(reference, "features", K_hat)` with another
(f = 600 px) from a start of tests/test_features_mujoco.py. Its frames are written as PNG files in
a folder, the reference depths (the scene's, per keypoint identity) as a points CSV: the command
replays them and prints the same verdicts and twists, frame by frame, as the session that moved
the camera did in process."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

import feature_world as fw

_WHY_NOT = fw.available()
if _WHY_NOT is not None:
    pytest.skip(_WHY_NOT, allow_module_level=True)

import mujoco_world as mw  # noqa: E402
import test_features_mujoco as t  # noqa: E402
import vsinv  # noqa: E402
from vsinv.cli import main  # noqa: E402

FRAMES = 6
K_HAT_OPTION = f"{t.K_HAT.fku!r},{t.K_HAT.fkv!r},{t.K_HAT.u0!r},{t.K_HAT.v0!r}"
OPTIONS = {"max_points": 80, "min_tracked": 20}
# The law's gain (the replay's other settings are the session's defaults) and the step that
# moves the camera between recorded frames.
GAIN, DT = 2.0, 0.04


def _record(tmp_path: Path) -> tuple[list[vsinv.ImageStep], int]:
    """Runs the session in closed loop for FRAMES frames, writing the reference, the frames and
    the reference depths to `tmp_path`; returns the steps and the points' count."""
    world = fw.TexturedBox(t.WIDTH, t.HEIGHT)
    try:
        reference = world.render(t.REFERENCE_POSE, t.FOVY_REFERENCE)
        probe = vsinv.ImageServo(reference, "features", t.K_HAT, depths="per_step", **OPTIONS)
        points = world.surface_point(t.REFERENCE_POSE, t.FOVY_REFERENCE, probe.reference_pixels)
        _, z = mw.project(t.REFERENCE_POSE, world.intrinsics(t.FOVY_REFERENCE), points)
        vsinv.vision.save_image(reference, tmp_path / "reference.png")
        with open(tmp_path / "depths.csv", "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(("id", "z"))
            w.writerows((int(i), repr(float(d))) for i, d in zip(probe.ids, z))
        servo = vsinv.ImageServo(reference, "features", t.K_HAT, law="invariant", reference_depths=z, gain=GAIN, **OPTIONS)
        (tmp_path / "frames").mkdir()
        pose, steps = t.start_poses(world, 1)[0], []
        for k in range(FRAMES):
            image = world.render(pose, t.FOVY_SERVO)
            vsinv.vision.save_image(image, tmp_path / "frames" / f"frame-{k:03d}.png")
            steps.append(servo.step(image))
            pose = pose @ vsinv.geometry.exp_twist(steps[-1].twist, DT)
        return steps, len(probe.ids)
    finally:
        world.close()


@pytest.mark.slow
def test_replay_of_recorded_frames_commands_what_the_session_did(capsys, tmp_path: Path) -> None:
    steps, n = _record(tmp_path)
    assert all(s.verdict == "running" for s in steps[:-1]) and np.linalg.norm(steps[0].twist) > 0
    args = [tmp_path / "reference.png", tmp_path / "frames", "--target", "features", "--K-hat", K_HAT_OPTION,
            "--reference-depths", tmp_path / "depths.csv", "--max-points", OPTIONS["max_points"],
            "--min-tracked", OPTIONS["min_tracked"], "--gain", GAIN, "--out", tmp_path / "out"]
    code = main(["replay", *(str(a) for a in args)])
    out, err = capsys.readouterr()
    lost = sum(int((~s.found).sum()) for s in steps)
    assert code == (1 if lost else 0), err
    assert f"{FRAMES} frames, {n} points; {lost} point-frames not found" in out
    with open(tmp_path / "out" / "replay.csv") as f:
        rows = list(csv.DictReader(f))
    assert [r["frame"] for r in rows] == [f"frame-{k:03d}.png" for k in range(FRAMES)]
    assert [r["verdict"] for r in rows] == [s.verdict for s in steps]
    assert [int(r["found"]) for r in rows] == [int(s.found.sum()) for s in steps]
    twists = np.array([[float(r[c]) for c in ("vx", "vy", "vz", "wx", "wy", "wz")] for r in rows])
    # The CSV keeps 9 significant digits: the same twists to that precision.
    np.testing.assert_allclose(twists, np.array([s.twist for s in steps]), rtol=1e-8, atol=1e-12)


def test_replay_refuses_a_bad_feature_option_by_its_name(capsys, tmp_path: Path) -> None:
    image = np.zeros((48, 64), np.uint8)
    vsinv.vision.save_image(image, tmp_path / "reference.png")
    (tmp_path / "frames").mkdir()
    vsinv.vision.save_image(image, tmp_path / "frames" / "a.png")
    base = ["replay", str(tmp_path / "reference.png"), str(tmp_path / "frames"), "--target", "features",
            "--K-hat", "600,600,32,24", "--law", "ibvs", "--depth", "0.5"]
    code = main([*base, "--point-ids", "1,x"])
    _, err = capsys.readouterr()
    assert code == 2 and "--point-ids" in err, err
    code = main([*base, "--max-points", "1"])
    _, err = capsys.readouterr()
    assert code == 2 and "--max-points" in err and "max_points" not in err, err
