"""Recordings (issue 31, item 5): `vsinv.recording.write_recording` and `vsinv run --record`.

The file is read back by a reader written here from the MCAP specification (records, chunks,
zstd/lz4), not by the writer's library, and by the `mcap` package's indexed reader (what
viewers use: the summary section and its statistics). Checked: the topics, message counts,
log times (the run's times), the images (decoded by OpenCV) against the frames the runs saw
(`vsinv.vision.render` of the kinematic run's pose and MuJoCo loop's last frame), the poses (the
quaternion turned back into a matrix) against the run's trajectory, the twists and the verdict.
"""

from __future__ import annotations

import base64
import json
import os
import struct

os.environ.setdefault("MUJOCO_GL", "egl")

from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import vsinv  # noqa: E402
import vsinv.vision  # noqa: E402

mcap = pytest.importorskip("mcap", reason="pip install 'vsinv[record]' (the mcap package)")
cv2 = pytest.importorskip("cv2")

from vsinv.recording import ARM_TOPICS, TOPICS, encode_png, write_recording  # noqa: E402

_MAGIC = b"\x89MCAP0\r\n"


def _string(b: bytes, at: int) -> tuple[str, int]:
    (n,) = struct.unpack_from("<I", b, at)
    return b[at + 4 : at + 4 + n].decode(), at + 4 + n


def _records(b: bytes, channels: dict[int, str], out: list[tuple[str, int, bytes]]) -> None:
    """Appends (topic, log_time, data) of every message of the records in `b` (the spec's
    opcodes: 0x04 channel, 0x05 message, 0x06 chunk; the others skipped; 0x0F data end stops)."""
    at = 0
    while at < len(b):
        op, length = struct.unpack_from("<BQ", b, at)
        body = b[at + 9 : at + 9 + length]
        at += 9 + length
        if op == 0x0F:
            return
        if op == 0x04:
            cid, _schema = struct.unpack_from("<HH", body, 0)
            channels[cid], _ = _string(body, 4)
        elif op == 0x05:
            cid, _seq, log_time, _pub = struct.unpack_from("<HIQQ", body, 0)
            out.append((channels[cid], log_time, body[22:]))
        elif op == 0x06:
            _start, _end, size, _crc = struct.unpack_from("<QQQI", body, 0)
            compression, p = _string(body, 28)
            (n,) = struct.unpack_from("<Q", body, p)
            data = body[p + 8 : p + 8 + n]
            if compression == "zstd":
                import zstandard

                data = zstandard.ZstdDecompressor().decompress(data, max_output_size=size)
            elif compression == "lz4":
                import lz4.frame

                data = lz4.frame.decompress(data)
            assert len(data) == size
            _records(data, channels, out)


def read_messages(path: Path) -> list[tuple[str, int, dict]]:
    b = path.read_bytes()
    assert b[:8] == _MAGIC and b[-8:] == _MAGIC
    raw: list[tuple[str, int, bytes]] = []
    _records(b[8:-8], {}, raw)
    return [(topic, t, json.loads(data)) for topic, t, data in raw]


def _rotation(q: dict) -> np.ndarray:
    x, y, z, w = q["x"], q["y"], q["z"], q["w"]
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def _png(message: dict) -> np.ndarray:
    assert message["format"] == "png"
    return cv2.imdecode(np.frombuffer(base64.b64decode(message["data"]), np.uint8), cv2.IMREAD_UNCHANGED)


def _check(path: Path, result: vsinv.RunResult, images: bool) -> list[tuple[str, int, dict]]:
    messages = read_messages(path)
    n = len(result.time)
    by_topic: dict[str, list[tuple[int, dict]]] = {}
    for topic, t, m in messages:
        by_topic.setdefault(topic, []).append((t, m))
    expected = {t: n for t in TOPICS + (ARM_TOPICS if result.joint_limits is not None else ())}
    expected["/summary"] = 1
    if not images:
        del expected["/camera/image"]
    assert {t: len(v) for t, v in by_topic.items()} == expected
    stamps = np.round(result.time * 1e9).astype(np.int64)
    for topic in expected:
        if topic != "/summary":
            assert [t for t, _ in by_topic[topic]] == list(stamps), topic
    for k, (_, tf) in enumerate(by_topic["/tf"]):
        camera = next(x for x in tf["transforms"] if x["child_frame_id"] == "camera")
        assert camera["parent_frame_id"] == "target"
        t = camera["translation"]
        np.testing.assert_allclose([t["x"], t["y"], t["z"]], result.pose[k][:3, 3], atol=1e-12)
        np.testing.assert_allclose(_rotation(camera["rotation"]), result.pose[k][:3, :3], atol=1e-9)
    steps = [m for _, m in by_topic["/servo"]]
    np.testing.assert_allclose([s["twist"] for s in steps[:-1]], result.twist[:-1], atol=0)
    np.testing.assert_allclose([s["image_error"] for s in steps], result.image_error)
    assert [s["verdict"] for s in steps] == ["running"] * (n - 1) + [result.summary["status"]]
    assert by_topic["/summary"][0][1]["iterations"] == result.summary["iterations"]
    found = [len(m["circles"]) for _, m in by_topic["/camera/detections"]]
    assert found == list(result.visible.sum(axis=1))
    # The library's indexed reader agrees on the count (its summary section and statistics).
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        reader = make_reader(f)
        assert reader.get_summary().statistics.message_count == len(messages)
        assert sum(1 for _ in reader.iter_messages()) == len(messages)
    return messages


def test_png_encoder_round_trips_through_opencv() -> None:
    image = np.random.default_rng(0).integers(0, 256, (7, 13), dtype=np.uint8)
    decoded = cv2.imdecode(np.frombuffer(encode_png(image), np.uint8), cv2.IMREAD_UNCHANGED)
    np.testing.assert_array_equal(decoded, image)


def test_a_kinematic_run_with_images(tmp_path: Path) -> None:
    d = vsinv.load_scenario("vision-12-6").to_dict()
    d["stop"]["max_iterations"] = 6
    result = vsinv.run_scenario(d)
    path = tmp_path / "run.mcap"
    count = write_recording(result, path)
    messages = _check(path, result, images=True)
    assert count == len(messages)
    images = [m for topic, _, m in messages if topic == "/camera/image"]
    k = 3
    np.testing.assert_array_equal(_png(images[k]), vsinv.vision.render(d, pose=result.pose[k], time=float(result.time[k])))


def test_a_kinematic_run_without_images_has_no_image_topic(tmp_path: Path) -> None:
    d = vsinv.load_scenario("lens-12-6").to_dict()
    d["stop"]["max_iterations"] = 5
    result = vsinv.run_scenario(d)
    path = tmp_path / "run.mcap"
    write_recording(result, path)
    _check(path, result, images=False)


def test_a_run_without_rows_is_refused(tmp_path: Path) -> None:
    result = vsinv.run_scenario("lens-12-6", record=False)
    with pytest.raises(vsinv.InvalidInput, match="record=True"):
        write_recording(result, tmp_path / "x.mcap")
    with pytest.raises(TypeError, match="result"):
        write_recording("lens-12-6", tmp_path / "x.mcap")  # type: ignore[arg-type]


def test_a_mujoco_run_records_the_frames_it_saw(tmp_path: Path) -> None:
    vm = pytest.importorskip("vsinv.mujoco")
    why = vm.available()
    if why is not None:
        pytest.skip(why)
    d = vsinv.load_scenario("mujoco-lens-12-6").to_dict()
    run = vm.run_loop(d, max_iterations=5)
    path = tmp_path / "run.mcap"
    write_recording(run.result, path)
    messages = _check(path, run.result, images=True)
    images = [m for topic, _, m in messages if topic == "/camera/image"]
    np.testing.assert_array_equal(_png(images[-1]), run.last_image)


def test_the_cli_writes_a_recording(tmp_path: Path) -> None:
    from vsinv.cli import main

    path = tmp_path / "run.mcap"
    code = main(["run", "lens-12-6", "--record", str(path), "--no-progress"])
    assert code in (0, 1)
    messages = read_messages(path)
    assert {t for t, _, _ in messages} == set(TOPICS) - {"/camera/image"}


@pytest.mark.parametrize("bad", [np.zeros((3, 4), np.float64), np.zeros((3, 4, 3), np.uint8), np.zeros((0, 4), np.uint8)])
def test_the_png_encoder_refuses_what_is_not_a_grey_image(bad: np.ndarray) -> None:
    with pytest.raises(vsinv.InvalidInput, match="image"):
        encode_png(bad)


def _pose(transform: dict) -> np.ndarray:
    t = transform["translation"]
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = _rotation(transform["rotation"]), [t["x"], t["y"], t["z"]]
    return out


def _arm_rows(messages: list[tuple[str, int, dict]], result: vsinv.RunResult) -> list[dict]:
    """Per row, the arm's frames after checking the joint states against the run's joints and
    joint velocities: `base` in its parent, `links` (each frame of base -> arm/<link> -> ... ->
    flange composed into the base frame), `flange` (the last), `chain` (their names in order)."""
    states = [m for topic, _, m in messages if topic == "/arm/joint_states"]
    names = list(result.joint_limits["names"])
    for k, m in enumerate(states):
        assert m["name"] == names
        np.testing.assert_array_equal(m["position"], result.joints[k])
        if k + 1 < len(states):
            np.testing.assert_array_equal(m["velocity"], result.joint_velocities[k])
        else:
            assert m["velocity"] == []  # no command followed the last image
    rows = []
    for _, _, tf in (x for x in messages if x[0] == "/tf"):
        by_child = {x["child_frame_id"]: x for x in tf["transforms"]}
        links, frame = {}, "flange"  # walk flange -> ... -> base, composing each link in the one before
        chain = []
        while frame != "base":
            chain.append(frame)
            frame = by_child[frame]["parent_frame_id"]
        pose = np.eye(4)
        for child in reversed(chain):  # base -> arm/<link> -> ... -> flange
            pose = pose @ _pose(by_child[child])
            links[child] = pose
        rows.append({"parent": by_child["base"]["parent_frame_id"], "base": _pose(by_child["base"]),
                     "flange": links["flange"], "links": links, "chain": list(reversed(chain))})
    return rows


def test_an_arm_runs_frames_and_joint_states(tmp_path: Path) -> None:
    d = vsinv.load_scenario("arm-ur5-12-6").to_dict()
    d["stop"]["max_iterations"] = 6
    result = vsinv.run_scenario(d)
    arm = result.scenario.arm()
    path = tmp_path / "run.mcap"
    write_recording(result, path)
    messages = _check(path, result, images=False)
    rows = _arm_rows(messages, result)
    assert len(rows) == len(result.time)
    for k, row in enumerate(rows):
        assert row["parent"] == "target"
        np.testing.assert_allclose(row["base"], arm.base, atol=1e-12)
        # the flange against the built-in kinematics (tool0 in the base link), and the chain
        # target -> base -> flange -> camera_mount against the run's camera pose
        np.testing.assert_allclose(row["flange"], vsinv.kinematics.fk("ur5", result.joints[k]), atol=1e-9)
        np.testing.assert_allclose(row["base"] @ row["flange"] @ arm.mount, result.pose[k], atol=1e-9)
        # every link of the chain, in order, against the built-in's kinematics of that link
        names = [n for n, _ in arm.link_poses(result.joints[k])][1:-1]
        assert row["chain"] == [f"arm/{n}" for n in names] + ["flange"]
        assert names[0] == "shoulder_link" and names[-1] == "wrist_3_link"


@pytest.mark.slow
@pytest.mark.parametrize("name", ["mujoco-arm-ur5e-12-6", "mujoco-eye-to-hand-12-6"])
def test_a_mujoco_arm_runs_frames_against_mujocos_poses(tmp_path: Path, name: str) -> None:
    vm = pytest.importorskip("vsinv.mujoco")
    why = vm.available()
    if why is not None:
        pytest.skip(why)
    import mujoco

    from vsinv.mujoco._arms import LINKS

    run = vm.run_loop(name, max_iterations=4)
    result = run.result
    arm = result.scenario.arm()
    path = tmp_path / "run.mcap"
    write_recording(result, path)
    messages = _check(path, result, images=True)
    images = [m for topic, _, m in messages if topic == "/camera/image"]
    np.testing.assert_array_equal(_png(images[-1]), run.last_image)  # the arm at the last row's joints
    eye_to_hand = name == "mujoco-eye-to-hand-12-6"
    world = vm.World.from_scenario(result.scenario)
    for k, row in enumerate(_arm_rows(messages, result)):
        assert row["parent"] == ("camera" if eye_to_hand else "target")
        np.testing.assert_allclose(row["flange"], vsinv.kinematics.fk("ur5e", result.joints[k]), atol=1e-9)
        chain = row["base"] @ row["flange"] @ arm.mount  # the camera (eye-in-hand) or F* (eye-to-hand)
        # result.pose is MuJoCo's camera (eye-in-hand: its body chain; eye-to-hand: the inverse of
        # the target's site seen from the fixed camera)
        expected = np.linalg.inv(result.pose[k]) if eye_to_hand else result.pose[k]
        np.testing.assert_allclose(chain, expected, atol=1e-6)
        # each link against MuJoCo's body of that name (xpos, xquat in MuJoCo's world: F*, or
        # the fixed camera's frame eye-to-hand, the frame `base` hangs from)
        world.data.qpos[:] = result.joints[k]
        mujoco.mj_kinematics(world.model, world.data)
        assert [b.removeprefix("arm/") for b in row["chain"][:-1]] == list(LINKS)
        for frame in row["chain"][:-1]:
            body, pose, rotation = world.data.body(frame.removeprefix("arm/")), np.eye(4), np.zeros(9)
            mujoco.mju_quat2Mat(rotation, body.xquat)
            pose[:3, :3], pose[:3, 3] = rotation.reshape(3, 3), body.xpos
            np.testing.assert_allclose(row["base"] @ row["links"][frame], pose, atol=1e-6)
    world.close()
