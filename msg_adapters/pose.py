"""``geometry_msgs/msg/PoseStamped`` <-> numpy (one sample, or a whole MarkerSeries)."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bsp_ros.core.streams import MarkerSeries
from msg_adapters._types import TypeLookup, as_vector
from msg_adapters.stamps import build_header, read_header
from msg_adapters.wrench import build_vector3, read_vector3

IDENTITY_XYZW = (0.0, 0.0, 0.0, 1.0)


@dataclass(frozen=True)
class PoseSample:
    """One stamped pose.

    Attributes
    ----------
    t_ns : header stamp in nanoseconds.
    frame_id : ``header.frame_id``.
    position_m : (3,) float64, position in m.
    orientation_xyzw : (4,) float64, quaternion as stored (not normalised).
    """

    t_ns: int
    frame_id: str
    position_m: np.ndarray
    orientation_xyzw: np.ndarray = field(default_factory=lambda: np.array(IDENTITY_XYZW))


def read_quaternion(quaternion: Any) -> np.ndarray:
    """Return a ``geometry_msgs/msg/Quaternion`` as a (4,) float64 array ``(x, y, z, w)``."""
    return np.array([quaternion.x, quaternion.y, quaternion.z, quaternion.w], dtype=np.float64)


def build_quaternion(types: TypeLookup, xyzw: Any) -> Any:
    """Build a ``geometry_msgs/msg/Quaternion`` from ``(x, y, z, w)`` (stored as given)."""
    x, y, z, w = (float(v) for v in as_vector("quaternion", xyzw, 4))
    return types("geometry_msgs/msg/Quaternion")(x=x, y=y, z=z, w=w)


def read_pose_stamped(msg: Any) -> PoseSample:
    """Read a ``PoseStamped`` into a :class:`PoseSample`."""
    t_ns, frame_id = read_header(msg.header)
    return PoseSample(t_ns, frame_id, read_vector3(msg.pose.position), read_quaternion(msg.pose.orientation))


def build_pose_stamped(types: TypeLookup, sample: PoseSample) -> Any:
    """Build a ``geometry_msgs/msg/PoseStamped`` from a :class:`PoseSample`."""
    pose = types("geometry_msgs/msg/Pose")(
        position=build_vector3(types, sample.position_m, "geometry_msgs/msg/Point"),
        orientation=build_quaternion(types, sample.orientation_xyzw),
    )
    return types("geometry_msgs/msg/PoseStamped")(header=build_header(types, sample.t_ns, sample.frame_id), pose=pose)


def marker_series_from_messages(messages: Iterable[Any]) -> MarkerSeries:
    """Stack ``PoseStamped`` messages, in the given order, into a :class:`MarkerSeries` (positions only)."""
    samples = [read_pose_stamped(m) for m in messages]
    return MarkerSeries(
        t_ns=np.array([s.t_ns for s in samples], dtype=np.int64),
        position_m=np.array([s.position_m for s in samples], dtype=np.float64).reshape(-1, 3),
    )


def pose_samples_from_series(series: MarkerSeries, frame_id: str = "world") -> list[PoseSample]:
    """Split a :class:`MarkerSeries` into one :class:`PoseSample` per stamp (identity orientation)."""
    return [PoseSample(int(t), frame_id, series.position_m[i].copy()) for i, t in enumerate(series.t_ns)]
