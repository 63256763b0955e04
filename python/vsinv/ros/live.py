"""Parameter changes while the node runs (``ros2 param set``), without ROS: which apply at
once, which at the next session, and which are refused with the reason. Pure Python."""

from __future__ import annotations

from typing import Any, Optional

from .._core import InvalidInput
from .params import _BY_NAME, _typed
from .session import BridgeSession

__all__ = ["AT_ONCE", "NEXT_SESSION", "apply_change"]

#: Applied to the next twist: the speed limits (lowered at once; raised up to the limits the
#: session started with, beyond them from the next session) and the watchdog.
AT_ONCE = ("max_linear_speed", "max_angular_speed", "watchdog_timeout")
#: Applied when the next session is built (a start after a reset or a final verdict): the
#: law's gains, which the running session holds.
NEXT_SESSION = ("gain", "gain_rz")


def apply_change(session: BridgeSession, name: str, value: Any) -> tuple[bool, str]:
    """Applies ``name = value`` to ``session`` (and its configuration): (accepted, reason)."""
    p = _BY_NAME.get(name)
    if p is None:
        return False, f"{name}: not a parameter of the bridge"
    if name not in AT_ONCE + NEXT_SESSION:
        return False, f"{name}: read at start only (restart the node with the new value)"
    try:
        number: Optional[float] = _typed(p, value)
    except InvalidInput as e:
        return False, str(e)
    if number is None or not number > 0.0:
        return False, f"parameter {name}: expected a positive number, got {value!r}"
    config = session.config
    if name == "watchdog_timeout":
        config.watchdog_timeout = number
        return True, f"{name} = {number} s, at once"
    config.servo_options[name] = number
    if name in NEXT_SESSION:
        return True, f"{name} = {number}, from the next session (a start after reset or a final verdict)"
    setattr(session, name, number)
    return True, f"{name} = {number}, at once (bounded by the session's starting limit until the next session)"
