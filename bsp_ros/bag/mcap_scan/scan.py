"""Stream the raw message records of one MCAP file chunk by chunk, checking chunk CRCs, surviving damage."""

from __future__ import annotations

import struct
import zlib
from collections.abc import Callable
from io import BytesIO
from pathlib import Path

import numpy as np
from mcap.data_stream import ReadDataStream
from mcap.exceptions import McapError
from mcap.records import Chunk, Message, MessageIndex, Metadata, Statistics

from bsp_ros.bag.errors import UnsupportedBagError
from bsp_ros.bag.mcap_scan.interface import MessageSink, ScanResult
from bsp_ros.bag.mcap_scan.records import (
    MCAP_MAGIC,
    OP_CHANNEL,
    OP_CHUNK,
    OP_DATA_END,
    OP_MESSAGE,
    OP_MESSAGE_INDEX,
    OP_METADATA,
    OP_SCHEMA,
    OP_STATISTICS,
    FramingError,
    check_mcap_magic,
    decompress_chunk,
    iter_records,
    parse_channel,
    parse_schema,
)
from bsp_ros.bag.mcap_scan.scanner import Scanner
from bsp_ros.bag.mcap_scan.summary import channel_counts, check_data_crc, preload_summary, resolve_counts


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
    scanner = Scanner(path, sink, result)
    preload_summary(path, scanner)
    size = path.stat().st_size
    with path.open("rb") as stream:
        stream.seek(len(MCAP_MAGIC))
        data_crc = zlib.crc32(MCAP_MAGIC)
        in_summary = False
        try:
            for opcode, offset, head, body in iter_records(stream, size):
                if opcode == OP_DATA_END:
                    check_data_crc(result, path, body, data_crc)
                    in_summary = True
                data_crc = zlib.crc32(body, zlib.crc32(head, data_crc))
                if in_summary:
                    continue  # the summary was read (CRC-checked) up front; only its framing is followed here
                if opcode == OP_MESSAGE_INDEX:
                    if scanner.bad_chunk_open:
                        _count_bad_chunk_index(scanner, body)
                    continue
                scanner.close_bad_chunk()
                try:
                    _read_record(scanner, opcode, body, offset)
                except UnsupportedBagError:
                    raise
                except (McapError, ValueError, struct.error, UnicodeDecodeError) as error:
                    if opcode == OP_CHUNK:
                        scanner.open_bad_chunk(offset)
                        result.crc_errors += 1
                    result.damage.append(f"{path.name}: record at byte {offset} is malformed ({error}); skipped")
                if opcode == OP_CHUNK and progress is not None:
                    progress(stream.tell())
        except FramingError as error:
            result.truncated = True
            result.damage.append(f"{path.name}: {error}; nothing after it is read")
        scanner.close_bad_chunk()
        scanner.flush()
        if progress is not None:
            progress(size)
    resolve_counts(scanner)
    return result


def _count_bad_chunk_index(scanner: Scanner, body: bytes) -> None:
    """Add the entries of a message index following a damaged chunk to that channel's loss."""
    try:
        index = MessageIndex.read(ReadDataStream(BytesIO(body)))
    except (McapError, ValueError, struct.error):
        return  # a damaged index: if no other one counts this chunk, its loss stays uncounted
    scanner.bad_chunk_indexed = True
    cid = index.channel_id
    scanner.lost_channel_counts[cid] = scanner.lost_channel_counts.get(cid, 0) + len(index.records)


def _read_record(scanner: Scanner, opcode: int, body: bytes, offset: int) -> None:
    """Act on one top-level record (a chunk, a schema or channel definition, statistics, metadata)."""
    result = scanner.result
    if opcode == OP_CHUNK:
        _read_chunk(scanner, Chunk.read(ReadDataStream(BytesIO(body))), offset)
    elif opcode == OP_SCHEMA:
        scanner.add_schema(*parse_schema(body, 0))
    elif opcode == OP_CHANNEL:
        scanner.add_channel(*parse_channel(body, 0))
    elif opcode == OP_MESSAGE:
        _read_loose_message(scanner, Message.read(ReadDataStream(BytesIO(body)), len(body)))
    elif opcode == OP_STATISTICS and scanner.summary_channel_counts is None:
        scanner.summary_channel_counts = channel_counts(Statistics.read(ReadDataStream(BytesIO(body))))
    elif opcode == OP_METADATA:
        metadata = Metadata.read(ReadDataStream(BytesIO(body)))
        if metadata.name == "rosbag2":
            result.rosbag2_metadata = metadata.metadata.get("serialized_metadata")


def _read_chunk(scanner: Scanner, chunk: Chunk, where: int) -> None:
    result = scanner.result
    try:
        data = decompress_chunk(chunk)
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


def _read_loose_message(scanner: Scanner, message: Message) -> None:
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
