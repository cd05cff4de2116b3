"""``diagnostic_msgs/msg/DiagnosticArray`` <-> plain Python values."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from msg_adapters._types import TypeLookup
from msg_adapters.stamps import build_header, read_header

OK, WARN, ERROR, STALE = 0, 1, 2, 3


@dataclass(frozen=True)
class DiagnosticStatusData:
    """One ``DiagnosticStatus``: ``level`` 0 OK, 1 WARN, 2 ERROR, 3 STALE; ``values`` ordered pairs."""

    level: int
    name: str
    message: str = ""
    hardware_id: str = ""
    values: tuple[tuple[str, str], ...] = ()

    @classmethod
    def with_values(
        cls, level: int, name: str, message: str, hardware_id: str, values: Mapping[str, object]
    ) -> DiagnosticStatusData:
        """Build a status from a mapping; values are converted with ``str``."""
        return cls(level, name, message, hardware_id, tuple((str(k), str(v)) for k, v in values.items()))


@dataclass(frozen=True)
class DiagnosticArraySample:
    """One stamped ``DiagnosticArray``."""

    t_ns: int
    frame_id: str = ""
    status: tuple[DiagnosticStatusData, ...] = field(default_factory=tuple)


def _level_to_int(level: Any) -> int:
    # rclpy holds the ``byte`` field as a length-1 ``bytes``; rosbags as an int.
    if isinstance(level, bytes | bytearray):
        return int(level[0])
    return int(level)


def _level_for(cls: type, level: int) -> Any:
    # The class's own constant tells which representation it wants.
    if isinstance(getattr(cls, "OK", 0), bytes | bytearray):
        return bytes([level])
    return level


def read_diagnostic_array(msg: Any) -> DiagnosticArraySample:
    """Read a ``DiagnosticArray`` into a :class:`DiagnosticArraySample`."""
    t_ns, frame_id = read_header(msg.header)
    status = tuple(
        DiagnosticStatusData(
            _level_to_int(s.level),
            str(s.name),
            str(s.message),
            str(s.hardware_id),
            tuple((str(kv.key), str(kv.value)) for kv in s.values),
        )
        for s in msg.status
    )
    return DiagnosticArraySample(t_ns, frame_id, status)


def build_diagnostic_array(types: TypeLookup, sample: DiagnosticArraySample) -> Any:
    """Build a ``diagnostic_msgs/msg/DiagnosticArray`` from a :class:`DiagnosticArraySample`.

    Raises
    ------
    ValueError
        If a level is not 0-255.
    """
    status_cls = types("diagnostic_msgs/msg/DiagnosticStatus")
    key_value = types("diagnostic_msgs/msg/KeyValue")
    status = []
    for s in sample.status:
        if not 0 <= int(s.level) <= 255:
            raise ValueError(f"diagnostic level must be a byte, got {s.level}")
        status.append(
            status_cls(
                level=_level_for(status_cls, int(s.level)),
                name=str(s.name),
                message=str(s.message),
                hardware_id=str(s.hardware_id),
                values=[key_value(key=k, value=v) for k, v in s.values],
            )
        )
    return types("diagnostic_msgs/msg/DiagnosticArray")(
        header=build_header(types, sample.t_ns, sample.frame_id), status=status
    )
