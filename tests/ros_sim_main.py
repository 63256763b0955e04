"""The command line the simulated ROS 2 rigs share (tests/ros_loop_sim.py, tests/ros_fault_sim.py):
read a JSON config, run the rig under rclpy, write its JSON result."""

from __future__ import annotations

import argparse
import json
from typing import Any, Callable


def main(run: Callable[[dict[str, Any]], dict[str, Any]]) -> None:
    import rclpy

    parser = argparse.ArgumentParser()
    parser.add_argument("--config", required=True)
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    with open(args.config) as f:
        config = json.load(f)
    rclpy.init()
    try:
        result = run(config)
    finally:
        rclpy.try_shutdown()
    with open(args.out, "w") as f:
        json.dump(result, f, indent=1)
