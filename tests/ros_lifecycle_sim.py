"""The simulated half of tests/test_ros_lifecycle.py, in its own process: the fault rig of
tests/ros_fault_sim.py (one rendered image with a fresh stamp each time, lock-step) driving the
bridge started with --lifecycle through its lifecycle services (lifecycle_msgs ChangeState and
GetState), as ``ros2 lifecycle set`` does. Writes JSON to --out."""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState, GetState
from rclpy.executors import SingleThreadedExecutor

from ros_fault_sim import Rig, call, spin_until, spun_rig


class LifecycleRig(Rig):
    def __init__(self, grey: np.ndarray, K: list[float]) -> None:
        super().__init__(grey, K)
        self.change = self.create_client(ChangeState, "/vsinv_ros/change_state")
        self.get = self.create_client(GetState, "/vsinv_ros/get_state")


def state(ex: SingleThreadedExecutor, rig: LifecycleRig) -> str:
    return str(call(ex, rig.get, GetState.Request()).current_state.label)


def transition(ex: SingleThreadedExecutor, rig: LifecycleRig, which: int) -> dict[str, Any]:
    """One transition: whether it succeeded, the state after it, the seconds it took."""
    t0 = time.monotonic()
    ok = bool(call(ex, rig.change, ChangeState.Request(transition=Transition(id=which))).success)
    return {"ok": ok, "state": state(ex, rig), "s": time.monotonic() - t0}


def twists_for(ex: SingleThreadedExecutor, rig: LifecycleRig, images: int) -> list[list[float]]:
    """Sends ``images`` images 30 ms apart: the twists that came back."""
    n = len(rig.twists)
    for _ in range(images):
        rig.image_pub.publish(rig.image())
        spin_until(ex, lambda: False, 0.03)
    spin_until(ex, lambda: False, 0.2)
    return [t for _, t, _, _ in rig.twists[n:]]


def run(config: dict[str, Any]) -> dict[str, Any]:
    with spun_rig(LifecycleRig, config) as (ex, rig):
        out: dict[str, Any] = {}
        out["initial"] = state(ex, rig)
        out["status_unconfigured"] = rig.statuses
        out["configure"] = transition(ex, rig, Transition.TRANSITION_CONFIGURE)
        spin_until(ex, lambda: rig.statuses > 0, 10.0)
        out["status_configured"] = dict(rig.status)
        out["activate_without_lens"] = transition(ex, rig, Transition.TRANSITION_ACTIVATE)
        rig.info_pub.publish(rig.info)
        spin_until(ex, lambda: rig.status.get("K_hat") is not None, 10.0)
        out["inactive_twists"] = twists_for(ex, rig, 5)
        out["activate"] = transition(ex, rig, Transition.TRANSITION_ACTIVATE)
        out["active_twists"] = twists_for(ex, rig, 5)
        n = len(rig.twists)
        t0 = time.monotonic()
        out["deactivate"] = transition(ex, rig, Transition.TRANSITION_DEACTIVATE)
        spin_until(ex, lambda: len(rig.twists) > n, 2.0)
        out["deactivate_ms"] = 1e3 * (rig.twists[n][0] - t0) if len(rig.twists) > n else None
        spin_until(ex, lambda: False, 0.3)
        out["deactivate_twists"] = [t for _, t, _, _ in rig.twists[n:]]
        out["after_deactivate_twists"] = twists_for(ex, rig, 5) + twists_for(ex, rig, 0)
        rig.image_pub.publish(rig.image(encoding="bayer_rggb8"))  # a fault while inactive: silent too
        out["inactive_fault_twists"] = twists_for(ex, rig, 0)
        out["status_inactive"] = dict(rig.status)
        out["reactivate"] = transition(ex, rig, Transition.TRANSITION_ACTIVATE)
        out["reactive_twists"] = twists_for(ex, rig, 5)
        out["deactivate_again"] = transition(ex, rig, Transition.TRANSITION_DEACTIVATE)
        out["cleanup"] = transition(ex, rig, Transition.TRANSITION_CLEANUP)
        out["cleanup_twists"] = twists_for(ex, rig, 3)
        out["reconfigure"] = transition(ex, rig, Transition.TRANSITION_CONFIGURE)
        spin_until(ex, lambda: rig.status.get("state") == "idle", 10.0)  # the new session's latched status
        rig.info_pub.publish(rig.info)
        spin_until(ex, lambda: rig.status.get("K_hat") is not None, 10.0)
        out["reactivate_after_cleanup"] = transition(ex, rig, Transition.TRANSITION_ACTIVATE)
        out["twists_after_cleanup"] = twists_for(ex, rig, 5)
        return out


if __name__ == "__main__":
    from ros_sim_main import main

    main(run)
