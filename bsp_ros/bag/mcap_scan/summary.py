"""An MCAP file's summary section (CRC-checked), its statistics' counts by topic, and the data-section CRC."""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

from mcap.reader import make_reader
from mcap.records import Statistics

from bsp_ros.bag.mcap_scan.interface import ScanResult
from bsp_ros.bag.mcap_scan.records import MCAP_MAGIC, OP_FOOTER, STRING
from bsp_ros.bag.mcap_scan.scanner import Scanner


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
        if opcode != OP_FOOTER or length != 20 or not stored or not 0 < summary_start <= footer_at:
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


def preload_summary(path: Path, scanner: Scanner) -> None:
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
        scanner.summary_channel_counts = channel_counts(summary.statistics)


def check_data_crc(result: ScanResult, path: Path, body: bytes, computed: int) -> None:
    """Compare the data-section CRC of the DataEnd record (0: not written) with ``computed``."""
    if len(body) >= 4:
        (stored,) = STRING.unpack_from(body, 0)
        if stored and stored != computed:
            result.damage.append(
                f"{path.name}: data-section CRC mismatch (stored {stored:#010x}, computed {computed:#010x}): "
                "bytes outside the chunk contents are damaged (indexes or record headers)"
            )


def channel_counts(statistics: Statistics) -> dict[int, int] | None:
    """Per-channel message counts of a Statistics record; None if it has messages but no per-channel counts
    (the field is optional: an empty map then means unknown, not zero)."""
    counts = {int(cid): int(n) for cid, n in statistics.channel_message_counts.items()}
    if statistics.message_count and sum(counts.values()) != statistics.message_count:
        return None
    return counts


def _topic_counts(per_channel: dict[int, int], result: ScanResult) -> dict[str, int]:
    counts: dict[str, int] = {}
    for cid, count in per_channel.items():
        topic = _topic_of(result, cid)
        counts[topic] = counts.get(topic, 0) + count
    return counts


def _topic_of(result: ScanResult, cid: int) -> str:
    info = result.channels.get(cid)
    return info.topic if info is not None else f"<channel {cid}>"


def resolve_counts(scanner: Scanner) -> None:
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
