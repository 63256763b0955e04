"""The MuJoCo built-ins from random starts, and where a MuJoCo iteration's time goes (issue 31,
"Measured").

How to run (from the repository root, with the package and the mujoco extra installed)::

    python benches/mujoco_starts.py            # 20 starts per built-in: about 40 minutes on 2 cores
    python benches/mujoco_starts.py --quick    # 1 start of 30 iterations per built-in (make bench-quick)

(a) Convergence: each `mujoco-*` built-in (`[world] engine = "mujoco"`) from `--starts` seeded
random starts: the scenario's `[start]` pose moved by a random translation (0-40 mm) and
turned by a random rotation (0-10 degrees), redrawn until every target point is at least 25 px
inside the servo camera's first image. Per built-in: the convergence rate, and the median and
largest final error by the scene's truth (the pose in F*). IBVS (`mujoco-ibvs-12-6`,
`mujoco-arm-ur5e-ibvs-12-6`) is expected never to converge: its rate is the point of the
comparison. With an arm (`mujoco-arm-*`) the start pose places the arm by the kinematic arm's
inverse kinematics; eye-to-hand (`mujoco-eye-to-hand-12-6`) the start is the camera's pose in
F*, the target's frame put at its inverse before the fixed camera.

(b) Per iteration: MuJoCo's render (set K, place the camera, render, read the pixels), the
image servo's step (detection + control, timed by `vsinv.mujoco.run_loop`), and control alone:
`vsinv.Servo` with the same law, K_hat, reference pixels and depths stepped on the pixels the
run recorded, so detection is the step minus control. A free camera moves by the twist: no
physics step. With an arm, control adds the arm's mapping (MuJoCo's site Jacobian and the
damped least squares, after the +) and physics is the frame's 20 MuJoCo steps (500 Hz under a
25 Hz law). Beside them the kinematic world's figures for the
same experiment: vsinv's own renderer (`vsinv.vision.render`) at the same poses and
resolution, and the Rust simulator's whole iteration with images in the loop (the kinematic
built-in with `[vision]`); and the kinematic built-in from the same starts (its verdicts and
final errors). An arm built-in's kinematic twin is the same scenario without `[world]` (the
kinematic simulator's arm), eye-to-hand's is `lens-12-6` (the same relative motion).

Agreement first: before anything is timed, the control replay must give the twists the run
sent (within 1e-9 m/s, rad/s) and each built-in from its own `[start]` must give the verdict
of the kinematic built-in of the same experiment (converged, or IBVS not); the script exits 1
otherwise. The tag built-ins render with `[world] supersample` (each pixel the mean of a block),
as their scenarios say. Without mujoco or EGL it says what to install and exits 0.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np  # noqa: E402

import vsinv  # noqa: E402
import vsinv.mujoco as vm  # noqa: E402
from vsinv import geometry  # noqa: E402
from vsinv.mujoco import _session  # noqa: E402

#: Each MuJoCo built-in and the kinematic built-in of the same experiment (None: the same
#: scenario without `[world]`, the kinematic simulator's arm; eye-to-hand's twin is the free
#: camera of the same relative motion).
BUILTINS: dict[str, str | None] = {
    "mujoco-lens-12-6": "lens-12-6",
    "mujoco-lens-12-6-tags": "tags-12-6",
    "mujoco-zoom": "zoom-servo",
    "mujoco-ibvs-12-6": "ibvs-12-6",
    "mujoco-arm-ur5e-12-6": None,
    "mujoco-arm-ur5e-12-6-tags": None,
    "mujoco-arm-panda-zoom": None,
    "mujoco-arm-ur5e-ibvs-12-6": None,
    "mujoco-eye-to-hand-12-6": "lens-12-6",
    "mujoco-arm-ur5e-zoom-stationary": "zoom-stationary",
}


def twin(name: str, kinematic: str | None) -> dict:
    """The kinematic twin's scenario dict."""
    if kinematic is not None:
        return vsinv.load_scenario(kinematic).to_dict()
    d = vsinv.load_scenario(name).to_dict()
    d.pop("world", None)
    d["name"] = f"{name} (kinematic arm)"
    return d


def twin_label(name: str, kinematic: str | None) -> str:
    return kinematic if kinematic is not None else f"{name} without [world]"
MARGIN = 25.0  # px: every target point this far inside the first image


def start_poses(d: dict, points: np.ndarray, count: int, seed: int) -> list[np.ndarray]:
    """`count` perturbed copies of the scenario's `[start]` with every point in view."""
    rng = np.random.default_rng(seed)
    s = d["start"]
    start = geometry.pose_from_position_thetau(s["position"], np.radians(s["rotation_deg"]))
    c = d["camera"]
    poses: list[np.ndarray] = []
    while len(poses) < count:
        t = rng.normal(size=3)
        t *= rng.uniform(0.0, 0.04) / np.linalg.norm(t)
        w = rng.normal(size=3)
        w *= np.radians(rng.uniform(0.0, 10.0)) / np.linalg.norm(w)
        pose = start @ geometry.pose_from_position_thetau(t, w)
        p = (points - pose[:3, 3]) @ pose[:3, :3]  # the points in the camera frame
        u = c["fku"] * p[:, 0] / p[:, 2] + c["u0"]
        v = c["fkv"] * p[:, 1] / p[:, 2] + c["v0"]
        inside = (u > MARGIN) & (u < c["width"] - 1 - MARGIN) & (v > MARGIN) & (v < c["height"] - 1 - MARGIN)
        if (p[:, 2] > 0.1).all() and inside.all():
            poses.append(pose)
    return poses


def control_replay(d: dict, world: vm.World, run: vm.MujocoRun) -> tuple[float, float]:
    """Seconds per step of `vsinv.Servo` (the law alone) on the run's recorded pixels, and the
    largest difference between its twists and the ones the run sent."""
    if world.arm is not None:  # the arm's own set-up (eye-to-hand: the target at F* for the reference)
        from vsinv.mujoco import _arm_loop

        defaults = _session._Options(None, None, None, False, None)
        session, _ = _arm_loop._start_session(d, world, defaults, _arm_loop._Geometry(world))
    else:
        session = _session._session(d, world, None, run.pose[0], None)  # the run's own ImageServo set-up
    options = _session.session_options(d, None)
    points = np.asarray(world.target_points)  # a World.from_scenario has them
    servo = vsinv.Servo(np.asarray(session.servo.reference_pixels), _session._intrinsics(d, "estimate"),
                        reference_depths=points[session.truth, 2], **options)
    r = run.result
    twists = []
    t0 = time.perf_counter()
    for pixels, visible in zip(r.pixels[:-1], r.visible[:-1]):
        twists.append(np.asarray(servo.step(np.nan_to_num(pixels), visible=visible).twist))
    seconds = (time.perf_counter() - t0) / max(len(twists), 1)
    gap = float(np.abs(np.array(twists) - r.twist[:-1]).max()) if twists else 0.0
    return seconds, gap


def kinematic_figures(twin_d: dict, poses: np.ndarray, times: np.ndarray) -> tuple[float, float]:
    """vsinv's renderer per frame at `poses` (seconds), and the Rust simulator's whole iteration
    with images in the loop (seconds) for the kinematic twin `twin_d`."""
    d = dict(twin_d)
    if "vision" not in d:  # images in the loop; [vision] brings its own noise (vision.noise_sigma)
        d["vision"] = {}
        d.pop("noise", None)
    t0 = time.perf_counter()
    for pose, t in zip(poses, times):
        vsinv.vision.render(d, pose, float(t))
    render = (time.perf_counter() - t0) / len(poses)
    t0 = time.perf_counter()
    r = vsinv.run_scenario(d)
    whole = (time.perf_counter() - t0) / max(r.summary["iterations"], 1)
    return render, whole


def kinematic_starts(twin_d: dict, starts: list[np.ndarray], max_iterations: int | None) -> tuple[float, list[float], list[float]]:
    """The kinematic twin `twin_d` from the same starts: its convergence rate and final
    errors (m, degrees)."""
    d = dict(twin_d)
    d["stop"] = dict(d["stop"])
    if max_iterations is not None:
        d["stop"]["max_iterations"] = max_iterations
    statuses, t_err, r_err = [], [], []
    for pose in starts:
        position, thetau = geometry.thetau_from_pose(pose)
        d["start"] = {"position": [float(x) for x in position], "rotation_deg": [float(x) for x in np.degrees(thetau)]}
        try:
            s = vsinv.run_scenario(d, record=False).summary
        except vsinv.InvalidInput:  # an arm that cannot reach the start
            statuses.append("unreachable")
            continue
        statuses.append(s["status"])
        t_err.append(s["final_translation_error"])
        r_err.append(float(np.degrees(s["final_rotation_error"])))
    return float(np.mean([st == "converged" for st in statuses])), t_err, r_err


def agreement(builtins: dict[str, str | None], max_iterations: int | None) -> bool:
    """The verdicts of the MuJoCo built-ins from their own starts against the kinematic ones
    (`max_iterations` None: full runs), and the control replay's twists against the run's."""
    ok = True
    for name, kinematic in builtins.items():
        d = vsinv.load_scenario(name).to_dict()
        with vm.World.from_scenario(d) as world:
            run = vm.run_loop(d, world=world, max_iterations=max_iterations)
            _, gap = control_replay(d, world, run)
        s = run.summary
        ok_twist = gap < 1e-9
        if max_iterations is None:
            k = vsinv.run_scenario(twin(name, kinematic)).summary
            same = (s["status"] == "converged") == (k["status"] == "converged")
            print(f"  {name}: {s['status']} in {s['iterations']} ({1e3 * s['final_translation_error']:.2f} mm); "
                  f"{twin_label(name, kinematic)}: {k['status']} in {k['iterations']} ({1e3 * k['final_translation_error']:.2f} mm); "
                  f"control replay within {gap:.1e}")
            ok = ok and same
        else:
            print(f"  {name}: control replay of {s['iterations']} steps within {gap:.1e}")
        ok = ok and ok_twist
    return ok


def sweep(name: str, kinematic: str | None, starts: int, max_iterations: int | None, seed: int) -> list[str]:
    """(a) and (b) for one built-in: the table's two rows."""
    d = vsinv.load_scenario(name).to_dict()
    statuses, t_err, r_err = [], [], []
    clock = {"render": 0.0, "servo": 0.0, "control": 0.0, "arm": 0.0, "physics": 0.0}
    frames, poses, times = 0, np.empty((0, 4, 4)), np.empty(0)
    with vm.World.from_scenario(d) as world:
        chosen = start_poses(d, np.asarray(world.target_points), starts, seed)
        for k, start in enumerate(chosen):
            try:
                run = vm.run_loop(d, world=world, start=start, max_iterations=max_iterations)
            except vsinv.InvalidInput as e:  # an arm that cannot reach the start: counted as not converged
                statuses.append("unreachable")
                print(f"    {name} start {k}: unreachable ({str(e)[:80]})", flush=True)
                continue
            s = run.summary
            statuses.append(s["status"])
            t_err.append(s["final_translation_error"])
            r_err.append(np.degrees(s["final_rotation_error"]))
            n = s["iterations"] + 1
            for key in ("render", "servo"):
                clock[key] += run.seconds_per_iteration[key] * n
            clock["arm"] += run.seconds_per_iteration.get("control", 0.0) * n  # Jacobian + damped least squares
            clock["physics"] += run.seconds_per_iteration.get("physics", 0.0) * n
            control, _ = control_replay(d, world, run)
            clock["control"] += control * n
            frames += n
            if len(poses) == 0:
                poses, times = run.pose[:: max(1, n // 50)], run.time[:: max(1, n // 50)]
            print(f"    {name} start {k}: {s['status']} in {s['iterations']}, {1e3 * t_err[-1]:.2f} mm, "
                  f"{r_err[-1]:.3f} deg; render {1e3 * run.seconds_per_iteration['render']:.1f} ms, "
                  f"load {os.getloadavg()[0]:.2f}", flush=True)
    rate = np.mean([st == "converged" for st in statuses])
    per = {key: 1e3 * v / frames for key, v in clock.items()}
    twin_d = twin(name, kinematic)
    k_render, k_whole = kinematic_figures(twin_d, poses, times)
    k_rate, k_t, k_r = kinematic_starts(twin_d, chosen, max_iterations)
    c = d["camera"]
    physics = f"{per['physics']:.2f}" if per["physics"] > 0 else "-"
    arm = f" + {per['arm']:.3f}" if per["arm"] > 0 else ""
    return [
        f"| {name} | {100 * rate:.0f} % of {starts} | {1e3 * np.median(t_err):.2f} / {1e3 * np.max(t_err):.2f} mm | "
        f"{np.median(r_err):.3f} / {np.max(r_err):.3f} deg | {per['render']:.1f} | {per['servo'] - per['control']:.2f} | "
        f"{per['control']:.3f}{arm} | {physics} | {int(c['width'])}x{int(c['height'])} |",
        f"| {twin_label(name, kinematic)} (kinematic) | {100 * k_rate:.0f} % of {starts} | {1e3 * np.median(k_t):.2f} / {1e3 * np.max(k_t):.2f} mm | "
        f"{np.median(k_r):.3f} / {np.max(k_r):.3f} deg | {1e3 * k_render:.1f} | whole iteration {1e3 * k_whole:.2f} ms | | - | |",
    ]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--starts", type=int, default=20)
    parser.add_argument("--seed", type=int, default=31)
    parser.add_argument("--quick", action="store_true", help="1 start of 30 iterations per built-in")
    parser.add_argument("--only", nargs="*", default=None, help="these built-ins only (default: all)")
    args = parser.parse_args()
    why = vm.available()
    if why is not None:
        print(f"skipped: {why}")
        return 0
    max_iterations = 30 if args.quick else None
    starts = 1 if args.quick else args.starts
    import mujoco

    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; MuJoCo {mujoco.__version__}")
    print("agreement:")
    chosen = {n: k for n, k in BUILTINS.items() if args.only is None or n in args.only}
    if not agreement(chosen, max_iterations):
        print("DISAGREEMENT: the control replay or a verdict differs (see above)")
        return 1
    rows = ["| built-in | converged | final translation median / max | final rotation median / max | "
            "render ms | detection ms | control ms | physics ms | image |", "|" + "---|" * 9]
    for name, kinematic in chosen.items():
        rows += sweep(name, kinematic, starts, max_iterations, args.seed)
    print("\n".join(rows))
    print(f"load average {os.getloadavg()[0]:.2f} at the end")
    return 0


if __name__ == "__main__":
    sys.exit(main())
