"""OpenCV's fisheye lens (Kannala-Brandt, ROS's `equidistant`) against cv2.fisheye, and beyond.

What OpenCV can express: `cv2.fisheye.distortPoints` takes normalised points `m = (X/Z, Y/Z)`,
so rays below 90 degrees from the axis only; `cv2.fisheye.projectPoints` divides by Z too (a
point behind the camera comes out mirrored, as the ray at `180 - theta`), and
`cv2.fisheye.undistortPoints` clamps `theta_d` to at most pi/2 and returns `tan(theta)`, so
it inverts only pixels whose `theta_d < pi/2` and whose ray is below 90 degrees. Rays from 90
degrees to the lens's range (`Distortion.max_angle`: its fold or 180 degrees) are checked
against numpy: `theta = arctan2(rho, Z)` and the polynomial for distortion, the real roots of
the polynomial (np.roots) for undistortion and for the fold.
"""

import math

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import vsinv
from vsinv.vision import Distortion, distort_points, distort_rays, undistort_points, undistort_rays

LENSES = 300  # random lenses
POINTS = 40  # rays per lens
# A fixed count of Newton steps: with an eps criterion OpenCV marks a pixel whose step never
# falls below eps (rounding) as failed (-1e6).
CRITERIA = (cv2.TERM_CRITERIA_COUNT, 100, 0.0)


def random_lens(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """K of a fisheye camera (about 200 degrees on a 1280 x 960 sensor) and coefficients of
    the size cv2.fisheye.calibrate gives (|k1| < 0.1, the others smaller)."""
    f = rng.uniform(250.0, 400.0)
    k = np.array([[f, 0.0, rng.uniform(600, 680)], [0.0, f * rng.uniform(0.98, 1.02), rng.uniform(440, 520)], [0, 0, 1]])
    d = np.array([rng.uniform(-0.1, 0.1), rng.uniform(-0.03, 0.03), rng.uniform(-0.005, 0.005), rng.uniform(-0.001, 0.001)])
    return k, d


def theta_d(d: np.ndarray, theta: np.ndarray) -> np.ndarray:
    t2 = theta * theta
    return theta * (1 + d[0] * t2 + d[1] * t2**2 + d[2] * t2**3 + d[3] * t2**4)


def slope(d: np.ndarray, theta: np.ndarray) -> np.ndarray:
    t2 = theta * theta
    return 1 + 3 * d[0] * t2 + 5 * d[1] * t2**2 + 7 * d[2] * t2**3 + 9 * d[3] * t2**4


def fold(d: np.ndarray) -> float:
    """The smallest positive root of d theta_d / d theta (np.roots), or pi."""
    # 9 k4 t^8 + 7 k3 t^6 + 5 k2 t^4 + 3 k1 t^2 + 1, highest power first.
    c = [9 * d[3], 0, 7 * d[2], 0, 5 * d[1], 0, 3 * d[0], 0, 1.0]
    roots = [r.real for r in np.roots(c) if abs(r.imag) < 1e-9 and r.real > 0]
    return min([math.pi, *roots])


def rays_at(theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    return np.column_stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])


def to_pixels(k: np.ndarray, m: np.ndarray) -> np.ndarray:
    return m @ k[:2, :2].T + k[:2, 2]


def test_against_cv2_fisheye_in_front_of_the_camera():
    """distort_points and distort_rays vs cv2.fisheye.distortPoints and projectPoints for rays
    up to 89.9 degrees; undistort_points vs cv2.fisheye.undistortPoints where OpenCV inverts
    (theta_d < pi/2)."""
    rng = np.random.default_rng(32)
    err_distort = err_rays = err_project = err_undistort = err_truth = 0.0
    widest = 0.0
    n_undistorted = 0
    for _ in range(LENSES):
        k, d = random_lens(rng)
        lens = Distortion(d, model="equidistant")
        top = min(lens.max_angle, math.radians(89.9))
        theta = np.concatenate([[0.0, 1e-9, top * 0.999999], rng.uniform(0, top, POINTS - 3)])
        phi = rng.uniform(-math.pi, math.pi, POINTS)
        rays = rays_at(theta, phi)
        m = rays[:, :2] / rays[:, 2:]
        cv = cv2.fisheye.distortPoints(m.reshape(-1, 1, 2), k, d).reshape(-1, 2)
        err_distort = max(err_distort, np.abs(distort_points(to_pixels(k, m), k, lens) - cv).max())
        err_rays = max(err_rays, np.abs(distort_rays(rays, k, lens) - cv).max())
        proj, _ = cv2.fisheye.projectPoints(rays.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), k, d)
        err_project = max(err_project, np.abs(proj.reshape(-1, 2) - cv).max())
        widest = max(widest, theta.max())

        # OpenCV inverts theta_d < pi/2; the undistorted pixel K m grows as tan(theta), and
        # its rounding error with it: compared below 80 degrees, and where the lens is well
        # conditioned (d theta_d / d theta >= 0.2: near the fold a pixel's rounding moves
        # theta by eps / slope, and OpenCV's iteration fails there, returning -1e6).
        ok = (theta_d(d, theta) < math.pi / 2) & (theta < math.radians(80)) & (slope(d, theta) >= 0.2)
        back_cv = cv2.fisheye.undistortPoints(cv[ok].reshape(-1, 1, 2), k, d, P=k, criteria=CRITERIA).reshape(-1, 2)
        back = undistort_points(cv[ok], k, lens)
        err_undistort = max(err_undistort, np.abs(back - back_cv).max())
        err_truth = max(err_truth, np.abs(back - to_pixels(k, m[ok])).max())
        n_undistorted += int(ok.sum())
    print(
        f"\nequidistant: {LENSES} lenses, rays up to {math.degrees(widest):.2f} deg: max |distort_points - "
        f"cv2.fisheye.distortPoints| = {err_distort:.2e} px, distort_rays {err_rays:.2e} px, "
        f"(cv2 projectPoints vs distortPoints {err_project:.2e} px); {n_undistorted} pixels up to 80 deg: "
        f"max |undistort_points - cv2.fisheye.undistortPoints| = {err_undistort:.2e} px, "
        f"- the true pinhole pixel {err_truth:.2e} px"
    )
    assert widest > math.radians(89.8)
    assert n_undistorted > LENSES * POINTS // 2
    assert err_distort <= 1e-9
    assert err_rays <= 1e-9
    assert err_undistort <= 1e-9
    assert err_truth <= 1e-9


def test_skew_is_opencvs_alpha():
    """cv2.fisheye's alpha multiplies f_x: u = f_x (x_d + alpha y_d) + c_x, K[0,1] = alpha f_x."""
    k = vsinv.Intrinsics(320.0, 300.0, 640.0, 480.0, skew=1.5)
    km = k.matrix
    d = np.array([0.05, -0.01, 0.002, -0.0003])
    m = np.random.default_rng(5).uniform(-3, 3, (100, 2))
    cv = cv2.fisheye.distortPoints(m.reshape(-1, 1, 2), km, d, alpha=km[0, 1] / km[0, 0]).reshape(-1, 2)
    ours = distort_points(m @ km[:2, :2].T + km[:2, 2], k, Distortion(d, model="equidistant"))
    assert np.abs(ours - cv).max() <= 1e-9


def test_beyond_ninety_degrees_against_numpy():
    """Rays from 90 degrees to the range's end, where OpenCV has no expression: theta_d by the
    polynomial, the pre-image by np.roots, the range by the fold's root."""
    rng = np.random.default_rng(90)
    err_px = err_ray = 0.0
    widest = 0.0
    for _ in range(LENSES):
        k, d = random_lens(rng)
        lens = Distortion(d, model="equidistant")
        assert abs(lens.max_angle - fold(d)) <= 1e-12, (d, lens.max_angle, fold(d))
        if lens.max_angle <= math.radians(95):
            continue
        theta = rng.uniform(math.pi / 2, lens.max_angle * 0.9999, POINTS)
        theta = theta[slope(d, theta) >= 0.2]  # np.roots is inaccurate near the fold's double root
        if len(theta) == 0:
            continue
        phi = rng.uniform(-math.pi, math.pi, len(theta))
        rays = rays_at(theta, phi) * rng.uniform(0.1, 10.0, (len(theta), 1))  # any length
        rho = np.hypot(rays[:, 0], rays[:, 1])
        t = np.arctan2(rho, rays[:, 2])
        expected = to_pixels(k, theta_d(d, t)[:, None] * rays[:, :2] / rho[:, None])
        px = distort_rays(rays, k, lens)
        err_px = max(err_px, np.abs(px - expected).max())
        back = undistort_rays(px, k, lens)
        for i in range(len(theta)):
            rd = theta_d(d, t[i])
            c = [d[3], 0, d[2], 0, d[1], 0, d[0], 0, 1.0, -rd]
            roots = sorted(r.real for r in np.roots(c) if abs(r.imag) < 1e-7 and 0 <= r.real < lens.max_angle)
            want = rays_at(np.array([roots[0]]), np.array([phi[i]]))[0]
            err_ray = max(err_ray, np.abs(back[i] - want).max())
        widest = max(widest, theta.max(initial=0.0))
    print(f"\nbeyond 90 deg, up to {math.degrees(widest):.1f} deg: max |distort_rays - numpy| = {err_px:.2e} px, "
          f"max |undistort_rays - np.roots| = {err_ray:.2e}")
    assert widest > math.radians(150)
    assert err_px <= 1e-9
    assert err_ray <= 1e-9


def test_jacobian_by_finite_differences_of_distort_points():
    """The renderer's local warp uses the analytic Jacobian: its determinant, seen from Python
    as the area ratio of distort_points on a small square, by central differences."""
    k = vsinv.Intrinsics(300.0, 300.0, 0.0, 0.0)
    d = Distortion([0.05, -0.01, 0.002, -0.0003], model="equidistant")
    h = 1e-4
    for m in ([0.3, -0.2], [2.0, 1.5], [-20.0, 5.0]):
        p = np.array(m) * 300.0
        fx = (distort_points([p + [h, 0]], k, d) - distort_points([p - [h, 0]], k, d))[0] / (2 * h)
        fy = (distort_points([p + [0, h]], k, d) - distort_points([p - [0, h]], k, d))[0] / (2 * h)
        r = math.hypot(*m)
        t = math.atan(r)
        c = d.coefficients
        td = t * (1 + c[0] * t**2 + c[1] * t**4 + c[2] * t**6 + c[3] * t**8)
        slope = 1 + 3 * c[0] * t**2 + 5 * c[1] * t**4 + 7 * c[2] * t**6 + 9 * c[3] * t**8
        det = (td / r) * slope / (1 + r * r)  # tangential scale times radial derivative
        assert abs(fx[0] * fy[1] - fx[1] * fy[0] - det) <= 1e-6 * max(1.0, det), m


@settings(max_examples=300, deadline=None)
@given(
    k1=st.floats(-0.1, 0.1), k2=st.floats(-0.03, 0.03), k3=st.floats(-0.005, 0.005), k4=st.floats(-0.001, 0.001),
    frac=st.floats(0.0, 0.999), phi=st.floats(-math.pi, math.pi),
)
def test_round_trip_property(k1, k2, k3, k4, frac, phi):
    k = vsinv.Intrinsics(300.0, 310.0, 640.0, 480.0, skew=1.55)
    lens = Distortion([k1, k2, k3, k4], model="equidistant")
    ray = rays_at(np.array([frac * lens.max_angle]), np.array([phi]))
    px = distort_rays(ray, k, lens)
    np.testing.assert_allclose(undistort_rays(px, k, lens), ray, atol=1e-12, rtol=0)
    if frac * lens.max_angle < math.radians(80):
        ideal = to_pixels(k.matrix, ray[:, :2] / ray[:, 2:])
        np.testing.assert_allclose(undistort_points(distort_points(ideal, k, lens), k, lens), ideal, atol=1e-9, rtol=0)


def test_bad_inputs_name_the_argument():
    k = vsinv.Intrinsics(300.0, 300.0, 320.0, 240.0)
    with pytest.raises(vsinv.InvalidInput, match="distortion coefficients: non-finite value at index 2"):
        Distortion([0.1, 0.0, math.nan, 0.0], model="equidistant")
    with pytest.raises(vsinv.InvalidInput, match=r"the equidistant model takes 4 \(k1, k2, k3, k4\) values, got 5"):
        Distortion([0.0] * 5, model="equidistant")
    assert Distortion([0.0] * 4).model == "plumb_bob"  # 4 numbers alone are OpenCV's k1, k2, p1, p2
    d = Distortion([-0.1, 0.0, 0.0, 0.0], model="equidistant")  # fold at sqrt(1/0.3) = 104.6 deg
    assert abs(d.max_angle - math.sqrt(1 / 0.3)) < 1e-12
    beyond = rays_at(np.array([0.2, d.max_angle + 1e-6]), np.zeros(2))
    with pytest.raises(vsinv.InvalidInput, match=r"distortion: point 1: the ray is 104\.\d+ deg from the optical axis, at or beyond the equidistant model's fold"):
        distort_rays(beyond, k, d)
    edge = theta_d(d.coefficients, d.max_angle)
    with pytest.raises(vsinv.InvalidInput, match=r"distortion: point 1: .* image of the model's fold"):
        undistort_rays([[320.0, 240.0], [320.0 + 300.0 * edge * 1.001, 240.0]], k, d)
    behind = distort_rays(rays_at(np.array([math.radians(100)]), np.zeros(1)), k, d)
    with pytest.raises(vsinv.InvalidInput, match=r"point 0: the ray is 100\.0+\d* deg .*no pinhole pixel"):
        undistort_points(behind, k, d)
    with pytest.raises(vsinv.InvalidInput, match="rays: non-finite value at row 0, column 2"):
        distort_rays([[0.0, 0.0, math.nan]], k, d)
    with pytest.raises(vsinv.InvalidInput, match="ray 0 is zero"):
        distort_rays([[0.0, 0.0, 0.0]], k, d)
    folds_early = Distortion([-0.2, 0.0, 0.0, 0.0], model="equidistant")  # fold at sqrt(1/0.6) = 73.97 deg
    with pytest.raises(vsinv.InvalidInput, match=r"point 0: the ray is 75\.96\d* deg .* fold at 73\.968\d* deg"):
        distort_points([[320.0 + 1200.0, 240.0]], k, folds_early)
    with pytest.raises(vsinv.InvalidInput, match="point 0: Newton's method on theta did not converge in 1 iterations"):
        undistort_points([[600.0, 400.0]], k, Distortion([0.05, -0.01, 0.002, -0.0003], model="equidistant"), max_iter=1)


@pytest.mark.parametrize("suffix", [".yaml", ".xml"])
def test_calibration_files_written_by_opencv(tmp_path, suffix):
    """A cv2.fisheye calibration saved with cv2.FileStorage and the model's ROS name, read back:
    the lens distorts as cv2.fisheye does. Without the name, 4 coefficients are plumb_bob."""
    k = np.array([[310.5, 0.0, 640.25], [0.0, 309.75, 480.5], [0.0, 0.0, 1.0]])
    d = np.array([[0.03], [-0.011], [0.0021], [-0.00032]])
    path = tmp_path / f"fisheye{suffix}"
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    fs.write("image_width", 1280)
    fs.write("image_height", 960)
    fs.write("camera_matrix", k)
    fs.write("distortion_model", "equidistant")
    fs.write("distortion_coefficients", d)
    fs.release()
    cal = vsinv.calibration.load_calibration(path)
    assert cal.distortion.model == "equidistant" and cal.image_size == (1280, 960)
    np.testing.assert_array_equal(cal.distortion.coefficients, d.ravel())
    m = np.random.default_rng(1).uniform(-2, 2, (50, 2))
    cv = cv2.fisheye.distortPoints(m.reshape(-1, 1, 2), k, d).reshape(-1, 2)
    assert np.abs(distort_points(to_pixels(k, m), cal.intrinsics, cal.distortion) - cv).max() <= 1e-9
    path.write_text(path.read_text().replace("equidistant", "fisheye"))
    with pytest.raises(vsinv.InvalidInput, match="distortion_model: unknown distortion model"):
        vsinv.calibration.load_calibration(path)


def test_ros_camera_info_yaml(tmp_path):
    path = tmp_path / "fisheye.yaml"
    path.write_text(
        "image_width: 1280\nimage_height: 960\ncamera_name: fisheye\n"
        "camera_matrix: {rows: 3, cols: 3, data: [310.5, 0, 640.25, 0, 309.75, 480.5, 0, 0, 1]}\n"
        "distortion_model: equidistant\n"
        "distortion_coefficients: {rows: 1, cols: 4, data: [0.03, -0.011, 0.0021, -0.00032]}\n"
    )
    assert vsinv.calibration.load_calibration(path).distortion == Distortion([0.03, -0.011, 0.0021, -0.00032], model="equidistant")
    path.write_text(path.read_text().replace("cols: 4, data: [0.03,", "cols: 5, data: [0.0, 0.03,"))
    with pytest.raises(vsinv.InvalidInput, match=r"distortion_coefficients: wrong coefficient count: the equidistant model takes 4"):
        vsinv.calibration.load_calibration(path)


def test_the_fisheye_builtin_servoes_to_a_pinhole_reference():
    """lens-12-fisheye: a 12 mm pinhole reference image, a fisheye servo lens known from its
    calibration; the invariant law converges, and the scenario keys round-trip."""
    s = vsinv.load_scenario("lens-12-fisheye")
    cam = s.to_dict()["camera"]
    assert cam["distortion_model"] == "equidistant" and cam["distortion"] == [-0.04, 0.01, -0.003, 0.0005]
    summary = vsinv.run_scenario(s, record=False).summary
    assert summary["status"] == "converged", summary["message"]
    assert summary["final_translation_error"] < 1e-3 and math.degrees(summary["final_rotation_error"]) < 0.1
    bad = s.to_dict()
    bad["camera"]["distortion"] = [-0.04, 0.01, -0.003, 0.0005, 0.0]
    with pytest.raises(vsinv.InvalidInput, match=r"camera\.distortion.*equidistant model takes 4"):
        vsinv.load_scenario(bad)
