"""The live window's EMG envelopes: rows of the newest seconds, kept as they come, copied into each window."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.identification.data import CLOCK_JUMP_NS
from bsp_ros.core.streams import EmgSeries
from bsp_ros.live.online.buffer import TimedBuffer

__all__ = ["EmgBuffer"]


class EmgBuffer:
    """EMG envelope rows of the newest ``horizon_ns``, as a window copies them (:meth:`series`).

    Rows are kept as they come, non-finite and negative values included: whether a window's envelopes can be used
    is the rule's to judge (:func:`bsp_ros.core.emg.check_emg`), as offline, where a lead that fell off makes the
    stream unusable instead of leaving its gaps unseen. A stamp at or before the newest is refused and counted; one
    more than a second before it (a clock jump) starts the buffer afresh. Channels that change (other names or
    another count) start it afresh too, and the earlier channels' rows still within the horizon count in each window
    that holds them as ``other_layout``: that window's EMG is not used (``channels_change``), as a bag's is not.

    Parameters
    ----------
    horizon_ns : how long rows are kept, ns.
    """

    def __init__(self, horizon_ns: int) -> None:
        self.horizon_ns = horizon_ns
        self.layout: tuple[tuple[str, ...], int] | None = None  # the label's names and the value count
        self._rows: TimedBuffer | None = None
        self._other_t_ns = np.zeros(0, dtype=np.int64)  # stamps of rows of earlier channels
        self.out_of_order = 0

    @property
    def channels(self) -> tuple[str, ...]:
        """The current channels' names (``channel_<k>`` where the label does not name every value)."""
        if self.layout is None:
            return ()
        names, count = self.layout
        return names if len(names) == count else tuple(f"channel_{k}" for k in range(count))

    def clear(self) -> None:
        """Forget every row (the window restarts)."""
        self.layout, self._rows = None, None
        self._other_t_ns = np.zeros(0, dtype=np.int64)

    def add(self, t_ns: int, channels: tuple[str, ...], values: np.ndarray) -> bool:
        """Add one message's envelopes ``values`` (C,) of ``channels`` (its label's names) at ``t_ns``; False if
        refused (a stamp at or before the newest)."""
        last = None if self._rows is None else self._rows.last_t_ns
        if last is not None and t_ns <= last:
            if last - t_ns <= CLOCK_JUMP_NS:
                self.out_of_order += 1
                return False
            self.clear()
        layout = (channels, int(values.size))
        if layout != self.layout or self._rows is None:
            self._start_layout(t_ns, layout)
        assert self._rows is not None
        self._rows.append(t_ns, values)
        return True

    def _start_layout(self, t_ns: int, layout: tuple[tuple[str, ...], int]) -> None:
        """Rows of other channels from ``t_ns`` on; the earlier channels' rows within the horizon are counted."""
        if self._rows is not None:
            earlier, _ = self._rows.since(t_ns - self.horizon_ns)
            self._other_t_ns = np.concatenate((self._other_t_ns, earlier))
        self._other_t_ns = self._other_t_ns[self._other_t_ns >= t_ns - self.horizon_ns]
        self.layout = layout
        self._rows = TimedBuffer(layout[1], self.horizon_ns, capacity=1024)

    def series(self, start_ns: int) -> EmgSeries | None:
        """A copy of the rows at or after ``start_ns`` (none where the stream stopped: the rule then says the
        window's EMG is too short), or None where no envelope ever came."""
        if self._rows is None:
            return None
        t_ns, envelope = self._rows.since(start_ns)
        other = int((self._other_t_ns >= start_ns).sum())
        return EmgSeries(t_ns=t_ns, envelope=envelope, channels=self.channels, other_layout=other)
