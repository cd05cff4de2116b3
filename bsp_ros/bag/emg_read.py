"""The EMG envelope topic's decoded messages as one :class:`EmgSeries` (its rows in receive order)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from bsp_ros.core.streams import EmgSeries

if TYPE_CHECKING:
    from bsp_ros.bag.reader.sink import Stream

__all__ = ["collect_envelopes"]


def collect_envelopes(stream: Stream | None) -> EmgSeries | None:
    """The envelopes of the messages whose channels are the first message's, in receive (log time) order; the
    others are counted in ``other_layout`` (a stream whose channels change is judged, not mended, downstream).

    Parameters
    ----------
    stream : the EMG topic's stream (one row of values per message, its channel names as the row's frame), or
        None where the bag has no message on it.

    Returns
    -------
    EmgSeries, or None without a decodable message.
    """
    if stream is None or not stream.t_ns:
        return None
    t_ns = np.concatenate(stream.t_ns)
    layout = np.concatenate(stream.frame_index)
    order = np.argsort(t_ns, kind="stable")
    names = sorted(stream.frames, key=stream.frames.__getitem__)
    first = int(layout[order[0]])
    count = stream.values[int(order[0])].size
    same = (layout == first) & np.array([row.size == count for row in stream.values])
    kept = order[same[order]]
    channels = tuple(name for name in names[first].split(",")) if names[first] else ()
    if len(channels) != count:  # a label that does not name every value: the channels by their index
        channels = tuple(f"channel_{k}" for k in range(count))
    envelope = np.array([stream.values[i] for i in kept.tolist()], dtype=np.float64).reshape(kept.size, count)
    return EmgSeries(t_ns=t_ns[kept], envelope=envelope, channels=channels, other_layout=int((~same).sum()))
