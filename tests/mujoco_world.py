"""A world vsinv did not draw: MuJoCo renders a box carrying white dots or AprilTags on three
faces, lit by MuJoCo's lights, seen by a free kinematic camera whose pose vsinv's twists move.

Shared by tests/test_mujoco_world.py and benches/lens_change_accuracy.py (the seed of issue 31's
`vsinv.mujoco`: the scene builder, the camera convention and the loop are separate pieces).

Conventions. A pose is a 4x4 world-from-camera transform in vsinv's camera frame (x right, y
down, z forward). MuJoCo's camera looks down its -z axis with y up and x right, so its frame is
vsinv's turned by pi about x: R_mujoco = R_vsinv diag(1, -1, -1). MuJoCo's `fovy` is the vertical
field of view, square pixels, the principal point at the image centre: f = (H / 2) / tan(fovy / 2),
(cx, cy) = ((W - 1) / 2, (H - 1) / 2) in the convention where pixel (0, 0) is the centre of the
first pixel (OpenCV's and vsinv's).

Importing this module sets MUJOCO_GL=egl (unless set) before importing mujoco; `available()` says
why rendering cannot run (no mujoco, no EGL) so the tests can skip with that reason.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

os.environ.setdefault("MUJOCO_GL", "egl")

try:  # an optional test dependency (pyproject's `test` extra)
    import mujoco
except ImportError as e:  # pragma: no cover - depends on the machine
    mujoco = None
    _IMPORT_ERROR: str | None = f"mujoco is not installed ({e}): pip install mujoco"
else:
    _IMPORT_ERROR = None

# The box: a cube of half side HALF at the origin, targets on its +x, +y and +z faces.
HALF = 0.1
FACES = {  # face name: (centre, in-face axis a, in-face axis b, outward normal)
    "+x": ((HALF, 0, 0), (0, 1, 0), (0, 0, 1), (1, 0, 0)),
    "+y": ((0, HALF, 0), (-1, 0, 0), (0, 0, 1), (0, 1, 0)),
    "+z": ((0, 0, HALF), (1, 0, 0), (0, 1, 0), (0, 0, 1)),
}
DOT_OFFSETS = [(-0.05, -0.05), (0.05, -0.05), (0.05, 0.05), (-0.05, 0.05)]
DOT_RADIUS = 0.012
TAG_SIDE = 0.15  # the black square, metres: the tile with its quiet zone nearly fills the 0.2 m face
TAG_IDS = {"+x": 3, "+y": 7, "+z": 12}  # tag36h11 identities


def available() -> str | None:
    """None when MuJoCo can render offscreen here, else why not (for pytest.skip): the package's
    own check (`vsinv.mujoco.available`)."""
    if _IMPORT_ERROR is not None:
        return _IMPORT_ERROR
    from vsinv.mujoco import available as package_available

    return package_available()


def look_at(eye: Any, target: Any, up: Any = (0.0, 0.0, 1.0)) -> np.ndarray:
    """The world-from-camera pose (vsinv's frame: z forward, y down) of a camera at `eye` looking at `target`."""
    eye, target, up = (np.asarray(v, float) for v in (eye, target, up))
    z = target - eye
    z /= np.linalg.norm(z)
    x = np.cross(z, up)  # right = forward x up when y is down
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    pose = np.eye(4)
    pose[:3, :3] = np.column_stack([x, y, z])
    pose[:3, 3] = eye
    return pose


def mujoco_camera(pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo's cam_pos and cam_quat (w, x, y, z) for a vsinv world-from-camera pose."""
    rotation = pose[:3, :3] @ np.diag([1.0, -1.0, -1.0])
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(rotation).reshape(9))
    return pose[:3, 3].copy(), quat


def intrinsics(fovy_deg: float, width: int, height: int) -> tuple[float, float, float, float]:
    """(fx, fy, cx, cy) of MuJoCo's camera with vertical field of view `fovy_deg`."""
    f = 0.5 * height / np.tan(np.radians(fovy_deg) / 2.0)
    return f, f, (width - 1) / 2.0, (height - 1) / 2.0


def project(pose: np.ndarray, K: tuple[float, float, float, float], points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pixels (n, 2) and depths (n,) of world points (n, 3) seen from `pose` (pinhole, no distortion)."""
    cam = (points - pose[:3, 3]) @ pose[:3, :3]
    fx, fy, cx, cy = K
    z = cam[:, 2]
    return np.column_stack([fx * cam[:, 0] / z + cx, fy * cam[:, 1] / z + cy]), z


def _frame(face: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    c, a, b, n = (np.asarray(v, float) for v in FACES[face])
    return c, a, b, n


def tag_image(tag_id: int, cell: int = 16) -> np.ndarray:
    """OpenCV's drawing of tag36h11 `tag_id` (8 x 8 cells, the black border included) with one
    white cell of quiet zone around it, as an RGB texture."""
    import cv2

    dictionary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11)
    marker = cv2.aruco.generateImageMarker(dictionary, tag_id, 8 * cell, borderBits=1)
    padded = cv2.copyMakeBorder(marker, cell, cell, cell, cell, cv2.BORDER_CONSTANT, value=255)
    return np.repeat(padded[:, :, None], 3, axis=2)


@dataclass
class BoxWorld:
    """The box with `target` ("dots" or "tags") on three faces, one MuJoCo model and one renderer
    reused for every frame; the camera's pose and field of view are set per frame."""

    target: str
    width: int = 400
    height: int = 300
    sphere_faces: tuple[str, ...] = ("+z",)  # dots on these faces are spheres, the others flat discs
    # A sensor's pixel integrates the light over its area; MuJoCo samples each pixel at 4 points
    # (llvmpipe's most), which quantizes a small dot's edge coverage in quarters and moves its
    # centroid by a few hundredths of a pixel, differently at each lens. The frame is rendered
    # `supersample` times larger and averaged over blocks, as a sensor would.
    supersample: int = 1
    model: Any = field(init=False)
    data: Any = field(init=False)
    renderer: Any = field(init=False)

    def __post_init__(self) -> None:
        if self.target not in ("dots", "tags"):
            raise ValueError(f"target: expected 'dots' or 'tags', got {self.target!r}")
        xml, assets = self.mjcf()
        self.model = mujoco.MjModel.from_xml_string(xml, assets)
        self.data = mujoco.MjData(self.model)
        if not 1 <= self.supersample <= 4:
            raise ValueError(f"supersample: expected 1 to 4, got {self.supersample!r}")
        self.renderer = mujoco.Renderer(self.model, self.height * self.supersample, self.width * self.supersample)

    def close(self) -> None:
        self.renderer.close()

    # -- the scene ---------------------------------------------------------------------------
    def mjcf(self) -> tuple[str, dict[str, bytes]]:
        """The MJCF text and its in-memory assets (the tag textures as PNG)."""
        box_rgba = "0.22 0.24 0.28 1" if self.target == "dots" else "0.93 0.93 0.9 1"
        assets: dict[str, bytes] = {}
        asset_xml, geoms = [], []
        for face in FACES:
            if self.target == "dots":
                geoms += self._dot_geoms(face)
            else:
                name, xml = self._tag_geom(face, assets)
                asset_xml.append(xml)
                geoms.append(name)
        return (
            f"""<mujoco model="vsinv-box-{self.target}">
  <visual><global offwidth="{self.width * self.supersample}" offheight="{self.height * self.supersample}"/>
    <headlight ambient="0.25 0.25 0.25" diffuse="0.3 0.3 0.3" specular="0.05 0.05 0.05"/></visual>
  <asset>{"".join(asset_xml)}</asset>
  <worldbody>
    <light name="sun" directional="true" pos="1 0.5 2" dir="-0.4 -0.3 -1" diffuse="0.6 0.6 0.6" specular="0.3 0.3 0.3" castshadow="false"/>
    <light name="lamp" pos="0.8 0.9 0.9" dir="-0.6 -0.7 -0.5" diffuse="0.3 0.3 0.3" specular="0.2 0.2 0.2" castshadow="false"/>
    <geom name="floor" type="plane" size="2 2 0.01" pos="0 0 -{HALF}" rgba="0.45 0.42 0.38 1"/>
    <geom name="box" type="box" size="{HALF} {HALF} {HALF}" rgba="{box_rgba}"/>
    {"".join(geoms)}
    <camera name="eye" pos="1 1 1" fovy="45"/>
  </worldbody>
</mujoco>""",
            assets,
        )

    def _dot_geoms(self, face: str) -> list[str]:
        c, a, b, n = _frame(face)
        out = []
        for k, (da, db) in enumerate(DOT_OFFSETS):
            p = c + da * a + db * b
            if face in self.sphere_faces:  # a white sphere resting on the face, shaded by the lights
                q = p + (DOT_RADIUS * 0.6) * n
                out.append(
                    f'<geom name="dot{face}{k}" type="sphere" size="{DOT_RADIUS * 0.8}" pos="{_v(q)}" '
                    'rgba="1 1 1 1" contype="0" conaffinity="0"/>'
                )
            else:  # a flat white disc, 0.4 mm thick on the face
                q = p + 0.0002 * n
                out.append(
                    f'<geom name="dot{face}{k}" type="cylinder" size="{DOT_RADIUS} 0.0002" pos="{_v(q)}" '
                    f'zaxis="{_v(n)}" rgba="1 1 1 1" contype="0" conaffinity="0"/>'
                )
        return out

    def _tag_geom(self, face: str, assets: dict[str, bytes]) -> tuple[str, str]:
        import cv2

        c, a, b, n = _frame(face)
        tag_id = TAG_IDS[face]
        ok, png = cv2.imencode(".png", tag_image(tag_id)[:, :, ::-1])
        if not ok:
            raise RuntimeError("cv2.imencode failed")
        assets[f"tag{tag_id}.png"] = png.tobytes()
        asset = (
            f'<texture name="tex{tag_id}" type="2d" file="tag{tag_id}.png"/>'
            f'<material name="mat{tag_id}" texture="tex{tag_id}" rgba="1 1 1 1" specular="0.1"/>'
        )
        half = TAG_SIDE * 10 / 8 / 2  # the tile carries the quiet zone: 10 cells for 8
        q = c + 0.0005 * n
        geom = (
            f'<geom name="tag{tag_id}" type="box" size="{half} {half} 0.0005" pos="{_v(q)}" '
            f'xyaxes="{_v(a)} {_v(b)}" material="mat{tag_id}" contype="0" conaffinity="0"/>'
        )
        return geom, asset

    # -- ground truth -----------------------------------------------------------------------
    def dot_centres(self) -> np.ndarray:
        """World centres (12, 3) of the dots, face by face (+x, +y, +z), in DOT_OFFSETS order."""
        pts = []
        for face in FACES:
            c, a, b, n = _frame(face)
            for da, db in DOT_OFFSETS:
                lift = DOT_RADIUS * 0.6 if face in self.sphere_faces else 0.0004
                pts.append(c + da * a + db * b + lift * n)
        return np.array(pts)

    def tag_corners(self) -> dict[int, np.ndarray]:
        """Per tag id, the world corners (4, 3) of its black square (in no particular order)."""
        out = {}
        for face in FACES:
            c, a, b, n = _frame(face)
            h = TAG_SIDE / 2
            out[TAG_IDS[face]] = np.array([c + sa * h * a + sb * h * b + 0.001 * n for sa, sb in ((-1, -1), (1, -1), (1, 1), (-1, 1))])
        return out

    def intrinsics(self, fovy_deg: float) -> tuple[float, float, float, float]:
        return intrinsics(fovy_deg, self.width, self.height)

    # -- rendering ---------------------------------------------------------------------------
    def render(self, pose: np.ndarray, fovy_deg: float) -> np.ndarray:
        """The (height, width) uint8 grey image seen from `pose` with vertical field of view
        `fovy_deg` (each pixel the mean of its `supersample` x `supersample` rendered block)."""
        k = self.supersample
        if k == 1:
            return render_grey(self.model, self.data, self.renderer, pose, fovy_deg)
        fine = render_grey(self.model, self.data, self.renderer, pose, fovy_deg, rounded=False)
        block = fine.reshape(self.height, k, self.width, k).mean(axis=(1, 3))
        return np.clip(np.rint(block), 0, 255).astype(np.uint8)


def render_grey(
    model: Any, data: Any, renderer: Any, pose: np.ndarray, fovy_deg: float, camera: str = "eye", rounded: bool = True
) -> np.ndarray:
    """Puts the model's camera `camera` (a child of the world body) at the vsinv pose `pose` with
    vertical field of view `fovy_deg` and renders it as (height, width) uint8 grey (Rec. 601 luma)."""
    cam = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera)
    pos, quat = mujoco_camera(pose)
    model.cam_pos[cam] = pos
    model.cam_quat[cam] = quat
    model.cam_fovy[cam] = fovy_deg
    mujoco.mj_kinematics(model, data)
    mujoco.mj_camlight(model, data)
    renderer.update_scene(data, camera=camera)
    rgb = renderer.render().astype(np.float64)
    grey = rgb[:, :, 0] * 0.299 + rgb[:, :, 1] * 0.587 + rgb[:, :, 2] * 0.114
    return np.clip(np.rint(grey), 0, 255).astype(np.uint8) if rounded else grey


def _v(x: Any) -> str:
    return " ".join(f"{float(t):.6g}" for t in x)


def pose_error(pose: np.ndarray, goal: np.ndarray) -> tuple[float, float]:
    """Translation (mm) and rotation (degrees) of `pose` against `goal`."""
    delta = np.linalg.inv(goal) @ pose
    angle = np.arccos(np.clip((np.trace(delta[:3, :3]) - 1.0) / 2.0, -1.0, 1.0))
    return 1e3 * float(np.linalg.norm(delta[:3, 3])), float(np.degrees(angle))


# -- dots under real light (issue 27, item 4) ------------------------------------------------
# White spheres (centre, radius) and tilted white discs (centre, radius, normal) over a grey
# floor, lit by one directional light and a dim ambient, seen from LIT_EYE.
LIT_SPHERES = [
    ((-0.12, -0.07, 0.0), 0.018),
    ((0.0, -0.08, 0.01), 0.02),
    ((0.12, -0.07, 0.0), 0.022),
    ((-0.12, 0.07, 0.02), 0.02),
    ((0.01, 0.06, -0.01), 0.016),
    ((0.13, 0.08, 0.0), 0.02),
]
LIT_DISCS = [((-0.06, 0.0, -0.02), 0.015, (0.3, 0.2, 1.0)), ((0.07, 0.0, -0.02), 0.015, (-0.4, 0.1, 1.0))]
LIT_EYE = ((0.05, -0.25, 0.45), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0))  # eye, target, up


def lit_dots(width: int, height: int, light: tuple[float, float, float], specular: float, shininess: float) -> tuple[Any, Any, Any]:
    """The MuJoCo model, data and renderer of the lit dots: `light` is the directional light's
    direction, `specular` and `shininess` the white material's (a highlight when specular > 0)."""
    geoms = "".join(f'<geom type="sphere" size="{r}" pos="{_v(c)}" material="white"/>' for c, r in LIT_SPHERES)
    geoms += "".join(
        f'<geom type="cylinder" size="{r} 0.0005" pos="{_v(c)}" zaxis="{_v(n)}" material="white"/>' for c, r, n in LIT_DISCS
    )
    xml = f"""<mujoco><visual><global offwidth="{width}" offheight="{height}"/>
      <headlight ambient="0.15 0.15 0.15" diffuse="0 0 0" specular="0 0 0"/></visual>
      <asset><material name="white" rgba="1 1 1 1" specular="{specular}" shininess="{shininess}"/></asset>
      <worldbody>
        <light directional="true" dir="{_v(light)}" diffuse="0.8 0.8 0.8" specular="0.9 0.9 0.9" castshadow="false"/>
        <geom type="plane" size="1 1 0.01" pos="0 0 -0.05" rgba="0.25 0.25 0.27 1"/>{geoms}
        <camera name="eye" pos="1 1 1"/>
      </worldbody></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    return model, mujoco.MjData(model), mujoco.Renderer(model, height, width)
