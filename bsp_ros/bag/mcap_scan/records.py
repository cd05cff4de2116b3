"""MCAP record framing: the magic, opcodes, the top-level record stream, schema and channel fields, chunk data."""

from __future__ import annotations

import struct
from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO

from mcap.opcode import Opcode
from mcap.records import Chunk

from bsp_ros.bag.compression import sniff_compressed_file
from bsp_ros.bag.errors import NotABagError, UnsupportedBagError

MCAP_MAGIC = b"\x89MCAP0\r\n"
OP_SCHEMA, OP_CHANNEL, OP_MESSAGE = Opcode.SCHEMA, Opcode.CHANNEL, Opcode.MESSAGE
OP_CHUNK, OP_MESSAGE_INDEX, OP_FOOTER = Opcode.CHUNK, Opcode.MESSAGE_INDEX, Opcode.FOOTER
OP_STATISTICS, OP_METADATA, OP_DATA_END = Opcode.STATISTICS, Opcode.METADATA, Opcode.DATA_END
RECORD = struct.Struct("<BQ")
STRING = struct.Struct("<I")
_CHANNEL_HEAD = struct.Struct("<HH")


def _read_string(data: bytes, pos: int) -> tuple[str, int]:
    (size,) = STRING.unpack_from(data, pos)
    end = pos + 4 + size
    if end > len(data):
        raise ValueError("string runs past its record")
    return data[pos + 4 : end].decode("utf-8"), end


def parse_schema(data: bytes, pos: int) -> tuple[int, str]:
    """The id and name of the Schema record whose fields start at ``data[pos]``."""
    (schema_id,) = struct.unpack_from("<H", data, pos)
    name, _ = _read_string(data, pos + 2)
    return schema_id, name


def parse_channel(data: bytes, pos: int) -> tuple[int, int, str, str]:
    """The id, schema id, topic and message encoding of the Channel record whose fields start at ``data[pos]``."""
    channel_id, schema_id = _CHANNEL_HEAD.unpack_from(data, pos)
    topic, pos = _read_string(data, pos + 4)
    encoding, _ = _read_string(data, pos)
    return channel_id, schema_id, topic, encoding


def decompress_chunk(chunk: Chunk) -> bytes:
    """The records of ``chunk``, decompressed (UnsupportedBagError for an unknown compression)."""
    if chunk.compression == "":
        return chunk.data
    if chunk.compression == "zstd":
        import zstandard

        return bytes(zstandard.ZstdDecompressor().decompress(chunk.data, max_output_size=chunk.uncompressed_size))
    if chunk.compression == "lz4":
        import lz4.frame

        return bytes(lz4.frame.decompress(chunk.data))
    raise UnsupportedBagError(f"MCAP chunk compression {chunk.compression!r} is not supported")


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


class FramingError(Exception):
    """The record framing cannot be followed any further (a truncated or corrupt file)."""


def iter_records(stream: BinaryIO, size: int) -> Iterator[tuple[int, int, bytes, bytes]]:
    """Yield ``(opcode, offset, head, body)`` of each top-level record after the magic, to the footer.

    Raises
    ------
    FramingError
        If the file ends inside a record or a record claims to run past the end of the file.
    """
    offset = stream.tell()
    while True:
        head = stream.read(9)
        if len(head) < 9:
            raise FramingError(f"the file ends at byte {offset + len(head)} without a footer (truncated)")
        opcode, length = RECORD.unpack(head)
        if offset + 9 + length > size:
            raise FramingError(
                f"the record at byte {offset} (opcode {opcode:#04x}) claims {length} bytes but the file ends "
                f"at byte {size} (truncated or corrupt)"
            )
        yield opcode, offset, head, stream.read(length)
        offset += 9 + length
        if opcode == OP_FOOTER:
            return
