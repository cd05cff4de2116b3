"""The state of one MCAP file scan: schemas, channels, damaged chunks, and the chunk walk feeding the sink."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from bsp_ros.bag.byte_windows import byte_windows
from bsp_ros.bag.compression import decompress_cdr_messages
from bsp_ros.bag.mcap_scan.interface import ChannelInfo, MessageSink, ScanResult
from bsp_ros.bag.mcap_scan.records import OP_CHANNEL, OP_MESSAGE, OP_SCHEMA, RECORD, parse_channel, parse_schema

_BATCH_BYTES = 4 * 2**20  # chunks are decoded in batches of about this size


class Scanner:
    """State of one file scan (schemas, channels, the chunk being walked)."""

    def __init__(self, path: Path, sink: MessageSink, result: ScanResult) -> None:
        self.path = path
        self.sink = sink
        self.result = result
        self.schemas: dict[int, str] = {}
        self.schema_of: dict[int, int] = {}
        self.bad_chunk_open = False
        self.bad_chunk_at = -1  # offset of the damaged chunk whose message indexes are being read
        self.bad_chunk_indexed = False
        self.lost_channel_counts: dict[int, int] = {}
        self.uncounted_channels: set[int] = set()
        self.chunk_channels: dict[int, set[int]] = {}  # chunk offset -> channel ids (summary chunk indexes)
        self.summary_channel_counts: dict[int, int] | None = None
        self.pending: list[tuple[bytes, np.ndarray]] = []
        self.pending_bytes = 0

    def add_schema(self, schema_id: int, name: str) -> None:
        """Note the message type (schema name) of schema ``schema_id``."""
        self.schemas[schema_id] = name

    def open_bad_chunk(self, where: int) -> None:
        """Start counting the loss of the damaged chunk at byte ``where`` from the message indexes after it."""
        self.close_bad_chunk()
        self.bad_chunk_open = True
        self.bad_chunk_at = where
        self.bad_chunk_indexed = False

    def close_bad_chunk(self) -> None:
        """End of a damaged chunk's message indexes: without any, its loss is uncounted."""
        if self.bad_chunk_open and not self.bad_chunk_indexed:
            self.note_uncounted(self.bad_chunk_at)
        self.bad_chunk_open = False

    def note_uncounted(self, where: int) -> None:
        """The chunk at byte ``where`` lost an unknown number of messages (its channels, if indexed)."""
        channels = self.chunk_channels.get(where)
        if channels is None:
            self.result.uncounted_loss_any = True
        else:
            self.uncounted_channels |= channels

    def add_channel(self, channel_id: int, schema_id: int, topic: str, encoding: str) -> None:
        """Note a channel (a definition without a known schema does not replace one with it)."""
        msgtype = self.schemas.get(schema_id, "")
        known = self.result.channels.get(channel_id)
        if known is not None and known.msgtype and not msgtype:
            return
        self.result.channels[channel_id] = ChannelInfo(channel_id, topic, msgtype, encoding)

    def walk_chunk(self, data: bytes, where: int) -> None:
        """Walk the records of one (CRC-checked) chunk and feed its messages per wanted channel."""
        end = len(data)
        pos = 0
        messages: list[int] = []
        append = messages.append
        unpack_record = RECORD.unpack_from
        try:
            while pos < end:
                opcode, length = unpack_record(data, pos)
                if opcode == OP_MESSAGE:
                    append(pos)
                elif opcode == OP_CHANNEL:
                    self.add_channel(*parse_channel(data, pos + 9))
                elif opcode == OP_SCHEMA:
                    self.add_schema(*parse_schema(data, pos + 9))
                pos += 9 + length
            if pos != end:
                raise ValueError(f"last record runs {pos - end} bytes past the chunk end")
        except (ValueError, struct.error, UnicodeDecodeError) as error:
            self.result.damage.append(f"{self.path.name}: chunk at byte {where}: malformed record ({error})")
            self.note_uncounted(where)
            if messages and messages[-1] + 9 + 22 > end:
                messages.pop()
        if messages:
            self.pending.append((data, np.array(messages, dtype=np.int64)))
            self.pending_bytes += len(data)
            if self.pending_bytes >= _BATCH_BYTES:
                self.flush()

    def flush(self) -> None:
        """Feed the chunks walked so far as one batch (fewer, larger numpy operations)."""
        if not self.pending:
            return
        if len(self.pending) == 1:
            data, starts = self.pending[0]
        else:
            bases = np.cumsum([0] + [len(d) for d, _ in self.pending[:-1]])
            starts = np.concatenate([s + base for (_, s), base in zip(self.pending, bases.tolist(), strict=True)])
            data = b"".join(d for d, _ in self.pending)
        self.pending.clear()
        self.pending_bytes = 0
        self.feed(data, starts)

    def feed(self, data: bytes, starts: np.ndarray) -> None:
        """Feed the message records starting at ``starts`` (byte offsets in ``data``) per wanted channel."""
        buf = np.frombuffer(data, dtype=np.uint8)
        head = byte_windows(buf, starts, 9 + 22)  # opcode, length, message header
        length = head[:, 1:9].copy().view("<u8")[:, 0].astype(np.int64) - 22
        channel = head[:, 9:11].copy().view("<u2")[:, 0]
        log_ns = head[:, 15:23].copy().view("<i8")[:, 0]
        offsets = starts + 9 + 22
        inside = (length >= 0) & (offsets + length <= buf.size)
        self.result.messages_seen += int(inside.sum())
        for cid in np.unique(channel).tolist():
            info = self.result.channels.get(cid)
            mask = (channel == cid) & inside
            if info is None:
                self.result.orphans += int(mask.sum())
            elif self.sink.wants(info):
                self.deliver(info, buf, offsets[mask], length[mask], log_ns[mask])

    def deliver(
        self, info: ChannelInfo, buf: np.ndarray, offsets: np.ndarray, lengths: np.ndarray, log_ns: np.ndarray
    ) -> None:
        """Feed a wanted channel's messages, first expanding any compressed one by one (rosbag2 message mode)."""
        if info.encoding == "cdr":
            plain = decompress_cdr_messages(buf, offsets, lengths, log_ns)
            self.result.messages_decompressed += plain.decompressed
            if plain.failed:
                self.result.damage.append(
                    f"{self.path.name}: {plain.failed} compressed messages on {info.topic} do not decompress "
                    f"({plain.first_error}); they are dropped"
                )
            buf, offsets, lengths, log_ns = plain.buf, plain.offsets, plain.lengths, plain.log_ns
        if offsets.size:
            self.sink.feed(info, buf, offsets, lengths, log_ns)
