"""A stamp for a message without a header (the EMG envelope): its receipt on the node clock, placed on the clock of
the wrench's stamps by the newest wrench's offset between the two."""

from __future__ import annotations

__all__ = ["ReceiptStamps"]


class ReceiptStamps:
    """Stamps headerless messages at their receipt, in the time base of the wrench's ``header.stamp``.

    A recorded session times such a message by its receive (log) time, on the recorder's clock, which on a cell is
    the clock the stamps are on. Live, the node clock at receipt is that time where the clocks agree (a cell, or
    ``use_sim_time`` with a played ``/clock``); carried by the newest wrench's offset (its stamp minus its receipt
    on the node clock) it also holds where they do not: a bag played without ``/clock`` keeps its recorded stamps.
    The offset holds the wrench's transport latency (milliseconds), far below the EMG rule's 100 ms; messages that
    waited in their queues while an update ran get the stamps of the wrenches taken beside them, not all one now.
    """

    def __init__(self) -> None:
        self.offset_ns: int | None = None  # the newest wrench's stamp minus its receipt, ns

    def wrench(self, stamp_ns: int, now_ns: int) -> None:
        """A wrench stamped ``stamp_ns`` was received at ``now_ns`` (node clock), ns."""
        self.offset_ns = stamp_ns - now_ns

    def stamp(self, now_ns: int) -> int | None:
        """The stamp of a message received at ``now_ns`` (node clock), ns; None before any wrench."""
        return None if self.offset_ns is None else now_ns + self.offset_ns
