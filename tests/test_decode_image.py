"""``vsinv.vision.decode_image`` (the compressed frames of the ROS bridge's ``image_transport:
compressed``) against OpenCV's decoder (``cv2.imdecode``, libpng and libjpeg-turbo), on a
rendered scene, random images of odd sizes and, when installed, ViSP's Klimt photograph (read
from visp-images-data, never copied): PNG to the bit, JPEG within what two IDCTs allow; the
refusals (empty, unknown, mislabelled, truncated, a header over the pixel limit, 16 bits)."""

from __future__ import annotations

import array
import time
import zlib
from pathlib import Path

import numpy as np
import pytest

import vsinv

cv2 = pytest.importorskip("cv2")

KLIMT = Path("/usr/share/visp-images-data/ViSP-images/Klimt/Klimt.png")


def images() -> list[np.ndarray]:
    """Grey and colour (BGR) test images: a rendering, smooth random fields of odd sizes, Klimt."""
    rng = np.random.default_rng(7)
    out = [vsinv.vision.render(vsinv.load_scenario("vision-12-6"))]
    for h, w in ((97, 131), (480, 641), (33, 17)):
        field = cv2.GaussianBlur(rng.uniform(0, 255, (h, w, 3)), (0, 0), 3) + rng.normal(0, 8, (h, w, 3))
        colour = np.clip(field, 0, 255).astype(np.uint8)
        out += [colour, colour[:, :, 1].copy()]
    if KLIMT.is_file():
        klimt = cv2.imread(str(KLIMT), cv2.IMREAD_COLOR)
        out += [klimt, cv2.cvtColor(klimt, cv2.COLOR_BGR2GRAY)]
    return out


def encode(image: np.ndarray, ext: str, *params: int) -> bytes:
    ok, data = cv2.imencode(ext, image, list(params))
    assert ok
    return data.tobytes()


def test_png_is_opencvs_to_the_bit() -> None:
    """Lossless: grey PNGs decode to their pixels, equal to ``imdecode(IMREAD_GRAYSCALE)``;
    colour PNGs to OpenCV's grey of their pixels (``cvtColor(imdecode(IMREAD_COLOR),
    BGR2GRAY)``) to the bit. ``IMREAD_GRAYSCALE`` of a colour PNG lets libpng convert with the
    same weights but truncating instead of rounding: at most one level below, never above."""
    for image in images():
        data = encode(image, ".png")
        mine = vsinv.vision.decode_image(data, "png")
        expected = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
        np.testing.assert_array_equal(mine, expected)
        libpng = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_GRAYSCALE).astype(int)
        if image.ndim == 2:
            np.testing.assert_array_equal(mine, libpng)
        else:
            assert set(np.unique(mine.astype(int) - libpng)) <= {0, 1}


def test_jpeg_matches_opencv_within_the_idct_differences() -> None:
    """JPEG's decoders may differ by their IDCT's rounding (the standard's accuracy test, IEEE
    1180, allows one level a sample) and, for colour, by the chroma upsampling and the colour
    conversion's rounding. Bound measured and asserted: grey JPEG at most 1 level from
    libjpeg-turbo's and on average under 0.1; colour JPEG (decoded to RGB, then luma, against
    OpenCV's colour decode then cvtColor) at most 3 levels and on average under 0.5."""
    worst = {1: (0, 0.0), 3: (0, 0.0)}
    for image in images():
        for quality in (75, 95):
            data = encode(image, ".jpg", cv2.IMWRITE_JPEG_QUALITY, quality)
            mine = vsinv.vision.decode_image(data, "jpeg").astype(int)
            theirs = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
            if image.ndim == 2:
                theirs = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_GRAYSCALE)
            else:
                theirs = cv2.cvtColor(theirs, cv2.COLOR_BGR2GRAY)
            diff = np.abs(mine - theirs.astype(int))
            channels = 1 if image.ndim == 2 else 3
            worst[channels] = (max(worst[channels][0], int(diff.max())), max(worst[channels][1], float(diff.mean())))
    print(f"\nJPEG vs OpenCV: grey max {worst[1][0]}, mean {worst[1][1]:.3f}; colour max {worst[3][0]}, mean {worst[3][1]:.3f}")
    assert worst[1][0] <= 1 and worst[1][1] < 0.1, worst
    assert worst[3][0] <= 3 and worst[3][1] < 0.5, worst


def test_every_buffer_type_is_read() -> None:
    grey = images()[0]
    data = encode(grey, ".png")
    for buffer in (data, bytearray(data), memoryview(data), array.array("B", data), np.frombuffer(data, np.uint8)):
        np.testing.assert_array_equal(vsinv.vision.decode_image(buffer), grey)


def png_declaring(width: int, height: int) -> bytes:
    """A one-pixel PNG whose header (CRC recomputed) declares ``width`` x ``height``."""
    b = bytearray(encode(np.zeros((1, 1), np.uint8), ".png"))
    b[16:20], b[20:24] = width.to_bytes(4, "big"), height.to_bytes(4, "big")
    b[29:33] = (zlib.crc32(bytes(b[12:29])) & 0xFFFFFFFF).to_bytes(4, "big")
    return bytes(b)


@pytest.mark.parametrize(
    "data, fmt, words",
    [
        (b"", None, "no data"),
        (b"GIF89a", None, "neither PNG nor JPEG"),
        (b"P5\n1 1\n255\n\x07", None, "neither PNG nor JPEG"),
        ("jpeg", "png", "the format says png but the data is jpeg"),
        ("png", "jpeg", "the format says jpeg but the data is png"),
        ("cut png", None, "not a valid"),
        ("cut jpeg", None, "truncated"),
        ("16-bit", None, "only 8-bit images are read"),
        ("bomb", None, "too large"),
    ],
)
def test_bad_data_is_refused(data: object, fmt: str | None, words: str) -> None:
    grey = images()[0]
    made = {"jpeg": encode(grey, ".jpg"), "png": encode(grey, ".png"), "16-bit": encode(grey.astype(np.uint16) * 257, ".png"),
            "bomb": png_declaring(60000, 60000)}
    made["cut png"], made["cut jpeg"] = made["png"][: len(made["png"]) // 2], made["jpeg"][: len(made["jpeg"]) // 2]
    payload = made[data] if isinstance(data, str) else data
    t0 = time.perf_counter()
    with pytest.raises(vsinv.InvalidInput, match=words):
        vsinv.vision.decode_image(payload, fmt)
    assert time.perf_counter() - t0 < 0.5  # refused from the header, nothing decoded


def test_bad_arguments_are_refused_by_name() -> None:
    with pytest.raises(vsinv.InvalidInput, match="format"):
        vsinv.vision.decode_image(b"\x89PNG", "gif")  # type: ignore[arg-type]
    with pytest.raises(vsinv.InvalidInput, match="expected bytes"):
        vsinv.vision.decode_image([1, 2, 3])  # type: ignore[arg-type]
