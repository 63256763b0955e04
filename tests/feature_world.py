"""A textured box nobody here drew, for the keypoint target (issue 32, item 2): MuJoCo renders a
box whose three visible faces carry photographs from ViSP's image data (read from Debian's
visp-images-data at run time, never copied into the repository: GPL), lit by MuJoCo's lights.
The reference camera and the servo camera have different lenses.

`available()` says why the scene cannot be rendered here (no mujoco, no EGL, no ViSP images,
no OpenCV to encode the textures) so that tests skip with the reason.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

import mujoco_world as mw

VISP = Path("/usr/share/visp-images-data/ViSP-images")
# The photographs on the +x, +y and +z faces: a painting, a group photograph, a real frame of
# ViSP's cube sequence (a desk seen from a camera).
TEXTURES = {
    "+x": "Klimt/Klimt.png",
    "+y": "Solvay/Solvay_conference_1927_Version2_640x440.png",
    "+z": "mbt/cube/image0000.pgm",
}


def available() -> str | None:
    """None when the textured box can be rendered here, else why not."""
    why = mw.available()
    if why is not None:
        return why
    missing = [p for p in TEXTURES.values() if not (VISP / p).is_file()]
    if missing:
        return f"ViSP's images are not installed ({missing[0]}): apt install visp-images-data"
    try:
        import cv2  # noqa: F401
    except ImportError:
        return "OpenCV is not installed (it encodes the textures): pip install opencv-python-headless"
    return None


class TexturedBox:
    """The box of half side mw.HALF with a photograph on each of three faces (a thin textured
    tile on the face), one MuJoCo model and renderer reused for every frame."""

    def __init__(self, width: int = 640, height: int = 480) -> None:
        import mujoco

        self.width, self.height = width, height
        xml, assets = self.mjcf()
        self.model = mujoco.MjModel.from_xml_string(xml, assets)
        self.data = mujoco.MjData(self.model)
        self.renderer = mujoco.Renderer(self.model, height, width)

    def close(self) -> None:
        self.renderer.close()

    def mjcf(self) -> tuple[str, dict[str, bytes]]:
        import cv2

        assets: dict[str, bytes] = {}
        asset_xml, geoms = [], []
        for k, face in enumerate(TEXTURES):
            ok, png = cv2.imencode(".png", photograph(face))
            if not ok:
                raise RuntimeError("cv2.imencode failed")
            assets[f"face{k}.png"] = png.tobytes()
            asset_xml.append(
                f'<texture name="tex{k}" type="2d" file="face{k}.png"/>'
                f'<material name="mat{k}" texture="tex{k}" rgba="1 1 1 1" specular="0.05"/>'
            )
            c, a, b, n = (np.asarray(v, float) for v in mw.FACES[face])
            q = c + 0.0005 * n
            half = 0.98 * mw.HALF
            geoms.append(
                f'<geom name="face{k}" type="box" size="{half} {half} 0.0005" pos="{mw._v(q)}" '
                f'xyaxes="{mw._v(a)} {mw._v(b)}" material="mat{k}" contype="0" conaffinity="0"/>'
            )
        xml = f"""<mujoco model="vsinv-textured-box">
  <visual><global offwidth="{self.width}" offheight="{self.height}"/>
    <headlight ambient="0.3 0.3 0.3" diffuse="0.3 0.3 0.3" specular="0.02 0.02 0.02"/></visual>
  <asset>{"".join(asset_xml)}</asset>
  <worldbody>
    <light name="sun" directional="true" pos="1 0.5 2" dir="-0.4 -0.3 -1" diffuse="0.5 0.5 0.5" specular="0.1 0.1 0.1" castshadow="false"/>
    <geom name="floor" type="plane" size="2 2 0.01" pos="0 0 -{mw.HALF}" rgba="0.45 0.42 0.38 1"/>
    <geom name="box" type="box" size="{mw.HALF} {mw.HALF} {mw.HALF}" rgba="0.5 0.5 0.5 1"/>
    {"".join(geoms)}
    <camera name="eye" pos="1 1 1" fovy="45"/>
  </worldbody>
</mujoco>"""
        return xml, assets

    def intrinsics(self, fovy_deg: float) -> tuple[float, float, float, float]:
        return mw.intrinsics(fovy_deg, self.width, self.height)

    def render(self, pose: np.ndarray, fovy_deg: float) -> np.ndarray:
        return mw.render_grey(self.model, self.data, self.renderer, pose, fovy_deg)

    def surface_point(self, pose: np.ndarray, fovy_deg: float, pixels: np.ndarray) -> np.ndarray:
        """The world points (n, 3) of the box seen at `pixels` (n, 2) from `pose` (the ray's first
        hit on the box's faces; NaN off the box): the truth a pixel is checked against."""
        fx, fy, cx, cy = self.intrinsics(fovy_deg)
        out = np.full((len(pixels), 3), np.nan)
        for i, (u, v) in enumerate(np.asarray(pixels, float)):
            ray = pose[:3, :3] @ np.array([(u - cx) / fx, (v - cy) / fy, 1.0])
            hit = _hit_box(pose[:3, 3], ray, mw.HALF + 0.001)  # the textured tiles stand 1 mm out
            if np.isnan(hit).any() and ray[2] < 0:  # the floor
                hit = pose[:3, 3] + ray * ((-mw.HALF - pose[2, 3]) / ray[2])
            out[i] = hit
        return out


class RenderedBox:
    """The same box drawn by the project's renderer (`tiles()` on the box's grey faces,
    `box_faces()`, the renderer's default blur and noise, a new noise draw each frame):
    TexturedBox's interface without MuJoCo or its light."""

    def __init__(self, width: int = 640, height: int = 480) -> None:
        self.width, self.height = width, height
        self.tiles = tiles() + box_faces()
        self.frame = 0

    def close(self) -> None:
        pass

    def intrinsics(self, fovy_deg: float) -> tuple[float, float, float, float]:
        return mw.intrinsics(fovy_deg, self.width, self.height)

    def render(self, pose: np.ndarray, fovy_deg: float) -> np.ndarray:
        import vsinv

        self.frame += 1
        k = vsinv.Intrinsics(*self.intrinsics(fovy_deg))
        return vsinv.vision.render_faces(self.tiles, pose, k, self.width, self.height, frame=self.frame)

    surface_point = TexturedBox.surface_point


def photograph(face: str) -> np.ndarray:
    """The colour (BGR) photograph on `face`: a square crop of the centre of ViSP's image."""
    import cv2

    image = cv2.imread(str(VISP / TEXTURES[face]), cv2.IMREAD_COLOR)
    side = min(image.shape[:2])
    top, left = (image.shape[0] - side) // 2, (image.shape[1] - side) // 2
    return image[top : top + side, left : left + side]


def tiles() -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """The photograph tiles as the project's renderer draws them (`vsinv.vision.render_faces`):
    per face the tile's outer square (1 mm out of the box, half side 0.98 HALF) counter-clockwise
    about the outward normal, and where MuJoCo puts the photograph on it (measured: column u
    along the face's axis a, row 0 at the +b edge)."""
    out = []
    for face in TEXTURES:
        c, a, b, n = (np.asarray(v, float) for v in mw.FACES[face])
        q, h = c + 0.001 * n, 0.98 * mw.HALF
        image = photograph(face)
        s = image.shape[0]
        vertices = np.array([q - h * a - h * b, q + h * a - h * b, q + h * a + h * b, q - h * a + h * b])
        coords = np.array([[-0.5, s - 0.5], [s - 0.5, s - 0.5], [s - 0.5, -0.5], [-0.5, -0.5]])
        out.append((vertices, coords, image))
    return out


def box_faces(grey: int = 128) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """The box's faces under the tiles (`render_faces`' form), plain `grey`, as MuJoCo's grey box
    shows around them: without them the background shows between two tiles, and the corners it
    makes with their edges are where the tiles' edges cross in the image, no point of the box
    (they move as the camera does)."""
    out = []
    for c, a, b, _ in mw.FACES.values():
        c, a, b, h = np.asarray(c, float), np.asarray(a, float), np.asarray(b, float), mw.HALF
        vertices = np.array([c - h * a - h * b, c + h * a - h * b, c + h * a + h * b, c - h * a + h * b])
        coords = np.array([[-0.5, 1.5], [1.5, 1.5], [1.5, -0.5], [-0.5, -0.5]])
        out.append((vertices, coords, np.full((2, 2), grey, np.uint8)))
    return out


def _hit_box(origin: np.ndarray, ray: np.ndarray, half: float) -> np.ndarray:
    """The first point of the axis-aligned cube of half side `half` on the ray (slab method)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (-half - origin) / ray
        t2 = (half - origin) / ray
    near = np.nanmax(np.minimum(t1, t2))
    far = np.nanmin(np.maximum(t1, t2))
    if near > far or far < 0:
        return np.full(3, np.nan)
    return origin + near * ray


def project(pose: np.ndarray, K: Any, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return mw.project(pose, K, points)
