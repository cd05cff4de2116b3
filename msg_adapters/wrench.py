"""``geometry_msgs/msg/WrenchStamped`` <-> numpy (one sample, or a whole WrenchSeries)."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from bsp_ros.core.streams import WrenchSeries
from msg_adapters._types import TypeLookup, as_vector
from msg_adapters.stamps import build_header, read_header


@dataclass(frozen=True)
class WrenchSample:
    """One stamped wrench.

    Attributes
    ----------
    t_ns : header stamp in nanoseconds.
    frame_id : ``header.frame_id``, the axes of force and torque.
    force_n : (3,) float64, force in N.
    torque_nm : (3,) float64, moment in Nm.
    """

    t_ns: int
    frame_id: str
    force_n: np.ndarray
    torque_nm: np.ndarray


def read_vector3(vector: Any) -> np.ndarray:
    """Return a ``geometry_msgs/msg/Vector3`` (or ``Point``) as a (3,) float64 array."""
    return np.array([vector.x, vector.y, vector.z], dtype=np.float64)


def build_vector3(types: TypeLookup, values: npt.ArrayLike, typename: str = "geometry_msgs/msg/Vector3") -> Any:
    """Build a ``Vector3`` (or another x/y/z type such as ``geometry_msgs/msg/Point``) from 3 numbers."""
    x, y, z = (float(v) for v in as_vector(typename, values, 3))
    return types(typename)(x=x, y=y, z=z)


def read_wrench_stamped(msg: Any) -> WrenchSample:
    """Read a ``WrenchStamped`` into a :class:`WrenchSample`."""
    t_ns, frame_id = read_header(msg.header)
    return WrenchSample(t_ns, frame_id, read_vector3(msg.wrench.force), read_vector3(msg.wrench.torque))


def build_wrench_stamped(types: TypeLookup, sample: WrenchSample) -> Any:
    """Build a ``geometry_msgs/msg/WrenchStamped`` from a :class:`WrenchSample`."""
    wrench = types("geometry_msgs/msg/Wrench")(
        force=build_vector3(types, sample.force_n), torque=build_vector3(types, sample.torque_nm)
    )
    return types("geometry_msgs/msg/WrenchStamped")(
        header=build_header(types, sample.t_ns, sample.frame_id), wrench=wrench
    )


def wrench_series_from_messages(messages: Iterable[Any], frame_id: str | None = None) -> WrenchSeries:
    """Stack ``WrenchStamped`` messages, in the given order, into a :class:`WrenchSeries`.

    Parameters
    ----------
    messages : WrenchStamped messages; none are dropped or reordered.
    frame_id : frame of an empty series (default ``world``); otherwise the messages' frame.

    Raises
    ------
    ValueError
        If the messages do not all share one ``header.frame_id``.
    """
    samples = [read_wrench_stamped(m) for m in messages]
    frames = {s.frame_id for s in samples}
    if len(frames) > 1:
        raise ValueError(f"wrench messages carry several frame ids: {sorted(frames)}")
    return WrenchSeries(
        t_ns=np.array([s.t_ns for s in samples], dtype=np.int64),
        force_n=np.array([s.force_n for s in samples], dtype=np.float64).reshape(-1, 3),
        torque_nm=np.array([s.torque_nm for s in samples], dtype=np.float64).reshape(-1, 3),
        frame_id=frames.pop() if frames else (frame_id or "world"),
    )


def wrench_samples_from_series(series: WrenchSeries) -> list[WrenchSample]:
    """Split a :class:`WrenchSeries` into one :class:`WrenchSample` per stamp."""
    return [
        WrenchSample(int(t), series.frame_id, series.force_n[i].copy(), series.torque_nm[i].copy())
        for i, t in enumerate(series.t_ns)
    ]
