"""The MJCF of a scenario's target: dots as white discs facing F*, tags as textured tiles (their
bit patterns drawn by vsinv's own renderer), two lights, and a free camera named `vsinv_camera`."""

from __future__ import annotations

import zlib
import struct
from typing import Any

import numpy as np

from .. import geometry, vision
from . import _mounted
from ._camera import PIXEL

CAMERA = "vsinv_camera"
PHYSICS_DT = 0.002  # s: 500 Hz physics under an arm
THIN = 0.0005


def backing(points: np.ndarray) -> str:
    """Eye-to-hand: a black plate facing F* 40 mm behind the target's farthest point, 100 mm
    wider than the target on each side, hiding the arm that carries it (F* coordinates)."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre = np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, hi[2] + 0.04])
    half = (hi[:2] - lo[:2]) / 2 + 0.1
    return (f'<geom name="backing" type="box" size="{half[0]} {half[1]} 0.004" pos="{_v(centre)}" rgba="0 0 0 1" '
            'contype="0" conaffinity="0"/>')  # half thickness of a tag tile and of a dot's disc, metres


def _v(x: Any) -> str:
    return " ".join(f"{float(t):.9g}" for t in np.ravel(x))


def _pose(entry: dict[str, Any]) -> np.ndarray:
    return geometry.pose_from_position_thetau(entry.get("position", [0.0, 0.0, 0.0]), np.radians(entry.get("rotation_deg", [0.0, 0.0, 0.0])))


def tag_poses(obj: dict[str, Any]) -> list[tuple[int, float, np.ndarray]]:
    """(id, size of the black square, pose in F*) of each tag of a scenario's `[object]`."""
    rig = _pose(obj["rig"]) if obj.get("rig") else np.eye(4)
    return [(int(t["id"]), float(t["size"]), rig @ _pose(t)) for t in obj["tags"]]


def tag_corners(obj: dict[str, Any]) -> dict[int, np.ndarray]:
    """Per tag id, the corners (4, 3) in F* of its black square (in no particular order)."""
    out = {}
    for tag_id, size, pose in tag_poses(obj):
        h = size / 2.0
        local = np.array([[sx * h, sy * h, 0.0, 1.0] for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))])
        out[tag_id] = (local @ pose.T)[:, :3]
    return out


def tag_texture(scenario: dict[str, Any], tag_id: int, pixels_per_cell: int = 12) -> tuple[np.ndarray, float]:
    """The tile of tag `tag_id` (its black square and white margin) as vsinv's renderer draws it,
    seen from the front (grey, uint8; MuJoCo maps it un-flipped on a box face whose xyaxes are the tag's x and y), and the tile's side
    in units of the black square's side."""
    size = 1.0
    f = 1000.0
    side = 2 * int(1.6 * f * size / 2)
    d: dict[str, Any] = {
        "name": "tag-texture",
        "description": "one tag seen square on",
        "start": {"position": [0.0, 0.0, 0.0], "rotation_deg": [0.0, 0.0, 0.0]},
        "object": {"tags": [  # a scenario needs 6 points: a second tag, out of view
            {"id": tag_id, "size": size, "position": [0.0, 0.0, 1.0], "rotation_deg": [180.0, 0.0, 0.0]},
            {"id": 1 if tag_id == 0 else 0, "size": size, "position": [50.0, 0.0, 1.0], "rotation_deg": [180.0, 0.0, 0.0]},
        ]},
        "camera": {"fku": f, "fkv": f, "u0": (side - 1) / 2.0, "v0": (side - 1) / 2.0, "width": side, "height": side},
        "vision": {"blur_sigma": 0.0, "noise_sigma": 0.0, "background": 0, "foreground": 255},
    }
    if "family" in scenario.get("object", {}):
        d["object"]["family"] = scenario["object"]["family"]
    for key in ("reference_camera", "estimate"):
        d[key] = dict(d["camera"])
    image = vision.render(d, np.eye(4))
    rows, cols = np.nonzero(image > 127)
    tile = image[rows.min() : rows.max() + 1, cols.min() : cols.max() + 1]
    return tile, tile.shape[1] / (f * size)


def _png(grey: np.ndarray) -> bytes:
    """A grey uint8 image as PNG bytes (MuJoCo reads textures from PNG assets)."""
    h, w = grey.shape
    raw = b"".join(b"\x00" + bytes(np.ascontiguousarray(row)) for row in grey.astype(np.uint8))

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")


def scene(scenario: dict[str, Any], width: int, height: int, arm: Any = None) -> tuple[str, dict[str, bytes], str, np.ndarray]:
    """The MJCF text, its assets, the target kind ("dots" or "tags") and the target's points in
    F* ((n, 3): the dots' centres, or the tags' corners tag by tag in `[object]` order). With
    `arm` (a `ScenarioArm`), the arm with mass carrying a second camera (`_mounted`), gravity
    along its base's -z, 500 Hz physics; with `[world] eye_to_hand`, the arm carries the target
    (its geoms in F*, `BACKING` behind them) and the free camera stays at the world's origin."""
    arm_body, actuators, option = "", "", ""
    eye_to_hand = scenario.get("world", {}).get("eye_to_hand") is not None
    obj = scenario["object"]
    assets: dict[str, bytes] = {}
    asset_xml: list[str] = []
    geoms: list[str] = []
    if obj.get("tags"):
        kind = "tags"
        for tag_id, size, pose in tag_poses(obj):
            tile, ratio = tag_texture(scenario, tag_id)
            name = f"tag{tag_id}"
            assets[f"{name}.png"] = _png(np.ascontiguousarray(tile))
            asset_xml.append(
                f'<texture name="{name}" type="2d" file="{name}.png"/>'
                f'<material name="{name}" texture="{name}" rgba="1 1 1 1" specular="0.1"/>'
            )
            half = size * ratio / 2.0
            centre = pose[:3, 3] - THIN * pose[:3, 2]  # the tile's top face on the tag's plane
            geoms.append(
                f'<geom name="{name}" type="box" size="{half} {half} {THIN}" pos="{_v(centre)}" '
                f'xyaxes="{_v(pose[:3, 0])} {_v(pose[:3, 1])}" material="{name}" contype="0" conaffinity="0"/>'
            )
        points = np.concatenate(list(tag_corners(obj).values()))
    else:
        kind = "dots"
        points = np.asarray(obj["points"], dtype=float)
        radius = float(scenario.get("vision", {}).get("dot_radius", 0.004))
        for k, p in enumerate(points):
            normal = -p / np.linalg.norm(p)  # the disc faces F*'s origin (the reference camera)
            geoms.append(
                f'<geom name="dot{k}" type="cylinder" size="{radius} {THIN}" pos="{_v(p)}" zaxis="{_v(normal)}" '
                'rgba="1 1 1 1" contype="0" conaffinity="0"/>'
            )
    if arm is not None:
        payload = ""
        if eye_to_hand:  # the target rides the arm, a dark plate behind it hiding the arm
            payload = "".join(geoms) + backing(points)
            geoms = []
        arm_body, actuators, gravity = _mounted.arm_xml(arm, width, height, height, payload)
        option = f'<option timestep="{PHYSICS_DT}" gravity="{_v(gravity)}" integrator="implicitfast"/>'
        actuators = f"<actuator>{actuators}</actuator>"
    xml = f"""<mujoco model="vsinv-{scenario.get("name", "scenario")}">
  <compiler angle="radian" autolimits="true"/>{option}
  <visual><global offwidth="{width}" offheight="{height}"/>
    <headlight ambient="0.45 0.45 0.45" diffuse="0.35 0.35 0.35" specular="0.05 0.05 0.05"/></visual>
  <asset>{"".join(asset_xml)}</asset>
  <worldbody>
    <light name="key" directional="true" pos="0 -1 -1" dir="0.2 0.3 1" diffuse="0.3 0.3 0.3" specular="0.1 0.1 0.1" castshadow="false"/>
    {"".join(geoms)}
    <camera name="{CAMERA}" pos="0 0 0" resolution="{width} {height}" sensorsize="{width * PIXEL} {height * PIXEL}" focalpixel="{height} {height}"/>
    {arm_body}
  </worldbody>{actuators}
</mujoco>"""
    return xml, assets, kind, points
