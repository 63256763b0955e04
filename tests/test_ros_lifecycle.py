"""The bridge as a lifecycle node (``vsinv-ros --lifecycle``) over real ROS 2 topics and its
lifecycle services (loopback, a domain id of its own, bounded in time; skipped without rclpy):
configure reads the parameters and latches the status, activate starts servoing (and fails
without a lens), deactivate sends one zero twist and then nothing (not even for a fault),
cleanup undoes configure and a new configure/activate servos again."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import vsinv
from test_ros_loop import K_6MM, SCENARIO, bridge_parameters, ros_ready, run_bridge_with  # noqa: F401

ZERO = [0.0] * 6


def test_lifecycle_transitions_start_and_stop_the_servo(tmp_path: Path) -> None:
    parameters = bridge_parameters(tmp_path)
    parameters.update(output_frame="camera", camera_frame="camera_optical_frame", stop={"max_iterations": 100000, "stall": False})
    for key in ("hand_eye", "end_effector_frame"):
        parameters.pop(key)
    start = vsinv.geometry.pose_from_position_thetau([0.2, -0.15, -0.15], np.radians([-19.33, -4.86, 77.28]))
    config = {"scenario": SCENARIO, "K": K_6MM, "start_pose": start.tolist()}
    r, err = run_bridge_with(tmp_path, parameters, "ros_lifecycle_sim.py", config, timeout=240, options=("--lifecycle",))
    print(f"\nlifecycle: deactivate -> zero twist {r['deactivate_ms']:.2f} ms; transitions "
          + ", ".join(f"{k} {r[k]['s'] * 1e3:.1f} ms" for k in ("configure", "activate", "deactivate", "cleanup")))
    assert r["initial"] == "unconfigured" and r["status_unconfigured"] == 0, (r, err[-2000:])
    assert r["configure"] == {**r["configure"], "ok": True, "state": "inactive"}, (r["configure"], err[-2000:])
    assert r["status_configured"].get("state") == "idle"  # latched from configure on
    assert not r["activate_without_lens"]["ok"] and r["activate_without_lens"]["state"] == "inactive"
    assert "no CameraInfo" in err  # the reason, in the log
    assert r["inactive_twists"] == []  # configured but inactive: images are not read
    assert r["activate"]["ok"] and r["activate"]["state"] == "active", (r["activate"], err[-2000:])
    assert len(r["active_twists"]) >= 3 and all(any(t) for t in r["active_twists"]), r["active_twists"]
    assert r["deactivate"]["ok"] and r["deactivate"]["state"] == "inactive"
    assert r["deactivate_twists"] == [ZERO], r["deactivate_twists"]  # one zero twist ...
    assert r["deactivate_ms"] < 1000.0 / 30.0
    assert r["after_deactivate_twists"] == [] and r["inactive_fault_twists"] == []  # ... then silent
    assert r["status_inactive"]["state"] == "stopped" and r["status_inactive"]["reason"] == "deactivated"
    assert r["reactivate"]["ok"] and len(r["reactive_twists"]) >= 3 and all(any(t) for t in r["reactive_twists"])
    assert r["deactivate_again"]["ok"]
    assert r["cleanup"]["ok"] and r["cleanup"]["state"] == "unconfigured" and r["cleanup_twists"] == []
    assert r["reconfigure"]["ok"] and r["reactivate_after_cleanup"]["ok"], (r, err[-2000:])
    assert len(r["twists_after_cleanup"]) >= 3 and all(any(t) for t in r["twists_after_cleanup"])
