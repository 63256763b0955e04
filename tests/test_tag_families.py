"""Every AprilTag family through every layer: a rig of each family's tags (``object.tag_family``),
drawn by vsinv's renderer from the family data the decoder uses, is read by an independent
decoder, the reference AprilTag library (pupil-apriltags), and by ``vsinv.vision.detect_tags``: the
same ids, and corners at the renderer's ground truth (the true projections of the rig's
corners). A tagStandard41h12 rig runs through ``load_scenario``/``vsinv run`` to ``converged``
as the tag36h11 built-ins do; a wrong family name is refused, naming the key and listing the
names of the one declaration (``vsinv.vision.TAG_FAMILIES``).

pupil-apriltags reports corners as the AprilTag library does (bottom-left, bottom-right,
top-right, top-left of its layout, pixel centres at +0.5): converted to OpenCV's order and
convention as in tests/tag_sets.py."""

from __future__ import annotations

import ast
import copy
import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import vsinv

#: pupil-apriltags' corner k is vsinv's corner VISP_TO_OPENCV[k] (tests/tag_sets.py).
VISP_TO_OPENCV = [1, 0, 3, 2]
#: Every family has at least 30 ids.
IDS = [0, 7, 29]
#: Turns of the three tags (theta-u, degrees, in the rig frame): facing the camera, then oblique.
TURNS = [[0.0, 0.0, 0.0], [0.0, 35.0, 10.0], [-30.0, -20.0, 0.0]]


#: The families read by OpenCV's aruco instead of the reference library (its corners in
#: vsinv's order and convention, subpixel-refined): pupil-apriltags has no tag36h10, and its
#: tag16h5 corrupts the heap on these images (glibc aborts its process).
OPENCV_ONLY = {"tag36h10": "DICT_APRILTAG_36h10", "tag16h5": "DICT_APRILTAG_16h5"}


#: Decodes the image of a .npy file with pupil-apriltags and prints the tags as JSON.
_PUPIL_SCRIPT = """
import json, sys
import numpy as np, pupil_apriltags
detector = pupil_apriltags.Detector(families=sys.argv[1], nthreads=1)
tags = detector.detect(np.load(sys.argv[2]))
print(json.dumps({int(t.tag_id): np.asarray(t.corners, float).tolist() for t in tags}))
"""


def _pupil(family: str, image: np.ndarray, tmp_path: Path) -> dict[int, np.ndarray]:
    """The reference library's tags, corners in vsinv's order and convention. In a process of
    its own: pupil-apriltags corrupts the heap when detectors of several families live in one
    process (glibc aborts it at exit)."""
    pytest.importorskip("pupil_apriltags")
    path = tmp_path / "image.npy"
    np.save(path, image)
    out = subprocess.run([sys.executable, "-c", _PUPIL_SCRIPT, family, str(path)], capture_output=True, text=True,
                         check=True, timeout=120)
    return {int(i): np.asarray(c, np.float64)[VISP_TO_OPENCV] - 0.5 for i, c in json.loads(out.stdout).items()}


def _reference(family: str, image: np.ndarray, tmp_path: Path) -> dict[int, np.ndarray]:
    """The tags an independent decoder reads, corners in vsinv's order and convention."""
    if family in OPENCV_ONLY:
        cv2 = pytest.importorskip("cv2")
        params = cv2.aruco.DetectorParameters()
        params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
        dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, OPENCV_ONLY[family]))
        corners, ids, _ = cv2.aruco.ArucoDetector(dictionary, params).detectMarkers(image)
        return {} if ids is None else {int(i): c.reshape(4, 2).astype(np.float64) for c, i in zip(corners, ids.ravel())}
    return _pupil(family, image, tmp_path)


def _rig(family: str, blur: float = 0.0, noise: float = 0.0) -> dict:
    """tags-12-12 with three 40 mm tags of ``family`` 0.6 m in front of the reference camera,
    0.11 m apart (the widest face, tagCircle49h12's, is 88 mm), no control."""
    d = vsinv.load_scenario("tags-12-12").to_dict()
    d["object"]["tag_family"] = family
    d["object"]["rig"] = {"position": [0.0, 0.0, 0.6], "rotation_deg": [180.0, 0.0, 0.0]}
    d["object"]["tags"] = [
        {"id": i, "size": 0.04, "position": [x, 0.0, 0.0], "rotation_deg": turn}
        for i, x, turn in zip(IDS, [-0.11, 0.0, 0.11], TURNS)
    ]
    d["control"] = {"law": "none", "dt": d["control"]["dt"]}
    d["vision"].update(blur_sigma=blur, noise_sigma=noise)
    return d


def _errors(found: dict[int, np.ndarray], truth: np.ndarray) -> np.ndarray:
    """Corner errors (px) of the decoded tags IDS against the projections, (3, 4)."""
    return np.array([np.hypot(*(found[i] - truth[4 * k : 4 * k + 4]).T) for k, i in enumerate(IDS)])


@pytest.mark.parametrize("blur, noise", [(0.0, 0.0), (0.8, 1.0)])
@pytest.mark.parametrize("family", vsinv.vision.TAG_FAMILIES)
def test_rendered_tags_of_every_family_decode_at_their_projected_corners(family, blur, noise, tmp_path):
    image, truth, visible = vsinv.vision.render_view(_rig(family, blur, noise), reference=True)
    assert visible.all()
    reference = _reference(family, image, tmp_path)
    # tag16h5's codes are 5 bits apart, tagCircle21h7's 7: the reference decoder may read a
    # random square of the blurred, noisy image as a tag too (pupil-apriltags reads a tag 31 of
    # tagCircle21h7 in this image); vsinv reads one bit error at most for tag16h5, and reports
    # exactly the tags drawn (below).
    few_bits = family in ("tag16h5", "tagCircle21h7")
    assert set(IDS) <= set(reference) and (few_bits or sorted(reference) == IDS), (family, sorted(reference))
    tags = vsinv.vision.detect_tags(image, family=family)
    ours = {int(i): c for i, c in zip(tags.ids, tags.corners)}
    assert sorted(ours) == IDS, family
    theirs, mine = _errors({i: reference[i] for i in IDS}, truth), _errors(ours, truth)
    print(f"{family} blur {blur}: reference median {np.median(theirs):.3f} max {theirs.max():.3f} px, "
          f"vsinv median {np.median(mine):.3f} max {mine.max():.3f} px")
    # The reference library's quad fit (OpenCV's subpixel refinement for tag36h10): within a
    # third of a pixel, so the drawn corners are where the family's layout puts them, in the
    # same order; vsinv's edge-measured corners within a tenth.
    # OpenCV's subpixel refinement pulls each corner about 0.3 px into the square (its bias,
    # tests/test_tag_rig.py).
    assert theirs.max() < (0.5 if family in OPENCV_ONLY else 0.35), (family, theirs)
    assert mine.max() < 0.1, (family, mine)


def test_a_round_family_is_cut_to_its_disc_and_the_others_are_square():
    # Fronto-parallel tag 0, 8 mm cells at 0.6 m with f = 1200 px: 16 px cells. The grid's
    # corner cells are outside tagCircle21h7's disc (background) and a data cell of
    # tagStandard41h12 (id 0's bit at its top-left corner: set or not, as pupil decodes it).
    for family, corner_dark in (("tagCircle21h7", True), ("tagStandard41h12", None)):
        d = _rig(family)
        d["object"]["tags"] = d["object"]["tags"][1:2]
        d["object"]["tags"][0].update(id=0, rotation_deg=[0.0, 0.0, 0.0], position=[0.0, 0.0, 0.0])
        image, truth, _ = vsinv.vision.render_view(d, reference=True)
        cell = (truth[2] - truth[0]) / 5.0  # the reported square: 5 cells
        centre = truth.mean(axis=0)
        background = d["vision"]["background"]
        for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            u, v = np.round(centre + 4.0 * cell * [su, sv]).astype(int)  # the grid's corner cells
            if corner_dark:
                assert abs(int(image[v, u]) - background) < 10, (family, u, v, image[v, u])
        # The white square inside the black ring: white at its inner cells, black just outside.
        for k in range(4):
            inside = np.round(truth[k] + 0.5 * np.sign(centre - truth[k]) * np.abs(cell)).astype(int)
            outside = np.round(truth[k] - 0.5 * np.sign(centre - truth[k]) * np.abs(cell)).astype(int)
            assert image[inside[1], inside[0]] > 200 and image[outside[1], outside[0]] < 60, (family, k)


def test_a_tag_standard_41h12_rig_runs_to_converged(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # tags-12-6 with tagStandard41h12 tags: 80 mm squares, whose faces (9 cells of 16 mm)
    # fit the cube's 150 mm faces (tag36h11's 100 mm squares have 125 mm faces). The stop rule
    # (0.5 px) leaves 2.87 mm and 0.031 degrees after 675 iterations (tag36h11's larger squares,
    # tags-12-6: 1.72 mm and 0.036 deg), with corner errors of median 0.013 px, max 0.08 px.
    d = copy.deepcopy(vsinv.load_scenario("tags-12-6").to_dict())
    d["name"] = "tags41-12-6"
    d["object"]["tag_family"] = "tagStandard41h12"
    for tag in d["object"]["tags"]:
        tag["size"] = 0.08
    result = vsinv.run_scenario(vsinv.load_scenario(d))
    s = result.summary
    print({k: s[k] for k in ("status", "iterations", "final_translation_error", "final_rotation_error")})
    assert s["status"] == "converged", s
    assert s["final_translation_error"] < 3e-3 and np.degrees(s["final_rotation_error"]) < 0.2, s
    detection = result.detection_error
    assert detection is not None and np.nanmax(detection) < 0.1
    # The same file through the command line.
    from vsinv import cli

    path = tmp_path / "tags41.toml"
    path.write_text(vsinv.load_scenario(d).to_toml())
    capsys.readouterr()
    code = cli.main(["run", str(path), "--json", "--no-progress"])
    summary = json.loads(capsys.readouterr().out)
    assert (code, summary["status"], summary["iterations"]) == (0, "converged", s["iterations"])


def test_a_wrong_family_is_refused_naming_the_key_and_the_families():
    d = _rig("tag36h11")
    d["object"]["tag_family"] = "tag36h12"
    with pytest.raises(vsinv.InvalidInput) as error:
        vsinv.load_scenario(d)
    message = str(error.value)
    assert "object.tag_family" in message and all(f'"{name}"' in message for name in vsinv.vision.TAG_FAMILIES), message
    d["object"]["tag_family"] = "tagCircle21h7"
    d["object"]["tags"][2]["id"] = 38  # the family has 38 ids
    with pytest.raises(vsinv.InvalidInput, match=re.escape("object.tags[2].id: a tagCircle21h7 id, 0 to 37, got 38")):
        vsinv.load_scenario(d)
    with pytest.raises(vsinv.InvalidInput, match='family: expected one of "tag36h11", .*, got "tag36h12"'):
        vsinv.vision.detect_tags(np.zeros((40, 40), np.uint8), family="tag36h12")


def test_the_stubs_name_the_families_of_the_one_declaration():
    stub = (Path(vsinv.__file__).parent / "_core.pyi").read_text()
    literal = re.search(r"_TagFamily = Literal\[(.*?)\]", stub, re.S)
    assert literal is not None
    assert tuple(ast.literal_eval(f"[{literal.group(1)}]")) == vsinv.vision.TAG_FAMILIES
    assert vsinv.vision.TAG_FAMILIES[0] == "tag36h11" and "tagStandard41h12" in vsinv.vision.TAG_FAMILIES


@pytest.mark.parametrize("family", ["tagStandard41h12", "tagCircle21h7"])
def test_invariance_reads_a_rendered_rig_of_the_family(family, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # The rig seen by the reference camera and by the servo camera at its start pose: the
    # command decodes the family's tags in both (12 corners by identity).
    from vsinv import cli

    d = _rig(family)
    vsinv.vision.save_image(vsinv.vision.render(d, reference=True), tmp_path / "ref.png")
    vsinv.vision.save_image(vsinv.vision.render(d, pose=np.diag([1.0, 1.0, 1.0, 1.0])), tmp_path / "cur.png")
    code = cli.main(["invariance", str(tmp_path / "ref.png"), str(tmp_path / "cur.png"), "--target", "tags",
                     "--family", family])
    captured = capsys.readouterr()
    assert code == 0 and "over 12 of 12" in captured.out, (captured.out, captured.err)
    code = cli.main(["invariance", str(tmp_path / "ref.png"), str(tmp_path / "cur.png"), "--target", "tags",
                     "--family", "tag36h11"])
    assert code != 0  # no tag36h11 tag in the reference image
