"""`World`: a MuJoCo model, its data and renderers, and the camera vsinv servoes."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from .. import geometry
from .._core import Intrinsics, InvalidInput, load_scenario
from . import _camera, _mounted, _scene, _urdf, _user_arm

os.environ.setdefault("MUJOCO_GL", "egl")  # CPU rendering through EGL unless the user chose


#: The largest MJCF file `World.from_mjcf` reads (bytes), and the largest side of a rendered
#: image (pixels, after supersampling): bounds on what a call may allocate.
MAX_MJCF_BYTES = 16 << 20
MAX_RENDER_SIDE = 8192


#: The largest supersampling factor (`[world] supersample`, `supersample=`): k x k samples a pixel.
MAX_SUPERSAMPLE = 4


def _check_size(width: Any, height: Any, supersample: Any, key: str | None = None) -> None:
    """The rendered image's size: whole numbers, at most `MAX_RENDER_SIDE` a side once
    supersampled. The error names the arguments, or `key` (a scenario key: `world.supersample`)."""
    whole = isinstance(supersample, (int, np.integer)) and not isinstance(supersample, bool)
    if not whole or not 1 <= supersample <= MAX_SUPERSAMPLE:
        raise InvalidInput(f"{key or 'supersample'}: expected a whole number from 1 to {MAX_SUPERSAMPLE}, "
                           f"got {supersample!r}")
    if not all(isinstance(n, (int, np.integer)) and not isinstance(n, bool) for n in (width, height)):
        raise InvalidInput(f"width, height: expected whole numbers, got {width!r} x {height!r}")
    if not (1 <= width * int(supersample) <= MAX_RENDER_SIDE and 1 <= height * int(supersample) <= MAX_RENDER_SIDE):
        raise InvalidInput(
            f"{key or 'width, height'}: expected 1 to {MAX_RENDER_SIDE} pixels a side once supersampled, "
            f"got {width} x {height} (supersample {supersample})"
        )


def scenario_supersample(d: dict[str, Any]) -> Any:
    """The scenario dict's `[world] supersample` (1 when absent): how many samples a side each
    pixel of its MuJoCo images integrates."""
    return (d.get("world") or {}).get("supersample", 1)


def _mujoco() -> Any:
    try:
        import mujoco
    except ImportError as e:  # pragma: no cover - depends on the machine
        raise ImportError(f"vsinv.mujoco needs MuJoCo ({e}): pip install 'vsinv[mujoco]'") from e
    return mujoco


def available() -> str | None:
    """None when MuJoCo can render offscreen here, else why not (what to install)."""
    try:
        mujoco = _mujoco()
    except ImportError as e:
        return str(e)
    try:
        model = mujoco.MjModel.from_xml_string("<mujoco><worldbody><geom size='.1'/></worldbody></mujoco>")
        with mujoco.Renderer(model, 8, 8) as r:
            r.update_scene(mujoco.MjData(model))
            r.render()
    except Exception as e:  # noqa: BLE001 - any failure to open a GL context means "cannot render"
        return (
            f"MuJoCo cannot render offscreen with MUJOCO_GL={os.environ.get('MUJOCO_GL')} ({type(e).__name__}: {e}); "
            "on Debian/Ubuntu: apt-get install libegl1 libopengl0 libegl-mesa0 libgl1-mesa-dri"
        )
    return None


def _compile_step(step: Any, path: Path) -> Any:
    """`step()` (reading or compiling a user's MJCF), MuJoCo's errors as InvalidInput naming
    `path` (MuJoCo's own message, which may quote the file, stays in the exception's cause)."""
    try:
        return step()
    except (ValueError, TypeError) as e:
        raise InvalidInput(f"path: MuJoCo could not load {str(path)!r} as MJCF ({type(e).__name__})") from e


def _k_of(d: dict[str, Any], key: str) -> tuple[tuple[float, float, float, float], int, int]:
    c = d[key]
    if abs(float(c.get("skew_deg", 90.0)) - 90.0) > 1e-9:
        raise InvalidInput(f"scenario [{key}]: MuJoCo's cameras have no skew (skew_deg = 90), got {c['skew_deg']}")
    return (float(c["fku"]), float(c["fkv"]), float(c["u0"]), float(c["v0"])), int(c["width"]), int(c["height"])


class World:
    """A MuJoCo scene seen by one camera, in vsinv's conventions.

    Poses are 4x4 world-from-camera transforms with vsinv's camera frame (x right, y down, z
    forward); MuJoCo's camera frame (y up, looking down -z) is turned by pi about x from it
    (`vsinv.mujoco.FLIP`). For a world made from a scenario, the world frame is F* (the
    reference camera's frame) and the target is where the scenario puts it.

    `K` is the camera's intrinsics as MuJoCo renders them (fx, fy, cx, cy, pixel (0, 0) the
    centre of the top-left pixel); `set_K` changes them (a zoom) through MuJoCo's camera
    intrinsics (`sensorsize`, `focalpixel`, `principalpixel`).
    """

    def __init__(self, model: Any, camera: str, width: int, height: int, *, supersample: int = 1,
                 target: str | None = None, target_points: Any = None, target_bodies: tuple[str, ...] = (),
                 reference_camera: str | None = None) -> None:
        mujoco = _mujoco()
        _check_size(width, height, supersample)
        self.model = model
        self.data = mujoco.MjData(model)
        self.camera = camera
        self.camera_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera)
        if self.camera_id < 0:
            raise InvalidInput(f"camera: no camera named {camera!r} in the model")
        self.width, self.height, self.supersample = int(width), int(height), int(supersample)
        self.target = target
        self.target_points = None if target_points is None else np.asarray(target_points, dtype=float)
        for name in target_bodies:
            if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name) < 0:
                raise InvalidInput(f"target_bodies: no body named {name!r} in the model")
        self.target_bodies = tuple(target_bodies)
        self.scenario: dict[str, Any] | None = None  # the scenario's dict (from_scenario)
        # A world whose camera rides an arm renders its reference image from a free camera at F*
        # (`render_reference`), the arm hidden; `set_K` sets both cameras' lenses.
        self.reference_camera_id = -1 if reference_camera is None else mujoco.mj_name2id(
            model, mujoco.mjtObj.mjOBJ_CAMERA, reference_camera)
        if reference_camera is not None and self.reference_camera_id < 0:
            raise InvalidInput(f"reference_camera: no camera named {reference_camera!r} in the model")
        self.arm: Any = None  # the scenario's `ScenarioArm` when the camera (or the target) rides an arm
        self.eye_to_hand = False  # the arm carries the target, the camera is fixed
        self.user_arm: Any = None  # from_mjcf's `arm_joints` (a `_user_arm.UserArm`)
        self._renderer = mujoco.Renderer(model, self.height * self.supersample, self.width * self.supersample)
        mujoco.mj_forward(model, self.data)

    # -- construction -----------------------------------------------------------------------
    @classmethod
    def from_scenario(cls, scenario: Any, *, supersample: int | None = None) -> World:
        """The scenario's target (dots as white discs facing F*, or its tag rig textured with the
        tags' bit patterns) lit by two lights, and a free camera with the scenario's `[camera]`
        resolution and K (10 um pixels). `scenario`: a `Scenario`, dict, built-in name or path;
        `supersample` overrides its `[world] supersample` (default: the scenario's, else 1)."""
        mujoco = _mujoco()
        d = load_scenario(scenario).to_dict()
        key = None
        if supersample is None:
            supersample, key = scenario_supersample(d), "world.supersample"
        K, width, height = _k_of(d, "camera")
        K_ref, w_ref, h_ref = _k_of(d, "reference_camera")
        if (w_ref, h_ref) != (width, height):
            raise InvalidInput(f"scenario: [reference_camera] is {w_ref} x {h_ref} and [camera] {width} x {height}; "
                               "vsinv.mujoco renders both with one sensor")
        eye_to_hand = (d.get("world") or {}).get("eye_to_hand") is not None
        has_arm = eye_to_hand or d.get("robot", {}).get("kind") == "urdf"
        arm = load_scenario(scenario).arm() if has_arm else None
        _check_size(width, height, supersample, key)
        w, h = width * supersample, height * supersample
        xml, assets, kind, points = _scene.scene(d, w, h, arm)
        if arm is not None and not _mounted.is_builtin(arm):  # a user's URDF arm
            model = _urdf.attach(mujoco.MjSpec.from_string(xml, assets=assets), arm, w, h, h)
        else:
            model = mujoco.MjModel.from_xml_string(xml, assets)
        if arm is None or eye_to_hand:  # the free camera (eye-to-hand: fixed at the world's origin)
            world = cls(model, _scene.CAMERA, width, height, supersample=supersample, target=kind, target_points=points)
        else:
            world = cls(model, _mounted.CAMERA, width, height, supersample=supersample, target=kind,
                        target_points=points, reference_camera=_scene.CAMERA)
        if arm is not None:
            world.arm, world.eye_to_hand = arm, eye_to_hand
            world.data.qpos[:] = arm.start
            mujoco.mj_forward(model, world.data)
        world.scenario = d
        world.set_K(K)
        return world

    @classmethod
    def from_mjcf(cls, path: str | os.PathLike[str], camera: str, *, width: int = 640, height: int = 480,
                  target_bodies: tuple[str, ...] = (), supersample: int = 1, arm_joints: tuple[str, ...] = (),
                  camera_site: str | None = None) -> World:
        """A user's own MJCF file: `camera` names the camera vsinv sees through (a camera of the
        world body can be moved by `render(pose)` and `move_camera`; one on a moving body follows
        it), `target_bodies` the bodies that carry the target (checked to exist). `arm_joints`
        names the joints of an arm carrying the camera, which `move_arm` drives, and
        `camera_site` a site whose frame is the camera's in vsinv's convention (default: one
        added at the camera); see `vsinv.mujoco._user_arm` for the actuators."""
        mujoco = _mujoco()
        _check_size(width, height, supersample)
        path = Path(path)
        # A regular file only (not a device or a FIFO, which is_file refuses), of bounded size;
        # MuJoCo's own message (which may quote the file) stays in the exception's cause.
        if not path.is_file():
            raise InvalidInput(f"path: no MJCF file at {str(path)!r}")
        if path.stat().st_size > MAX_MJCF_BYTES:
            raise InvalidInput(f"path: {str(path)!r} is larger than {MAX_MJCF_BYTES >> 20} MiB")
        joints = tuple(arm_joints)
        spec = _compile_step(lambda: mujoco.MjSpec.from_file(str(path)), path)
        spec.visual.global_.offwidth = max(spec.visual.global_.offwidth, width * supersample)
        spec.visual.global_.offheight = max(spec.visual.global_.offheight, height * supersample)
        site = _user_arm.prepare(spec, camera, joints, camera_site) if joints else None
        model = _compile_step(spec.compile, path)
        if joints and _user_arm.add_actuators(spec, model, joints, str(path)):
            model = _compile_step(spec.compile, path)
        world = cls(model, camera, width, height, supersample=supersample, target_bodies=target_bodies)
        if site is not None:
            world.user_arm = _user_arm.UserArm(model, joints, site)
        return world

    def close(self) -> None:
        """Frees the renderer's GL context."""
        self._renderer.close()

    def __enter__(self) -> World:
        return self

    def __exit__(self, *_: object) -> None:
        self.close()

    # -- the camera -------------------------------------------------------------------------
    @property
    def K(self) -> Intrinsics:
        """The intrinsics MuJoCo renders with (fx, fy, cx, cy) at `width` x `height`."""
        m, c = self.model, self.camera_id
        if np.all(m.cam_sensorsize[c] > 0):
            k = _camera.k_of_intrinsics(m.cam_intrinsic[c], m.cam_sensorsize[c], self.width, self.height)
        else:
            k = _camera.k_of_fovy(float(m.cam_fovy[c]), self.width, self.height)
        return Intrinsics(*k)

    def set_K(self, K: Any) -> None:
        """Renders from now on with K = (fx, fy, cx, cy) (an `Intrinsics` or 4 numbers): a zoom."""
        fx, fy, cx, cy = (float(v) for v in (K if not isinstance(K, Intrinsics) else (K.fku, K.fkv, K.u0, K.v0)))
        if not (fx > 0 and fy > 0 and np.isfinite([cx, cy]).all()):
            raise InvalidInput(f"K: expected positive focal lengths and a finite principal point, got {(fx, fy, cx, cy)}")
        intrinsic, sensor = _camera.intrinsics_of_k((fx, fy, cx, cy), self.width, self.height, _camera.PIXEL)
        for c in (self.camera_id, self.reference_camera_id):
            if c >= 0:
                self.model.cam_intrinsic[c] = intrinsic
                self.model.cam_sensorsize[c] = sensor

    @property
    def free_camera(self) -> bool:
        """Whether the camera hangs from the world body (then `render(pose)` and `move_camera` place it)."""
        return int(self.model.cam_bodyid[self.camera_id]) == 0

    def camera_pose(self) -> np.ndarray:
        """The camera's pose (4x4, vsinv's frame) in the world, after the model's kinematics."""
        mujoco = _mujoco()
        mujoco.mj_kinematics(self.model, self.data)
        mujoco.mj_camlight(self.model, self.data)  # the cameras' poses (mj_kinematics leaves them)
        c = self.camera_id
        return _camera.vsinv_pose(self.data.cam_xpos[c], self.data.cam_xmat[c])

    def set_camera_pose(self, pose: Any) -> None:
        """Places a free camera at `pose` (4x4, vsinv's frame)."""
        pose = np.asarray(pose, dtype=float)
        if pose.shape != (4, 4) or not np.isfinite(pose).all():
            raise InvalidInput(f"pose: expected a finite 4x4 matrix, got shape {pose.shape}")
        if not self.free_camera:
            raise InvalidInput(f"pose: camera {self.camera!r} is carried by a body; move the body (data.qpos) instead")
        mujoco = _mujoco()
        position, rotation = _camera.mujoco_pose(pose)
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, np.ascontiguousarray(rotation).reshape(9))
        self.model.cam_pos[self.camera_id] = position
        self.model.cam_quat[self.camera_id] = quat

    def move_camera(self, twist: Any, dt: float) -> np.ndarray:
        """Moves a free camera by `twist` (vx, vy, vz, wx, wy, wz in its own frame, m/s and rad/s)
        held for `dt` seconds (pose <- pose exp(twist dt)); returns the new pose."""
        pose = self.camera_pose() @ geometry.exp_twist(np.asarray(twist, dtype=float), float(dt))
        self.set_camera_pose(pose)
        return pose

    def move_arm(self, twist: Any, dt: float, damping: float = 0.02) -> np.ndarray:
        """Drives the arm of `from_mjcf(..., arm_joints=)` so that the camera follows `twist`
        (vx, vy, vz, wx, wy, wz in its own frame) for `dt` seconds: joint velocities from
        MuJoCo's Jacobian of the camera's site (`mj_jacSite`) and the damped least squares of
        the kinematic arm (`vsinv.kinematics.damped_least_squares`), held on the joints'
        velocity actuators for the physics steps of `dt`; returns them (n,)."""
        from ..kinematics import damped_least_squares

        if self.user_arm is None:
            raise InvalidInput("arm_joints: this world has no arm to move (World.from_mjcf(..., arm_joints=...))")
        twist = np.asarray(twist, dtype=float)
        if twist.shape != (6,) or not np.isfinite(twist).all() or not (float(dt) > 0):
            raise InvalidInput(f"twist, dt: expected 6 finite numbers and dt > 0, got shape {twist.shape} and {dt!r}")
        mujoco = _mujoco()
        dq = np.asarray(damped_least_squares(self.user_arm.jacobian(self.model, self.data), twist, damping))
        self.data.ctrl[self.user_arm.actuators] = dq
        for _ in range(max(1, round(float(dt) / self.model.opt.timestep))):
            mujoco.mj_step(self.model, self.data)
        return dq

    def project(self, points: Any, pose: Any = None) -> tuple[np.ndarray, np.ndarray]:
        """Pixels (n, 2) and depths (n,) of world points (n, 3) seen with `K` from `pose` (default: the camera's)."""
        pose = self.camera_pose() if pose is None else np.asarray(pose, dtype=float)
        cam = (np.asarray(points, dtype=float) - pose[:3, 3]) @ pose[:3, :3]
        k = self.K
        z = cam[:, 2]
        return np.column_stack([k.fku * cam[:, 0] / z + k.u0, k.fkv * cam[:, 1] / z + k.v0]), z

    # -- rendering --------------------------------------------------------------------------
    def render(self, pose: Any = None) -> np.ndarray:
        """The (height, width) uint8 grey image (Rec. 601 luma) the camera sees, from `pose`
        (placing a free camera there first) or from where it is; with `supersample` k > 1 each
        pixel is the mean of a k x k block rendered at k times the resolution."""
        mujoco = _mujoco()
        if pose is not None:
            self.set_camera_pose(pose)
        mujoco.mj_kinematics(self.model, self.data)
        mujoco.mj_camlight(self.model, self.data)
        self._renderer.update_scene(self.data, camera=self.camera)
        return self._grey()

    def render_reference(self) -> np.ndarray:
        """The image at F* (the reference image's pose) with the current K: `render(identity)`
        for a free camera; for a camera riding an arm, the free reference camera's image with
        the arm hidden (the reference image is the target's, as the kinematic world's)."""
        if self.reference_camera_id < 0:
            return self.render(np.eye(4))
        return self._render_free(self.reference_camera_id, np.eye(4))

    def render_view(self, pose: Any) -> np.ndarray:
        """The image from the camera's pose `pose` in F* (4x4) without moving the world: `render(pose)`
        for a free camera; with an arm, a free camera placed at `pose` relative to the target
        (eye-to-hand: to the target's frame where the arm holds it) with the arm hidden (the
        figures' views of a recorded run)."""
        pose = np.asarray(pose, dtype=float)
        if self.arm is None:
            return self.render(pose)
        if not self.eye_to_hand:
            return self._render_free(self.reference_camera_id, pose)
        target = np.asarray(self.arm.camera_pose(self.data.qpos))  # F* in the world
        image = self._render_free(self.camera_id, target @ pose)
        self.set_camera_pose(np.eye(4))  # the fixed camera back at the world's origin
        return image

    def _render_free(self, camera: int, pose: np.ndarray) -> np.ndarray:
        """The image of the world-body camera `camera` placed at `pose` (vsinv's frame, in the
        world), the arm's geoms (group `_mounted.GROUP`) hidden."""
        mujoco = _mujoco()
        position, rotation = _camera.mujoco_pose(pose)
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, np.ascontiguousarray(rotation).reshape(9))
        self.model.cam_pos[camera], self.model.cam_quat[camera] = position, quat
        mujoco.mj_kinematics(self.model, self.data)
        mujoco.mj_camlight(self.model, self.data)
        option = mujoco.MjvOption()
        option.geomgroup[_mounted.GROUP] = 0
        self._renderer.update_scene(self.data, camera=camera, scene_option=option)
        return self._grey()

    def _grey(self) -> np.ndarray:
        """The renderer's image as grey uint8, averaged over the supersampling blocks."""
        rgb = self._renderer.render().astype(np.float64)
        grey = rgb[:, :, 0] * 0.299 + rgb[:, :, 1] * 0.587 + rgb[:, :, 2] * 0.114
        k = self.supersample
        if k > 1:
            grey = grey.reshape(self.height, k, self.width, k).mean(axis=(1, 3))
        return np.clip(np.rint(grey), 0, 255).astype(np.uint8)
