"""The class lookup a builder gets from its caller, and how each middleware wants number sequences."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

#: Maps a ROS type name such as ``geometry_msgs/msg/WrenchStamped`` to its message class
#: (rosbags: ``lambda n: typestore.types[n]``; rclpy: ``bsp_ros.live.runtime.ros.message_class``).
TypeLookup = Callable[[str], type]


def float_sequence(cls: type, values: npt.ArrayLike) -> Any:
    """Return ``values`` in the form ``cls`` accepts for a ``float64[]`` field.

    rosbags message classes (they carry ``__msgtype__``) serialise numpy arrays; rclpy classes take a
    list of Python floats.
    """
    array = np.asarray(values, dtype=np.float64).reshape(-1)
    if hasattr(cls, "__msgtype__"):
        return array.copy()
    return [float(v) for v in array]


def string_sequence(values: Sequence[str]) -> list[str]:
    """Return ``values`` as a list of ``str`` (every middleware accepts that for ``string[]``)."""
    return [str(v) for v in values]


def as_vector(name: str, values: npt.ArrayLike, size: int) -> np.ndarray:
    """Return ``values`` as a float64 vector of ``size`` entries; raise ValueError naming ``name``."""
    array = np.asarray(values, dtype=np.float64)
    if array.shape != (size,):
        raise ValueError(f"{name} must have shape ({size},), got {array.shape}")
    return array
