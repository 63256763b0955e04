"""AprilTag rigs as the simulator renders them, checked by an independent decoder: OpenCV's
aruco ``DICT_APRILTAG_36h11`` reads the rendered tags with their ids, the corners in its order
(top-left, top-right, bottom-right, bottom-left as it prints the tag) at the true projections
of the rig's 3D corners (points ``4 k .. 4 k + 3`` of tag ``k``), and each cell as
``cv2.aruco.generateImageMarker`` prints it."""

from __future__ import annotations

import copy
import re

import numpy as np
import pytest

import vsinv

cv2 = pytest.importorskip("cv2")


def _detector(win: int = 5):
    params = cv2.aruco.DetectorParameters()
    params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    params.cornerRefinementWinSize = win
    dictionary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11)
    return cv2.aruco.ArucoDetector(dictionary, params)


def _one_tag(tag_id: int, rotation_deg: list[float], noise: float, blur: float) -> dict:
    """tags-12-12 with one 80 mm tag at 0.6 m on the optical axis, turned by rotation_deg from
    facing the reference camera (its printed face towards it, upright)."""
    d = vsinv.load_scenario("tags-12-12").to_dict()
    d["object"]["rig"] = {"position": [0.0, 0.0, 0.6], "rotation_deg": [180.0, 0.0, 0.0]}
    d["object"]["tags"] = [{"id": tag_id, "size": 0.08, "position": [0.0, 0.0, 0.0], "rotation_deg": rotation_deg}]
    d["control"]["law"] = "none"
    for key in ("gain", "gain_rz", "depths", "rz_task", "max_linear_speed", "max_angular_speed_deg"):
        d["control"].pop(key, None)
    d["vision"].update(noise_sigma=noise, blur_sigma=blur)
    return d


def _decode(image: np.ndarray, win: int = 5) -> dict[int, np.ndarray]:
    corners, ids, _ = _detector(win).detectMarkers(image)
    return {} if ids is None else {int(i): c.reshape(4, 2) for c, i in zip(corners, ids.ravel())}


@pytest.mark.parametrize("rotation_deg", [[0.0, 0.0, 0.0], [0.0, -25.0, 10.0], [0.0, 45.0, 0.0]])
def test_opencv_reads_a_rendered_tag_at_its_projected_corners(rotation_deg):
    image, pixels, visible = vsinv.vision.render_view(_one_tag(42, rotation_deg, 0.0, 0.0), reference=True)
    assert visible.all()
    found = _decode(image)
    assert list(found) == [42]
    error = np.hypot(*(found[42] - pixels).T)
    # OpenCV's subpixel refinement pulls each corner about 0.14 px into the black square (on
    # its own generated marker too: test below); the centre is unbiased.
    assert error.max() < 0.2, error
    assert np.abs(found[42].mean(axis=0) - pixels.mean(axis=0)).max() < 0.03


def test_opencv_has_the_same_corner_bias_on_its_own_marker():
    # OpenCV's marker, 20 px cells, its black square's top-left pixel at (120, 100): the square
    # spans u in [119.5, 279.5] in the pixel-centre convention.
    dictionary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11)
    image = np.full((400, 400), 220, np.uint8)
    marker = cv2.aruco.generateImageMarker(dictionary, 42, 160, borderBits=1)
    image[100:260, 120:280] = np.where(marker > 127, 220, 30)
    found = _decode(image)[42]
    truth = np.array([[119.5, 99.5], [279.5, 99.5], [279.5, 259.5], [119.5, 259.5]])
    inward = (found - truth) * np.sign(truth.mean(axis=0) - truth)
    assert (inward > 0.03).all() and np.hypot(*(found - truth).T).max() < 0.2


def test_a_pixel_aligned_tag_is_opencvs_marker_pixel_for_pixel():
    # 0.08 m at 0.6 m with f = 1200 px: 160 px; moved by half a pixel (0.25 mm) so that the
    # black square spans whole pixels, 336..495 x 232..391.
    d = _one_tag(42, [0.0, 0.0, 0.0], 0.0, 0.0)
    d["object"]["rig"]["position"] = [-0.00025, -0.00025, 0.6]
    image, pixels, _ = vsinv.vision.render_view(d, reference=True)
    np.testing.assert_allclose(pixels[0], [335.5, 231.5], atol=1e-9)
    dictionary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11)
    marker = cv2.aruco.generateImageMarker(dictionary, 42, 160, borderBits=1)
    background, foreground = d["vision"]["background"], d["vision"]["foreground"]
    expected = np.full((200, 200), foreground, np.uint8)  # the quiet zone: one 20 px cell
    expected[20:180, 20:180] = np.where(marker > 127, foreground, background)
    assert np.array_equal(image[212:412, 316:516], expected)


def test_the_built_in_rigs_decode_by_identity_with_both_lenses():
    for name in ("tags-12-12", "tags-12-6"):
        for reference in (True, False):
            image, pixels, visible = vsinv.vision.render_view(name, reference=reference)
            assert visible.all()
            found = _decode(image)
            assert sorted(found) == [1, 2, 3], (name, reference)
            for k, tag_id in enumerate([1, 2, 3]):
                # Each decoded corner is nearest to its own projected corner (the order); on
                # these oblique, small, blurred and noisy faces OpenCV's refinement strays by
                # up to 5 px (the 6 mm start view's bottom tag), less than a cell.
                corners = pixels[4 * k : 4 * k + 4]
                distance = np.hypot(*(found[tag_id][:, None, :] - corners[None, :, :]).transpose(2, 0, 1))
                assert (distance.argmin(axis=1) == np.arange(4)).all(), (name, reference, tag_id)
                assert distance.diagonal().max() < 6.0, (name, reference, tag_id, distance.diagonal())


def test_the_cells_are_printed_as_opencv_prints_them():
    # Fronto-parallel, 0.08 m at 0.6 m with f = 1200 px: 20 px cells, read at their centres.
    for tag_id in (0, 7, 586):
        image, pixels, _ = vsinv.vision.render_view(_one_tag(tag_id, [0.0, 0.0, 0.0], 0.0, 0.0), reference=True)
        top_left, bottom_right = pixels[0], pixels[2]
        cell = (bottom_right - top_left) / 8.0
        read = np.zeros((10, 10), dtype=bool)
        for r in range(10):
            for c in range(10):
                u, v = top_left + cell * (np.array([c, r]) - 1 + 0.5)
                read[r, c] = image[int(round(v)), int(round(u))] > 125
        dictionary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11)
        printed = cv2.aruco.generateImageMarker(dictionary, tag_id, 80, borderBits=1)[5::10, 5::10] > 127
        assert (read[1:9, 1:9] == printed).all(), tag_id
        # The white quiet zone around the black border.
        assert read[0].all() and read[9].all() and read[:, 0].all() and read[:, 9].all()


@pytest.mark.parametrize(
    "edit, key",
    [
        (lambda d: d["object"]["tags"][1].update(id=587), "object.tags[1].id"),
        (lambda d: d["object"]["tags"][2].update(id=1), "object.tags[2].id"),
        (lambda d: d["object"]["tags"][0].update(size=0.0), "object.tags[0].size"),
        (lambda d: d["object"]["tags"][0].update(shape="square"), "object.tags"),
        (lambda d: d["object"]["tags"][0].pop("size"), "object.tags"),
        (lambda d: d["object"].update(points=[[0.0, 0.0, 1.0]] * 6), "object.points"),
        (lambda d: d["object"].update(normals=[[0.0, 0.0, -1.0]] * 12), "object.normals"),
        (lambda d: d["object"]["rig"].update(position=[0.0, 0.0, -0.65]), "object.tags[0]"),
        (lambda d: d["object"].update(tags=d["object"]["tags"][:1]), "object.tags"),
    ],
)
def test_bad_tags_name_the_key(edit, key):
    d = copy.deepcopy(vsinv.load_scenario("tags-12-6").to_dict())
    edit(d)
    with pytest.raises(vsinv.InvalidInput, match=re.escape(key)):
        vsinv.sim.Scenario.from_dict(d)


def test_views_outline_each_tag_with_its_id():
    pytest.importorskip("matplotlib")
    from vsinv.view_plots import _CYAN, _gif_frame, _tag_ids, plot_view

    scenario = vsinv.load_scenario("tags-12-12")
    assert _tag_ids(scenario) == [1, 2, 3] and _tag_ids(vsinv.load_scenario("vision-12-12")) == []
    image, pixels, _ = vsinv.vision.render_view(scenario, reference=True)
    hidden = pixels.copy()
    hidden[4:8] = np.nan  # tag 2 not detected: no outline
    fig = plot_view(image, hidden, pixels, "tags", tag_ids=_tag_ids(scenario))
    texts = [t.get_text() for t in fig.axes[0].texts]
    assert "id 1" in texts and "id 3" in texts and "id 2" not in texts
    drawn = np.asarray(_gif_frame(image, pixels, pixels, [1, 2, 3], "t = 0.00 s"))  # the GIF's frame
    # The outline passes through the corners' pixels.
    u, v = np.round(pixels[0]).astype(int)
    assert (drawn[v - 1 : v + 2, u - 1 : u + 2] == _CYAN).any()
    assert not (np.asarray(_gif_frame(image, pixels, pixels, [], "t = 0.00 s")) == _CYAN).any()


def test_the_scene_figure_places_a_rigs_corners():
    from vsinv.plots import _object_points

    d = vsinv.load_scenario("tags-12-12").to_dict()
    _, pixels, _ = vsinv.vision.render_view(d, reference=True)
    corners = _object_points(d)
    assert corners.shape == (12, 3)
    # Projected with K* at F*: the rendered views' true projections.
    projected = 1200.0 * corners[:, :2] / corners[:, 2:] + [416.0, 312.0]
    np.testing.assert_allclose(projected, pixels, atol=1e-6)
