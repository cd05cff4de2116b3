"""Test helpers: a session bag rewritten in the layouts real tools write (mcap writer options, rosbags Writer
storage and compression modes), and a chunk of an MCAP file damaged with its true content known."""

from __future__ import annotations

import struct
from collections import Counter
from io import BytesIO
from pathlib import Path
from typing import Any

import yaml
from mcap.data_stream import ReadDataStream
from mcap.reader import NonSeekingReader, make_reader
from mcap.records import Chunk, Message
from mcap.stream_reader import breakup_chunk
from mcap.writer import Writer
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin
from rosbags.rosbag2 import Writer as RosbagsWriter
from rosbags.typesys import Stores, get_typestore

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
_CHUNK = 0x06


def raw_messages(bag: Path) -> list[tuple[str, str, int, bytes]]:
    """(topic, type, log time, CDR) of every message of a bag's single ``.mcap``, in file order."""
    (file,) = bag.glob("*.mcap")
    with file.open("rb") as stream:
        return [
            (channel.topic, schema.name, message.log_time, bytes(message.data))
            for schema, channel, message in make_reader(stream).iter_messages(log_time_order=False)
        ]


def write_mcap(bag: Path, out: Path, **writer_options: Any) -> Path:
    """The messages of ``bag`` as one ``.mcap`` written by the mcap package's Writer with ``writer_options``
    (``repeat_channels``, ``use_statistics``, ``index_types``, ``chunk_size``, ``compression``...)."""
    (file,) = bag.glob("*.mcap")
    with file.open("rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        assert summary is not None
        messages = [(channel.id, message) for _, channel, message in reader.iter_messages(log_time_order=False)]
    with out.open("wb") as stream:
        writer = Writer(stream, **writer_options)
        writer.start(profile="ros2", library="test bag_layouts")
        schema_ids = {sid: writer.register_schema(s.name, s.encoding, s.data) for sid, s in summary.schemas.items()}
        channel_ids = {
            cid: writer.register_channel(c.topic, c.message_encoding, schema_ids[c.schema_id], dict(c.metadata))
            for cid, c in summary.channels.items()
        }
        for cid, message in messages:
            writer.add_message(
                channel_ids[cid],
                log_time=message.log_time,
                data=message.data,
                publish_time=message.publish_time,
                sequence=message.sequence,
            )
        writer.finish()
    return out


def write_rosbags(
    bag: Path, out: Path, storage: StoragePlugin = StoragePlugin.MCAP, mode: CompressionMode | None = None
) -> Path:
    """The messages of ``bag`` rewritten by rosbags' Writer (rosbag2 version 9) with ``storage`` and ``mode``
    (zstd) compression."""
    messages = raw_messages(bag)
    writer = RosbagsWriter(out, version=9, storage_plugin=storage)
    if mode is not None:
        writer.set_compression(mode, CompressionFormat.ZSTD)
    with writer:
        connections: dict[str, Any] = {}
        for topic, msgtype, log_ns, data in messages:
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, msgtype, typestore=TYPESTORE)
            writer.write(connections[topic], log_ns, data)
    return out


def edit_metadata(bag: Path, **changes: Any) -> None:
    """Set keys of ``rosbag2_bagfile_information`` in ``bag/metadata.yaml``."""
    path = bag / "metadata.yaml"
    meta = yaml.safe_load(path.read_text())
    meta["rosbag2_bagfile_information"].update(changes)
    path.write_text(yaml.safe_dump(meta, sort_keys=False))


def chunk_offsets(file: Path) -> list[int]:
    """Byte offsets of the top-level Chunk records of an MCAP file, in order."""
    data = file.read_bytes()
    offsets, pos = [], 8
    while pos + 9 <= len(data):
        opcode, length = struct.unpack_from("<BQ", data, pos)
        if opcode == _CHUNK:
            offsets.append(pos)
        if opcode == 0x02:  # Footer
            break
        pos += 9 + length
    return offsets


def damage_chunk(file: Path, index: int) -> Counter[str]:
    """Flip a byte in the middle of the stored records of chunk ``index``; return its messages per topic
    (mcap's own decoding of the intact chunk: the truth of what is lost)."""
    with file.open("rb") as stream:
        topics = {c.id: c.topic for _, c, _ in NonSeekingReader(stream).iter_messages(log_time_order=False)}
    data = bytearray(file.read_bytes())
    offset = chunk_offsets(file)[index]
    (length,) = struct.unpack_from("<Q", data, offset + 1)
    chunk = Chunk.read(ReadDataStream(BytesIO(bytes(data[offset + 9 : offset + 9 + length]))))
    held = Counter(topics[r.channel_id] for r in breakup_chunk(chunk) if isinstance(r, Message))
    data[offset + 9 + length - len(chunk.data) // 2] ^= 0x5A
    file.write_bytes(bytes(data))
    return held
