"""The tag target's options, declared once (``vsinv/cli_tags.py``) and shared: ``vsinv replay``
and ``vsinv invariance`` with ``--target tags``, ``--family``, ``--tag-ids`` and
``--decimation``; ``ImageServo(..., decimation=...)``. A bad value is refused by the library,
named as the user gave it."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

import vsinv
from vsinv.cli import main

cv2 = pytest.importorskip("cv2")
pytest.importorskip("matplotlib")

K_HAT = vsinv.Intrinsics(600.0, 600.0, 320.0, 240.0)
MARKERS = [(1, 60, 60, 120), (2, 300, 80, 120), (3, 180, 280, 120)]


def canvas(placements: list[tuple[int, int, int, int]], du: int = 0, dv: int = 0) -> np.ndarray:
    """A white 480 x 640 image with OpenCV's tag36h11 markers (id, left, top, side in px),
    moved by (du, dv) pixels."""
    dictionary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11)
    image = np.full((480, 640), 255, np.uint8)
    for tag, left, top, side in placements:
        image[top + dv : top + dv + side, left + du : left + du + side] = cv2.aruco.generateImageMarker(dictionary, tag, side)
    return image


def run_cli(capsys, *args):
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def test_image_servo_takes_a_decimation() -> None:
    reference = canvas(MARKERS)
    for decimation in (1, 3, None):
        pipeline = vsinv.ImageServo(reference, "tags", K_HAT, decimation=decimation, law="none", depths=0.5)
        step = pipeline.step(canvas(MARKERS, 4, -3))
        assert step.found.all() and len(pipeline.ids) == 12
        np.testing.assert_allclose(step.pixels - pipeline.reference_pixels, np.tile([4.0, -3.0], (12, 1)), atol=1e-6)
    for bad in (0, 9, -1):
        with pytest.raises(vsinv.InvalidInput, match="decimation: must be in 1..=8"):
            vsinv.ImageServo(reference, "tags", K_HAT, decimation=bad, law="none", depths=0.5)
    with pytest.raises(vsinv.InvalidInput, match="decimation: not an argument of target"):
        vsinv.ImageServo(reference, "dots", K_HAT, reference_points=np.zeros((3, 2)), decimation=2, law="none", depths=0.5)


def test_replay_takes_the_decimation(capsys, tmp_path: Path) -> None:
    vsinv.vision.save_image(canvas(MARKERS), tmp_path / "ref.png")
    (tmp_path / "frames").mkdir()
    for k in range(3):
        vsinv.vision.save_image(canvas(MARKERS, 3 * k, k), tmp_path / "frames" / f"{k}.png")
    args = ["replay", tmp_path / "ref.png", tmp_path / "frames", "--target", "tags", "--K-hat", "600,600,320,240",
            "--law", "ibvs", "--depth", "0.5"]
    code, out, err = run_cli(capsys, *args, "--decimation", "3")
    assert code == 0 and "3 frames, 12 points; 0 point-frames not found" in out, err
    for options, named in [(("--decimation", "9"), "--decimation: must be in 1..=8"),
                           (("--decimation", "x"), "argument --decimation: invalid int value"),
                           (("--family", "tag99"), "--family: expected one of")]:
        code, _, err = run_cli(capsys, *args, *options)
        assert code == 2 and named in err, err


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path) as f:
        return list(csv.DictReader(f))


def test_invariance_follows_tags_by_identity(capsys, tmp_path: Path) -> None:
    """The frames are the reference moved by whole pixels, one without tag 2: the image error is
    the shift, the invariant error zero (q is invariant to a shift of the image, eq. 7), and tag
    2's corners are not found in the frame without it."""
    vsinv.vision.save_image(canvas(MARKERS), tmp_path / "ref.png")
    shifts = [(0, 0), (5, -3), (-8, 6)]
    for k, (du, dv) in enumerate(shifts):
        vsinv.vision.save_image(canvas(MARKERS, du, dv), tmp_path / f"{k}.png")
    vsinv.vision.save_image(canvas([MARKERS[0], MARKERS[2]]), tmp_path / "without-2.png")
    images = [tmp_path / f"{k}.png" for k in range(3)] + [tmp_path / "without-2.png"]
    code, out, err = run_cli(capsys, "invariance", tmp_path / "ref.png", *images, "--target", "tags",
                             "--decimation", "1", "--out", tmp_path / "inv")
    assert code == 1 and "not every dot was found" in err, err  # tag 2 is missing from the last image
    rows = _rows(tmp_path / "inv" / "invariance.csv")
    assert len(rows) == 4 * 12
    for k, (du, dv) in enumerate(shifts):
        for row in rows[12 * k : 12 * (k + 1)]:
            assert row["found"] == "1"
            assert abs(float(row["image_error_px"]) - np.hypot(du, dv)) < 1e-5  # the CSV has 6 digits
            assert float(row["invariant_error"]) < 1e-8
    last = rows[36:]
    assert [r["found"] for r in last] == ["1"] * 4 + ["0"] * 4 + ["1"] * 4
    tags = vsinv.vision.detect_tags(canvas(MARKERS), decimation=1)
    np.testing.assert_allclose([[float(r["u"]), float(r["v"])] for r in rows[:12]], tags.corners.reshape(-1, 2), atol=1e-9)
    code, _, err = run_cli(capsys, "invariance", tmp_path / "ref.png", tmp_path / "0.png", "--target", "tags",
                           "--tag-ids", "3,1")
    assert code == 0, err


@pytest.mark.parametrize(
    ("options", "named"),
    [
        (("--target", "tags", "--decimation", "0"), "--decimation: must be in 1..=8"),
        (("--target", "tags", "--family", "tag99"), "--family: expected one of"),
        (("--target", "tags", "--tag-ids", "1,5"), "--tag-ids: tag 5 is not decoded"),
        (("--target", "tags", "--tag-ids", "a"), "--tag-ids: expected tag ids"),
        (("--target", "tags", "--points", "ref.csv"), "--points: not an option of --target tags"),
        (("--target", "dots",), "--points: --target dots needs"),
    ],
)
def test_invariance_tag_errors_name_the_option(capsys, tmp_path: Path, options, named) -> None:
    vsinv.vision.save_image(canvas(MARKERS), tmp_path / "ref.png")
    (tmp_path / "ref.csv").write_text("u,v\n1,2\n")
    options = tuple(str(tmp_path / o) if o.endswith(".csv") else o for o in options)
    code, _, err = run_cli(capsys, "invariance", tmp_path / "ref.png", tmp_path / "ref.png", *options)
    assert code == 2 and named in err, err
