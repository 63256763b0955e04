"""Image files other than PNG: PGM/PPM (binary and ASCII) and JPEG, read by `vsinv.vision.load_image`
and compared with what OpenCV wrote; broken files are refused naming the file."""

from pathlib import Path

import numpy as np
import pytest

import vsinv
from vsinv.cli import main

cv2 = pytest.importorskip("cv2")


def _grey(seed: int = 0, shape: tuple[int, int] = (37, 53)) -> np.ndarray:
    rng = np.random.default_rng(seed)
    ramp = np.add.outer(np.arange(shape[0]) * 3, np.arange(shape[1]) * 2)
    return ((ramp + rng.integers(0, 40, size=shape)) % 256).astype(np.uint8)


def _colour(seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.integers(0, 256, size=(29, 41, 3), dtype=np.uint8)


def test_pgm_round_trip_is_exact(tmp_path: Path) -> None:
    image = _grey()
    path = tmp_path / "a.pgm"
    assert cv2.imwrite(str(path), image)
    assert path.read_bytes()[:2] == b"P5"
    assert np.array_equal(vsinv.vision.load_image(path), image)


def test_ascii_pgm_and_ppm(tmp_path: Path) -> None:
    image = _grey(2, (3, 4))
    text = "P2\n# a comment\n4 3\n255\n" + "\n".join(" ".join(str(v) for v in row) for row in image) + "\n"
    (tmp_path / "a.pgm").write_text(text)
    assert np.array_equal(vsinv.vision.load_image(tmp_path / "a.pgm"), image)
    rgb = np.stack([image, image, image], axis=-1)
    text = "P3\n4 3\n255\n" + "\n".join(" ".join(str(v) for v in row.ravel()) for row in rgb) + "\n"
    (tmp_path / "a.ppm").write_text(text)
    assert np.array_equal(vsinv.vision.load_image(tmp_path / "a.ppm"), image)


def test_ppm_is_converted_with_rec_601_luma(tmp_path: Path) -> None:
    bgr = _colour()
    path = tmp_path / "a.ppm"
    assert cv2.imwrite(str(path), bgr)
    assert path.read_bytes()[:2] == b"P6"
    grey = vsinv.vision.load_image(path)
    # OpenCV's BGR -> grey: 0.299 R + 0.587 G + 0.114 B in fixed point, the same as ours.
    assert np.array_equal(grey, cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY))
    rgb = bgr[..., ::-1].astype(float)
    expected = rgb @ np.array([0.299, 0.587, 0.114])
    assert np.abs(grey - expected).max() <= 0.51


def test_jpeg_grey_and_colour(tmp_path: Path) -> None:
    image = _grey()
    path = tmp_path / "a.jpg"
    assert cv2.imwrite(str(path), image, [cv2.IMWRITE_JPEG_QUALITY, 95])
    ours = vsinv.vision.load_image(path).astype(int)
    theirs = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE).astype(int)
    assert ours.shape == image.shape
    assert np.abs(ours - theirs).max() <= 2  # two IDCTs, both exact to a level or two
    assert np.abs(ours - image.astype(int)).mean() < 4.0
    bgr = _colour()
    path = tmp_path / "c.jpeg"
    assert cv2.imwrite(str(path), bgr, [cv2.IMWRITE_JPEG_QUALITY, 95])
    ours = vsinv.vision.load_image(path).astype(int)
    theirs = cv2.cvtColor(cv2.imread(str(path), cv2.IMREAD_COLOR), cv2.COLOR_BGR2GRAY).astype(int)
    assert np.abs(ours - theirs).max() <= 3


def _refused(path: Path) -> str:
    with pytest.raises(vsinv.InvalidInput) as info:
        vsinv.vision.load_image(path)
    message = str(info.value)
    assert str(path) in message
    return message


@pytest.mark.parametrize("suffix", ["pgm", "ppm", "jpg"])
def test_truncated_files_are_refused(tmp_path: Path, suffix: str) -> None:
    image = _grey() if suffix != "ppm" else _colour()
    path = tmp_path / f"a.{suffix}"
    assert cv2.imwrite(str(path), image)
    blob = path.read_bytes()
    path.write_bytes(blob[: len(blob) // 2])
    _refused(path)


def test_wrong_magic_and_16_bit_are_refused(tmp_path: Path) -> None:
    path = tmp_path / "a.pgm"
    path.write_bytes(b"Q5\n4 3\n255\n" + b"\x41" * 12)
    message = _refused(path)
    assert "AAAA" not in message  # never quotes the contents
    deep = tmp_path / "deep.pgm"
    assert cv2.imwrite(str(deep), (_grey().astype(np.uint16) * 257))
    assert "16-bit" in _refused(deep)
    corrupt = tmp_path / "c.pgm"
    corrupt.write_bytes(b"P5\n4 x3\n255\n" + b"\x41" * 12)
    assert "AAAA" not in _refused(corrupt)


def test_invariance_command_reads_pgm(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
    assert main(["render", "vision-zoom", "--out", str(tmp_path)]) == 0
    names = ["reference", "start"] + [f"image-{k}" for k in range(1, 6)]
    for name in names:
        assert cv2.imwrite(str(tmp_path / f"{name}.pgm"), cv2.imread(str(tmp_path / f"{name}.png"), cv2.IMREAD_GRAYSCALE))
    capsys.readouterr()
    args = ["invariance", *(str(tmp_path / f"{n}.pgm") for n in names), "--points", str(tmp_path / "reference.csv")]
    code = main(args + ["--basis", "0,7,10"])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "0 of 96 dots not found" in out
