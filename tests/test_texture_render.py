"""The renderer's textured planar faces (`vsinv.vision.render_faces`, issue 32, item 2) against
an independent computation: OpenCV's `warpPerspective` of the texture by the homography
K [r1 r2 t] A (A: texture pixels to the face's plane coordinates).

What the renderer computes: a pixel is the mean, at n x n samples of the pixel's footprint, of the
texture read bilinearly between texel centres (texel (i, j) is the value at (i, j); edge texels
clamped), n = clamp(ceil(4 s), 4, 16) for s texels per pixel (render/texture.rs). OpenCV's
equivalent: the texture warped with its linear filter (`INTER_LINEAR`) onto an image `k` times
finer, then averaged over each k x k block (`cv2.resize` with `INTER_AREA` at an integer factor:
the block mean, an area average where the face is minified). With k = n the two take the same
samples, so where s is constant (a face seen head-on) they agree to the renderer's rounding plus
OpenCV's fixed-point weights (its linear filter weighs in steps of 1/32 of a texel: up to C / 64
grey levels across a texel step of contrast C, under 2 levels for this texture). With k = 32
OpenCV's image is nearly the exact area average, and the difference is the renderer's sampling
error, small: the bilinear surface has no step, so the midpoint samples err by a fraction of a
texel's contrast times 1 / n^2. Compared away from the face's outline (3 pixels in: the outline's
pixels mix the face and the background by coverage, and OpenCV's filter mixes the texture's edge
texels with its border value).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

cv2 = pytest.importorskip("cv2")

import vsinv  # noqa: E402

WIDTH, HEIGHT = 160, 120
F = 200.0
K = np.array([[F, 0.0, (WIDTH - 1) / 2], [0.0, F, (HEIGHT - 1) / 2], [0.0, 0.0, 1.0]])
HALF = 0.1  # the face: a square of 0.2 m at the origin of F*, in the plane z = 0
DENSE = 32  # OpenCV's samples per pixel and axis for the area average


def texture(size: int = 128) -> np.ndarray:
    """A seeded texture with fine grain and sharp edges: smoothed noise plus a checkerboard of
    8-texel squares."""
    rng = np.random.default_rng(32)
    noise = cv2.GaussianBlur(rng.random((size, size)), (0, 0), 1.2)
    noise = (noise - noise.min()) / np.ptp(noise)
    i, j = np.meshgrid(np.arange(size), np.arange(size))
    board = ((i // 8 + j // 8) % 2).astype(float)
    return np.clip(np.rint(40 + 120 * noise + 80 * board), 0, 255).astype(np.uint8)


def face(tex: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The square face: vertices counter-clockwise about -z (its front faces a camera on the -z
    side), texture coordinates covering the whole texture."""
    h, w = tex.shape
    vertices = np.array([[-HALF, -HALF, 0.0], [-HALF, HALF, 0.0], [HALF, HALF, 0.0], [HALF, -HALF, 0.0]])
    coords = np.array([[-0.5, -0.5], [-0.5, h - 0.5], [w - 0.5, h - 0.5], [w - 0.5, -0.5]])
    return vertices, coords, tex


def texture_to_plane(tex: np.ndarray) -> np.ndarray:
    """A: texture pixel (u, v, 1) to plane coordinates (x, y, 1) of the face."""
    h, w = tex.shape
    return np.array([[2 * HALF / w, 0.0, -HALF + HALF / w], [0.0, 2 * HALF / h, -HALF + HALF / h], [0.0, 0.0, 1.0]])


def camera(distance: float, tilt_deg: float, offset: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
    """A camera on the -z side looking at the face's centre from `distance`, turned by `tilt_deg`
    about the face's y axis, its optical axis shifted by `offset` metres in the plane."""
    a = np.radians(tilt_deg)
    rot = np.array([[np.cos(a), 0.0, np.sin(a)], [0.0, 1.0, 0.0], [-np.sin(a), 0.0, np.cos(a)]])
    pose = np.eye(4)
    pose[:3, :3] = rot
    pose[:3, 3] = np.array([offset[0], offset[1], 0.0]) - distance * rot[:, 2]
    return pose


def opencv_view(tex: np.ndarray, pose: np.ndarray, s: int) -> tuple[np.ndarray, np.ndarray]:
    """OpenCV's image of the face (block means of an `s` times finer bilinear warp by
    K [r1 r2 t] A) and the face's mask shrunk by 3 pixels (the pixels compared)."""
    rot, t = pose[:3, :3].T, -pose[:3, :3].T @ pose[:3, 3]  # F* to the camera
    h = K @ np.column_stack([rot[:, 0], rot[:, 1], t]) @ texture_to_plane(tex)
    fine_to_coarse = np.array([[1 / s, 0.0, (1 / s - 1) / 2], [0.0, 1 / s, (1 / s - 1) / 2], [0.0, 0.0, 1.0]])
    h_fine = np.linalg.inv(fine_to_coarse) @ h
    size = (WIDTH * s, HEIGHT * s)
    fine = cv2.warpPerspective(tex.astype(np.float32), h_fine, size, flags=cv2.INTER_LINEAR, borderValue=0.0)
    image = cv2.resize(fine, (WIDTH, HEIGHT), interpolation=cv2.INTER_AREA)
    inside = cv2.warpPerspective(np.ones_like(tex), h, (WIDTH, HEIGHT), flags=cv2.INTER_NEAREST)
    mask = cv2.erode(inside, np.ones((7, 7), np.uint8)) > 0
    return image, mask


def render(tex: np.ndarray, pose: np.ndarray) -> np.ndarray:
    return vsinv.vision.render_faces([face(tex)], pose, K, WIDTH, HEIGHT, blur_sigma=0.0, noise_sigma=0.0, background=0)


# (distance m, tilt deg, offset m): head-on with 2.2 texels a pixel (a minification: n = 9),
# head-on magnified 1.5 times (n = 4), oblique at 50 and 65 degrees (the scale changes across the
# face: magnified at the near side, minified at the far side).
HEAD_ON = {
    "head-on, minified 2.2x": ((0.6875, 0.0, (0.0123, -0.0071)), 9),
    "head-on, magnified 1.5x": ((0.208, 0.0, (0.0031, 0.0017)), 4),
}
OBLIQUE = {"oblique 50 deg": (0.45, 50.0, (0.01, 0.0)), "oblique 65 deg": (0.5, 65.0, (0.0, 0.02))}
VIEWS = {**{name: view for name, (view, _) in HEAD_ON.items()}, **OBLIQUE}


def compared(view: str, s: int) -> np.ndarray:
    """The renderer's image minus OpenCV's with `s` samples a pixel and axis, on the face's inner
    pixels, and the check that off the face the renderer left the background."""
    tex = texture()
    distance, tilt, offset = VIEWS[view]
    pose = camera(distance, tilt, offset)
    expected, mask = opencv_view(tex, pose, s)
    image = render(tex, pose)
    assert image.shape == (HEIGHT, WIDTH) and image.dtype == np.uint8
    assert mask.sum() > 2000, view  # the face covers much of the image
    far = cv2.dilate((expected > 0).astype(np.uint8), np.ones((5, 5), np.uint8)) == 0
    assert (image[far] == 0).all()
    return (image.astype(float) - expected)[mask]


@pytest.mark.parametrize("view", sorted(HEAD_ON))
def test_a_face_seen_head_on_is_opencvs_warp_with_the_same_samples(view: str) -> None:
    """OpenCV with the renderer's n x n samples: equal to the renderer's rounding (0.5 level) plus
    OpenCV's fixed-point weights (C / 64 for the texture's strongest texel step C)."""
    diff = np.abs(compared(view, HEAD_ON[view][1]))
    tex = texture().astype(float)
    steepest = max(np.abs(np.diff(tex, axis=0)).max(), np.abs(np.diff(tex, axis=1)).max())
    print(f"{view}: max |diff| {diff.max():.3f}, mean {diff.mean():.3f}, bound {0.5 + steepest / 64:.3f}")
    assert diff.max() <= 0.5 + steepest / 64 + 1e-4, (view, diff.max())


@pytest.mark.parametrize("view", sorted(VIEWS))
def test_a_face_is_the_area_average_of_opencvs_warp_within_the_sampling_error(view: str) -> None:
    """Against OpenCV's 32 x 32 samples: the mean absolute difference under 0.5 level and the
    99th percentile under 1.5 (measured: 0.25-0.27 and 0.62-0.75, the rounding and OpenCV's
    fixed-point weights; a nearest-texel texture's steps gave up to C / (2n) = 12 levels)."""
    diff = np.abs(compared(view, DENSE))
    mean, p99 = float(diff.mean()), float(np.percentile(diff, 99))
    print(f"{view}: {diff.size} px, mean |diff| {mean:.3f}, 99th percentile {p99:.2f}, max {diff.max():.1f}")
    assert mean < 0.5 and p99 < 1.5, (view, mean, p99)


def test_the_face_seen_from_behind_is_not_drawn() -> None:
    tex = texture()
    behind = camera(0.5, 180.0)
    image = vsinv.vision.render_faces([face(tex)], behind, K, WIDTH, HEIGHT, noise_sigma=0.0, background=9)
    assert (image == 9).all()


def test_a_bad_face_is_refused_naming_faces_and_its_position() -> None:
    tex = texture()
    good = face(tex)
    v, c, _ = good
    bent = v.copy()
    bent[2, 2] = 0.01
    nan = v.copy()
    nan[3, 1] = np.nan
    cases = [
        ("faces[1]: invalid parameter `face`: not planar", 1, [good, (bent, c, tex)]),
        ("faces[2] vertices: expected shape (n, 3)", 2, [good, good, (v[:, :2], c, tex)]),
        ("faces[0]: expected (vertices, texture_coords, texture)", 0, [(v, c)]),
        ("faces[1] texture: expected a uint8 NumPy array", 1, [good, (v, c, tex.astype(float))]),
        ("faces[0]: invalid parameter `texture coordinates`: coordinate 2", 0, [(v, c[[0, 0, 2, 3]], tex)]),
        ("faces[1]: face vertices: non-finite value at index 10", 1, [good, (nan, c, tex)]),
        # An endless face is read to its fourth part, not forever.
        ("faces[0]: expected (vertices, texture_coords, texture)", 0, [itertools.repeat(v)]),
        # An endless sequence of faces is read to one past the limit, not forever.
        ("faces[64]: more than 64 faces", 64, itertools.repeat(good)),
    ]
    for start, index, faces in cases:
        with pytest.raises(vsinv.InvalidInput) as err:
            vsinv.vision.render_faces(faces, camera(0.5, 0.0), K, WIDTH, HEIGHT)
        assert str(err.value).startswith(start), str(err.value)
        assert err.value.argument == "faces" and err.value.location == ("faces", index), str(err.value)


@pytest.mark.slow
def test_the_textured_box_agrees_with_mujocos_image_of_it() -> None:
    """The box of tests/feature_world.py (ViSP's photographs on three faces) rendered by MuJoCo and
    by the project's renderer (`feature_world.tiles`) from the reference pose with f = 1200 px and
    from two starts of tests/test_features_mujoco.py with f = 600 px. The tiles' corners project to
    the same pixels with vsinv.geometry.project as with the MuJoCo world's pinhole; keypoints matched
    between the two images sit on the same pixel (measured: median 0.09-0.11 px, all within 1 px);
    on each tile, 32 x 32 cells of the two images correlate above 0.85 (measured: 0.91 and more;
    MuJoCo's image is lit, so a face's grey levels are scaled, and its texture filtered by
    mipmaps, so a cell's correlation is not 1)."""
    import feature_world as fw

    why = fw.available()
    if why is not None:
        pytest.skip(why)
    import mujoco_world as mw
    import test_features_mujoco as t

    world = fw.TexturedBox(t.WIDTH, t.HEIGHT)
    tiles = fw.tiles()
    views = [(t.REFERENCE_POSE, t.FOVY_REFERENCE), *((p, t.FOVY_SERVO) for p in t.start_poses(world, 2))]
    try:
        for pose, fovy in views:
            fx, fy, cx, cy = world.intrinsics(fovy)
            k = vsinv.Intrinsics(fx, fy, cx, cy)
            corners = np.concatenate([v for v, _, _ in tiles])
            in_camera = (corners - pose[:3, 3]) @ pose[:3, :3]
            np.testing.assert_allclose(vsinv.geometry.project(in_camera, k)[0], mw.project(pose, (fx, fy, cx, cy), corners)[0], atol=1e-9)
            mujoco = world.render(pose, fovy)
            ours = vsinv.vision.render_faces(tiles, pose, k, t.WIDTH, t.HEIGHT, blur_sigma=0.0, noise_sigma=0.0)
            ref_px, px = vsinv.vision.match_features(mujoco, ours)
            error = np.linalg.norm(px - ref_px, axis=1)
            assert len(error) >= 40 and np.median(error) < 0.3 and error.max() < 1.5, (fovy, len(error), np.median(error), error.max())
            cells = tile_cell_correlations(tiles, pose, k, mujoco, ours)
            print(f"f = {fx:.0f}: {len(error)} matches, median {np.median(error):.3f} px, max {error.max():.2f} px; "
                  f"{len(cells)} cells, correlation min {min(cells):.3f}")
            assert len(cells) >= 5 and min(cells) > 0.85, cells
    finally:
        world.close()


def tile_cell_correlations(tiles: list, pose: np.ndarray, k: object, a: np.ndarray, b: np.ndarray) -> list[float]:
    """The correlation of images `a` and `b` on each 32 x 32 cell of the image grid lying inside one
    tile (2 pixels in from its outline) and not flat in either image."""
    height, width = a.shape
    out = []
    for vertices, coords, _ in tiles:
        white = [(vertices, coords, np.full((2, 2), 255, np.uint8))]
        mask = vsinv.vision.render_faces(white, pose, k, width, height, blur_sigma=0.0, noise_sigma=0.0, background=0)
        mask = cv2.erode((mask == 255).astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
        for y in range(0, height - 31, 32):
            for x in range(0, width - 31, 32):
                cell = (slice(y, y + 32), slice(x, x + 32))
                p, q = a[cell].astype(float).ravel(), b[cell].astype(float).ravel()
                if mask[cell].all() and p.std() > 3 and q.std() > 3:
                    out.append(float(np.corrcoef(p, q)[0, 1]))
    return out
