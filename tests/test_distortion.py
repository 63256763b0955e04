"""Lens distortion against OpenCV, and calibration files.

distort_points is compared with cv2.projectPoints (points in the camera frame, rvec = tvec =
0) and undistort_points with cv2.undistortPoints(..., P=K) run to convergence (criteria of 2000 iterations, eps 1e-15), on seeded
random lenses of both models with realistic coefficients (strong barrel included). The
points are drawn where the model is invertible: det of the distortion Jacobian > 0.2 on the
whole segment from the principal point, so that the pre-image is unique and OpenCV's
fixed-point iteration converges.
"""

import math
import pathlib

import cv2
import numpy as np
import pytest

import vsinv

FIXTURES = pathlib.Path(__file__).resolve().parent / "fixtures" / "calibration"
CASES = 1000  # random lenses per model
POINTS = 12  # points per lens
CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 2000, 1e-15)


def coefficients(rng: np.random.Generator, model: str) -> np.ndarray:
    """Realistic coefficients: barrel from mild to strong (k1 down to -0.4) and some pincushion."""
    k1 = rng.uniform(-0.4, 0.15)
    k2 = rng.uniform(0.05, 0.2) if k1 < -0.25 else rng.uniform(-0.1, 0.15)
    p1, p2 = rng.uniform(-0.002, 0.002, 2)
    k3 = rng.uniform(-0.05, 0.05)
    if model == "plumb_bob":
        return np.array([k1, k2, p1, p2, k3])
    # Rational fits have large numerator and denominator terms whose leading ratio is the barrel.
    k4, k5, k6 = rng.uniform(0.0, 2.0), rng.uniform(0.0, 0.8), rng.uniform(0.0, 0.1)
    return np.array([k1 + k4, k2 + k5 + k1 * k4, p1, p2, k3 + k6, k4, k5, k6])


def radial_and_jacobian_det(d: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """det of the distortion Jacobian, by central differences of cv2.projectPoints at depth 1."""
    h = 1e-7
    pts = np.stack([x, y], axis=-1).reshape(-1, 2)

    def dist(p: np.ndarray) -> np.ndarray:
        obj = np.hstack([p, np.ones((len(p), 1))])
        out, _ = cv2.projectPoints(obj, np.zeros(3), np.zeros(3), np.eye(3), d)
        return out.reshape(-1, 2)

    jx = (dist(pts + [h, 0]) - dist(pts - [h, 0])) / (2 * h)
    jy = (dist(pts + [0, h]) - dist(pts - [0, h])) / (2 * h)
    det = jx[:, 0] * jy[:, 1] - jx[:, 1] * jy[:, 0]
    return det.reshape(np.shape(x))


def lens_case(rng: np.random.Generator, model: str):
    """A random camera, coefficients and points in its camera frame, inside the invertible region."""
    w, h = [(640, 480), (1280, 960), (1920, 1080)][rng.integers(3)]
    fx = rng.uniform(0.6, 1.4) * w
    k = np.array([[fx, 0.0, w / 2 + rng.uniform(-20, 20)], [0.0, fx * rng.uniform(0.97, 1.03), h / 2 + rng.uniform(-20, 20)], [0.0, 0.0, 1.0]])
    d = coefficients(rng, model)
    # Normalised points across the image (and a little beyond), kept where the model is
    # invertible along the whole ray from the principal point.
    u = rng.uniform(-0.1 * w, 1.1 * w, 4 * POINTS)
    v = rng.uniform(-0.1 * h, 1.1 * h, 4 * POINTS)
    x = (u - k[0, 2]) / k[0, 0]
    y = (v - k[1, 2]) / k[1, 1]
    t = np.linspace(0.05, 1.0, 20)[:, None]
    ok = (radial_and_jacobian_det(d, t * x, t * y) > 0.2).all(axis=0)
    x, y = x[ok][:POINTS], y[ok][:POINTS]
    z = rng.uniform(0.3, 5.0, len(x))
    points = np.stack([x * z, y * z, z], axis=1)
    return k, d, points


def project_cv(points: np.ndarray, k: np.ndarray, d: np.ndarray) -> np.ndarray:
    out, _ = cv2.projectPoints(points, np.zeros(3), np.zeros(3), k, d)
    return out.reshape(-1, 2)


def undistort_cv(pixels: np.ndarray, k: np.ndarray, d: np.ndarray) -> np.ndarray:
    """cv2.undistortPoints run to convergence (OpenCV 4: undistortPointsIter; 5: criteria=)."""
    src = pixels.reshape(-1, 1, 2)
    if hasattr(cv2, "undistortPointsIter"):
        return cv2.undistortPointsIter(src, k, d, None, k, CRITERIA).reshape(-1, 2)
    return cv2.undistortPoints(src, k, d, R=None, P=k, criteria=CRITERIA).reshape(-1, 2)


@pytest.mark.parametrize("model", ["plumb_bob", "rational_polynomial"])
def test_against_opencv(model):
    rng = np.random.default_rng(20240611 + len(model))
    err_distort = err_undistort = err_round = 0.0
    n_points = 0
    for _ in range(CASES):
        k, d, points = lens_case(rng, model)
        ideal = (k @ (points / points[:, 2:]).T).T[:, :2]
        distorted_cv = project_cv(points, k, d)
        distorted = vsinv.vision.distort_points(ideal, k, d)
        err_distort = max(err_distort, np.abs(distorted - distorted_cv).max())

        undist_cv = undistort_cv(distorted_cv, k, d)
        undist = vsinv.vision.undistort_points(distorted_cv, k, d)
        err_undistort = max(err_undistort, np.abs(undist - undist_cv).max())

        back = vsinv.vision.undistort_points(distorted, k, d)
        err_round = max(err_round, np.abs(back - ideal).max())
        n_points += len(points)
    print(
        f"\n{model}: {CASES} lenses, {n_points} points: max |distort - cv2.projectPoints| = {err_distort:.2e} px, "
        f"max |undistort - cv2.undistortPoints| = {err_undistort:.2e} px, round trip {err_round:.2e} px"
    )
    assert n_points >= 5 * CASES
    assert err_distort <= 1e-6
    assert err_undistort <= 1e-6
    assert err_round <= 1e-9


def test_distortion_object_and_models():
    d = vsinv.vision.Distortion([-0.3, 0.1, 0.001, -0.002])
    assert d.model == "plumb_bob"
    np.testing.assert_array_equal(d.coefficients, [-0.3, 0.1, 0.001, -0.002, 0.0])
    r = vsinv.vision.Distortion(np.arange(8) * 0.01)
    assert r.model == "rational_polynomial" and r.coefficients.shape == (8,)
    assert vsinv.vision.Distortion([0.0] * 5, model="plumb_bob") == vsinv.vision.Distortion([0.0] * 4)
    for bad in ([0.1, 0.2, 0.0], [0.0] * 6, [0.0] * 12, [0.0] * 14):
        with pytest.raises(vsinv.InvalidInput, match=r"invalid parameter `distortion coefficients`: expected 4 or 5 \(plumb_bob"):
            vsinv.vision.Distortion(bad)
    with pytest.raises(vsinv.InvalidInput, match="distortion coefficients: non-finite value at index 1"):
        vsinv.vision.Distortion([0.1, math.nan, 0.0, 0.0, 0.0])
    with pytest.raises(vsinv.InvalidInput, match="unknown distortion model"):
        vsinv.vision.Distortion([0.0] * 5, model="fisheye")
    with pytest.raises(vsinv.InvalidInput, match="rational_polynomial model takes 8"):
        vsinv.vision.Distortion([0.0] * 5, model="rational_polynomial")
    k = vsinv.Intrinsics(800.0, 800.0, 320.0, 240.0)
    px = np.array([[100.0, 50.0], [600.0, 400.0]])
    # A Distortion, a list, a (1, 5) array as OpenCV returns them: the same.
    a = vsinv.vision.distort_points(px, k, d)
    np.testing.assert_array_equal(a, vsinv.vision.distort_points(px, k, [-0.3, 0.1, 0.001, -0.002]))
    np.testing.assert_array_equal(a, vsinv.vision.distort_points(px, k.matrix, np.array([[-0.3, 0.1, 0.001, -0.002, 0.0]])))
    np.testing.assert_array_equal(vsinv.vision.distort_points(px, k, [0.0] * 5), px)
    assert vsinv.vision.distort_points(np.zeros((0, 2)), k, d).shape == (0, 2)
    with pytest.raises(vsinv.InvalidInput, match="pixels: non-finite value at row 0, column 1"):
        vsinv.vision.distort_points([[1.0, math.nan]], k, d)
    with pytest.raises(vsinv.InvalidInput, match="invalid parameter `max_iter`: must be >= 1"):
        vsinv.vision.undistort_points(px, k, d, max_iter=0)


def test_skew_against_opencv_in_normalised_coordinates():
    """With skew, the distortion acts on K^-1 p and the full K maps back: OpenCV distorts the
    normalised points (camera matrix I), and the skewed K is applied here."""
    rng = np.random.default_rng(7)
    k = vsinv.Intrinsics(900.0, 850.0, 330.0, 250.0, skew=1.35)
    km = k.matrix
    assert km[0, 1] != 0.0
    for model in ("plumb_bob", "rational_polynomial"):
        d = coefficients(rng, model)
        m = rng.uniform(-0.35, 0.35, (200, 2))
        ideal = (km @ np.hstack([m, np.ones((200, 1))]).T).T[:, :2]
        md = project_cv(np.hstack([m, np.ones((200, 1))]), np.eye(3), d)
        expected = (km @ np.hstack([md, np.ones((200, 1))]).T).T[:, :2]
        distorted = vsinv.vision.distort_points(ideal, k, d)
        np.testing.assert_allclose(distorted, expected, atol=1e-8, rtol=0)
        np.testing.assert_allclose(vsinv.vision.undistort_points(distorted, k, d), ideal, atol=1e-9, rtol=0)


def test_large_arrays_round_trip():
    k = vsinv.Intrinsics(700.0, 700.0, 640.0, 480.0)
    d = vsinv.vision.Distortion([-0.38, 0.16, 0.0005, -0.0005, -0.02])
    rng = np.random.default_rng(3)
    px = np.column_stack([rng.uniform(0, 1280, 100_000), rng.uniform(0, 960, 100_000)])
    back = vsinv.vision.undistort_points(vsinv.vision.distort_points(px, k, d), k, d)
    assert np.abs(back - px).max() <= 1e-9


def test_fold_raises_naming_the_point():
    """k1 = -0.4: r_d = r (1 - 0.4 r^2) peaks at r = 0.913 (r_d = 0.609): a distorted pixel
    farther out has no pre-image on the lens's side of the fold."""
    k = vsinv.Intrinsics(500.0, 500.0, 320.0, 240.0)
    d = [-0.4, 0.0, 0.0, 0.0]
    px = np.array([[320.0, 240.0], [320.0 + 0.5 * 500, 240.0], [320.0 + 0.7 * 500, 240.0], [320.0, 240.0]])
    with pytest.raises(vsinv.InvalidInput, match=r"point 2: the model folds"):
        vsinv.vision.undistort_points(px, k, d)
    with pytest.raises(vsinv.InvalidInput, match=r"point 0: did not converge in 1 iterations"):
        vsinv.vision.undistort_points([[600.0, 400.0]], k, d, tol=1e-12, max_iter=1)
    # The distortion of a point beyond the fold is defined (as OpenCV computes it), but it
    # undistorts to the point on the lens's side, not back.
    outer = np.array([[320.0 + 1.2 * 500, 240.0]])
    back = vsinv.vision.undistort_points(vsinv.vision.distort_points(outer, k, d), k, d)
    assert back[0, 0] < 320.0 + 0.913 * 500


EXPECTED = {
    "ros_plumb_bob.yaml": ((812.25, 809.75, 323.5, 236.125), "plumb_bob", [-0.3125, 0.109375, 0.00125, -0.0009765625, -0.015625], (640, 480)),
    "opencv.yaml": ((812.25, 809.75, 323.5, 236.125), "plumb_bob", [-0.3125, 0.109375, 0.00125, -0.0009765625, -0.015625], (640, 480)),
    "ros_rational_polynomial.yaml": (
        (1103.5, 1101.0, 959.25, 541.75),
        "rational_polynomial",
        [1.25, 0.375, 0.0005, -0.00075, 0.0078125, 1.5625, 0.5, 0.03125],
        (1920, 1080),
    ),
    "opencv.xml": (
        (1103.5, 1101.0, 959.25, 541.75),
        "rational_polynomial",
        [1.25, 0.375, 0.0005, -0.00075, 0.0078125, 1.5625, 0.5, 0.03125],
        (1920, 1080),
    ),
}


def check(cal: vsinv.calibration.Calibration, expected) -> None:
    (fx, fy, cx, cy), model, coeffs, size = expected
    k = cal.intrinsics
    assert (k.fku, k.fkv, k.u0, k.v0) == (fx, fy, cx, cy)
    assert k.skew == math.pi / 2
    assert cal.distortion.model == model
    np.testing.assert_array_equal(cal.distortion.coefficients, coeffs)
    assert cal.image_size == size


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_calibration_files_load(name):
    cal = vsinv.calibration.load_calibration(FIXTURES / name)
    check(cal, EXPECTED[name])
    # What OpenCV reads from the same file, for its own files.
    if name.startswith("opencv"):
        fs = cv2.FileStorage(str(FIXTURES / name), cv2.FILE_STORAGE_READ)
        np.testing.assert_array_equal(cal.intrinsics.matrix, fs.getNode("camera_matrix").mat())
        np.testing.assert_array_equal(cal.distortion.coefficients, fs.getNode("distortion_coefficients").mat().ravel())
        fs.release()
    # The loaded lens works with the functions.
    px = np.array([[100.0, 120.0]])
    np.testing.assert_allclose(
        vsinv.vision.undistort_points(vsinv.vision.distort_points(px, cal.intrinsics, cal.distortion), cal.intrinsics, cal.distortion),
        px,
        atol=1e-9,
    )


def test_opencv4_header_and_dist_coeffs(tmp_path):
    """OpenCV 4 writes `%YAML:1.0` (not valid YAML) and some tools name the entry dist_coeffs."""
    text = (FIXTURES / "opencv.yaml").read_text()
    assert text.startswith("%YAML 1.2")
    path = tmp_path / "cv4.yaml"
    path.write_text(text.replace("%YAML 1.2", "%YAML:1.0", 1).replace("distortion_coefficients", "dist_coeffs"))
    check(vsinv.calibration.load_calibration(str(path)), EXPECTED["opencv.yaml"])
    xml = tmp_path / "cv.xml"
    xml.write_text((FIXTURES / "opencv.xml").read_text().replace("distortion_coefficients", "dist_coeffs"))
    check(vsinv.calibration.load_calibration(xml), EXPECTED["opencv.xml"])


ROS = (FIXTURES / "ros_plumb_bob.yaml").read_text() if (FIXTURES / "ros_plumb_bob.yaml").exists() else ""
XML = (FIXTURES / "opencv.xml").read_text() if (FIXTURES / "opencv.xml").exists() else ""


@pytest.mark.parametrize(
    "suffix, old, new, field, reason",
    [
        (".yaml", "image_width: 640\n", "", "image_width", "missing"),
        (".yaml", "image_height: 480", "image_height: tall", "image_height", "expected an integer"),
        (".yaml", "image_height: 480", "image_height: -480", "image_height", "positive integer"),
        (".yaml", "  cols: 3\n  data: [812.25", "  cols: 4\n  data: [812.25", "camera_matrix", "3x3"),
        (".yaml", "rows: 3\n  cols: 3\n  data: [812.25, 0.0,", "rows: 3\n  cols: 3\n  data: [0.0,", "camera_matrix.data", "data has 8"),
        (".yaml", "data: [812.25, 0.0, 323.5", "data: [812.25, 0.0, abc", "camera_matrix.data[2]", "non-numeric"),
        (".yaml", "data: [812.25, 0.0, 323.5", "data: [812.25, 2.5, 323.5", "camera_matrix", "skew"),
        (".yaml", "0.0, 0.0, 1.0]", "0.0, 0.0, 2.0]", "camera_matrix", "last row"),
        (".yaml", "data: [812.25", "data: [-812.25", "camera_matrix", "> 0"),
        (".yaml", "distortion_model: plumb_bob", "distortion_model: fisheye", "distortion_model", "unknown distortion model"),
        (".yaml", "distortion_model: plumb_bob", "distortion_model: equidistant", "distortion_coefficients", "equidistant model takes 4"),
        (".yaml", "distortion_model: plumb_bob", "distortion_model: rational_polynomial", "distortion_coefficients", "wrong coefficient count"),
        (".yaml", "cols: 5\n  data: [-0.3125,", "cols: 6\n  data: [0.0, -0.3125,", "distortion_coefficients", "wrong coefficient count"),
        (".yaml", "data: [-0.3125,", "data: [.nan,", "distortion_coefficients.data[0]", "non-finite"),
        (".yaml", "distortion_coefficients:", "distortion:", "distortion_coefficients", "missing"),
        (".yaml", "camera_matrix:\n  rows: 3", "camera_matrix:\n  rowz: 3", "camera_matrix.rows", "missing"),
        (".yaml", "image_width: 640", "image_width: [640", "", "not valid YAML"),
        (".xml", "<rows>3</rows>", "<rows>three</rows>", "camera_matrix.rows", "expected an integer"),
        (".xml", "1101. 541.75", "1101. x541.75", "camera_matrix.data[5]", "non-numeric"),
        (".xml", "<cols>8</cols>", "<cols>7</cols>", "distortion_coefficients.data", "data has 8"),
        (".xml", "<image_height>1080</image_height>", "", "image_height", "missing"),
        (".xml", "</opencv_storage>", "", "", "not valid XML"),
    ],
)
def test_malformed_calibration_files(tmp_path, suffix, old, new, field, reason):
    text = ROS if suffix == ".yaml" else XML
    assert old in text
    path = tmp_path / f"bad{suffix}"
    path.write_text(text.replace(old, new, 1))
    prefix = f"calibration file {path}: {field + ': ' if field else ''}"
    with pytest.raises(vsinv.InvalidInput) as info:
        vsinv.calibration.load_calibration(path)
    message = str(info.value)
    assert message.startswith(prefix), message
    assert reason in message, message
    assert isinstance(info.value, ValueError)


def test_missing_file():
    with pytest.raises(vsinv.InvalidInput, match="calibration file /nonexistent/cal.yaml: cannot read"):
        vsinv.calibration.load_calibration("/nonexistent/cal.yaml")
