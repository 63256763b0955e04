"""The bridge's servo session, without ROS: builds :class:`vsinv.ImageServo` from the
configuration and the lens, steps it on every image while running, and says what to publish
(the twist in the output frame, the status). It stops, with a zero twist, when the verdict is
final (converged, features lost, ...), when a frame cannot be used, when no image came for
the watchdog timeout, or on request; starting again after a final verdict starts a new
session. Nothing here exits the process."""

from __future__ import annotations

import json
import logging
import math
from dataclasses import dataclass
from typing import Any, Optional

import numpy as np
import numpy.typing as npt

from .._core import Distortion, ImageServo, ImageStep, Intrinsics, InvalidInput, VsinvError
from .conversions import twist_in_end_effector_frame
from .params import BridgeConfig

log = logging.getLogger("vsinv.ros")

__all__ = ["BridgeSession", "Output", "validate_pipeline"]

ZERO_TWIST = np.zeros(6)


@dataclass
class Output:
    """What to publish after an event: the twist (output frame; None: nothing), the step
    (None when no step came of it), and whether a frame went to the pipeline (stepped or
    refused by it)."""

    twist: Optional[npt.NDArray[np.float64]]
    step: Optional[ImageStep] = None
    frame_used: bool = False


def _stand_in_lens(reference: npt.NDArray[np.uint8]) -> Intrinsics:
    """A plausible K for checking the options before any CameraInfo: focal length the image
    width, principal point the centre."""
    h, w = reference.shape
    return Intrinsics(float(w), float(w), w / 2.0, h / 2.0)


def validate_pipeline(config: BridgeConfig) -> None:
    """Builds the pipeline once (with K_hat, or a stand-in lens until CameraInfo gives it) so
    that bad target or law options are refused at start, named as the parameters are."""
    k = config.K_hat if config.K_hat is not None else _stand_in_lens(config.reference_image)
    try:
        ImageServo(config.reference_image, config.target, k, **config.servo_options)
    except VsinvError as e:
        raise type(e)(f"parameters: {e}") from None


class BridgeSession:
    """The state (idle, running, stopped), the pipeline and the last step."""

    def __init__(self, config: BridgeConfig) -> None:
        self.config = config
        self.state = "idle"
        self.reason: Optional[str] = None
        self.message: Optional[str] = None
        self.lens: Optional[tuple[Intrinsics, Distortion]] = None
        if config.K_hat is not None:
            self.lens = (config.K_hat, config.distortion or Distortion([0.0, 0.0, 0.0, 0.0]))
        self.lens_in_use: Optional[tuple[Intrinsics, Distortion]] = None
        # the live speed limits (a parameter set lowers them at once; the pipeline's own,
        # from the session's start, still bound the twist)
        self.max_linear_speed: Optional[float] = config.servo_options.get("max_linear_speed")
        self.max_angular_speed: Optional[float] = config.servo_options.get("max_angular_speed")
        self.pipeline: Optional[ImageServo] = None
        self.finished = False
        self.last_image: Optional[float] = None
        self.started_at: Optional[float] = None
        self.last_step: Optional[ImageStep] = None
        self.twist = ZERO_TWIST.copy()

    # ---- the lens -------------------------------------------------------------------------
    def camera_info(self, lens: tuple[Intrinsics, Distortion]) -> None:
        """A CameraInfo's lens; unused when K_hat is a parameter. It is applied when a session
        is built (the first start, a start after a reset or a final verdict): the status shows
        the lens in use (``K_hat``) and a newer one received (``K_hat_next``)."""
        if self.config.K_hat is None and (self.lens is None or self.lens[0] != lens[0] or self.lens[1] != lens[1]):
            self.lens = lens

    # ---- requests -------------------------------------------------------------------------
    def start(self, now: float) -> tuple[bool, str]:
        """Starts (or resumes) servoing; a new session after a final verdict or a reset."""
        if self.state == "running":
            return True, "already running"
        if self.pipeline is None or self.finished:
            if self.lens is None:
                return False, "no CameraInfo received yet and no K_hat parameter: cannot build the servo"
            k, d = self.lens
            try:
                self.pipeline = ImageServo(self.config.reference_image, self.config.target, k, distortion=d, **self.config.servo_options)
            except VsinvError as e:
                return False, f"cannot build the servo: {e}"
            self.finished, self.last_step, self.lens_in_use = False, None, self.lens
        self.state, self.reason, self.message = "running", None, None
        self.started_at, self.last_image = now, None
        log.info("vsinv-ros: servoing started")
        return True, "running"

    def stop(self, reason: str) -> Output:
        """Stops with a zero twist (published even when not running: stopping is always safe)."""
        if self.state == "running":
            self.state, self.reason = "stopped", reason
            log.info("vsinv-ros: stopped: %s", reason)
        self.twist = ZERO_TWIST.copy()
        return Output(self.output_twist(self.twist))

    def reset(self) -> Output:
        """Forgets the session (the next start builds a new one) and stops."""
        out = self.stop("reset")
        self.pipeline, self.finished, self.last_step = None, False, None
        self.state, self.reason, self.message = "idle", None, None
        return out

    # ---- events ---------------------------------------------------------------------------
    def frame(self, grey: npt.NDArray[np.uint8], now: float) -> Output:
        """An image: stepped while running (the twist to send), else nothing to publish."""
        if self.config.autostart and self.state == "idle" and self.pipeline is None:
            self.start(now)
        if self.state != "running" or self.pipeline is None:
            return Output(None)
        self.last_image = now
        try:
            step = self.pipeline.step(grey)
        except VsinvError as e:
            self.finished = True
            out = self.stop(f"frame refused: {e}")
            out.frame_used = True
            return out
        self.last_step = step
        if not step.running:
            self.finished = True
            out = self.stop(f"{step.verdict}: {step.reason}")
            out.step, out.frame_used = step, True
            return out
        self.twist = self.limited(np.asarray(step.twist, dtype=float))
        return Output(self.output_twist(self.twist), step, True)

    def limited(self, twist: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        """The twist scaled as a whole to the live speed limits (as the pipeline scales it)."""
        scale = 1.0
        for limit, part in ((self.max_linear_speed, twist[:3]), (self.max_angular_speed, twist[3:])):
            norm = float(np.linalg.norm(part))
            if limit is not None and norm > limit:
                scale = min(scale, limit / norm)
        return twist * scale

    def refuse_frame(self, error: InvalidInput | str) -> Output:
        """A message that is no usable image (or a refused CameraInfo): a zero twist at once,
        a stop while running (resumed by a start), the cause in the status; not an image for
        the watchdog."""
        self.message = str(error)
        log.warning("vsinv-ros: %s", error)
        return self.stop(f"refused: {error}")

    def watchdog(self, now: float) -> Output:
        """While running with no image for the timeout: stop with a zero twist."""
        if self.state != "running":
            return Output(None)
        last = self.last_image if self.last_image is not None else self.started_at
        if last is not None and now - last > self.config.watchdog_timeout:
            return self.stop(f"watchdog: no image for {now - last:.3f} s (timeout {self.config.watchdog_timeout} s)")
        return Output(None)

    # ---- outputs --------------------------------------------------------------------------
    def output_twist(self, twist: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        """The camera twist in the output frame."""
        if self.config.output_frame == "end_effector" and self.config.hand_eye is not None:
            return twist_in_end_effector_frame(twist, self.config.hand_eye)
        return np.array(twist, dtype=float)

    def status(self) -> dict[str, Any]:
        """The state, verdict, errors, points found and uncertainty, as JSON-ready values."""
        s: dict[str, Any] = {"state": self.state, "reason": self.reason, "message": self.message}
        s["iterations"] = self.pipeline.iterations if self.pipeline is not None else 0
        s["twist"] = [float(x) for x in self.output_twist(self.twist)]
        s["output_frame"] = self.config.output_frame
        in_use = self.lens_in_use if self.pipeline is not None else self.lens
        k = in_use[0] if in_use is not None else None
        s["K_hat"] = [k.fku, k.fkv, k.u0, k.v0] if k is not None else None
        nxt = self.lens[0] if self.lens is not None and self.lens is not in_use else None
        s["K_hat_next"] = [nxt.fku, nxt.fkv, nxt.u0, nxt.v0] if nxt is not None else None
        step = self.last_step
        if step is None:
            s.update(verdict=None, points=None)
            return s
        t = step.telemetry
        s["verdict"] = step.verdict
        s["errors"] = {k: float(t[k]) for k in ("image_error", "invariant_error", "tracking_error") if t.get(k) is not None}
        found = np.asarray(step.found, dtype=bool)
        s["points"] = {"found": int(found.sum()), "total": int(found.size), "found_mask": [bool(x) for x in found],
                       "pixels": [[float(u), float(v)] for u, v in np.asarray(step.pixels)]}
        s["uncertainty"] = self.pipeline.certainty() if self.pipeline is not None else None
        return s

    def status_json(self, **extra: Any) -> str:
        """:meth:`status` and ``extra`` as strict JSON (NaN and infinities as null)."""
        return json.dumps(_finite({**self.status(), **extra}), allow_nan=False)


def _finite(value: Any) -> Any:
    """JSON-ready: NaN and infinities as null, NumPy scalars as Python's, recursively."""
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    return value
