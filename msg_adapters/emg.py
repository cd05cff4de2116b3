"""``std_msgs/msg/Float32MultiArray`` as docs/contract.md's EMG envelope <-> numpy: one value per channel in
``data``, the channels' names joined by commas in ``layout.dim[0].label``; no header."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from msg_adapters._types import TypeLookup

__all__ = ["EMG_TYPE", "build_envelope", "read_envelope"]

EMG_TYPE = "std_msgs/msg/Float32MultiArray"


def read_envelope(msg: Any) -> tuple[tuple[str, ...], np.ndarray]:
    """The channels' names (the first dimension's label split at commas; ``()`` without a dimension or label) and
    the envelopes (C,) float64 of one message."""
    dims = msg.layout.dim
    label = str(dims[0].label) if len(dims) else ""
    channels = tuple(name.strip() for name in label.split(",")) if label else ()
    return channels, np.asarray(msg.data, dtype=np.float64).reshape(-1)


def build_envelope(types: TypeLookup, channels: Sequence[str], values: npt.ArrayLike) -> Any:
    """A ``Float32MultiArray`` of ``values`` (C,) as ``data``, ``channels`` (C,) joined by commas as its one
    dimension's label (size and stride C).

    Raises
    ------
    ValueError
        A channel name holding a comma, or not one value per channel.
    """
    data = np.asarray(values, dtype=np.float32).reshape(-1)
    if data.size != len(channels) or any("," in name for name in channels):
        raise ValueError(f"one value per channel and no comma in a name: {list(channels)} for {data.size} values")
    cls = types(EMG_TYPE)
    dim = types("std_msgs/msg/MultiArrayDimension")(label=",".join(channels), size=data.size, stride=data.size)
    layout = types("std_msgs/msg/MultiArrayLayout")(dim=[dim], data_offset=0)
    return cls(layout=layout, data=data.copy() if hasattr(cls, "__msgtype__") else [float(v) for v in data])
