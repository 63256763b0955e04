"""ViSP's AprilTag benchmark images, their degraded versions and the reference detectors,
shared by tests/test_tags_robustness.py and benches/tags_robustness.py.

The images are read from Debian's visp-images-data (GPL: never copied here). Every corner
here is in OpenCV's order and pixel convention (as `vsinv.vision.detect_tags` reports them): ViSP's
corner files and pupil-apriltags follow the AprilTag library (corners bottom-left,
bottom-right, top-right, top-left of the AprilTag layout, pixel centres at +0.5), converted as
in tests/test_tags.py. A degradation that moves the pixels (rotation, resizing) moves the
ground truth by the same map.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

BENCHMARK = Path("/usr/share/visp-images-data/ViSP-images/AprilTag/benchmark")
VISP_TO_OPENCV = [1, 0, 3, 2]

# family -> (ViSP's file stem, OpenCV's dictionary or None)
FAMILIES = {
    "tag36h11": ("tag36_11", "DICT_APRILTAG_36h11"),
    "tag25h9": ("tag25_09", "DICT_APRILTAG_25h9"),
    "tag16h5": ("tag16_05", "DICT_APRILTAG_16h5"),
    "tagStandard41h12": ("tag41_12", None),
    "tagStandard52h13": ("tag52_13", None),
    "tagCircle21h7": ("tag21_07", None),
    "tagCircle49h12": ("tag49_12", None),
    "tagCustom48h12": ("tag48_12", None),
}

Corners = dict[int, np.ndarray]


def visp_corners(path: Path) -> Corners:
    """A benchmark corners file (`id`, then four lines `u v`) in OpenCV's order and convention."""
    lines = [line for line in path.read_text().splitlines() if line.strip()]
    out = {}
    for k in range(0, len(lines), 5):
        tag = int(re.search(r"(\d+)\s*$", lines[k]).group(1))  # type: ignore[union-attr]
        xy = np.array([[float(x) for x in lines[k + j].split()] for j in range(1, 5)])
        out[tag] = xy[VISP_TO_OPENCV] - 0.5
    return out


@dataclass
class Case:
    """One image: its name, family, pixels, the ids present and their true corners (None
    where none are published)."""

    name: str
    family: str
    image: np.ndarray
    ids: set[int]
    truth: Corners | None


def benchmark(family: str, resolution: str) -> Case:
    stem = FAMILIES[family][0]
    image = cv2.imread(str(BENCHMARK / resolution / f"{stem}_{resolution}.png"), cv2.IMREAD_GRAYSCALE)
    truth = visp_corners(BENCHMARK / "640x480" / f"corners_{stem}.txt")
    # The 1920x1080 image shows the same tags (no corners are published for it).
    return Case(f"{resolution}", family, image, set(truth), truth if resolution == "640x480" else None)


# Five tags of 50-120 px, drawn by `rendered` at 640 x 480 (moved and scaled with the image): id, centre (u, v), side of the black square (px), turn (rad), perspective (the far side
# shrunk by this fraction).
RENDERED_PLACEMENTS = [
    (0, (140.0, 130.0), 90.0, 0.3, 0.15),
    (1, (470.0, 120.0), 100.0, -0.5, 0.10),
    (2, (320.0, 290.0), 120.0, 1.2, 0.20),
    (3, (120.0, 380.0), 60.0, 2.0, 0.05),
    (4, (530.0, 390.0), 50.0, -2.5, 0.25),
]
#: Supersampling of `rendered`: each pixel is the mean of 8 x 8 samples of the tag.
RENDER_SAMPLES = 8


def rendered(family: str, resolution: str) -> Case:
    """Tags whose corners are known exactly, drawn independently of vsinv: OpenCV's own marker
    image (`generateImageMarker`, black 30 on white 220, a quiet zone of two cells) mapped by a
    homography (`warpPerspective`) at 8 x 8 samples a pixel, then averaged over each pixel
    (`resize` with `INTER_AREA`), as a camera's pixel integrates light. The corners are the
    homography's images of the black square's corners, in OpenCV's convention. ViSP's published
    corners (`benchmark`) come from a detector (they agree with pupil-apriltags to 0.05 px, with
    the projections of ViSP's own `cMo_*.txt` poses only to 0.26 px): this set is the truth that
    owes nothing to any detector."""
    width, height = (int(x) for x in resolution.split("x"))
    scale = np.array([width / 640.0, height / 480.0])
    dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, FAMILIES[family][1]))
    image = np.full((height, width), 220, np.uint8)
    truth = {}
    for tag, centre, side, turn, perspective in RENDERED_PLACEMENTS:
        h = _tag_homography(np.multiply(centre, scale), side * scale.min(), turn, perspective)
        truth[tag] = _draw_marker(image, dictionary, tag, h)
    return Case(f"rendered {resolution}", family, image, set(truth), truth)


def _tag_homography(centre: np.ndarray, side: float, turn: float, perspective: float) -> np.ndarray:
    """The map from the unit square (the black square's edge coordinates) to the image's edge
    coordinates (a pixel u spans [u, u + 1])."""
    c, s = np.cos(turn), np.sin(turn)
    unit = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    corners = (unit - 0.5) * side @ np.array([[c, s], [-s, c]])
    corners[2:] *= 1.0 - perspective
    corners += centre + 0.5
    return cv2.getPerspectiveTransform(unit.astype(np.float32), corners.astype(np.float32))


def _draw_marker(image: np.ndarray, dictionary, tag: int, h: np.ndarray) -> np.ndarray:  # type: ignore[no-untyped-def]
    """Draws marker `tag` through `h` (unit square -> image edge coordinates) into `image`,
    supersampled in the tag's bounding box only; returns its corners (OpenCV's convention)."""
    cell, n = 32, RENDER_SAMPLES
    side = (dictionary.markerSize + 2) * cell
    marker = cv2.aruco.generateImageMarker(dictionary, tag, side, borderBits=1)
    marker = cv2.copyMakeBorder(np.where(marker > 127, 220, 30).astype(np.uint8), *[2 * cell] * 4, cv2.BORDER_CONSTANT, value=220)
    # Marker pixel centres -> marker edges -> unit square -> image edges.
    to_unit = np.array([[1.0 / side, 0.0, (0.5 - 2 * cell) / side], [0.0, 1.0 / side, (0.5 - 2 * cell) / side], [0.0, 0.0, 1.0]])
    q = 2.0 / (dictionary.markerSize + 2)  # the quiet zone, in units of the black square
    outline = cv2.perspectiveTransform(np.array([[[-q, -q], [1 + q, -q], [1 + q, 1 + q], [-q, 1 + q]]]), h)[0]
    u0, v0 = np.maximum(np.floor(outline.min(axis=0)).astype(int), 0)
    u1, v1 = np.minimum(np.ceil(outline.max(axis=0)).astype(int), image.shape[::-1])
    # Image edges -> the box's supersampled pixel centres.
    to_box = np.array([[n, 0.0, -n * u0 - 0.5], [0.0, n, -n * v0 - 0.5], [0.0, 0.0, 1.0]])
    size = ((u1 - u0) * n, (v1 - v0) * n)
    drawn = cv2.warpPerspective(marker, to_box @ h @ to_unit, size, flags=cv2.INTER_LINEAR, borderValue=220)
    image[v0:v1, u0:u1] = np.minimum(image[v0:v1, u0:u1], cv2.resize(drawn, (u1 - u0, v1 - v0), interpolation=cv2.INTER_AREA))
    unit_corners = np.array([[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]])
    return cv2.perspectiveTransform(unit_corners, h)[0] - 0.5


def _affine(case: Case, name: str, image: np.ndarray, m: np.ndarray) -> Case:
    """`case` with `image`, its truth moved by the 2x3 map `m` (OpenCV's convention)."""
    truth = None if case.truth is None else {t: c @ m[:, :2].T + m[:, 2] for t, c in case.truth.items()}
    return Case(f"{case.name} {name}", case.family, image, case.ids, truth)


def resized(case: Case, factor: float, name: str | None = None) -> Case:
    h, w = case.image.shape
    size = (round(w * factor), round(h * factor))
    method = cv2.INTER_AREA if factor < 1 else cv2.INTER_LINEAR
    image = cv2.resize(case.image, size, interpolation=method)
    fx, fy = size[0] / w, size[1] / h
    m = np.array([[fx, 0.0, (fx - 1) / 2], [0.0, fy, (fy - 1) / 2]])
    return _affine(case, name or f"x{factor:g}", image, m)


def rotated(case: Case, degrees: float) -> Case:
    h, w = case.image.shape
    if degrees == 90:
        # Counter-clockwise on the screen: pixel (u, v) goes to (v, w - 1 - u).
        m = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, w - 1.0]])
        return _affine(case, "rot90", np.ascontiguousarray(np.rot90(case.image)), m)
    m = cv2.getRotationMatrix2D(((w - 1) / 2, (h - 1) / 2), degrees, 1.0)
    image = cv2.warpAffine(case.image, m, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    return _affine(case, f"rot{degrees:g}", image, m)


def blurred(case: Case, sigma: float) -> Case:
    image = cv2.GaussianBlur(case.image, (0, 0), sigma)
    return Case(f"{case.name} blur{sigma:g}", case.family, image, case.ids, case.truth)


def noisy(case: Case, sigma: float, seed: int = 7) -> Case:
    noise = np.random.default_rng(seed).normal(0.0, sigma, case.image.shape)
    image = np.clip(case.image + noise, 0, 255).round().astype(np.uint8)
    return Case(f"{case.name} noise{sigma:g}", case.family, image, case.ids, case.truth)


def jpeg(case: Case, quality: int) -> Case:
    ok, data = cv2.imencode(".jpg", case.image, [cv2.IMWRITE_JPEG_QUALITY, quality])
    assert ok
    image = cv2.imdecode(data, cv2.IMREAD_GRAYSCALE)
    return Case(f"{case.name} jpeg{quality}", case.family, image, case.ids, case.truth)


DEGRADATIONS: dict[str, Callable[[Case], Case]] = {
    "clean": lambda c: c,
    "blur1": lambda c: blurred(c, 1.0),
    "blur2": lambda c: blurred(c, 2.0),
    "blur3": lambda c: blurred(c, 3.0),
    "noise5": lambda c: noisy(c, 5.0),
    "noise10": lambda c: noisy(c, 10.0),
    "noise20": lambda c: noisy(c, 20.0),
    "320x240": lambda c: resized(c, 320 / c.image.shape[1], "320x240"),
    "rot90": lambda c: rotated(c, 90),
    "rot15": lambda c: rotated(c, 15),
    "rot30": lambda c: rotated(c, 30),
    "rot45": lambda c: rotated(c, 45),
    "jpeg20": lambda c: jpeg(c, 20),
    "x2": lambda c: resized(c, 2.0),
    "x3": lambda c: resized(c, 3.0),
}


def cases(families: list[str], resolutions: list[str], degradations: list[str], base=benchmark) -> Iterator[Case]:  # type: ignore[no-untyped-def]
    """Every degradation of every family's `base` image (ViSP's `benchmark`, or `rendered`) at
    every resolution (upscaled 3x only from 640 x 480)."""
    for family in families:
        for resolution in resolutions:
            image = base(family, resolution)
            for name in degradations:
                if name == "x3" and resolution != "640x480":
                    continue  # 5760 x 3240: no more than x2 shows
                yield DEGRADATIONS[name](image)


# --------------------------------------------------------------------------- reference detectors


def opencv(family: str, refine: str = "subpix") -> Callable[[np.ndarray], Corners] | None:
    """OpenCV's aruco detector of the family (None: OpenCV has not got it); `refine`: "none",
    "subpix" or "apriltag" (whose corners are in the AprilTag library's convention: moved by
    -0.5 here)."""
    name = FAMILIES[family][1]
    if name is None:
        return None
    params = cv2.aruco.DetectorParameters()
    params.cornerRefinementMethod = {
        "none": cv2.aruco.CORNER_REFINE_NONE,
        "subpix": cv2.aruco.CORNER_REFINE_SUBPIX,
        "apriltag": cv2.aruco.CORNER_REFINE_APRILTAG,
    }[refine]
    detector = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, name)), params)
    shift = 0.5 if refine == "apriltag" else 0.0

    def detect(image: np.ndarray) -> Corners:
        corners, ids, _ = detector.detectMarkers(image)
        if ids is None:
            return {}
        return {int(i): c.reshape(4, 2).astype(np.float64) - shift for i, c in zip(ids.ravel(), corners)}

    return detect


@functools.cache
def _pupil_detector(family: str):  # type: ignore[no-untyped-def]
    # One detector per family for the process: pupil-apriltags aborts when detectors of one
    # family are made and freed again and again.
    import pupil_apriltags

    return pupil_apriltags.Detector(families=family, nthreads=1)


def pupil(family: str) -> Callable[[np.ndarray], Corners] | None:
    """The reference AprilTag library (pupil-apriltags; None when not installed)."""
    try:
        detector = _pupil_detector(family)
    except ImportError:
        return None

    def detect(image: np.ndarray) -> Corners:
        return {int(t.tag_id): np.asarray(t.corners, np.float64)[VISP_TO_OPENCV] - 0.5 for t in detector.detect(image)}

    return detect


def vsinv_detector(family: str) -> Callable[[np.ndarray], Corners]:
    import vsinv

    def detect(image: np.ndarray) -> Corners:
        tags = vsinv.vision.detect_tags(image, family=family)
        return {int(i): c for i, c in zip(tags.ids, tags.corners)}

    return detect


def paired_medians(ours: Corners, theirs: Corners, truth: Corners | None) -> tuple[float, float] | None:
    """The median corner errors of two detectors on the tags both decoded (None: no such tag)."""
    both = set(ours) & set(theirs)
    if not both:
        return None
    a, b = (float(np.median(corner_errors({t: f[t] for t in both}, truth))) for f in (ours, theirs))
    return a, b


def in_view(case: Case) -> set[int]:
    """The ids of the tags whose four true corners are in the image (all of them where no truth
    is known). A tag cut by the border has a corner nobody can measure: vsinv does not report it
    (pupil-apriltags does, with that corner pixels off: 4.3 px for tag 1 of the rendered set
    turned by 45 degrees)."""
    if case.truth is None:
        return case.ids
    h, w = case.image.shape[:2]
    return {t for t, c in case.truth.items() if np.all((c >= -0.5) & (c <= np.array([w, h]) - 0.5))}


def corner_errors(found: Corners, truth: Corners | None) -> np.ndarray:
    """Distances (pixels) of the found tags' corners to the true ones."""
    if truth is None:
        return np.empty(0)
    errors = [np.linalg.norm(found[t] - c, axis=1) for t, c in truth.items() if t in found]
    return np.concatenate(errors) if errors else np.empty(0)
