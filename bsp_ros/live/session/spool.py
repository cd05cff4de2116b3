"""A session's input messages, written as they arrive into a rosbag2 MCAP bag (one ``.mcap`` and metadata.yaml)."""

from __future__ import annotations

import datetime as dt
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bsp_ros import __version__
from bsp_ros.bag.errors import BagWriteError
from bsp_ros.bag.mcap_writer import started_mcap_writer
from bsp_ros.bag.metadata import (
    METADATA_FILE,
    TopicRecord,
    build_metadata,
    channel_metadata,
    dump_metadata,
    qos_profile,
)

__all__ = ["SessionSpool", "SpoolSummary", "spool_dir_name"]

# Small CRC-checked chunks: a killed recorder loses at most one open chunk (about 0.1 s of a 1 kHz wrench).
CHUNK_BYTES = 48 * 1024


def spool_dir_name(started_ns: int) -> str:
    """The bag directory name of a session started at ``started_ns`` (ns since the epoch): ``live_<UTC time>``.

    Never a subject id: a bag's name travels with the bag (file listings, `bsp sessions add` sources).
    """
    started = dt.datetime.fromtimestamp(started_ns / 1e9, tz=dt.timezone.utc)
    return "live_" + started.strftime("%Y%m%dT%H%M%S") + f"_{started_ns % 1_000_000_000 // 1_000_000:03d}Z"


@dataclass(frozen=True, kw_only=True)
class SpoolSummary:
    """What a finished spool holds.

    Attributes
    ----------
    path : the bag directory.
    counts : topic -> messages written.
    first_ns, last_ns : first and last receive time, ns since the epoch (0 when nothing was written).
    """

    path: Path
    counts: dict[str, int]
    first_ns: int
    last_ns: int

    @property
    def duration_s(self) -> float:
        """The receive span of the messages written, s."""
        return max(0, self.last_ns - self.first_ns) / 1e9


class SessionSpool:
    """Writes raw (CDR) messages of known topics into a new bag directory as they arrive, from one thread.

    Each topic's channel opens with its first message, so that ``metadata.yaml`` lists only topics that hold
    messages (a missing wrist marker then reads as a two-segment arm, as in a bag `bsp record` wrote). Channel
    and ``metadata.yaml`` carry the same fixed QoS profile (rosbags pairs them by it); log time and publish time
    are the receive time.

    Parameters
    ----------
    out_dir : the bag directory to create (must not exist; its parent is created).
    types : topic -> message type (``geometry_msgs/msg/WrenchStamped``...) of every topic that may be written.
    latched : topics offered transient-local in the bag (``/tf_static``), so that a replay latches them.

    Raises
    ------
    BagWriteError
        If ``out_dir`` exists or cannot be created.
    """

    def __init__(self, out_dir: Path, types: dict[str, str], latched: frozenset[str] = frozenset()) -> None:
        from rosbags.typesys import Stores, get_typestore

        self.path = Path(out_dir)
        if self.path.exists():
            raise BagWriteError(f"{self.path} exists already: refusing to overwrite a bag")
        try:
            self.path.mkdir(parents=True)
            self.mcap_name = f"{self.path.name}_0.mcap"
            self._stream = (self.path / self.mcap_name).open("xb")
        except OSError as error:
            raise BagWriteError(f"cannot create the session bag {self.path}: {error}") from None
        self._types = dict(types)
        self._latched = latched
        self._typestore = get_typestore(Stores.ROS2_JAZZY)
        self._writer = started_mcap_writer(self._stream, CHUNK_BYTES, "session_recorder")
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, int] = {}
        self._records: dict[str, TopicRecord] = {}
        self.counts: dict[str, int] = {}
        self.first_ns = 0
        self.last_ns = 0
        self.finished = False

    def _channel(self, topic: str) -> int:
        """The MCAP channel of ``topic``, registered (with its schema) at its first message."""
        if topic in self._channels:
            return self._channels[topic]
        msgtype = self._types[topic]
        if msgtype not in self._schemas:
            msgdef, _ = self._typestore.generate_msgdef(msgtype, ros_version=2)
            self._schemas[msgtype] = self._writer.register_schema(msgtype, "ros2msg", msgdef.encode("utf-8"))
        latched = topic in self._latched
        qos = (qos_profile(transient_local=latched, depth=1 if latched else 10),)
        record = TopicRecord(topic, msgtype, self._typestore.hash_rihs01(msgtype), qos, 0)
        self._records[topic] = record
        self._channels[topic] = self._writer.register_channel(
            topic, "cdr", self._schemas[msgtype], channel_metadata(record)
        )
        self.counts[topic] = 0
        return self._channels[topic]

    def add(self, topic: str, t_ns: int, data: bytes) -> None:
        """Write one serialized message of ``topic`` received at ``t_ns`` (ns since the epoch)."""
        channel = self._channel(topic)
        self._writer.add_message(channel, log_time=t_ns, data=data, publish_time=t_ns, sequence=self.counts[topic])
        self.counts[topic] += 1
        self.first_ns = t_ns if not self.first_ns else min(self.first_ns, t_ns)
        self.last_ns = max(self.last_ns, t_ns)

    def decode(self, topic: str, data: bytes) -> Any:
        """A serialized message of ``topic`` as a rosbags message object (e.g. to read a wrench's frame id)."""
        return self._typestore.deserialize_cdr(data, self._types[topic])

    def flush(self) -> None:
        """Close the open chunk and hand it to the OS: a killed recorder keeps everything written so far."""
        if not self.finished:
            self._writer.flush()
            self._stream.flush()

    def finish(self, custom_data: Mapping[str, str] | None = None) -> SpoolSummary:
        """Write the MCAP summary and ``metadata.yaml`` (with ``custom_data``, e.g. the sensor mounting the cell
        states); the bag is then complete (`bsp identify` reads it)."""
        if not self.finished:
            records = [
                TopicRecord(r.name, r.msgtype, r.type_hash, r.qos, self.counts[name])
                for name, r in self._records.items()
            ]
            custom = {"writer": f"bsp_ros {__version__} session_recorder", **(custom_data or {})}
            meta = build_metadata(self.mcap_name, records, self.first_ns, self.last_ns, custom)
            self._writer.add_metadata(
                "rosbag2",
                {"serialized_metadata": dump_metadata(meta["rosbag2_bagfile_information"]), "ROS_DISTRO": "jazzy"},
            )
            self._writer.finish()
            self._stream.flush()
            os.fsync(self._stream.fileno())
            self._stream.close()
            tmp = self.path / (METADATA_FILE + ".tmp")
            tmp.write_text(dump_metadata(meta), "utf-8")
            os.replace(tmp, self.path / METADATA_FILE)
            self.finished = True
        return SpoolSummary(path=self.path, counts=dict(self.counts), first_ns=self.first_ns, last_ns=self.last_ns)

    def discard(self) -> None:
        """Close and delete the bag (a reset session, or one that received nothing)."""
        if not self._stream.closed:
            self._stream.close()
        self.finished = True
        for file in self.path.iterdir():
            file.unlink()
        self.path.rmdir()
