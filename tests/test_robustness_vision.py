"""Robustness of the public Python API under hypothesis, images: rendering, dot detection and
tracking, image files.

The promise and the harness are described in tests/robustness_harness.py.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

import vsinv
from robustness_harness import (
    ANY, INVALID, RAISE, RETURN, SAME, TYPE, V, VISION, arrays, call, choices, covers, cv2, floats, fuzz,
    fuzz_settings, ints, k_variants, returned,
)


# ---------------------------------------------------------------------------------------------
# images


def image_variants(valid: np.ndarray) -> st.SearchStrategy[V]:
    h, w = valid.shape
    return st.sampled_from([
        V(valid, SAME, "valid"),
        V(np.asfortranarray(valid), SAME, "fortran"),
        V(np.repeat(valid, 2, axis=1)[:, ::2], SAME, "strided"),
        V(valid.astype(np.int64), INVALID, "int64"),
        V(valid.astype(np.float64), INVALID, "float64"),
        V(valid.astype(np.uint16), INVALID, "uint16"),
        V(np.stack([valid] * 3, axis=-1), SAME, "colour"),  # BGR of equal channels: the same grey
        V(np.stack([valid] * 3 + [255 - valid], axis=-1), SAME, "bgra"),  # alpha ignored
        V(valid[:, :, None], SAME, "one channel"),
        V(np.stack([valid] * 2, axis=-1), INVALID, "two channels"),
        V(valid.ravel(), INVALID, "1-d"),
        V(valid.tolist(), INVALID, "list"),
        V(None, INVALID, "none"),
        V("abc", INVALID, "str"),
        V(np.zeros((0, w), np.uint8), INVALID, "empty"),
        V(np.zeros((h, 0), np.uint8), INVALID, "no columns"),
        V(np.zeros((1, 1), np.uint8), ANY, "1x1"),
        V(np.zeros_like(valid), ANY, "black"),
        V(np.full_like(valid, 255), ANY, "white"),
        V(valid[: h // 2], ANY, "half"),
        V(valid.astype(object), INVALID, "object"),
        V(valid.view(np.int8), INVALID, "int8"),
    ])


IMG_LOCK: dict[str, Any] = {}


def rendered() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if "view" not in IMG_LOCK:
        IMG_LOCK["view"] = vsinv.vision.render_view(VISION)
    return IMG_LOCK["view"]


@covers("render", "render_view")
@fuzz_settings(40)
@given(st.data())
def test_render(data: Any) -> None:
    fn = data.draw(st.sampled_from([vsinv.vision.render, vsinv.vision.render_view]))
    p0 = vsinv.geometry.pose_from_position_thetau([0.02, -0.01, -0.05], [0.05, -0.02, 0.1])
    scen = dict(VISION)
    size = data.draw(st.sampled_from([None, (64, 48), (1, 1), (0, 48), (-5, 48), (70000, 10), (12.5, 48), ("a", 48)]))
    if size is not None:
        scen = json.loads(json.dumps(VISION))
        for cam in ("reference_camera", "camera"):
            if scen.get(cam):
                scen[cam]["width"], scen[cam]["height"] = size
    valid_size = size is None or (isinstance(size[0], (int, float)) and 1 <= size[0] <= 65536)  # sizes are real numbers
    args = {"scenario": scen, "pose": p0, "time": 0.0, "reference": False}
    pose_over = {"zero": INVALID, "negative": INVALID, "fewer": INVALID, "empty": INVALID, "flat": INVALID, "huge": INVALID,
                 "bool": INVALID, "tiny": INVALID, "none": ANY, "float32": ANY}  # None: the start pose
    strategies = {"pose": arrays(p0, overrides=pose_over),
                  "time": floats(0.0, overrides={"negative": INVALID, "neghuge": INVALID, "neginf": INVALID, "posinf": INVALID}),
                  "reference": choices([True, False, np.bool_(True)], ["yes", None, 0], TYPE),
                  "scenario": st.sampled_from([V(scen, SAME, "dict"), V("vision-12-12", ANY, "name"), V("lens-12-12", ANY, "no vision"),
                                               V("nope", INVALID, "unknown"), V(None, INVALID, "none"), V(3, INVALID, "int")])}

    def check(out: Any) -> None:
        image = out[0] if isinstance(out, tuple) else out
        assert image.dtype == np.uint8 and image.ndim == 2 and image.flags.c_contiguous
        if isinstance(out, tuple):
            _, px, vis = out
            assert px.shape == (len(vis), 2) and vis.dtype == np.bool_

    if not valid_size:
        call(fn, **args, _expect=INVALID, _names=("width", "height", "camera"))
        return
    ref = fn(**args)
    fuzz(data, fn, args, strategies, ref=ref, check=check, finite=False,
         digest=lambda o: o if isinstance(o, np.ndarray) else o[0])
    if size is None and fn is vsinv.vision.render_view:
        image, px, vis = ref
        h, w = image.shape
        inside = (px[:, 0] >= 0) & (px[:, 0] < w) & (px[:, 1] >= 0) & (px[:, 1] < h)
        assert (vis <= inside).all()


@covers("detect_dots", "Dots", "Dots.centroids", "Dots.areas", "Dots.bboxes")
@fuzz_settings(100)
@given(st.data())
def test_detect_dots(data: Any) -> None:
    image, px, vis = rendered()
    ref = vsinv.vision.detect_dots(image)
    assert len(ref) == int(vis.sum())
    args = {"image": image, "threshold": None, "min_area": 8, "max_area": None,
            "min_fill": 0.95, "min_contrast": 20, "max_ring_residual": 0.15}
    digest = lambda d: (d.centroids, d.areas, d.bboxes)  # noqa: E731
    out_of_unit = {k: INVALID for k in ("negative", "neghuge", "neginf", "posinf", "huge")}
    negative = {k: INVALID for k in ("negative", "neghuge", "neginf")}
    name, v, out = fuzz(data, vsinv.vision.detect_dots, args,
                        {"image": image_variants(image),
                         "threshold": ints(128, overrides={"huge": INVALID, "none": SAME, "valid": ANY, "npint": ANY}),
                         "min_area": ints(8),
                         "max_area": ints(10_000, overrides={"none": SAME}),
                         "min_fill": floats(0.95, overrides=out_of_unit),
                         "min_contrast": ints(20, overrides={"huge": INVALID}),
                         "max_ring_residual": floats(0.15, overrides=negative)},
                        digest=digest, ref=ref)
    if returned(out):
        c = call(getattr, out, "centroids", _api="Dots.centroids")
        a = call(getattr, out, "areas", _api="Dots.areas")
        b = call(getattr, out, "bboxes", _api="Dots.bboxes")
        m = len(out)
        assert c.shape == (m, 2) and a.shape == (m,) and b.shape == (m, 4) and b.dtype == np.int64
        assert (b[:, 0] <= c[:, 0]).all() and (c[:, 0] <= b[:, 2]).all()


# max_area_ratio must be finite and above 1.
RATIO_ABOVE_ONE = {k: INVALID for k in ("nan", "posinf", "neginf", "zero", "negative", "neghuge", "tiny", "int")}


@covers("DotTracker", "DotTracker.track", "DotTracker.positions")
@fuzz_settings(100)
@given(st.data())
def test_dot_tracker(data: Any) -> None:
    image, px, vis = rendered()
    clicks = px[vis] + 1.0
    args = {"image": image, "initial_pixels": clicks, "search_radius": 20.0, "max_search_radius": 80.0, "min_area": 4}
    ref = vsinv.vision.DotTracker(**args)
    digest = lambda t: t.positions  # noqa: E731
    over = {"fewer": ANY, "empty": ANY, "huge": ANY, "zero": ANY}
    name, v, out = fuzz(data, vsinv.vision.DotTracker, args,
                        {"image": image_variants(image), "initial_pixels": arrays(clicks, overrides=over),
                         "search_radius": floats(20.0, overrides={"nan": INVALID}),
                         "max_search_radius": floats(80.0, overrides={"nan": INVALID}), "min_area": ints(4),
                         "max_area_ratio": floats(1.5, overrides=RATIO_ABOVE_ONE)},
                        api="DotTracker", digest=digest, ref=ref)
    tracker = out if returned(out) else ref
    pos = call(getattr, tracker, "positions", _api="DotTracker.positions")
    assert pos.shape == (len(tracker), 2)
    nxt = data.draw(image_variants(image), label="track image")
    res = call(tracker.track, nxt.value, _expect=nxt.expect if nxt.expect != SAME else RETURN, _names=("image",))
    if returned(res):
        p, found = res
        assert p.shape == (len(tracker), 2) and found.shape == (len(tracker),) and found.dtype == np.bool_
        if nxt.expect == SAME and tracker is ref:
            np.testing.assert_allclose(p[found], px[vis][found], atol=0.5)


@covers("load_image", "save_image")
@fuzz_settings(60)
@given(data=st.data())
def test_images_on_disk(tmp_path_factory: Any, data: Any) -> None:
    image = rendered()[0][:40, :50].copy()
    folder = tmp_path_factory.mktemp("img")
    v = data.draw(image_variants(image), label="image")
    target = data.draw(st.sampled_from(["ok.png", "dir", "missing/x.png", "noext", "ok.gif"]), label="path")
    path = folder / target if target != "dir" else folder
    expect = v.expect
    if expect in (SAME, ANY) and target in ("dir", "missing/x.png"):
        expect = RAISE
    out = call(vsinv.vision.save_image, v.value, path, _expect=expect, _names=("image", str(path), "path"))
    if returned(out) and v.expect == SAME and target == "ok.png":
        back = call(vsinv.vision.load_image, path, _expect=RETURN)
        assert np.array_equal(back, image)
        assert np.array_equal(cv2.imread(str(path), cv2.IMREAD_UNCHANGED), image)
    # bad files
    garbage = folder / "bad.png"
    kind = data.draw(st.sampled_from(["truncated", "text", "empty", "colour", "gif"]), label="file")
    if kind == "truncated":
        cv2.imwrite(str(garbage), image)
        blob = garbage.read_bytes()
        garbage.write_bytes(blob[: data.draw(st.integers(0, len(blob) - 1))])
        expect = ANY  # a PNG cut after its image data still decodes
    elif kind == "text":
        garbage.write_text("not a png")
        expect = RAISE
    elif kind == "empty":
        garbage.write_bytes(b"")
        expect = RAISE
    elif kind == "colour":
        cv2.imwrite(str(garbage), np.stack([image, image // 2, image // 3], axis=-1))
        expect = RETURN
    else:
        garbage = folder / "bad.gif"
        garbage.write_bytes(b"GIF89a" + bytes(20))
        expect = RAISE
    out = call(vsinv.vision.load_image, garbage, _expect=expect, _names=(str(garbage), "image"))
    if returned(out):
        assert out.dtype == np.uint8 and out.shape == image.shape
    for bad, e in ((folder / "nothing.png", RAISE), (folder, RAISE), (None, TYPE), (3, TYPE)):
        call(vsinv.vision.load_image, bad, _expect=e, _names=(str(bad), "path", "image"))


# ---------------------------------------------------------------------------------------------
# the pipeline from image to twist, frame sources, replay


def reference_view() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if "reference" not in IMG_LOCK:
        IMG_LOCK["reference"] = vsinv.vision.render_view(VISION, reference=True)
    return IMG_LOCK["reference"]


@covers("TagTracker", "TagTracker.track", "TagTracker.reset", "TagTracker.read_whole", "TagTracker.reads")
@fuzz_settings(60)
@given(st.data())
def test_tag_tracker(data: Any) -> None:
    image = tag_image()
    ref = vsinv.vision.TagTracker()
    families = st.sampled_from([V("tag36h11", SAME, "default"), V("tag16h5", RETURN, "other family"),
                                V("tag36h12", INVALID, "unknown"), V(None, TYPE, "none")])
    decimations = st.sampled_from([V(None, SAME, "default"), V(1, RETURN, "full size"), V(8, RETURN, "largest"),
                                   V(0, INVALID, "zero"), V(9, INVALID, "too large"), V(2**40, INVALID, "huge"),
                                   V(2.0, TYPE, "float")])
    refreshes = st.sampled_from([V(15, SAME, "default"), V(0, RETURN, "never"), V(1, RETURN, "every frame"),
                                 V(-1, INVALID, "negative"), V(2**40, INVALID, "huge"), V(1.5, TYPE, "float")])
    name, v, out = fuzz(data, vsinv.vision.TagTracker, {"family": "tag36h11", "decimation": None, "refresh": 15},
                        {"family": families, "decimation": decimations, "refresh": refreshes},
                        digest=lambda t: t.read_whole, ref=ref)
    tracker = out if returned(out) else ref
    for _ in range(2):
        nxt = data.draw(image_variants(image), label="frame")
        tags = call(tracker.track, nxt.value, _api="TagTracker.track", _expect=nxt.expect, _names=("image",))
        if returned(tags):
            assert isinstance(call(getattr, tracker, "read_whole", _api="TagTracker.read_whole"), bool)
            reads = call(getattr, tracker, "reads", _api="TagTracker.reads")
            assert len(reads) == len(tags) and set(reads) <= {"edges", "crop", "whole"}, reads
            if nxt.expect == SAME and tracker is ref:
                assert list(tags.ids) == [0, 5]
    call(tracker.reset, _api="TagTracker.reset", _finite=False)
    call(tracker.track, image, _api="TagTracker.track", _names=("image",))
    assert call(getattr, tracker, "read_whole", _api="TagTracker.read_whole") is True


@covers("ImageServo", "ImageServo.step", "ImageServo.ids", "ImageServo.reference_pixels", "ImageServo.iterations",
        "ImageServo.basis", "ImageServo.basis_switches",
        "ImageServo.basis_held_images", "ImageServo.pixel_sigma", "ImageServo.certainty", "ImageStep", "ImageStep.found", "ImageStep.pixels", "ImageStep.stopped_early", "ImageStep.twist",
        "ImageStep.verdict", "ImageStep.reason", "ImageStep.running", "ImageStep.telemetry")
@fuzz_settings(60)
@given(st.data())
def test_image_servo(data: Any) -> None:
    ref, ref_px, _ = reference_view()
    image, px, vis = rendered()
    assert vis.all()
    args = {"reference_image": ref, "target": "dots", "K_hat": np.diag([600.0, 600.0, 1.0]), "reference_points": ref_px + 1.0,
            "first_points": px + 1.0, "law": "ibvs", "depths": 0.6, "gain": 0.5}
    ref_pipeline = vsinv.ImageServo(**args)
    digest = lambda p: p.reference_pixels  # noqa: E731
    over = {"fewer": ANY, "empty": ANY, "huge": ANY, "zero": ANY, "negative": ANY}
    name, v, out = fuzz(data, vsinv.ImageServo, args,
                        {"reference_image": image_variants(ref), "reference_points": arrays(ref_px + 1.0, overrides=over),
                         "first_points": arrays(px + 1.0, overrides={**over, "fewer": INVALID, "empty": INVALID, "none": RETURN}),
                         "target": choices(["dots"], ["tags?", "", 3], bad_expect=TYPE),
                         "gain": floats(0.5, overrides={"nan": INVALID, "zero": INVALID, "negative": INVALID,
                                                        "none": RETURN}),  # a law option: None is its default
                         "depths": floats(0.6, overrides={"nan": INVALID, "zero": INVALID, "negative": INVALID})},
                        api="ImageServo", digest=digest, ref=ref_pipeline,
                        names={"first_points": ("first_points",), "reference_image": ("reference_image", "reference_points")})
    pipeline = out if returned(out) else ref_pipeline
    n = len(call(getattr, pipeline, "ids", _api="ImageServo.ids"))
    assert call(getattr, pipeline, "reference_pixels", _api="ImageServo.reference_pixels").shape == (n, 2)
    assert call(getattr, pipeline, "iterations", _api="ImageServo.iterations") == 0
    assert len(call(getattr, pipeline, "basis", _api="ImageServo.basis")) == 3
    assert call(getattr, pipeline, "basis_switches", _api="ImageServo.basis_switches") >= 0
    assert call(getattr, pipeline, "basis_held_images", _api="ImageServo.basis_held_images") == 0
    nxt = data.draw(image_variants(image), label="step image")
    step = call(pipeline.step, nxt.value, _api="ImageServo.step", _expect=ANY, _names=("image", "first_points"))
    if returned(step):
        assert isinstance(step, vsinv.ImageStep)
        found = call(getattr, step, "found", _api="ImageStep.found")
        assert found.shape == (n,) and found.dtype == np.bool_
        assert call(getattr, step, "pixels", _api="ImageStep.pixels").shape == (n, 2)
        assert call(getattr, step, "stopped_early", _api="ImageStep.stopped_early") in (False, True)
        assert call(getattr, step, "twist", _api="ImageStep.twist").shape == (6,)
        verdict = call(getattr, step, "verdict", _api="ImageStep.verdict")
        running = call(getattr, step, "running", _api="ImageStep.running")
        assert running == (verdict == "running")
        assert (call(getattr, step, "reason", _api="ImageStep.reason", _finite=False) is None) == running
        assert "image_error" in call(getattr, step, "telemetry", _api="ImageStep.telemetry", _finite=False)
        if nxt.expect == SAME and pipeline is ref_pipeline:
            assert found.all()
    # one frame: no noise measured yet (three are needed), and the certainty a dict or None
    assert call(getattr, pipeline, "pixel_sigma", _api="ImageServo.pixel_sigma", _finite=False) is None
    certainty = call(pipeline.certainty, _api="ImageServo.certainty", _expect=ANY, _finite=False)
    assert certainty is None or set(certainty) >= {"translation_sigma", "rotation_bound"}


@covers("frames", "replay", "ReplayResult", "ReplayResult.table", "ReplayResult.write_csv", "ReplayResult.plot")
@fuzz_settings(30)
@given(st.data())
def test_frames_and_replay(tmp_path_factory: Any, data: Any) -> None:
    ref, ref_px, _ = reference_view()
    image, px, _ = rendered()
    source = data.draw(st.sampled_from([
        V(np.stack([image, image]), RETURN, "stack"),
        V([image], RETURN, "list"),
        V(image, RETURN, "one image"),
        V(np.zeros((2, 2, 2, 2), np.uint8), INVALID, "4-d"),
        V(3.5, INVALID, "number"),
        V("/nonexistent/folder", INVALID, "missing path"),
        V([image.astype(np.float32)], INVALID, "float frames"),
    ]), label="source")
    frames = call(lambda s: list(vsinv.frames(s)), source.value, _api="frames",
                  _expect=RETURN if source.label == "float frames" else source.expect, _names=("source",), _finite=False)
    result = call(vsinv.replay, ref, source.value, np.diag([600.0, 600.0, 1.0]), "dots", _api="replay", _expect=source.expect,
                  _names=("source", "image"), _finite=False, reference_points=ref_px, first_points=px, law="ibvs", depths=0.6)
    if source.expect == RETURN:
        assert isinstance(result, vsinv.ReplayResult) and len(result.names) == len(frames)
        assert result.found.all() and result.twists.shape == (len(frames), 6)
        text = call(result.table, _api="ReplayResult.table", _finite=False)
        assert len(text.splitlines()) == len(frames) + 1
        path = tmp_path_factory.mktemp("replay") / "replay.csv"
        call(result.write_csv, path, _api="ReplayResult.write_csv", _finite=False)
        assert len(path.read_text().splitlines()) == len(frames) + 1
        import matplotlib.pyplot as plt

        fig = call(result.plot, _api="ReplayResult.plot", _finite=False)
        plt.close(fig)
def tag_image() -> np.ndarray:
    """Two tag36h11 markers drawn by OpenCV (ids 0 and 5), 6 pixels a bit."""
    if "tags" not in IMG_LOCK:
        dictionary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11)
        image = np.full((100, 160), 220, np.uint8)
        for k, tag in enumerate((0, 5)):
            marker = cv2.aruco.generateImageMarker(dictionary, tag, 48, borderBits=1)
            image[26:74, 16 + 80 * k : 64 + 80 * k] = np.where(marker > 0, 220, 30)
        IMG_LOCK["tags"] = image
    return IMG_LOCK["tags"]


@covers("detect_tags", "Tags", "Tags.ids", "Tags.corners", "Tags.family", "Tags.stopped_early", "TAG_FAMILIES")
@fuzz_settings(100)
@given(st.data())
def test_detect_tags(data: Any) -> None:
    image = tag_image()
    ref = vsinv.vision.detect_tags(image)
    assert list(ref.ids) == [0, 5]
    families = st.sampled_from([V("tag36h11", SAME, "default"), V("tag16h5", RETURN, "other family"),
                                V("tag25h9", RETURN, "other"), V("tag36h10", RETURN, "other"),
                                V("tagStandard41h12", RETURN, "AprilTag 3's"), V("tagCircle21h7", RETURN, "round"),
                                V("tag36h12", INVALID, "unknown"), V("TAG36H11", INVALID, "case"),
                                V("", INVALID, "empty"), V(None, TYPE, "none"), V(36, TYPE, "int")])
    decimations = st.sampled_from([V(None, SAME, "default (per image)"), V(2, RETURN, "AprilTag's"), V(1, RETURN, "full size"), V(4, RETURN, "coarse"),
                                   V(8, RETURN, "largest"), V(0, INVALID, "zero"), V(9, INVALID, "too large"),
                                   V(-1, INVALID, "negative"), V(2**40, INVALID, "huge"), V(2.0, TYPE, "float"),
                                   V("2", TYPE, "str")])
    digest = lambda t: (t.ids, t.corners)  # noqa: E731
    name, v, out = fuzz(data, vsinv.vision.detect_tags, {"image": image, "family": "tag36h11", "decimation": None},
                        {"image": image_variants(image), "family": families, "decimation": decimations},
                        digest=digest, ref=ref)
    if returned(out):
        ids = call(getattr, out, "ids", _api="Tags.ids")
        corners = call(getattr, out, "corners", _api="Tags.corners")
        family = call(getattr, out, "family", _api="Tags.family")
        early = call(getattr, out, "stopped_early", _api="Tags.stopped_early")
        assert early is False  # an ordinary image is searched whole
        m = len(out)
        assert ids.shape == (m,) and ids.dtype == np.int64 and corners.shape == (m, 4, 2)
        assert family in vsinv.vision.TAG_FAMILIES and repr(out).startswith("Tags(")
        assert isinstance(vsinv.vision.TAG_FAMILIES, tuple) and all(isinstance(f, str) for f in vsinv.vision.TAG_FAMILIES)
        assert (np.diff(ids) > 0).all()


# ---------------------------------------------------------------------------------------------
# colour to grey


def colour_variants(valid: np.ndarray) -> st.SearchStrategy[V]:
    h, w, _ = valid.shape
    return st.sampled_from([
        V(valid, SAME, "valid"),
        V(np.asfortranarray(valid), SAME, "fortran"),
        V(np.repeat(valid, 2, axis=1)[:, ::2], SAME, "strided"),
        V(valid[:, :, 0], ANY, "grey"),  # returned as a copy
        V(np.concatenate([valid, valid[:, :, :1]], axis=2), SAME, "rgba"),  # alpha ignored
        V(valid[:, :, :2], INVALID, "two channels"),
        V(valid.astype(np.float64), INVALID, "float64"),
        V(valid.astype(np.uint16), INVALID, "uint16"),
        V(valid.tolist(), INVALID, "list"),
        V(None, INVALID, "none"),
        V(np.zeros((0, w, 3), np.uint8), INVALID, "empty"),
        V(np.zeros((1, 1, 3), np.uint8), ANY, "1x1"),
        V(valid.astype(object), INVALID, "object"),
    ])


@covers("decode_image")
@fuzz_settings(100)
@given(st.data())
def test_decode_image(data: Any) -> None:
    grey, _, _ = rendered()
    png = cv2.imencode(".png", grey)[1].tobytes()
    jpeg = cv2.imencode(".jpg", grey)[1].tobytes()
    ref = vsinv.vision.decode_image(png)
    # Independent: OpenCV's decoder of the same bytes, to the bit (a lossless grey PNG).
    assert np.array_equal(ref, cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_GRAYSCALE))
    payloads = st.sampled_from([
        V(png, SAME, "bytes"), V(bytearray(png), SAME, "bytearray"), V(memoryview(png), SAME, "memoryview"),
        V(np.frombuffer(png, np.uint8), SAME, "array"), V(jpeg, ANY, "jpeg"), V(b"", INVALID, "empty"),
        V(png[: len(png) // 2], INVALID, "truncated"), V(png[::-1], INVALID, "reversed"), V(b"GIF89a", INVALID, "gif"),
        V(list(png[:16]), INVALID, "list"), V(None, INVALID, "none"), V("png", INVALID, "str"),
    ])
    formats = st.sampled_from([V("png", SAME, "png"), V(None, SAME, "none"), V("jpeg", INVALID, "other"),
                               V("PNG", INVALID, "upper"), V(1, INVALID, "int")])
    fuzz(data, vsinv.vision.decode_image, {"data": png, "format": "png"}, {"data": payloads, "format": formats}, ref=ref,
         names={"data": ("data",), "format": ("format", "data")})


@covers("to_grey")
@fuzz_settings(100)
@given(st.data())
def test_to_grey(data: Any) -> None:
    colour, variants = colour_frame()
    ref = vsinv.vision.to_grey(colour)
    # Independent: OpenCV's Rec. 601 conversion of the same frame, to the bit.
    assert np.array_equal(ref, cv2.cvtColor(colour, cv2.COLOR_RGB2GRAY))
    orders = st.sampled_from([V("rgb", SAME, "rgb"), V(None, SAME, "none"), V("bgr", ANY, "bgr"),
                              V("RGB", INVALID, "upper"), V(3, INVALID, "int"), V("", INVALID, "empty")])
    fuzz(data, vsinv.vision.to_grey, {"image": colour, "order": "rgb"}, {"image": variants, "order": orders}, ref=ref)


def colour_frame() -> tuple[np.ndarray, st.SearchStrategy[V]]:
    """A colour frame made of the rendered view and its variants, built once (the list and
    object variants of 832 x 624 x 3 pixels take a second each to make)."""
    if "colour" not in IMG_LOCK:
        grey, _, _ = rendered()
        colour = np.stack([grey, 255 - grey, grey // 2], axis=-1)
        IMG_LOCK["colour"] = (colour, colour_variants(colour))
    return IMG_LOCK["colour"]


@covers("degrade")
@fuzz_settings(80)
@given(st.data())
def test_degrade(data: Any) -> None:
    image, _, _ = rendered()
    image = image[:120, :160].copy()
    args = {"image": image, "blur_sigma": 0.8, "noise_sigma": 2.0, "seed": 3, "frame": 5}
    ref = vsinv.vision.degrade(image, blur_sigma=0.8, noise_sigma=2.0, seed=3, frame=5)
    # Independent: without noise, OpenCV's Gaussian blur of the frame inside the border (to rounding).
    clean = vsinv.vision.degrade(image, blur_sigma=0.8, noise_sigma=0.0)
    blurred = cv2.GaussianBlur(image.astype(np.float64), (7, 7), 0.8)
    assert np.abs(clean[3:-3, 3:-3] - blurred[3:-3, 3:-3]).max() <= 0.5 + 1e-3
    ranged = {k: INVALID for k in ("nan", "posinf", "neginf", "negative", "neghuge", "huge")}

    def check(out: Any) -> None:
        assert out.dtype == np.uint8 and out.ndim == 2 and out.flags.c_contiguous

    fuzz(data, vsinv.vision.degrade, args,
         {"image": image_variants(image), "blur_sigma": floats(0.8, overrides=ranged),
          "noise_sigma": floats(2.0, overrides=ranged), "seed": ints(3), "frame": ints(5)},
         ref=ref, check=check)


def texture(shift: tuple[int, int] = (0, 0)) -> np.ndarray:
    """A 160 x 120 random texture (smoothed noise, seeded), moved by `shift` pixels (u, v)."""
    rng = np.random.default_rng(32)
    noise = rng.random((126, 166))
    smooth = sum(np.roll(np.roll(noise, i, 0), j, 1) for i in range(-2, 3) for j in range(-2, 3)) / 25.0
    image = np.clip(255 * (smooth - smooth.min()) / np.ptp(smooth), 0, 255).astype(np.uint8)
    return np.ascontiguousarray(image[3 - shift[1] : 123 - shift[1], 3 - shift[0] : 163 - shift[0]])


@covers("match_features")
@fuzz_settings(25)
@given(st.data())
def test_match_features(data: Any) -> None:
    a, b = texture(), texture((2, 1))
    args = {"reference_image": a, "image": b, "threshold": 1.5}
    ref = vsinv.vision.match_features(**args)
    assert len(ref[0]) >= 12
    error = np.linalg.norm(ref[1] - ref[0] - [2.0, 1.0], axis=1)
    assert np.median(error) < 0.3 and error.max() < 1.5  # 1.5: the epipolar bound
    positive = {k: INVALID for k in ("zero", "negative", "neghuge", "neginf", "posinf", "nan")}
    fuzz(data, vsinv.vision.match_features, args,
         {"reference_image": image_variants(a), "image": image_variants(b), "threshold": floats(1.5, overrides=positive)},
         digest=lambda out: out, ref=ref, names={"reference_image": ("reference_image", "image")})


@covers("track_points")
@fuzz_settings(60)
@given(st.data())
def test_track_points(data: Any) -> None:
    a, b = texture(), texture((2, 1))
    points = np.array([[40.0, 30.0], [80.0, 60.0], [120.0, 90.0], [60.5, 70.25]])
    args = {"previous_image": a, "next_image": b, "points": points, "max_error": 0.5}
    ref = vsinv.vision.track_points(**args)
    assert ref[1].all()
    np.testing.assert_allclose(ref[0], points + [2.0, 1.0], atol=0.05)
    positive = {k: INVALID for k in ("zero", "negative", "neghuge", "neginf", "posinf", "nan")}
    over = {"fewer": ANY, "empty": ANY, "huge": ANY, "zero": ANY, "negative": ANY}
    fuzz(data, vsinv.vision.track_points, args,
         {"previous_image": image_variants(a), "next_image": image_variants(b), "points": arrays(points, overrides=over),
          "max_error": floats(0.5, overrides=positive)},
         digest=lambda out: out, ref=ref, finite=False,
         names={"previous_image": ("previous_image", "next_image"), "next_image": ("next_image", "previous_image")})


def textured_square(tex: np.ndarray, z: float = 0.5) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A 0.1 m square at depth `z` facing a camera at F* (vertices counter-clockwise about -z),
    the whole texture on it."""
    h, w = tex.shape[:2]
    vertices = np.array([[-0.05, -0.05, z], [-0.05, 0.05, z], [0.05, 0.05, z], [0.05, -0.05, z]])
    coords = np.array([[-0.5, -0.5], [-0.5, h - 0.5], [w - 0.5, h - 0.5], [w - 0.5, -0.5]])
    return vertices, coords, tex


@covers("render_faces")
@fuzz_settings(80)
@given(st.data())
def test_render_faces(data: Any) -> None:
    tex = texture()[:40, :50].copy()
    good = textured_square(tex)
    v, c, _ = good
    k = vsinv.Intrinsics(400.0, 400.0, 31.5, 23.5)
    args = {"faces": [good], "pose": np.eye(4), "K": k, "width": 64, "height": 48, "blur_sigma": 0.8,
            "noise_sigma": 2.0, "background": 30, "seed": 3, "frame": 5}
    ref = vsinv.vision.render_faces(**args)
    bent = v.copy()
    bent[2, 2] += 0.01
    bow = v[[0, 2, 1, 3]]
    faces = st.sampled_from([
        V([good], SAME, "list"), V((good,), SAME, "tuple"), V([(v, c, np.stack([tex] * 3, -1))], SAME, "colour texture"),
        V([(v.tolist(), c.tolist(), tex)], SAME, "nested lists"), V([], ANY, "no face"), V(None, INVALID, "none"),
        V(3, INVALID, "int"), V("abc", INVALID, "str"), V([good, (v[:2], c[:2], tex)], INVALID, "two vertices"),
        V([(bent, c, tex)], INVALID, "bent"), V([(bow, c, tex)], INVALID, "bow tie"), V([(v, c)], INVALID, "pair"),
        V([(v, c, tex.astype(float))], INVALID, "float texture"), V([(v, c, tex[:0])], INVALID, "empty texture"),
        V([(v, c[:, :1], tex)], INVALID, "one coordinate"), V([(np.where(v == v[1, 1], np.nan, v), c, tex)], INVALID, "nan"),
        V([(v, c[[0, 0, 2, 3]], tex)], INVALID, "folded coordinates"), V([(v[::-1], c[::-1], tex)], ANY, "turned away"),
    ])
    pose_over = {"zero": INVALID, "negative": INVALID, "fewer": INVALID, "empty": INVALID, "flat": INVALID, "huge": INVALID,
                 "bool": INVALID, "tiny": INVALID, "float32": ANY}
    ranged = {kind: INVALID for kind in ("nan", "posinf", "neginf", "negative", "neghuge", "huge")}
    sides = {"zero": INVALID, "negative": INVALID, "huge": INVALID, "bool": ANY}

    def check(out: Any) -> None:
        assert out.dtype == np.uint8 and out.ndim == 2 and out.flags.c_contiguous

    fuzz(data, vsinv.vision.render_faces, args,
         {"faces": faces, "pose": arrays(np.eye(4), overrides=pose_over), "K": k_variants(k),
          "width": ints(64, overrides=sides), "height": ints(48, overrides=sides),
          "blur_sigma": floats(0.8, overrides=ranged), "noise_sigma": floats(2.0, overrides=ranged),
          "background": ints(30, overrides={"huge": INVALID}), "seed": ints(3), "frame": ints(5)},
         ref=ref, check=check, names={"K": ("K", "intrinsics", "fku", "fkv", "skew", "matrix")})
