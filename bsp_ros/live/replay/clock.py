"""The replayed ``/clock``: its messages, and sleeping until a message's time while ticking it."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from bsp_ros.live.runtime.qos import QosSpec

CLOCK_TYPE = "rosgraph_msgs/msg/Clock"
CLOCK_QOS = QosSpec(reliable=False, depth=1)  # rclcpp::ClockQoS
_SLEEP_SLICE_S = 0.05


_clock_store: Any = None


def clock_bytes(t_ns: int) -> bytes:
    """A ``/clock`` message at ``t_ns`` (ns), serialized CDR."""
    global _clock_store
    if _clock_store is None:
        from rosbags.typesys import Stores, get_typestore

        _clock_store = get_typestore(Stores.ROS2_JAZZY)
    store = _clock_store
    time_cls = store.types["builtin_interfaces/msg/Time"]
    msg = store.types[CLOCK_TYPE](clock=time_cls(sec=t_ns // 1_000_000_000, nanosec=t_ns % 1_000_000_000))
    return bytes(store.serialize_cdr(msg, CLOCK_TYPE))


def sleep_until(
    target: float,
    stop: threading.Event,
    clock_write: Callable[[bytes], None] | None,
    next_clock_ns: int | None,
    clock_period_ns: int,
    t_log0: int,
    t_wall0: float,
    rate: float,
) -> int | None:
    """Sleep until the monotonic time ``target``, publishing ``/clock`` ticks meanwhile; returns the next tick."""
    while not stop.is_set():
        now = time.monotonic()
        wake = target
        if clock_write is not None and next_clock_ns is not None:
            tick_at = t_wall0 + (next_clock_ns - t_log0) / 1e9 / rate
            if tick_at <= now and tick_at < target:
                clock_write(clock_bytes(next_clock_ns))
                next_clock_ns += clock_period_ns
                continue
            wake = min(target, tick_at)
        if target <= now:
            return next_clock_ns
        delay = max(0.0, wake - now)
        if delay > _SLEEP_SLICE_S:
            stop.wait(_SLEEP_SLICE_S)
        else:
            time.sleep(delay)
    return next_clock_ns
