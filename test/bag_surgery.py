"""Test helpers that alter bags written into tmp_path: drop CRCs or topics, flip one bit of a stored value."""

from __future__ import annotations

import struct
from pathlib import Path

import yaml
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer


def mcap_file(bag: Path) -> Path:
    """The bag's single ``.mcap`` file."""
    (file,) = bag.glob("*.mcap")
    return file


def rewrite_without_crcs(bag: Path, drop_topics: tuple[str, ...] = ()) -> Path:
    """Rewrite the bag's MCAP uncompressed and without chunk or data CRCs (rosbag2's default), leaving out
    ``drop_topics`` there and in ``metadata.yaml`` (a bag that lost them, or never recorded them)."""
    file = mcap_file(bag)
    with file.open("rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        assert summary is not None
        messages = [(channel.id, message) for _, channel, message in reader.iter_messages(log_time_order=False)]
        metadata = list(reader.iter_metadata())
    out = file.with_suffix(".tmp")
    with out.open("wb") as stream:
        writer = Writer(stream, compression=CompressionType.NONE, enable_crcs=False, enable_data_crcs=False)
        writer.start(profile="ros2", library="bag_surgery")
        schema_ids = {sid: writer.register_schema(s.name, s.encoding, s.data) for sid, s in summary.schemas.items()}
        channel_ids = {
            cid: writer.register_channel(c.topic, c.message_encoding, schema_ids[c.schema_id], dict(c.metadata))
            for cid, c in summary.channels.items()
            if c.topic not in drop_topics
        }
        for cid, message in messages:
            if cid in channel_ids:
                writer.add_message(
                    channel_ids[cid],
                    log_time=message.log_time,
                    data=message.data,
                    publish_time=message.publish_time,
                    sequence=message.sequence,
                )
        for record in metadata:
            writer.add_metadata(record.name, dict(record.metadata))
        writer.finish()
    out.replace(file)
    if drop_topics:
        meta_path = bag / "metadata.yaml"
        meta = yaml.safe_load(meta_path.read_text())
        info = meta["rosbag2_bagfile_information"]
        kept = [t for t in info["topics_with_message_count"] if t["topic_metadata"]["name"] not in drop_topics]
        info["message_count"] = sum(t["message_count"] for t in kept)
        info["topics_with_message_count"] = kept
        for entry in info.get("files", []):
            entry["message_count"] = info["message_count"]
        meta_path.write_text(yaml.safe_dump(meta, sort_keys=False))
    return bag


def flip_bit_of_value(bag: Path, topic: str, index: int, value: float, bit: int) -> float:
    """Flip bit ``bit`` (0 = least significant of the IEEE 754 double) of the stored ``value`` inside message
    ``index`` of ``topic``, in place in the uncompressed MCAP; return the value as it now reads."""
    file = mcap_file(bag)
    with file.open("rb") as stream:
        reader = make_reader(stream)
        payloads = [m.data for _, c, m in reader.iter_messages(topics=[topic], log_time_order=False)]
    payload = payloads[index]
    data = bytearray(file.read_bytes())
    at = data.find(payload)
    assert at >= 0 and data.find(payload, at + 1) < 0, "the message payload must appear exactly once"
    packed = struct.pack("<d", value)
    offset = payload.find(packed)
    assert offset >= 0, f"{value} is not stored in that message"
    position = at + offset + bit // 8
    data[position] ^= 1 << (bit % 8)
    file.write_bytes(bytes(data))
    (flipped,) = struct.unpack("<d", bytes(data[at + offset : at + offset + 8]))
    return float(flipped)
