"""`vsinv.vision.detect_tags` on ViSP's AprilTag benchmark and degraded versions of it (blur, noise,
downscaling, rotations, JPEG, upscaling; tests/tag_sets.py), against OpenCV's aruco detector and
the reference AprilTag library (pupil-apriltags): every tag either of them decodes, vsinv decodes
too, no id that is not in the image, and on the clean images its corners are as close to ViSP's
published ground truth as the reference library's (median within 0.1 px).

Skipped when visp-images-data, OpenCV or pupil-apriltags is absent.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
cv2 = pytest.importorskip("cv2")
pupil_apriltags = pytest.importorskip("pupil_apriltags")
import tag_sets  # noqa: E402

if not tag_sets.BENCHMARK.is_dir():
    pytest.skip("ViSP's image dataset is not installed: apt-get install visp-images-data", allow_module_level=True)

# Kept to a few seconds: every degradation on tag36h11 at 640 x 480, the costly ones (1920 x
# 1080, upscaled) on a few; the other families on a sample.
CASES = [
    ("tag36h11", "640x480", list(tag_sets.DEGRADATIONS)),
    ("tag36h11", "1920x1080", ["clean", "blur3", "noise20", "320x240", "rot90", "rot30", "jpeg20"]),
    ("tag25h9", "640x480", ["clean", "blur2", "noise20", "320x240", "rot45"]),
    ("tag16h5", "640x480", ["clean", "blur2", "noise10", "320x240", "rot15", "jpeg20"]),
    ("tag16h5", "1920x1080", ["clean", "noise20"]),
    # AprilTag 3's families (a bright square in a dark ring): pupil-apriltags only.
    ("tagStandard41h12", "640x480", ["clean", "noise10", "320x240", "rot90"]),
    ("tagStandard41h12", "1920x1080", ["clean"]),
    ("tagStandard52h13", "640x480", ["clean", "blur1"]),
    ("tagCircle21h7", "640x480", ["clean", "rot30"]),
    ("tagCircle49h12", "640x480", ["clean", "jpeg20"]),
    ("tagCustom48h12", "640x480", ["clean", "noise5"]),
]


# pupil-apriltags takes 15-25 s to build its decoding table of these large families: for them
# the ground truth's tags stand for the references (all of them must be found), and the
# corners' median against the truth must be below 0.1 px (pupil-apriltags: 0.026, 0.060 and
# 0.041 px on the clean images, measured by benches/tags_robustness.py).
SLOW_REFERENCE = {"tagStandard52h13", "tagCircle49h12", "tagCustom48h12"}


def params() -> list:
    return [pytest.param(f, r, d, id=f"{f}-{r}-{d}") for f, r, degs in CASES for d in degs]


@pytest.mark.parametrize(("family", "resolution", "degradation"), params())
def test_every_tag_the_references_decode_is_decoded_with_no_wrong_id(family: str, resolution: str, degradation: str) -> None:
    case = tag_sets.DEGRADATIONS[degradation](tag_sets.benchmark(family, resolution))
    ours = tag_sets.vsinv_detector(family)(case.image)
    if family in SLOW_REFERENCE:
        theirs = case.ids
    else:
        references = [d for d in (tag_sets.opencv(family), tag_sets.pupil(family)) if d is not None]
        theirs = set().union(*(set(d(case.image)) & case.ids for d in references))
    assert not set(ours) - case.ids, f"{case.name}: wrong ids {sorted(set(ours) - case.ids)}"
    assert theirs <= set(ours), f"{case.name}: missed {sorted(theirs - set(ours))} (references found {sorted(theirs)})"
    if case.truth is not None:
        errors = tag_sets.corner_errors(ours, case.truth)
        # Blur of 3 px on 5 px cells moves every detector's corners by up to about a pixel.
        assert errors.max() < (1.5 if degradation in ("blur2", "blur3") else 0.75), case.name


@pytest.mark.parametrize("family", list(tag_sets.FAMILIES))
def test_clean_corners_are_as_accurate_as_the_reference_librarys(family: str) -> None:
    case = tag_sets.benchmark(family, "640x480")
    ours = tag_sets.corner_errors(tag_sets.vsinv_detector(family)(case.image), case.truth)
    if family in SLOW_REFERENCE:
        print(f"{family}: vsinv median {np.median(ours):.3f} px")
        assert ours.size == 4 * len(case.truth) and np.median(ours) < 0.1  # type: ignore[arg-type]
        return
    reference = tag_sets.corner_errors(tag_sets.pupil(family)(case.image), case.truth)  # type: ignore[misc]
    print(f"{family}: vsinv median {np.median(ours):.3f} px, pupil-apriltags {np.median(reference):.3f} px")
    assert ours.size == reference.size == 4 * len(case.truth)  # type: ignore[arg-type]
    assert np.median(ours) <= np.median(reference) + 0.1


def test_the_small_tag_blurred_by_2_px_is_found_as_accurately_as_by_the_reference_library() -> None:
    """Tag 4 of the 640 x 480 image (40 px, 5 px cells) blurred by 2 px: the blur reaches the
    data cells and the dark background beyond the one-cell quiet zone, and its edges settle
    slowly (src/vision/tags/edges.rs, `refine_blurred_corners`). pupil-apriltags decodes it
    (OpenCV does not): vsinv's corners are no farther from ViSP's ground truth than its."""
    case = tag_sets.DEGRADATIONS["blur2"](tag_sets.benchmark("tag36h11", "640x480"))
    ours = tag_sets.vsinv_detector("tag36h11")(case.image)
    theirs = tag_sets.pupil("tag36h11")(case.image)  # type: ignore[misc]
    assert 4 in ours and 4 in theirs
    truth = case.truth[4]  # type: ignore[index]
    ours_error = np.linalg.norm(ours[4] - truth, axis=1)
    theirs_error = np.linalg.norm(theirs[4] - truth, axis=1)
    print(f"tag 4 blurred: vsinv {ours_error.round(2)} px, pupil-apriltags {theirs_error.round(2)} px")
    assert np.median(ours_error) <= np.median(theirs_error) + 0.1
    assert ours_error.max() <= theirs_error.max() + 0.1


# Rendered tags (tests/tag_sets.py's `rendered`: corners known exactly, owing nothing to any
# detector). On the tags both decode, vsinv's corners are the most accurate of all: sharp,
# blurred, resampled or turned (medians 0.001-0.03 px; pupil-apriltags 0.02-0.07, OpenCV's
# AprilTag refinement 0.05-0.2, its subpixel refinement 0.2-1.2), and under noise and JPEG
# artefacts (0.02-0.09 px; pupil-apriltags 0.06-0.10), measured by benches/tags_robustness.py.
RENDERED_BEST = [
    ("tag36h11", "640x480", ["clean", "blur1", "blur2", "x2", "rot90", "rot15", "320x240"]),
    ("tag36h11", "1920x1080", ["clean", "blur3", "rot15"]),
    ("tag25h9", "640x480", ["clean", "blur2", "rot45"]),
    ("tag36h11", "640x480", ["rot45"]),
    ("tag16h5", "640x480", ["clean", "blur3", "320x240"]),
]
RENDERED_NOISY = [
    ("tag36h11", "640x480", ["noise10", "noise20", "jpeg20"]),
    ("tag25h9", "640x480", ["blur3", "noise10"]),
    ("tag16h5", "1920x1080", ["noise10", "jpeg20"]),
]


def rendered_params(sets: list) -> list:
    return [pytest.param(f, r, d, id=f"{f}-{r}-{d}") for f, r, degs in sets for d in degs]


def rendered_medians(family: str, resolution: str, degradation: str) -> dict[str, tuple[float, float]]:
    """Per reference detector, vsinv's median corner error and the reference's on the tags of the
    rendered set both decode; vsinv must report no id that is not in the image and every tag a
    reference decodes whose corners are all in the image."""
    case = tag_sets.DEGRADATIONS[degradation](tag_sets.rendered(family, resolution))
    ours = tag_sets.vsinv_detector(family)(case.image)
    assert set(ours) <= case.ids, f"{case.name}: wrong ids {sorted(set(ours) - case.ids)}"
    references = {"cv subpix": tag_sets.opencv(family), "cv april": tag_sets.opencv(family, "apriltag"),
                  "pupil": tag_sets.pupil(family)}
    medians = {"vsinv": (float(np.median(tag_sets.corner_errors(ours, case.truth))),) * 2}
    for name, detect in references.items():
        found = detect(case.image)  # type: ignore[misc]
        missed = set(found) & tag_sets.in_view(case) - set(ours)
        assert not missed, f"{case.name}: {name} decoded {sorted(missed)} too"
        paired = tag_sets.paired_medians(ours, found, case.truth)
        if paired is not None:
            medians[name] = paired
    print(case.name, {k: tuple(round(m, 3) for m in v) for k, v in medians.items()})
    return medians


@pytest.mark.parametrize(("family", "resolution", "degradation"), rendered_params(RENDERED_BEST))
def test_rendered_tags_corners_are_the_most_accurate(family: str, resolution: str, degradation: str) -> None:
    medians = rendered_medians(family, resolution, degradation)
    assert medians.pop("vsinv")[0] < 0.05
    for name, (ours, theirs) in medians.items():
        assert ours <= theirs, f"{name}: {theirs:.3f} px, vsinv {ours:.3f} px on the same tags"


@pytest.mark.parametrize(("family", "resolution", "degradation"), rendered_params(RENDERED_NOISY))
def test_rendered_noisy_tags_corners_are_the_most_accurate_too(family: str, resolution: str, degradation: str) -> None:
    medians = rendered_medians(family, resolution, degradation)
    # Blur of 3 px reaches the data cells of 9 px cells: vsinv decodes all five tags (the
    # smallest at 0.1-1.1 px), pupil-apriltags four.
    assert medians.pop("vsinv")[0] < (0.15 if degradation == "blur3" else 0.1)
    for name, (ours, theirs) in medians.items():
        assert ours <= theirs, f"{name}: {theirs:.3f} px, vsinv {ours:.3f} px on the same tags"


def test_rendered_corners_are_where_the_homography_puts_them() -> None:
    """The rendering's own check, without any detector: each tag's black square, averaged over
    the pixels it covers, is dark exactly inside the corners (the mean grey level of the pixels
    well inside is black, of a ring just outside is white), and 8 x 8 samples a pixel give the
    same image as 16 x 16 within a grey level or two away from the edges."""
    case = tag_sets.rendered("tag36h11", "640x480")
    for tag, corners in case.truth.items():  # type: ignore[union-attr]
        centre = corners.mean(axis=0)
        inside = (corners - centre) * 0.9 + centre
        outside = (corners - centre) * 1.15 + centre
        mask_in = np.zeros(case.image.shape, np.uint8)
        cv2.fillConvexPoly(mask_in, np.round(inside).astype(np.int32), 1)
        ring = np.zeros(case.image.shape, np.uint8)
        cv2.fillConvexPoly(ring, np.round(outside).astype(np.int32), 1)
        cv2.fillConvexPoly(ring, np.round((corners - centre) * 1.03 + centre).astype(np.int32), 0)
        # A one-cell black border, then data cells: the border's ring inside is black.
        border = np.zeros(case.image.shape, np.uint8)
        cv2.fillConvexPoly(border, np.round((corners - centre) * 0.97 + centre).astype(np.int32), 1)
        cv2.fillConvexPoly(border, np.round((corners - centre) * 0.8 + centre).astype(np.int32), 0)
        assert case.image[border > 0].mean() < 35, tag
        assert case.image[ring > 0].mean() > 215, tag
        assert mask_in.sum() > 0
    finer = tag_sets.RENDER_SAMPLES
    try:
        tag_sets.RENDER_SAMPLES = 16
        fine = tag_sets.rendered("tag36h11", "640x480").image
    finally:
        tag_sets.RENDER_SAMPLES = finer
    assert np.abs(fine.astype(int) - case.image.astype(int)).max() <= 12
    assert np.abs(fine.astype(int) - case.image.astype(int)).mean() < 0.05
