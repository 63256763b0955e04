"""``vsinv-ros`` / ``python -m vsinv.ros``: runs the bridge node until interrupted; a bad
parameter stops it at start with a message naming it and exit status 2, and without rclpy
it says where rclpy comes from. ``--help`` lists the parameters (no ROS needed)."""

from __future__ import annotations

import signal
import sys
from typing import Any, Optional, Sequence

from .params import parameter_help

USAGE = """usage: vsinv-ros [--lifecycle] [--ros-args -p NAME:=VALUE ... | --params-file FILE]

The vsinv ROS 2 bridge: images and CameraInfo in, a TwistStamped for MoveIt Servo out.
Services ~/start, ~/stop, ~/reset (std_srvs/Trigger); status as JSON on ~/status (latched,
a heartbeat every status_period) and on /diagnostics. An unusable image publishes a zero
twist at once and stops. As a ROS 2 package (ros/vsinv, colcon build):
ros2 launch vsinv servo.launch.py params_file:=FILE, or ros2 run vsinv vsinv_ros.

--lifecycle: a managed node (configure reads the parameters, activate starts servoing,
deactivate sends one zero twist and goes silent, cleanup undoes configure); the
~/start, ~/stop and ~/reset services are then not offered.

parameters:
"""

NO_RCLPY = (
    "vsinv-ros: rclpy is not importable: the bridge runs with a ROS 2 installation "
    "(source /opt/ros/<distro>/setup.bash in this shell, then run vsinv-ros again)"
)


def _interrupt(_signum: int, _frame: Any) -> None:
    raise KeyboardInterrupt


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Runs the node; returns the exit status."""
    args = list(sys.argv if argv is None else argv)
    ros_at = args.index("--ros-args") if "--ros-args" in args else len(args)
    lifecycle = "--lifecycle" in args[1:ros_at]
    if lifecycle:
        args.remove("--lifecycle")
    if any(a in ("-h", "--help") for a in args[1:2]):
        print(USAGE + parameter_help())
        return 0
    try:
        import rclpy
        from rclpy.executors import ExternalShutdownException

        from .node import BridgeNode, LifecycleBridgeNode
    except ImportError as e:
        print(f"{NO_RCLPY} ({e})", file=sys.stderr)
        return 2
    from .._core import VsinvError

    # Our own handlers (not rclpy's), so that the context is still up for the last zero twist.
    options = getattr(getattr(rclpy, "signals", None), "SignalHandlerOptions", None)
    rclpy.init(args=args, **({"signal_handler_options": options.NO} if options is not None else {}))
    signal.signal(signal.SIGINT, _interrupt)
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        try:
            node = LifecycleBridgeNode() if lifecycle else BridgeNode()
        except VsinvError as e:
            print(f"vsinv-ros: refused to start: {e}", file=sys.stderr)
            return 2
        try:
            rclpy.spin(node)
        except (KeyboardInterrupt, ExternalShutdownException):
            pass
        finally:
            node.halt()
            node.destroy_node()
    finally:
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
