"""Stamps: integer nanoseconds <-> ``builtin_interfaces/msg/Time`` and ``std_msgs/msg/Header``."""

from __future__ import annotations

from typing import Any

from msg_adapters._types import TypeLookup

NS_PER_S = 1_000_000_000
_INT32_MIN, _INT32_MAX = -(2**31), 2**31 - 1


def stamp_to_ns(stamp: Any) -> int:
    """Return a ``Time`` message (anything with ``sec`` and ``nanosec``) as integer nanoseconds."""
    return int(stamp.sec) * NS_PER_S + int(stamp.nanosec)


def ns_to_sec_nanosec(t_ns: int) -> tuple[int, int]:
    """Split nanoseconds into ``(sec, nanosec)`` with ``0 <= nanosec < 1e9`` (floor division).

    Raises
    ------
    ValueError
        If ``sec`` does not fit the int32 of ``builtin_interfaces/msg/Time``.
    """
    sec, nanosec = divmod(int(t_ns), NS_PER_S)
    if not _INT32_MIN <= sec <= _INT32_MAX:
        raise ValueError(f"stamp {t_ns} ns does not fit builtin_interfaces/msg/Time (int32 seconds)")
    return sec, nanosec


def build_time(types: TypeLookup, t_ns: int) -> Any:
    """Build a ``builtin_interfaces/msg/Time`` for ``t_ns`` nanoseconds."""
    sec, nanosec = ns_to_sec_nanosec(t_ns)
    return types("builtin_interfaces/msg/Time")(sec=sec, nanosec=nanosec)


def read_header(header: Any) -> tuple[int, str]:
    """Return ``(stamp_ns, frame_id)`` of a ``std_msgs/msg/Header``."""
    return stamp_to_ns(header.stamp), str(header.frame_id)


def build_header(types: TypeLookup, t_ns: int, frame_id: str) -> Any:
    """Build a ``std_msgs/msg/Header`` stamped ``t_ns`` nanoseconds in frame ``frame_id``."""
    return types("std_msgs/msg/Header")(stamp=build_time(types, t_ns), frame_id=str(frame_id))
