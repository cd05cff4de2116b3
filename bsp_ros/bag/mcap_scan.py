"""Stream the raw message records of one MCAP file chunk by chunk, checking chunk CRCs, surviving damage."""

from __future__ import annotations

import struct
import zlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from io import BytesIO
from pathlib import Path
from typing import BinaryIO, Protocol

import numpy as np
from mcap.data_stream import ReadDataStream
from mcap.exceptions import McapError
from mcap.opcode import Opcode
from mcap.reader import make_reader
from mcap.records import Chunk, Message, MessageIndex, Metadata, Statistics

from bsp_ros.bag.compression import decompress_cdr_messages, sniff_compressed_file
from bsp_ros.bag.errors import NotABagError, UnsupportedBagError

MCAP_MAGIC = b"\x89MCAP0\r\n"
_OP_SCHEMA, _OP_CHANNEL, _OP_MESSAGE = Opcode.SCHEMA, Opcode.CHANNEL, Opcode.MESSAGE
_OP_CHUNK, _OP_MESSAGE_INDEX, _OP_FOOTER = Opcode.CHUNK, Opcode.MESSAGE_INDEX, Opcode.FOOTER
_OP_STATISTICS, _OP_METADATA, _OP_DATA_END = Opcode.STATISTICS, Opcode.METADATA, Opcode.DATA_END
_RECORD = struct.Struct("<BQ")
_BATCH_BYTES = 4 * 2**20  # chunks are decoded in batches of about this size
_STRING = struct.Struct("<I")
_CHANNEL_HEAD = struct.Struct("<HH")

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


@dataclass
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


def _read_string(data: bytes, pos: int) -> tuple[str, int]:
    (size,) = _STRING.unpack_from(data, pos)
    end = pos + 4 + size
    if end > len(data):
        raise ValueError("string runs past its record")
    return data[pos + 4 : end].decode("utf-8"), end


def _parse_schema(data: bytes, pos: int) -> tuple[int, str]:
    (schema_id,) = struct.unpack_from("<H", data, pos)
    name, _ = _read_string(data, pos + 2)
    return schema_id, name


def _parse_channel(data: bytes, pos: int) -> tuple[int, int, str, str]:
    channel_id, schema_id = _CHANNEL_HEAD.unpack_from(data, pos)
    topic, pos = _read_string(data, pos + 4)
    encoding, _ = _read_string(data, pos)
    return channel_id, schema_id, topic, encoding


def _decompress(chunk: Chunk) -> bytes:
    if chunk.compression == "":
        return chunk.data
    if chunk.compression == "zstd":
        import zstandard

        return bytes(zstandard.ZstdDecompressor().decompress(chunk.data, max_output_size=chunk.uncompressed_size))
    if chunk.compression == "lz4":
        import lz4.frame

        return bytes(lz4.frame.decompress(chunk.data))
    raise UnsupportedBagError(f"MCAP chunk compression {chunk.compression!r} is not supported")


class _Scanner:
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
        unpack_record = _RECORD.unpack_from
        try:
            while pos < end:
                opcode, length = unpack_record(data, pos)
                if opcode == _OP_MESSAGE:
                    append(pos)
                elif opcode == _OP_CHANNEL:
                    self.add_channel(*_parse_channel(data, pos + 9))
                elif opcode == _OP_SCHEMA:
                    self.add_schema(*_parse_schema(data, pos + 9))
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
        head = buf[starts[:, None] + np.arange(9 + 22, dtype=np.int64)]  # opcode, length, message header
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


def _summary_crc_ok(path: Path, result: ScanResult) -> bool:
    """False if the file has a summary section whose CRC (in the footer) does not match (damage noted)."""
    size = path.stat().st_size
    footer_at = size - len(MCAP_MAGIC) - 29
    if footer_at < len(MCAP_MAGIC):
        return True
    with path.open("rb") as stream:
        stream.seek(footer_at)
        footer = stream.read(29)
        opcode, length, summary_start, _, stored = struct.unpack("<BQQQI", footer)
        if opcode != _OP_FOOTER or length != 20 or not stored or not 0 < summary_start <= footer_at:
            return True  # no footer here (truncated) or no summary CRC: nothing to check
        stream.seek(summary_start)
        computed = zlib.crc32(stream.read(footer_at + 25 - summary_start))
    if computed != stored:
        result.damage.append(
            f"{path.name}: summary CRC mismatch (stored {stored:#010x}, computed {computed:#010x}): "
            "the summary is ignored"
        )
        return False
    return True


def _preload_summary(path: Path, scanner: _Scanner) -> None:
    """Read schemas, channels and statistics from the summary section, if the file has an intact one."""
    if not _summary_crc_ok(path, scanner.result):
        return
    try:
        with path.open("rb") as stream:
            summary = make_reader(stream).get_summary()
    except Exception:  # a damaged footer or summary just means: no summary
        return
    if summary is None:
        return
    for schema in summary.schemas.values():
        scanner.add_schema(schema.id, schema.name)
    for channel in summary.channels.values():
        scanner.add_channel(channel.id, channel.schema_id, channel.topic, channel.message_encoding)
    stats = summary.statistics
    scanner.result.channels_complete = bool(summary.channels) and (
        stats is None or stats.channel_count == len(summary.channels)
    )
    for index in summary.chunk_indexes:
        if index.message_index_offsets:  # empty when the chunk has no message indexes: no channel list then
            scanner.chunk_channels[index.chunk_start_offset] = set(index.message_index_offsets)
    if summary.statistics is not None:
        scanner.summary_channel_counts = _channel_counts(summary.statistics)


def check_mcap_magic(path: Path) -> None:
    """Raise NotABagError unless ``path`` starts with the MCAP magic."""
    with path.open("rb") as stream:
        head = stream.read(16)
    if head.startswith(MCAP_MAGIC):
        return
    kind = sniff_compressed_file(head)
    if kind is not None:
        raise UnsupportedBagError(f"{path} is {kind}")
    raise NotABagError(f"{path} is not an MCAP file (it does not start with the MCAP magic)")


class _FramingError(Exception):
    """The record framing cannot be followed any further (a truncated or corrupt file)."""


def _records(stream: BinaryIO, size: int) -> Iterator[tuple[int, int, bytes, bytes]]:
    """Yield ``(opcode, offset, head, body)`` of each top-level record after the magic, to the footer.

    Raises
    ------
    _FramingError
        If the file ends inside a record or a record claims to run past the end of the file.
    """
    offset = stream.tell()
    while True:
        head = stream.read(9)
        if len(head) < 9:
            raise _FramingError(f"the file ends at byte {offset + len(head)} without a footer (truncated)")
        opcode, length = _RECORD.unpack(head)
        if offset + 9 + length > size:
            raise _FramingError(
                f"the record at byte {offset} (opcode {opcode:#04x}) claims {length} bytes but the file ends "
                f"at byte {size} (truncated or corrupt)"
            )
        yield opcode, offset, head, stream.read(length)
        offset += 9 + length
        if opcode == _OP_FOOTER:
            return


def scan_mcap(
    path: Path,
    sink: MessageSink,
    progress: Callable[[int], None] | None = None,
) -> ScanResult:
    """Feed every intact message of the wanted channels of ``path`` to ``sink``, in file order.

    Chunks whose CRC does not match are not fed (their indexed message counts are reported); reading
    stops where the record framing cannot be followed (a truncated file: everything before the cut).

    Parameters
    ----------
    path : the MCAP file.
    sink : decides which channels to take and receives their raw messages.
    progress : called with the bytes of ``path`` read so far.

    Returns
    -------
    ScanResult
    """
    check_mcap_magic(path)
    result = ScanResult()
    scanner = _Scanner(path, sink, result)
    _preload_summary(path, scanner)
    size = path.stat().st_size
    with path.open("rb") as stream:
        stream.seek(len(MCAP_MAGIC))
        data_crc = zlib.crc32(MCAP_MAGIC)
        in_summary = False
        try:
            for opcode, offset, head, body in _records(stream, size):
                if opcode == _OP_DATA_END:
                    _check_data_crc(result, path, body, data_crc)
                    in_summary = True
                data_crc = zlib.crc32(body, zlib.crc32(head, data_crc))
                if in_summary:
                    continue  # the summary was read (CRC-checked) up front; only its framing is followed here
                if opcode == _OP_MESSAGE_INDEX:
                    if scanner.bad_chunk_open:
                        _count_bad_chunk_index(scanner, body)
                    continue
                scanner.close_bad_chunk()
                try:
                    _read_record(scanner, opcode, body, offset)
                except UnsupportedBagError:
                    raise
                except (McapError, ValueError, struct.error, UnicodeDecodeError) as error:
                    if opcode == _OP_CHUNK:
                        scanner.open_bad_chunk(offset)
                        result.crc_errors += 1
                    result.damage.append(f"{path.name}: record at byte {offset} is malformed ({error}); skipped")
                if opcode == _OP_CHUNK and progress is not None:
                    progress(stream.tell())
        except _FramingError as error:
            result.truncated = True
            result.damage.append(f"{path.name}: {error}; nothing after it is read")
        scanner.close_bad_chunk()
        scanner.flush()
        if progress is not None:
            progress(size)
    _resolve_counts(scanner)
    return result


def _count_bad_chunk_index(scanner: _Scanner, body: bytes) -> None:
    """Add the entries of a message index following a damaged chunk to that channel's loss."""
    try:
        index = MessageIndex.read(ReadDataStream(BytesIO(body)))
    except (McapError, ValueError, struct.error):
        return  # a damaged index: if no other one counts this chunk, its loss stays uncounted
    scanner.bad_chunk_indexed = True
    cid = index.channel_id
    scanner.lost_channel_counts[cid] = scanner.lost_channel_counts.get(cid, 0) + len(index.records)


def _topic_of(result: ScanResult, cid: int) -> str:
    info = result.channels.get(cid)
    return info.topic if info is not None else f"<channel {cid}>"


def _resolve_counts(scanner: _Scanner) -> None:
    """Name per topic the per-channel counts (statistics, losses), now that every Channel record was seen.

    A summary need not repeat the Channel records (rosbag2 ``noRepeatedChannels``, mcap
    ``repeat_channels=False``): its Statistics counts by channel id then resolve only with the channels
    defined in the data section.
    """
    result = scanner.result
    for cid, count in scanner.lost_channel_counts.items():
        topic = _topic_of(result, cid)
        result.lost_in_bad_chunks[topic] = result.lost_in_bad_chunks.get(topic, 0) + count
    result.uncounted_loss |= {_topic_of(result, cid) for cid in scanner.uncounted_channels}
    if scanner.summary_channel_counts is not None:
        result.summary_counts = _topic_counts(scanner.summary_channel_counts, result)


def _check_data_crc(result: ScanResult, path: Path, body: bytes, computed: int) -> None:
    """Compare the data-section CRC of the DataEnd record (0: not written) with ``computed``."""
    if len(body) >= 4:
        (stored,) = _STRING.unpack_from(body, 0)
        if stored and stored != computed:
            result.damage.append(
                f"{path.name}: data-section CRC mismatch (stored {stored:#010x}, computed {computed:#010x}): "
                "bytes outside the chunk contents are damaged (indexes or record headers)"
            )


def _read_record(scanner: _Scanner, opcode: int, body: bytes, offset: int) -> None:
    """Act on one top-level record (a chunk, a schema or channel definition, statistics, metadata)."""
    result = scanner.result
    if opcode == _OP_CHUNK:
        _read_chunk(scanner, Chunk.read(ReadDataStream(BytesIO(body))), offset)
    elif opcode == _OP_SCHEMA:
        scanner.add_schema(*_parse_schema(body, 0))
    elif opcode == _OP_CHANNEL:
        scanner.add_channel(*_parse_channel(body, 0))
    elif opcode == _OP_MESSAGE:
        _read_loose_message(scanner, Message.read(ReadDataStream(BytesIO(body)), len(body)))
    elif opcode == _OP_STATISTICS and scanner.summary_channel_counts is None:
        scanner.summary_channel_counts = _channel_counts(Statistics.read(ReadDataStream(BytesIO(body))))
    elif opcode == _OP_METADATA:
        metadata = Metadata.read(ReadDataStream(BytesIO(body)))
        if metadata.name == "rosbag2":
            result.rosbag2_metadata = metadata.metadata.get("serialized_metadata")


def _channel_counts(statistics: Statistics) -> dict[int, int] | None:
    """Per-channel message counts of a Statistics record; None if it has messages but no per-channel counts
    (the field is optional: an empty map then means unknown, not zero)."""
    counts = {int(cid): int(n) for cid, n in statistics.channel_message_counts.items()}
    if statistics.message_count and sum(counts.values()) != statistics.message_count:
        return None
    return counts


def _topic_counts(channel_counts: dict[int, int], result: ScanResult) -> dict[str, int]:
    counts: dict[str, int] = {}
    for cid, count in channel_counts.items():
        topic = _topic_of(result, cid)
        counts[topic] = counts.get(topic, 0) + count
    return counts


def _read_chunk(scanner: _Scanner, chunk: Chunk, where: int) -> None:
    result = scanner.result
    try:
        data = _decompress(chunk)
    except UnsupportedBagError:
        raise
    except Exception as error:  # any decompressor failure is damage
        result.crc_errors += 1
        scanner.open_bad_chunk(where)
        result.damage.append(f"{scanner.path.name}: chunk at byte {where} does not decompress ({error})")
        return
    if chunk.uncompressed_crc == 0:
        result.chunks_without_crc += 1
    elif zlib.crc32(data) != chunk.uncompressed_crc:
        result.crc_errors += 1
        scanner.open_bad_chunk(where)
        result.damage.append(
            f"{scanner.path.name}: chunk at byte {where} fails its CRC "
            f"(stored {chunk.uncompressed_crc:#010x}, computed {zlib.crc32(data):#010x}); its messages are dropped"
        )
        return
    if len(data) != chunk.uncompressed_size:
        result.damage.append(f"{scanner.path.name}: chunk at byte {where} has a wrong uncompressed size")
    result.chunks_read += 1
    scanner.walk_chunk(data, where)


def _read_loose_message(scanner: _Scanner, message: Message) -> None:
    scanner.result.messages_seen += 1
    info = scanner.result.channels.get(message.channel_id)
    if info is None:
        scanner.result.orphans += 1
        return
    if scanner.sink.wants(info):
        data = bytes(message.data)
        scanner.deliver(
            info,
            np.frombuffer(data, dtype=np.uint8),
            np.zeros(1, dtype=np.int64),
            np.array([len(data)], dtype=np.int64),
            np.array([message.log_time], dtype=np.int64),
        )
