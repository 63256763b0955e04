"""A ROS 2 parameters file's nested tables as the dotted names a node declares
(`image_qos: {depth: 1}` is the parameter `image_qos.depth`), for the bridge's parser in tests."""

from __future__ import annotations

from typing import Any


def flat(d: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in d.items():
        out.update(flat(v, f"{prefix}{k}.") if isinstance(v, dict) else {f"{prefix}{k}": v})
    return out
