"""`[world] engine = "mujoco"` (issue 31, item 1): one key sends a scenario to MuJoCo through
`vsinv run` and `vsinv.run_scenario`, and the result is a `RunResult` of the kinematic run's
schema (`RunResult.from_recording` checks it); `[world] latency_frames` delays the twist
(issue 31, item 2).

The independent checks: the kinematic simulator's own run of the same scenario (its summary keys
and `.npz` columns), the scene's truth for the verdict, and the recorded poses integrated again
from the recorded twists for the latency. Skips (saying what to install) when mujoco or an
EGL/OpenGL stack is missing (the refusals by the Rust runner and by `from_recording` run
without MuJoCo).
"""

from __future__ import annotations

import json
import os

os.environ.setdefault("MUJOCO_GL", "egl")

from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import vsinv  # noqa: E402
import vsinv.mujoco as vm  # noqa: E402
from vsinv.cli import main  # noqa: E402

pytestmark = pytest.mark.sim

_WHY_NOT = vm.available()
needs_mujoco = pytest.mark.skipif(_WHY_NOT is not None, reason=_WHY_NOT or "")


def _scenario(name: str = "lens-12-6", **world: object) -> dict:
    d = vsinv.load_scenario(name).to_dict()
    d["world"] = {"engine": "mujoco", **world}
    return d


# -- the key, without MuJoCo ---------------------------------------------------------------------
def test_the_engine_key_defaults_to_kinematic_and_is_read_once() -> None:
    assert vsinv.load_scenario("lens-12-6").engine == "kinematic"
    assert "world" not in vsinv.load_scenario("lens-12-6").to_dict()  # the default is not written
    s = vsinv.sim.Scenario.from_dict(_scenario(latency_frames=2))
    assert s.engine == "mujoco" and s.to_dict()["world"] == {"engine": "mujoco", "latency_frames": 2}
    assert 'engine = "mujoco"' in s.to_toml()


def test_supersample_defaults_to_one_and_is_written_when_set() -> None:
    """`[world] supersample`: 1 unless said (not written then), kept by to_dict and to_toml, and
    the kinematic simulator takes `supersample = 1` (its default) with `engine = "kinematic"`."""
    assert "supersample" not in vsinv.load_scenario("mujoco-lens-12-6").to_dict()["world"]
    s = vsinv.sim.Scenario.from_dict(_scenario(supersample=3))
    assert s.to_dict()["world"] == {"engine": "mujoco", "latency_frames": 0, "supersample": 3}
    assert "supersample = 3" in s.to_toml()
    d = vsinv.load_scenario("lens-12-6").to_dict() | {"world": {"engine": "kinematic", "supersample": 1}}
    assert "world" not in vsinv.sim.Scenario.from_dict(d).to_dict()


@pytest.mark.parametrize(
    ("world", "key", "words"),
    [
        ({"engine": "physx"}, "world.engine", "unknown variant"),
        ({"engine": "kinematic", "latency_frames": 1}, "world.latency_frames", "mujoco"),
        ({"engine": "mujoco", "latency_frames": 1001}, "world.latency_frames", "1000"),
        ({"engine": "mujoco", "lag": 1}, "world", "lag"),
        ({"engine": "mujoco", "supersample": 0}, "world.supersample", "positive whole number"),
        ({"engine": "mujoco", "supersample": -2}, "world.supersample", ""),
        ({"engine": "mujoco", "supersample": 1.5}, "world.supersample", ""),
        ({"engine": "kinematic", "supersample": 2}, "world.supersample", "mujoco"),
    ],
)
def test_bad_world_keys_are_refused_by_name(world: dict, key: str, words: str) -> None:
    d = vsinv.load_scenario("lens-12-6").to_dict()
    d["world"] = world
    with pytest.raises(vsinv.InvalidInput) as e:
        vsinv.sim.Scenario.from_dict(d)
    assert key in str(e.value) and words in str(e.value), str(e.value)


@pytest.mark.parametrize(
    ("table", "value", "key"),
    [("noise", {"pixel_sigma": 0.5}, "noise.pixel_sigma"), ("path", {"samples": 100}, "path"),
     ("control", {"depths": "true"}, "control.depths"), ("camera", {"distortion": [0.1, 0.0, 0.0, 0.0]}, "camera.distortion")],
)
def test_what_the_mujoco_loop_does_not_simulate_is_refused(table: str, value: dict, key: str) -> None:
    """A key the MuJoCo loop would ignore (pixel noise, a planned path, true depths, a lens
    distortion) is refused by name when the scenario is loaded, not silently dropped."""
    d = _scenario()
    d[table] = {**(d.get(table) or {}), **value}
    with pytest.raises(vsinv.InvalidInput) as e:
        vsinv.sim.Scenario.from_dict(d)
    assert key in str(e.value) and "not simulated" in str(e.value), str(e.value)
    d["world"]["engine"] = "kinematic"
    vsinv.sim.Scenario.from_dict(d)  # the kinematic simulator takes it


def test_the_rust_runner_refuses_mujoco_by_name() -> None:
    """The Rust simulator (`_core.run_scenario`, `_core.run_batch`) does not run a MuJoCo
    scenario: a Scenario error naming world.engine that says where it runs (`vsinv.sim.run_batch`
    runs them in Python: tests/test_mujoco_batch.py)."""
    d = _scenario()
    with pytest.raises(vsinv.InvalidInput) as e:
        vsinv._core.run_scenario(d)
    msg = str(e.value)
    assert "world.engine" in msg and "Python" in msg and "vsinv[mujoco]" in msg, msg
    assert e.value.location == ("world", "engine")
    with pytest.raises(vsinv.InvalidInput, match="world.engine"):
        vsinv._core.run_batch([d])


def test_from_recording_rebuilds_a_kinematic_run_and_checks_it() -> None:
    """A kinematic run's own summary and columns make the same RunResult; each departure from
    the schema is refused naming the key or column."""
    r = vsinv.run_scenario("vision-12-6")
    summary, arrays = dict(r.summary), dict(r.arrays)
    again = vsinv.RunResult.from_recording(r.scenario, summary, arrays)
    assert list(again.summary) == list(r.summary) and again.summary == r.summary
    for name, a in r.arrays.items():
        np.testing.assert_array_equal(again.arrays[name], a)
        assert again.arrays[name].dtype == a.dtype
    assert set(again.arrays) == set(r.arrays)

    def refused(s: dict, a: dict, words: str) -> None:
        with pytest.raises(vsinv.InvalidInput) as e:
            vsinv.RunResult.from_recording(r.scenario, s, a)
        assert words in str(e.value), str(e.value)

    refused({**summary, "engine": "mujoco"}, arrays, 'summary["engine"]')
    refused({k: v for k, v in summary.items() if k != "prop1"}, arrays, '"prop1" is missing')
    refused({**summary, "status": "fine"}, arrays, "converged")
    refused({**summary, "name": "other"}, arrays, "vision-12-6")
    refused({**summary, "iterations": -1}, arrays, "iterations")
    refused({**summary, "final_translation_error": "0"}, arrays, "final_translation_error")
    refused({**summary, "basis": [0, 1, 99]}, arrays, "basis")
    refused(summary, {k: v for k, v in arrays.items() if k != "eps"}, '"eps" is missing')
    refused(summary, {**arrays, "K": arrays["time"]}, 'arrays["K"]')
    refused(summary, {**arrays, "pose": arrays["pose"][:-1]}, 'arrays["pose"]')
    refused(summary, {**arrays, "visible": arrays["visible"].astype(float)}, "bool")
    refused(summary, {**arrays, "time": arrays["time"][::-1].copy()}, "increasing")


# -- through MuJoCo ----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def mujoco_run() -> vsinv.RunResult:
    if _WHY_NOT is not None:
        pytest.skip(_WHY_NOT)
    return vsinv.run_scenario(_scenario())


@needs_mujoco
def test_run_scenario_runs_mujoco_with_the_kinematic_schema(mujoco_run: vsinv.RunResult) -> None:
    """lens-12-6 under MuJoCo: `converged` (within the scenario's tolerances by the scene's
    truth), and the summary's keys (in order) and the columns are those of the kinematic run of
    the same scenario with images in the loop (`[vision]`: a MuJoCo run always has images)."""
    r = mujoco_run
    s = r.summary
    print({k: s[k] for k in ("status", "iterations", "final_translation_error", "final_rotation_error", "message")})
    assert s["status"] == "converged", s["message"]
    assert s["within_tolerance"] and s["final_translation_error"] < 5e-3, s
    kinematic = vsinv.load_scenario("lens-12-6").to_dict()
    kinematic["vision"] = {}
    k = vsinv.run_scenario(kinematic)
    assert list(s) == list(k.summary)
    for key in ("stop_rule", "prop1", "prop2", "basis"):  # what the scenario decides
        assert s[key] == k.summary[key], key
    for key in ("start_translation_error", "start_rotation_error"):
        assert s[key] == pytest.approx(k.summary[key], rel=1e-9), key
    assert set(r.arrays) == set(k.arrays)
    n = s["iterations"] + 1
    for name, a in r.arrays.items():
        assert a.dtype == k.arrays[name].dtype, name
        assert a.shape[1:] == k.arrays[name].shape[1:] or name == "reference_pixels", name
        assert name == "reference_pixels" or len(a) == n, name
    assert r.scenario.engine == "mujoco"
    assert np.isnan(r.twist[-1]).all() and np.isfinite(r.twist[:-1]).all()
    np.testing.assert_allclose(r.translation_error[-1], s["final_translation_error"])
    assert s["detection_error_max"] < 1.0  # MuJoCo's dots are tracked within a pixel of the truth


@needs_mujoco
def test_vsinv_run_writes_the_kinematic_files_from_mujoco(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`vsinv run file.toml --out` on a MuJoCo scenario: exit 0 (converged), trajectory.npz with
    the kinematic run's entries, the figures and the views (MuJoCo's renders) written."""
    d = _scenario()
    d["stop"]["max_iterations"] = 400
    path = tmp_path / "mj.toml"
    path.write_text(vsinv.sim.Scenario.from_dict(d).to_toml())
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--json", "--no-progress"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["status"] == "converged"
    kinematic = vsinv.load_scenario("lens-12-6").to_dict()
    kinematic["vision"] = {}
    kpath = tmp_path / "k.toml"
    kpath.write_text(vsinv.sim.Scenario.from_dict(kinematic).to_toml())
    main(["run", str(kpath), "--out", str(tmp_path / "k"), "--json", "--no-progress"])
    capsys.readouterr()
    with np.load(tmp_path / "out" / "trajectory.npz") as a, np.load(tmp_path / "k" / "trajectory.npz") as b:
        assert sorted(a.files) == sorted(b.files)
        assert list(json.loads(str(a["summary_json"]))) == list(json.loads(str(b["summary_json"])))
    written = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert written == sorted(p.name for p in (tmp_path / "k").iterdir()), written
    assert "camera.gif" in written and "view_last.png" in written


@needs_mujoco
def test_the_views_are_mujocos_renders(mujoco_run: vsinv.RunResult) -> None:
    """The figures' views of a MuJoCo run are MuJoCo's images: the dots found in the last view
    are where the run tracked them (within 0.5 px), and the view is not vsinv's own drawing."""
    from vsinv.view_plots import _Renderer

    r = mujoco_run
    with _Renderer(r.scenario) as view:
        image = view(pose=r.pose[-1], time=float(r.time[-1]))
    found = vsinv.vision.detect_dots(image).centroids
    gap = np.linalg.norm(found[:, None] - r.pixels[-1][None], axis=2).min(axis=0)
    assert gap.max() < 0.5, gap
    own = vsinv.vision.render(r.scenario.to_dict() | {"world": {"engine": "kinematic"}}, pose=r.pose[-1], time=float(r.time[-1]))
    assert np.abs(image.astype(float) - own.astype(float)).mean() > 1.0


# -- supersample ---------------------------------------------------------------------------------
@needs_mujoco
def test_supersample_past_the_render_bound_is_refused_by_its_key() -> None:
    """`world.supersample` beyond `MAX_SUPERSAMPLE`, or making the rendered side exceed
    `MAX_RENDER_SIDE`, is refused naming the key when the world is made; the argument
    `supersample=` overrides the key (and is then the name in the error)."""
    with pytest.raises(vsinv.InvalidInput, match=f"^world.supersample: .*1 to {vm.MAX_SUPERSAMPLE}, got 5"):
        vm.World.from_scenario(_scenario(supersample=vm.MAX_SUPERSAMPLE + 1))
    wide = _scenario(supersample=4)
    for lens in ("reference_camera", "camera"):
        wide[lens]["width"] = vm.MAX_RENDER_SIDE // 4 + 1
    with pytest.raises(vsinv.InvalidInput, match=f"^world.supersample: expected 1 to {vm.MAX_RENDER_SIDE} pixels"):
        vm.World.from_scenario(wide)
    with pytest.raises(vsinv.InvalidInput, match="^supersample: "):
        vm.World.from_scenario(_scenario(supersample=2), supersample=0)
    with vm.World.from_scenario(_scenario(supersample=2), supersample=1) as world:
        assert world.supersample == 1


@needs_mujoco
def test_every_layer_renders_with_the_scenario_supersample(tmp_path: Path) -> None:
    """The key is read wherever a MuJoCo scenario is rendered: the loop's frames are the world's
    k x k means (not its one-sample frames), `vsinv.mujoco.run`'s `supersample=` defaults to it,
    and the recording re-renders the loop's frames pixel for pixel."""
    from vsinv.mujoco._effects import camera_image
    from vsinv.recording import frames

    d = _scenario(supersample=2)
    run = vm.run_loop(d, max_iterations=2)
    n = len(run.result.time)
    with vm.World.from_scenario(d) as world:
        assert world.supersample == 2
        np.testing.assert_array_equal(run.last_image, camera_image(world, d, run.result.pose[-1], n))
    with vm.World.from_scenario(d, supersample=1) as plain:
        assert np.abs(run.last_image.astype(float) - camera_image(plain, d, run.result.pose[-1], n)).max() > 10
    np.testing.assert_array_equal(vm.run(d, max_iterations=2).pose, run.result.pose)
    np.testing.assert_array_equal(list(frames(run.result))[-1], run.last_image)


# -- latency (issue 31, item 2) -------------------------------------------------------------------
def _integrated(run: vsinv.RunResult, latency: int) -> np.ndarray:
    """The poses the recorded twists give when the twist of frame k moves the camera after
    frame k + latency."""
    dt = float(run.time[1] - run.time[0])
    poses = [run.pose[0]]
    for k in range(len(run.time) - 1):
        twist = run.twist[k - latency] if k >= latency else np.zeros(6)
        poses.append(poses[-1] @ vsinv.geometry.exp_twist(twist, dt))
    return np.array(poses)


@needs_mujoco
def test_latency_zero_is_the_run_without_the_key(mujoco_run: vsinv.RunResult) -> None:
    """latency_frames = 0 is today's loop exactly; its poses are the twists integrated at once."""
    zero = vsinv.run_scenario(_scenario(latency_frames=0))
    for name, a in mujoco_run.arrays.items():
        np.testing.assert_array_equal(zero.arrays[name], a, err_msg=name)
    np.testing.assert_allclose(mujoco_run.pose, _integrated(mujoco_run, 0), atol=1e-12)


@needs_mujoco
def test_a_two_frame_latency_still_converges() -> None:
    """latency_frames = 2 (80 ms at 25 Hz): the camera moves by the twist of two frames before
    (the poses are the recorded twists integrated with that delay) and lens-12-6 still ends
    `converged`."""
    r = vsinv.run_scenario(_scenario(latency_frames=2))
    s = r.summary
    print({k: s[k] for k in ("status", "iterations", "final_translation_error", "final_rotation_error", "message")})
    np.testing.assert_allclose(r.pose, _integrated(r, 2), atol=1e-9)
    np.testing.assert_array_equal(r.pose[0], r.pose[2])  # nothing applied before frame 2
    assert s["status"] == "converged", s["message"]


@needs_mujoco
def test_record_and_progress_as_for_a_kinematic_run() -> None:
    """`record=False` keeps the summary and no rows (as the simulator does), `progress(done,
    total)` follows the frames up to `[stop] max_iterations`, and a run stopped by its limit
    says `max_iterations` in the same schema."""
    d = _scenario()
    d["stop"]["max_iterations"] = 5
    calls: list[tuple[int, int]] = []
    r = vsinv.run_scenario(d, record=False, progress=lambda done, total: calls.append((done, total)))
    k = vsinv.run_scenario(vsinv.load_scenario("lens-12-6").to_dict() | {"vision": {}, "stop": d["stop"]}, record=False)
    assert r.summary["status"] == k.summary["status"] == "max_iterations"
    assert r.summary["iterations"] == 5 and list(r.summary) == list(k.summary)
    assert {n: a.shape for n, a in r.arrays.items() if n != "reference_pixels"} == {
        n: a.shape for n, a in k.arrays.items() if n != "reference_pixels"}
    assert calls == [(i, 5) for i in range(1, 7)]
    with pytest.raises(TypeError, match="progress"):
        vsinv.run_scenario(d, progress="abc")
