"""What an MCAP scan takes and gives: channels, the message sink, the scan result, the progress callback."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

#: Called with ``(bytes_read, bytes_total)`` as a read progresses.
ProgressCallback = Callable[[int, int], None]


@dataclass(frozen=True)
class ChannelInfo:
    """One MCAP channel: id (per file), topic, message type (schema name) and message encoding."""

    id: int
    topic: str
    msgtype: str
    encoding: str


class MessageSink(Protocol):
    """Receives the raw messages of the channels it wants."""

    def wants(self, channel: ChannelInfo) -> bool:
        """Whether messages of ``channel`` should be fed."""
        ...

    def feed(
        self, channel: ChannelInfo, buf: np.ndarray, offsets: np.ndarray, lengths: np.ndarray, log_ns: np.ndarray
    ) -> None:
        """Take messages ``buf[offsets[i]:offsets[i] + lengths[i]]`` (uint8 buffer, int64 arrays)."""
        ...


@dataclass(kw_only=True)
class ScanResult:
    """What scanning one file found besides the messages.

    Attributes
    ----------
    channels : channel id -> channel (from the summary and the data section).
    summary_counts : topic -> message count from the MCAP Statistics record (its channels resolved with
        every Channel record of the file, so a summary without repeated channels counts too), None if the
        file has no intact Statistics record or it gives no per-channel counts.
    rosbag2_metadata : the ``serialized_metadata`` YAML rosbag2 embeds, if found.
    lost_in_bad_chunks : topic -> messages listed in the message indexes of CRC-failed chunks.
    uncounted_loss : topics that lost messages in damaged chunks without message indexes (how many is
        unknown; the summary's chunk index names the channels).
    uncounted_loss_any : a damaged chunk without message indexes or chunk index lost messages of channels
        unknown (any topic may have lost some).
    channels_complete : the summary repeats every Channel record of the file (a loss cannot hide a topic).
    messages_seen : message records in the intact part of the file, on every channel.
    messages_decompressed : messages stored compressed one by one (rosbag2 ``compression_mode: message``)
        and expanded before being fed.
    orphans : messages on channel ids never defined (their Channel record was lost).
    chunks_read, chunks_without_crc, crc_errors : chunk counts.
    truncated : the file ended before its footer.
    damage : one line per damaged place.
    """

    channels: dict[int, ChannelInfo] = field(default_factory=dict)
    summary_counts: dict[str, int] | None = None
    rosbag2_metadata: str | None = None
    lost_in_bad_chunks: dict[str, int] = field(default_factory=dict)
    uncounted_loss: set[str] = field(default_factory=set)
    uncounted_loss_any: bool = False
    channels_complete: bool = False
    messages_seen: int = 0
    messages_decompressed: int = 0
    orphans: int = 0
    chunks_read: int = 0
    chunks_without_crc: int = 0
    crc_errors: int = 0
    truncated: bool = False
    damage: list[str] = field(default_factory=list)
