"""Every class of ``vsinv._core`` shared by several threads (issue 28, finding 5): an
``ImageServo`` shared by 8 threads raised PyO3's ``RuntimeError: Already borrowed`` in 600-700
of 800 calls (its step releases the GIL while it changes the object). Every class must work
from several threads (calls take turns) or raise one of the package's own exceptions; none
may raise anything else. The mutable classes must keep a consistent state: N calls from
threads count as N calls."""

from __future__ import annotations

import inspect
import threading
from typing import Any, Callable

import numpy as np
import pytest

import vsinv
import vsinv._core as core

THREADS = 8
CALLS = 25  # per thread


def hammer(call: Callable[[], Any], threads: int = THREADS, calls: int = CALLS) -> dict[str, int]:
    """Runs `call` `calls` times on each of `threads` threads started together; counts the
    outcomes by exception class name ("returned" for none)."""
    counts: dict[str, int] = {}
    lock = threading.Lock()
    start = threading.Barrier(threads)

    def work() -> None:
        start.wait()
        for _ in range(calls):
            try:
                call()
                kind = "returned"
            except vsinv.VsinvError as e:
                kind = f"vsinv.{type(e).__name__}"
            except Exception as e:  # noqa: BLE001 - what the test looks for
                kind = f"{type(e).__module__}.{type(e).__name__}: {e}"
            with lock:
                counts[kind] = counts.get(kind, 0) + 1

    workers = [threading.Thread(target=work) for _ in range(threads)]
    for w in workers:
        w.start()
    for w in workers:
        w.join(timeout=120)
    assert not any(w.is_alive() for w in workers), "a thread did not finish (deadlock?)"
    return counts


def works(call: Callable[[], Any], **kw: Any) -> None:
    counts = hammer(call, **kw)
    total = kw.get("threads", THREADS) * kw.get("calls", CALLS)
    assert counts == {"returned": total}, counts


# ---------------------------------------------------------------------------------------------
# The scene: the vision-12-6 scenario's reference and start images and pixels


@pytest.fixture(scope="module")
def scene() -> dict[str, Any]:
    sc = vsinv.load_scenario("vision-12-6")
    ref, ref_px, _ = vsinv.vision.render_view(sc, reference=True)
    start, start_px, _ = vsinv.vision.render_view(sc)
    # The scenario's object (F*, metres): the reference depths zeta* are its z coordinates
    # (test_image_servo.py); the start depths roughly the same.
    ref_z = start_z = np.array([0.60, 0.66, 0.56, 0.63, 0.54, 0.65, 0.62, 0.57, 0.64, 0.55, 0.61, 0.66])
    k = vsinv.Intrinsics(648.0, 570.0, 427.0, 304.0)
    return {"scenario": sc, "ref": ref, "ref_px": ref_px, "ref_z": ref_z, "start": start,
            "start_px": start_px, "start_z": start_z, "k": k}


def servo_args(scene: dict[str, Any]) -> dict[str, Any]:
    return {"reference_depths": scene["ref_z"], "stop": {"max_iterations": 1_000_000, "stall": False}}


def test_image_servo_steps_from_threads(scene: dict[str, Any]) -> None:
    """The finding: 8 threads x 100 steps of one ImageServo."""
    servo = vsinv.ImageServo(scene["ref"], "dots", scene["k"], reference_points=scene["ref_px"],
                             first_points=scene["start_px"], **servo_args(scene))
    results: list[int] = []

    def step() -> None:
        s = servo.step(scene["start"])
        assert s.found.all() and np.isfinite(s.twist).all()
        results.append(servo.iterations)
        repr(servo), servo.basis, servo.pixel_sigma, servo.certainty(), servo.ids, servo.reference_pixels

    works(step, calls=100)
    assert servo.iterations == THREADS * 100  # every step counted once


def test_tag_tracker_from_threads(scene: dict[str, Any]) -> None:
    sc = vsinv.load_scenario("vision-tags-12-6") if "vision-tags-12-6" in dict(vsinv.sim.list_scenarios()) else None
    image = vsinv.vision.render_view(sc)[0] if sc is not None else scene["start"]
    tracker = vsinv.vision.TagTracker(refresh=3)
    expected = vsinv.vision.detect_tags(image).ids.tolist()

    def track() -> None:
        assert tracker.track(image).ids.tolist() == expected
        tracker.read_whole
        if np.random.default_rng().random() < 0.1:
            tracker.reset()

    works(track)


def test_dot_tracker_from_threads(scene: dict[str, Any]) -> None:
    tracker = vsinv.vision.DotTracker(scene["start"], scene["start_px"])
    n = len(scene["start_px"])

    def track() -> None:
        px, found = tracker.track(scene["start"])
        assert found.all() and px.shape == (n, 2)
        assert tracker.positions.shape == (n, 2) and len(tracker) == n and repr(tracker)

    works(track)


def test_servo_and_controllers_from_threads(scene: dict[str, Any]) -> None:
    servo = vsinv.Servo(scene["ref_px"], scene["k"], reference_depths=scene["ref_z"],
                        stop={"max_iterations": 1_000_000})
    works(lambda: (servo.step(scene["start_px"]), servo.certainty(), servo.basis))
    assert servo.iterations == THREADS * CALLS
    inv = vsinv.laws.InvariantController(scene["ref_px"], scene["k"])
    works(lambda: (inv.step(scene["start_px"], scene["start_z"]), inv.pose_uncertainty(scene["start_px"], scene["start_z"], pixel_sigma=0.5)))
    ibvs = vsinv.laws.IbvsController(scene["ref_px"], scene["k"])
    works(lambda: (ibvs.step(scene["start_px"], scene["start_z"]), ibvs.pixel_error))
    meter = vsinv.vision.PixelNoiseMeter(capacity=50)
    works(lambda: (meter.push(scene["start_px"]), meter.sigma))
    resection = vsinv.calibration.ResectionDepths(scene["start_px"], scene["start_z"], scene["ref_px"])
    works(lambda: resection.estimate(scene["start_px"]))


def test_results_from_threads(scene: dict[str, Any], tmp_path: Any) -> None:
    """The frozen classes: their methods and getters from threads."""
    px, ref = scene["start_px"], scene["ref_px"]
    k = scene["k"]
    run = vsinv.run_scenario("lens-12-6")
    path = vsinv.laws.InvariantPath(px, ref, duration=2.0)
    rng = np.random.default_rng(1)
    g = np.array([vsinv.geometry.pose_from_position_thetau(rng.normal(size=3) * 0.1, rng.normal(size=3) * 0.5) for _ in range(6)])
    x = vsinv.geometry.pose_from_position_thetau([0.01, 0.02, 0.1], [0.1, 0.2, 0.3])
    target = vsinv.geometry.pose_from_position_thetau([0.5, 0.0, 0.0], [0.0, 0.0, 0.0])
    c = np.array([np.linalg.inv(gi @ x) @ target for gi in g])
    servo = vsinv.Servo(ref, k, reference_depths=scene["ref_z"])
    image_step = vsinv.ImageServo(scene["ref"], "dots", k, reference_points=ref, first_points=px,
                                  **servo_args(scene)).step(scene["start"])
    yaml = tmp_path / "camera.yaml"
    yaml.write_text("image_width: 640\nimage_height: 480\ncamera_matrix:\n  rows: 3\n  cols: 3\n"
                    "  data: [800.0, 0, 320.0, 0, 800.0, 240.0, 0, 0, 1]\ndistortion_coefficients:\n  rows: 1\n  cols: 5\n"
                    "  data: [0, 0, 0, 0, 0]\n")
    calls: dict[str, Callable[[], Any]] = {
        "Calibration": (lambda cal: lambda: (cal.intrinsics, cal.distortion, cal.image_size))(vsinv.calibration.load_calibration(yaml)),
        "Intrinsics": lambda: (k.matrix, repr(k)),
        "StabilityReport": lambda: vsinv.laws.check_stability(k, k).tracking_bound(0.1),
        "ServoStep": (lambda s: lambda: (s.twist, s.verdict, s.telemetry))(servo.step(px)),
        "ImageStep": lambda: (image_step.found, image_step.pixels, image_step.stopped_early, image_step.telemetry),
        "PoseUncertainty": (lambda u: lambda: (u.covariance, u.translation_bound()))(
            vsinv.laws.InvariantController(ref, k).pose_uncertainty(px, scene["start_z"], pixel_sigma=0.5)),
        "PlaneParallax": (lambda p: lambda: (p.gamma, p.epipole))(path.plane_parallax),
        "InvariantPath": lambda: path.sample(1.0),
        "Scenario": lambda: (scene["scenario"].to_dict(), scene["scenario"].name),
        "RunResult": lambda: (run.summary, run.arrays, run.pose),
        "Dots": (lambda d: lambda: (d.centroids, d.areas))(vsinv.vision.detect_dots(scene["start"])),
        "Tags": (lambda t: lambda: (t.ids, t.corners, t.family))(vsinv.vision.detect_tags(scene["start"])),
        "IkSolution": (lambda s: lambda: (s.joints, s.position_residual))(
            vsinv.kinematics.ik("ur5", vsinv.kinematics.fk("ur5", [0.1, -1.2, 1.0, -0.5, 1.4, 0.3]))),
        "Distortion": (lambda d: lambda: (d.coefficients, d.model))(vsinv.vision.Distortion([0.1, 0.01, 0, 0, 0], "plumb_bob")),
        "HandEyeCalibration": (lambda h: lambda: (h.matrix, h.residuals))(vsinv.calibration.calibrate_hand_eye(g, c)),
        "HandEyeAgreement": (lambda h: lambda: (h.calibrations, h.max_rotation_deg))(vsinv.calibration.compare_hand_eye_methods(g, c)),
        "ScenarioArm": (lambda a: lambda: (a.manipulability(a.start), a.joint_names, a.base))(
            vsinv.load_scenario("arm-ur5-12-6").arm()),
    }
    for name, call in calls.items():
        counts = hammer(call)
        assert counts == {"returned": THREADS * CALLS}, (name, counts)


STATEFUL = {"InvariantController", "IbvsController", "Servo", "PixelNoiseMeter", "ResectionDepths",
            "DotTracker", "ImageServo", "TagTracker"}
FROZEN = {"Intrinsics", "StabilityReport", "ServoStep", "ImageStep", "PoseUncertainty", "PlaneParallax",
          "InvariantPath", "Scenario", "RunResult", "Dots", "Tags", "IkSolution", "Distortion",
          "HandEyeCalibration", "HandEyeAgreement", "Calibration", "ScenarioArm"}


def test_every_class_is_covered() -> None:
    classes = {n for n, o in vars(core).items()
               if inspect.isclass(o) and not issubclass(o, BaseException)}
    assert classes == STATEFUL | FROZEN, classes ^ (STATEFUL | FROZEN)


def test_docstrings_say_threads_take_turns() -> None:
    for name in ("ImageServo", "TagTracker", "DotTracker"):
        assert "several threads" in (getattr(vsinv.vision if "Tracker" in name else vsinv, name).__doc__ or ""), name
