"""``sensor_msgs/msg/JointState`` <-> numpy."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from msg_adapters._types import TypeLookup, float_sequence, string_sequence
from msg_adapters.stamps import build_header, read_header


def _empty() -> np.ndarray:
    return np.zeros(0, dtype=np.float64)


@dataclass(frozen=True)
class JointStateSample:
    """One stamped joint state; an empty array means the field was not given.

    Attributes
    ----------
    t_ns : header stamp in nanoseconds.
    frame_id : ``header.frame_id``.
    names : joint names, (J,).
    position : (J,) or (0,) float64, rad.
    velocity : (J,) or (0,) float64, rad/s.
    effort : (J,) or (0,) float64, Nm.
    """

    t_ns: int
    frame_id: str
    names: tuple[str, ...]
    position: np.ndarray = field(default_factory=_empty)
    velocity: np.ndarray = field(default_factory=_empty)
    effort: np.ndarray = field(default_factory=_empty)


def read_joint_state(msg: Any) -> JointStateSample:
    """Read a ``JointState`` into a :class:`JointStateSample`."""
    t_ns, frame_id = read_header(msg.header)
    return JointStateSample(
        t_ns,
        frame_id,
        tuple(str(n) for n in msg.name),
        np.array(msg.position, dtype=np.float64).reshape(-1),
        np.array(msg.velocity, dtype=np.float64).reshape(-1),
        np.array(msg.effort, dtype=np.float64).reshape(-1),
    )


def build_joint_state(types: TypeLookup, sample: JointStateSample) -> Any:
    """Build a ``sensor_msgs/msg/JointState`` from a :class:`JointStateSample`.

    Raises
    ------
    ValueError
        If a non-empty position, velocity or effort does not have one entry per name.
    """
    n = len(sample.names)
    for name in ("position", "velocity", "effort"):
        size = np.asarray(getattr(sample, name)).size
        if size not in (0, n):
            raise ValueError(f"JointState {name} has {size} entries for {n} joint names")
    cls = types("sensor_msgs/msg/JointState")
    return cls(
        header=build_header(types, sample.t_ns, sample.frame_id),
        name=string_sequence(sample.names),
        position=float_sequence(cls, sample.position),
        velocity=float_sequence(cls, sample.velocity),
        effort=float_sequence(cls, sample.effort),
    )
