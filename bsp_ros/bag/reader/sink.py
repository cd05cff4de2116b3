"""Decode the mapped topics' raw messages from the scanner into per-topic streams (bulk where possible)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bsp_ros.bag.cdr import FIXED_LAYOUT_FLOATS, decode_fixed, decode_tf_message, decode_transform_stamped
from bsp_ros.bag.emg_cdr import EMG_TYPE, decode_envelope
from bsp_ros.bag.emg_read import collect_envelopes
from bsp_ros.bag.mcap_scan import ChannelInfo
from bsp_ros.bag.topics import TF_TYPE, TRANSFORM_TYPE, TopicMap
from bsp_ros.core.streams import EmgSeries
from msg_adapters import (
    TransformSample,
    read_pose_stamped,
    read_tf_message,
    read_wrench_stamped,
)
from msg_adapters.tf import read_transform_stamped

#: A stream's stamps, values, frame indexes, frame names and receive times (:func:`collect_stream`).
Collected = tuple[np.ndarray, np.ndarray, np.ndarray, list[str], np.ndarray]


@dataclass(kw_only=True)
class Stream:
    """Accumulates the decoded messages of one topic."""

    topic: str
    msgtype: str
    t_ns: list[np.ndarray] = field(default_factory=list)
    values: list[np.ndarray] = field(default_factory=list)
    frame_index: list[np.ndarray] = field(default_factory=list)
    log_ns: list[np.ndarray] = field(default_factory=list)
    frames: dict[str, int] = field(default_factory=dict)
    transforms: list[tuple[int, list[TransformSample]]] = field(default_factory=list)
    undecodable: int = 0
    first_error: str = ""


class SessionSink:
    """Takes the mapped topics' messages from the scanner and decodes them (bulk where possible)."""

    def __init__(self, topics: TopicMap) -> None:
        self.expected = topics.expected_types()
        self.streams: dict[str, Stream] = {}
        self.wrong: dict[str, set[str]] = {}
        self.unsupported: list[str] = []
        self._typestore: Any = None

    @property
    def typestore(self) -> Any:
        """rosbags' Jazzy type store, loaded only when a message needs it (a non-fixed layout or a damaged one)."""
        if self._typestore is None:
            from rosbags.typesys import Stores, get_typestore  # imports most bags never need

            self._typestore = get_typestore(Stores.ROS2_JAZZY)
        return self._typestore

    def wants(self, channel: ChannelInfo) -> bool:
        """Whether ``channel`` is a mapped topic of the expected type in CDR (the others are noted as wrong or
        unsupported)."""
        want = self.expected.get(channel.topic)
        if want is None:
            return False
        if channel.msgtype != want:
            self.wrong.setdefault(channel.topic, set()).add(channel.msgtype or "<no schema>")
            return False
        if channel.encoding != "cdr":
            self.unsupported.append(f"{channel.topic} is encoded as {channel.encoding!r}, not cdr")
            return False
        return True

    def stream(self, channel: ChannelInfo) -> Stream:
        """The stream collecting ``channel``'s topic, made on its first message."""
        stream = self.streams.get(channel.topic)
        if stream is None:
            stream = self.streams[channel.topic] = Stream(topic=channel.topic, msgtype=channel.msgtype)
        return stream

    def feed(
        self, channel: ChannelInfo, buf: np.ndarray, offsets: np.ndarray, lengths: np.ndarray, log_ns: np.ndarray
    ) -> None:
        """Decode messages ``buf[offsets[i]:offsets[i] + lengths[i]]`` of ``channel``: fixed layouts in bulk, a
        message the bulk decoder cannot take (and every other type) through rosbags."""
        stream = self.stream(channel)
        n_floats = FIXED_LAYOUT_FLOATS.get(channel.msgtype)
        if n_floats is None:
            self._feed_generic(stream, buf, offsets, lengths, log_ns)
            return
        batch = decode_fixed(buf, offsets, lengths, n_floats, stream.frames)
        for i in np.flatnonzero(~batch.ok):
            decoded = self._deserialize(stream, buf, int(offsets[i]), int(lengths[i]))
            if decoded is None:
                continue
            if n_floats == 6:
                sample = read_wrench_stamped(decoded)
                batch.t_ns[i] = sample.t_ns
                batch.values[i] = np.concatenate([sample.force_n, sample.torque_nm])
                frame = sample.frame_id
            else:
                pose = read_pose_stamped(decoded)
                batch.t_ns[i] = pose.t_ns
                batch.values[i] = np.concatenate([pose.position_m, pose.orientation_xyzw])
                frame = pose.frame_id
            batch.frame_index[i] = stream.frames.setdefault(frame, len(stream.frames))
        keep = batch.frame_index >= 0
        stream.t_ns.append(batch.t_ns[keep])
        stream.values.append(batch.values[keep])
        stream.frame_index.append(batch.frame_index[keep])
        stream.log_ns.append(log_ns[keep])

    def _deserialize(self, stream: Stream, buf: np.ndarray, offset: int, length: int) -> Any:
        try:
            return self.typestore.deserialize_cdr(buf[offset : offset + length].tobytes(), stream.msgtype)
        except Exception as error:  # any failure to decode these bytes counts them as undecodable
            stream.undecodable += 1
            stream.first_error = stream.first_error or f"{error.__class__.__name__}: {error}"
            return None

    def _feed_generic(
        self, stream: Stream, buf: np.ndarray, offsets: np.ndarray, lengths: np.ndarray, log_ns: np.ndarray
    ) -> None:
        for offset, length, log in zip(offsets.tolist(), lengths.tolist(), log_ns.tolist(), strict=True):
            raw = buf[offset : offset + length].tobytes()
            if stream.msgtype == EMG_TYPE:
                self._feed_envelope(stream, raw, int(log))
                continue
            if stream.msgtype == TF_TYPE:
                transforms = decode_tf_message(raw)
            elif stream.msgtype == TRANSFORM_TYPE:
                one = decode_transform_stamped(raw)
                transforms = None if one is None else [one]
            else:
                transforms = None
            if transforms is not None:
                stream.transforms.append((int(log), transforms))
                continue
            decoded = self._deserialize(stream, buf, offset, length)
            if decoded is None or stream.msgtype not in (TF_TYPE, TRANSFORM_TYPE):
                continue
            try:
                read = read_tf_message(decoded) if stream.msgtype == TF_TYPE else [read_transform_stamped(decoded)]
                stream.transforms.append((int(log), read))
            except ValueError as error:
                stream.undecodable += 1
                stream.first_error = stream.first_error or str(error)

    @staticmethod
    def _feed_envelope(stream: Stream, raw: bytes, log_ns: int) -> None:
        """One EMG envelope message: its values as a row, its channel names as the row's frame, its log time as its
        stamp (the message carries none)."""
        decoded = decode_envelope(raw)
        if decoded is None:
            stream.undecodable += 1
            stream.first_error = stream.first_error or "not a little-endian CDR Float32MultiArray"
            return
        channels, values = decoded
        stream.t_ns.append(np.array([log_ns], dtype=np.int64))
        stream.values.append(values)
        stream.frame_index.append(np.array([stream.frames.setdefault(",".join(channels), len(stream.frames))]))
        stream.log_ns.append(np.array([log_ns], dtype=np.int64))


def collect_stream(stream: Stream | None, n_floats: int) -> Collected:
    """Stamps, values, frame indexes, frame names and receive times of a stream, in receive order."""
    if stream is None or not stream.t_ns:
        empty = np.zeros(0, dtype=np.int64)
        return empty, np.zeros((0, n_floats)), empty, [], empty
    t_ns = np.concatenate(stream.t_ns)
    values = np.concatenate(stream.values)
    frame_index = np.concatenate(stream.frame_index)
    log_ns = np.concatenate(stream.log_ns)
    if log_ns.size > 1 and (np.diff(log_ns) < 0).any():
        order = np.argsort(log_ns, kind="stable")
        t_ns, values, frame_index, log_ns = t_ns[order], values[order], frame_index[order], log_ns[order]
    names = sorted(stream.frames, key=stream.frames.__getitem__)
    return t_ns, values, frame_index, names, log_ns


@dataclass
class Streams:
    """The streams of a session, collected in receive order (:data:`Collected` each).

    Attributes
    ----------
    wrench : the wrench topic's (empty if it has no message).
    markers : marker name -> its topic's, for the marker topics the bag has.
    pose : the robot's handle pose, if the bag has its topic and it is not a marker topic.
    emg : the EMG envelope topic's messages (:func:`bsp_ros.bag.emg_read.collect_envelopes`), if the bag has them.
    """

    wrench: Collected
    markers: dict[str, Collected]
    pose: Collected | None
    emg: EmgSeries | None = None


def collect_streams(sink: SessionSink, topic_map: TopicMap, present: Mapping[str, str]) -> Streams:
    """Collect the wrench, marker and handle pose streams a sink decoded.

    Parameters
    ----------
    sink : the sink the bag's files were scanned into.
    topic_map : the topics of the streams.
    present : topic -> type of every topic the bag has.

    Returns
    -------
    Streams
    """
    wrench = collect_stream(sink.streams.get(topic_map.wrench), 6)
    markers = {}
    for name, topic in topic_map.markers.items():
        if topic in present or topic in sink.streams:
            markers[name] = collect_stream(sink.streams.get(topic), 7)
    pose_topic = topic_map.handle_pose
    pose = None
    if pose_topic not in topic_map.markers.values() and (pose_topic in present or pose_topic in sink.streams):
        pose = collect_stream(sink.streams.get(pose_topic), 7)
    return Streams(wrench, markers, pose, collect_envelopes(sink.streams.get(topic_map.emg)) if topic_map.emg else None)
