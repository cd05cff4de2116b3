"""The MCAP conformance input files (foxglove/mcap tests/conformance/data), rebuilt at test time.

The upstream files are stored there as Git LFS objects, out of reach of CI; this module writes the same
files, byte for byte, from the published ``mcap`` package's record classes. Each input (a few records) is
written once per valid combination of the conformance feature flags:

``ch`` chunks (one uncompressed chunk holding schemas, channels and messages), ``mx`` message indexes after
the chunk, ``chx`` a chunk index, ``st`` a Statistics record, ``rsh``/``rch`` the schemas/channels repeated
in the summary, ``ax``/``mdx`` attachment/metadata indexes, ``sum`` summary offsets, ``pad`` three extra
bytes (``01 ff ff``) at the end of every record that may carry them (not messages, chunks, data end, footer,
nor the records inside a chunk).

``CONFORMANCE_SHA256`` (test/data/mcap_conformance_sha256.txt) holds the SHA-256 of each upstream file, as
its LFS pointer records it; the tests check every rebuilt file against it.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Iterator
from dataclasses import dataclass, field
from itertools import combinations
from pathlib import Path

from mcap.data_stream import RecordBuilder
from mcap.opcode import Opcode
from mcap.records import (
    Attachment,
    AttachmentIndex,
    Channel,
    Chunk,
    ChunkIndex,
    DataEnd,
    Footer,
    Header,
    McapRecord,
    Message,
    MessageIndex,
    Metadata,
    MetadataIndex,
    Schema,
    Statistics,
    SummaryOffset,
)

MAGIC = b"\x89MCAP0\r\n"
PAD = b"\x01\xff\xff"
FEATURES = ("ch", "mx", "st", "rsh", "rch", "ax", "mdx", "chx", "sum", "pad")
SHA256_FILE = Path(__file__).resolve().parents[2] / "data" / "mcap_conformance_sha256.txt"

_TEN_LOG_TIMES = (0, 2, 1, 3, 3, 5, 4, 7, 8, 9)
_SCHEMA = Schema(id=1, name="Example", encoding="c", data=bytes([4, 5, 6]))
_CHANNEL = Channel(id=1, topic="example", message_encoding="a", schema_id=1, metadata={"foo": "bar"})
_ONE_MESSAGE = Message(channel_id=1, sequence=10, log_time=2, publish_time=1, data=bytes([1, 2, 3]))

#: Input name -> its records, in file order.
INPUTS: dict[str, list[McapRecord]] = {
    "NoData": [],
    "OneSchemalessMessage": [
        Channel(id=1, topic="example", message_encoding="text", schema_id=0, metadata={}),
        _ONE_MESSAGE,
    ],
    "OneMessage": [_SCHEMA, _CHANNEL, _ONE_MESSAGE],
    "OneAttachment": [
        Attachment(
            log_time=2, create_time=1, name="myFile", media_type="application/octet-stream", data=bytes([1, 2, 3])
        )
    ],
    "OneMetadata": [Metadata(name="myMetadata", metadata={"foo": "bar"})],
    "TenMessages": [
        _SCHEMA,
        _CHANNEL,
        *(
            Message(channel_id=1, sequence=i, log_time=t, publish_time=t, data=bytes([1, 2, 3]))
            for i, t in enumerate(_TEN_LOG_TIMES)
        ),
    ],
}


@dataclass(frozen=True)
class Variant:
    """One conformance file: its name (``TenMessages-ch-mx-st``), input and feature flags."""

    name: str
    base: str
    features: frozenset[str] = field(default_factory=frozenset)

    @property
    def records(self) -> list[McapRecord]:
        return INPUTS[self.base]

    @property
    def messages(self) -> list[Message]:
        return [r for r in self.records if isinstance(r, Message)]


def _valid(records: list[McapRecord], features: frozenset[str]) -> bool:
    """The rules the conformance suite applies: a flag only where the input has what it indexes or repeats."""
    kinds = {type(r) for r in records}
    if "ax" in features and Attachment not in kinds:
        return False
    if "mdx" in features and Metadata not in kinds:
        return False
    if "rsh" in features and Schema not in kinds:
        return False
    if "rch" in features and Channel not in kinds:
        return False
    if not kinds & {Message, Channel, Schema} and features & {"ch", "chx", "mx"}:
        return False
    if "sum" in features and not features & {"chx", "rsh", "rch", "mdx", "ax", "st"}:
        return False
    return not (features & {"chx", "mx"} and "ch" not in features)


def variants() -> Iterator[Variant]:
    """Every conformance file: each input with each valid feature combination."""
    for base, records in INPUTS.items():
        for size in range(len(FEATURES) + 1):
            for combo in combinations(FEATURES, size):
                features = frozenset(combo)
                if _valid(records, features):
                    yield Variant("-".join([base, *sorted(features)]), base, features)


def conformance_sha256() -> dict[str, str]:
    """File name (``TenMessages-st``) -> SHA-256 of the upstream file."""
    table = {}
    for line in SHA256_FILE.read_text("utf-8").splitlines():
        if line and not line.startswith("#"):
            name, digest = line.split()
            table[name] = digest
    return table


class _Out:
    """The file being built: records appended, padded where the flag asks and the record allows."""

    def __init__(self, pad: bool) -> None:
        self.data = bytearray()
        self.pad = pad

    def record(self, record: McapRecord, pad: bool = True) -> int:
        """Append ``record``; return its length in bytes (opcode, length field and body)."""
        builder = RecordBuilder()
        record.write(builder)
        raw = builder.end()
        if self.pad and pad:
            opcode, length = struct.unpack_from("<BQ", raw)
            raw = struct.pack("<BQ", opcode, length + len(PAD)) + raw[9:] + PAD
        self.data += raw
        return len(raw)


def build(variant: Variant) -> bytes:
    """The bytes of one conformance file."""
    f = variant.features
    out = _Out("pad" in f)
    out.data += MAGIC
    out.record(Header(profile="", library=""))
    chunk = bytearray() if "ch" in f else None
    indexes: dict[int, list[tuple[int, int]]] = {}
    channel_counts: dict[int, int] = {}
    metadata_indexes: list[MetadataIndex] = []
    attachment_indexes: list[AttachmentIndex] = []
    counts = {"schema": 0, "channel": 0, "attachment": 0, "metadata": 0}
    times: list[int] = []
    for record in variant.records:
        if isinstance(record, (Schema, Channel, Message)):
            if isinstance(record, Schema):
                counts["schema"] += 1
            elif isinstance(record, Channel):
                counts["channel"] += 1
                indexes.setdefault(record.id, [])
            else:
                channel_counts[record.channel_id] = channel_counts.get(record.channel_id, 0) + 1
                times.append(record.log_time)
            if chunk is None:
                out.record(record, pad=not isinstance(record, Message))
                continue
            if isinstance(record, Message):
                indexes.setdefault(record.channel_id, []).append((record.log_time, len(chunk)))
            builder = RecordBuilder()  # records inside a chunk carry no padding
            record.write(builder)
            chunk += builder.end()
        elif isinstance(record, Attachment):
            counts["attachment"] += 1
            offset = len(out.data)
            length = out.record(record)
            if "ax" in f:
                attachment_indexes.append(
                    AttachmentIndex(
                        offset=offset,
                        length=length,
                        log_time=record.log_time,
                        create_time=record.create_time,
                        data_size=len(record.data),
                        name=record.name,
                        media_type=record.media_type,
                    )
                )
        elif isinstance(record, Metadata):
            counts["metadata"] += 1
            offset = len(out.data)
            length = out.record(record)
            if "mdx" in f:
                metadata_indexes.append(MetadataIndex(offset=offset, length=length, name=record.name))
    chunk_indexes = []
    if chunk is not None:
        start, end = (min(times), max(times)) if times else (0, 0)
        chunk_offset = len(out.data)
        chunk_length = out.record(
            Chunk(
                message_start_time=start,
                message_end_time=end,
                uncompressed_size=len(chunk),
                uncompressed_crc=zlib.crc32(chunk),
                compression="",
                data=bytes(chunk),
            ),
            pad=False,
        )
        offsets = {}
        index_length = 0
        if "mx" in f:
            for cid, entries in indexes.items():
                offsets[cid] = len(out.data)
                index_length += out.record(MessageIndex(channel_id=cid, records=entries))
        if "chx" in f:
            chunk_indexes.append(
                ChunkIndex(
                    message_start_time=start,
                    message_end_time=end,
                    chunk_start_offset=chunk_offset,
                    chunk_length=chunk_length,
                    message_index_offsets=offsets,
                    message_index_length=index_length,
                    compression="",
                    compressed_size=len(chunk),
                    uncompressed_size=len(chunk),
                )
            )
    out.record(DataEnd(data_section_crc=zlib.crc32(out.data)), pad=False)

    summary_start = len(out.data)
    groups: list[tuple[int, int, int]] = []

    def group(opcode: int, records: list[McapRecord]) -> None:
        begin = len(out.data)
        for record in records:
            out.record(record)
        if len(out.data) > begin:
            groups.append((opcode, begin, len(out.data) - begin))

    group(Opcode.SCHEMA, [r for r in variant.records if isinstance(r, Schema)] if "rsh" in f else [])
    group(Opcode.CHANNEL, [r for r in variant.records if isinstance(r, Channel)] if "rch" in f else [])
    if "st" in f:
        statistics = Statistics(
            message_count=len(times),
            schema_count=counts["schema"],
            channel_count=counts["channel"],
            attachment_count=counts["attachment"],
            metadata_count=counts["metadata"],
            chunk_count=1 if chunk is not None else 0,
            message_start_time=min(times) if times else 0,
            message_end_time=max(times) if times else 0,
            channel_message_counts=channel_counts,
        )
        group(Opcode.STATISTICS, [statistics])
    group(Opcode.METADATA_INDEX, list(metadata_indexes))
    group(Opcode.ATTACHMENT_INDEX, list(attachment_indexes))
    group(Opcode.CHUNK_INDEX, list(chunk_indexes))
    has_summary = len(out.data) != summary_start
    summary_offset_start = 0
    if "sum" in f:
        summary_offset_start = len(out.data)
        for opcode, begin, length in groups:
            out.record(SummaryOffset(group_opcode=opcode, group_start=begin, group_length=length))
    footer_head = struct.pack("<BQQQ", Opcode.FOOTER, 20, summary_start if has_summary else 0, summary_offset_start)
    summary_crc = zlib.crc32(footer_head, zlib.crc32(bytes(out.data[summary_start:])))
    out.record(
        Footer(
            summary_start=summary_start if has_summary else 0,
            summary_offset_start=summary_offset_start,
            summary_crc=summary_crc,
        ),
        pad=False,
    )
    out.data += MAGIC
    return bytes(out.data)


def write_all(directory: Path) -> dict[str, Path]:
    """Write every conformance file into ``directory``; return name -> path."""
    directory.mkdir(parents=True, exist_ok=True)
    paths = {}
    for variant in variants():
        path = directory / f"{variant.name}.mcap"
        path.write_bytes(build(variant))
        paths[variant.name] = path
    return paths
