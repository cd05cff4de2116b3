"""Read a rosbag2 MCAP bag (directory or single ``.mcap``) into a Session, fast, reporting every loss."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from rosbags.typesys import Stores, get_typestore

from bsp_ros.bag.cdr import FIXED_LAYOUT_FLOATS, decode_fixed, decode_tf_message
from bsp_ros.bag.errors import (
    BagCorruptError,
    EmptyBagError,
    MessageTypeError,
    MissingTopicError,
    UnsupportedBagError,
)
from bsp_ros.bag.layout import resolve_bag
from bsp_ros.bag.mcap_scan import ChannelInfo, ProgressCallback, ScanResult, scan_mcap
from bsp_ros.bag.metadata import BagMetadata
from bsp_ros.bag.report import ReadReport, TopicReport
from bsp_ros.bag.topics import TF_TYPE, WORLD_FRAME, TopicMap
from bsp_ros.core.streams import MarkerSeries, Session, WrenchSeries
from msg_adapters import (
    TransformSample,
    read_pose_stamped,
    read_tf_message,
    read_wrench_stamped,
)
from msg_adapters.rotation_track import RotationTrack, TransformBuffer

REQUIRED_MARKERS = ("shoulder", "elbow", "hand")


class BagRead(NamedTuple):
    """The result of :func:`read_session`.

    Attributes
    ----------
    session : the streams, in receive order (stamps as recorded, nothing dropped or fixed).
    report : what the read found (:class:`ReadReport`).
    receive_ns : stream name (``wrench``, marker names) -> (N,) int64 receive (log) times, ns.
    """

    session: Session
    report: ReadReport
    receive_ns: dict[str, np.ndarray]


@dataclass
class _Stream:
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


class _SessionSink:
    """Takes the mapped topics' messages from the scanner and decodes them (bulk where possible)."""

    def __init__(self, topics: TopicMap) -> None:
        self.expected = topics.expected_types()
        self.streams: dict[str, _Stream] = {}
        self.wrong: dict[str, set[str]] = {}
        self.unsupported: list[str] = []
        self._typestore: Any = None

    @property
    def typestore(self) -> Any:
        if self._typestore is None:
            self._typestore = get_typestore(Stores.ROS2_JAZZY)
        return self._typestore

    def wants(self, channel: ChannelInfo) -> bool:
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

    def stream(self, channel: ChannelInfo) -> _Stream:
        stream = self.streams.get(channel.topic)
        if stream is None:
            stream = self.streams[channel.topic] = _Stream(channel.topic, channel.msgtype)
        return stream

    def feed(
        self, channel: ChannelInfo, buf: np.ndarray, offsets: np.ndarray, lengths: np.ndarray, log_ns: np.ndarray
    ) -> None:
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

    def _deserialize(self, stream: _Stream, buf: np.ndarray, offset: int, length: int) -> Any:
        try:
            return self.typestore.deserialize_cdr(buf[offset : offset + length].tobytes(), stream.msgtype)
        except Exception as error:  # any failure to decode these bytes counts them as undecodable
            stream.undecodable += 1
            stream.first_error = stream.first_error or f"{error.__class__.__name__}: {error}"
            return None

    def _feed_generic(
        self, stream: _Stream, buf: np.ndarray, offsets: np.ndarray, lengths: np.ndarray, log_ns: np.ndarray
    ) -> None:
        for offset, length, log in zip(offsets.tolist(), lengths.tolist(), log_ns.tolist(), strict=True):
            if stream.msgtype == TF_TYPE:
                transforms = decode_tf_message(buf[offset : offset + length].tobytes())
                if transforms is not None:
                    stream.transforms.append((int(log), transforms))
                    continue
            decoded = self._deserialize(stream, buf, offset, length)
            if decoded is None:
                continue
            if stream.msgtype == TF_TYPE:
                try:
                    stream.transforms.append((int(log), read_tf_message(decoded)))
                except ValueError as error:
                    stream.undecodable += 1
                    stream.first_error = stream.first_error or str(error)


def _collect(stream: _Stream | None, n_floats: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[str], np.ndarray]:
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


def _resolve_files(path: Path, report: ReadReport) -> tuple[list[Path], BagMetadata | None]:
    """The bag's MCAP files and metadata (:func:`bsp_ros.bag.layout.resolve_bag`), noting its findings."""
    layout = resolve_bag(path)
    report.warnings.extend(layout.warnings)
    report.damage.extend(layout.damage)
    return layout.files, layout.metadata


def _topic_report(stream: _Stream | None, topic: str, msgtype: str, expected: int | None) -> TopicReport:
    report = TopicReport(topic=topic, msgtype=msgtype, expected=expected)
    if stream is not None:
        report.undecodable = stream.undecodable
    return report


@dataclass
class _Losses:
    """What the scans know of the messages lost to damage, for topics whose expected count is unknown.

    Attributes
    ----------
    counted : topic -> messages listed in the message indexes of damaged chunks.
    uncounted : topics that lost an unknown number of messages (damaged chunks without message indexes).
    unknown : some loss cannot be attributed to a topic (truncation, damaged chunks of unknown channels,
        channels defined only in lost parts): any topic may have lost messages.
    """

    counted: dict[str, int] = field(default_factory=dict)
    uncounted: set[str] = field(default_factory=set)
    unknown: bool = False

    def add(self, scan: ScanResult) -> None:
        for topic, count in scan.lost_in_bad_chunks.items():
            self.counted[topic] = self.counted.get(topic, 0) + count
        self.uncounted |= scan.uncounted_loss
        self.unknown = self.unknown or scan.truncated or scan.uncounted_loss_any
        self.unknown = self.unknown or any(t.startswith("<channel ") for t in scan.lost_in_bad_chunks)

    def of(self, topic: str, damaged: bool) -> int | None:
        """Messages of ``topic`` lost, None if unknown (never 0 where messages may have been lost)."""
        if topic in self.uncounted or (damaged and self.unknown):
            return None
        if topic in self.counted:
            return self.counted[topic]
        return 0 if damaged else None


def _finish_counts(report: TopicReport, read: int, lost_to_damage: int | None, warnings: list[str]) -> None:
    report.read = read
    if report.expected is not None:
        missing = report.expected - read - report.undecodable
        if missing < 0:
            warnings.append(f"{report.topic}: {read} messages read but the bag lists only {report.expected}")
        report.lost = max(0, missing)
    else:
        report.lost = lost_to_damage
    if report.lost:
        warnings.append(f"{report.topic}: {report.lost} of {report.expected or '?'} messages lost")
    if report.undecodable:
        warnings.append(f"{report.topic}: {report.undecodable} messages could not be decoded and are not returned")


def _rotation(
    transforms: TransformBuffer,
    t_ns: np.ndarray,
    wrench_frame: str,
    world_frame: str,
    frame_aliases: Mapping[str, str],
    report: ReadReport,
) -> np.ndarray:
    """R_world_from_wrench: (3, 3) for a fixed chain, (N, 3, 3) at each wrench stamp when a /tf link turns.

    A turning chain is slerped between its /tf samples (:class:`msg_adapters.rotation_track.TransformBuffer`);
    wrench samples before its first or after its last /tf sample hold the nearest orientation (see
    :func:`held_warning`).
    """
    if wrench_frame == world_frame:
        report.rotation_source = "tf"
        return np.eye(3)
    source = wrench_frame
    track = transforms.track(world_frame, source, t_ns)
    if track is None and wrench_frame in frame_aliases:
        source = frame_aliases[wrench_frame]
        track = transforms.track(world_frame, source, t_ns) if source != world_frame else None
        if source == world_frame or track is not None:
            report.rotation_source = "alias"
            report.warnings.append(f"wrench frame {wrench_frame} taken as {source} (frame mapping option)")
            return np.eye(3) if track is None else track.session_rotation
    if track is None:
        report.rotation_source = "assumed"
        report.warnings.append(
            f"no transform connects the wrench frame {wrench_frame} to {world_frame}: "
            f"the wrench is taken as given in {world_frame}"
        )
        return np.eye(3)
    report.rotation_source = "tf"
    warning = held_warning(track, t_ns, f"{wrench_frame} -> {world_frame}")
    if warning:
        report.warnings.append(warning)
    return track.session_rotation


# Wrench samples at most this far outside the /tf track hold its nearest orientation without a warning: the
# streams of a recording start and stop a fraction of a second apart.
HOLD_QUIET_S = 0.5


def held_warning(track: RotationTrack, t_ns: np.ndarray, what: str) -> str:
    """A warning when wrench samples lie more than :data:`HOLD_QUIET_S` outside a turning /tf track ('' if not).

    They are held at the track's nearest orientation, not dropped: the reader returns the streams as
    recorded, and at the ends of a recording the turning handle (moved at the arm's ~2 deg/s) errs by
    less than the sensor noise over the fraction of a second the streams start and stop apart. A longer
    hold (a /tf publisher that started late or died) is named so the user can judge the estimate.
    """
    count, longest_s = track.held_summary(t_ns)
    if count == 0 or longest_s <= HOLD_QUIET_S:
        return ""
    return (
        f"the rotation {what} turns (from /tf) but {count} of {np.asarray(t_ns).size} wrench samples lie outside "
        f"its /tf samples (up to {longest_s:.3g} s): the nearest orientation is held there"
    )


def read_session(
    path: str | Path,
    *,
    topics: TopicMap | None = None,
    world_frame: str = WORLD_FRAME,
    frame_aliases: Mapping[str, str] | None = None,
    strict: bool = False,
    progress: ProgressCallback | None = None,
) -> BagRead:
    """Read a session bag: a rosbag2 directory (``metadata.yaml`` + ``.mcap``) or a single ``.mcap``.

    WrenchStamped and PoseStamped messages are decoded in bulk from their CDR bytes (bit-exact);
    anything else through rosbags. Chunks failing their CRC and the part of a truncated file past the
    damage are not returned; the loss is counted per topic against ``metadata.yaml`` (or the MCAP
    summary). Out-of-order or duplicate stamps and non-finite values are returned as recorded and
    counted in the report. Messages are returned in receive (log time) order.

    Parameters
    ----------
    path : bag directory, its ``metadata.yaml``, or an ``.mcap`` file.
    topics : topic names (default: docs/contract.md's).
    world_frame : name of the ``world`` frame.
    frame_aliases : frame id -> frame it coincides with (no rotation), used when TF does not connect
        the wrench frame to ``world_frame`` (e.g. ``{"ft_link": "world"}`` silences the warning).
    strict : raise :class:`BagCorruptError` on any CRC error, truncation or lost message instead of
        returning the intact part.
    progress : called with ``(bytes_read, bytes_total)``.

    Returns
    -------
    BagRead
        ``(session, report, receive_ns)``.

    Raises
    ------
    BagNotFoundError, NotABagError, EmptyBagError, MissingTopicError, MessageTypeError,
    BagCorruptError, UnsupportedBagError
        All subclasses of :class:`bsp_ros.errors.BagError`, each with a ``code``.
    """
    topic_map = topics or TopicMap()
    aliases = dict(frame_aliases or {})
    root = Path(path)
    report = ReadReport(path=str(root))
    files, metadata = _resolve_files(root, report)
    report.files = [str(f) for f in files]
    report.bytes_total = sum(f.stat().st_size for f in files)
    expected_types = topic_map.expected_types()

    if metadata is not None:
        report.present.update({name: entry.msgtype for name, entry in metadata.topics.items()})
        _check_types(report.present, expected_types)

    sink = _SessionSink(topic_map)
    scans: list[ScanResult] = []
    done = 0
    for file in files:
        base = done

        def on_progress(n: int, base: int = base) -> None:
            report.bytes_read = base + n
            if progress is not None:
                progress(report.bytes_read, report.bytes_total)

        scan = scan_mcap(file, sink, on_progress)
        scans.append(scan)
        done += file.stat().st_size
        for channel in scan.channels.values():
            report.present.setdefault(channel.topic, channel.msgtype)
        report.crc_errors += scan.crc_errors
        report.chunks_read += scan.chunks_read
        report.chunks_without_crc += scan.chunks_without_crc
        report.truncated = report.truncated or scan.truncated
        report.damage.extend(scan.damage)
        if scan.orphans:
            report.warnings.append(f"{file.name}: {scan.orphans} messages on channels whose definition was lost")
    if sink.wrong:
        topic, found = sorted(sink.wrong.items())[0]
        raise MessageTypeError(topic, expected_types[topic], found)
    _check_types(report.present, expected_types)
    if sink.unsupported:
        raise UnsupportedBagError("; ".join(sorted(set(sink.unsupported))))

    expected_counts = _expected_counts(metadata, scans)
    losses = _Losses()
    for scan in scans:
        losses.add(scan)

    total_expected = sum(expected_counts.values()) if expected_counts is not None else 0
    seen = sum(scan.messages_seen for scan in scans)
    orphans = sum(scan.orphans for scan in scans)
    nothing_lost = not (losses.counted or losses.uncounted or losses.unknown)
    if not report.present or (seen == 0 and total_expected == 0 and nothing_lost):
        if report.damaged:
            raise BagCorruptError(
                f"{root}: no intact message survives ({_damage_summary(report.damage)})", report.crc_errors, None
            )
        raise EmptyBagError(f"{root} holds no messages")

    # Streams.
    wrench_topic = topic_map.wrench
    t_w, v_w, _, frames_w, log_w = _collect(sink.streams.get(wrench_topic), 6)
    marker_data = {}
    for name, topic in topic_map.markers.items():
        if topic in report.present or topic in sink.streams:
            marker_data[name] = _collect(sink.streams.get(topic), 7)
    pose_topic = topic_map.handle_pose
    pose_data = None
    if pose_topic not in topic_map.markers.values() and (pose_topic in report.present or pose_topic in sink.streams):
        pose_data = _collect(sink.streams.get(pose_topic), 7)

    def topic_report(topic: str, read: int) -> TopicReport:
        expected = None if expected_counts is None else expected_counts.get(topic, 0)
        stream = sink.streams.get(topic)
        rep = _topic_report(stream, topic, report.present.get(topic, expected_types[topic]), expected)
        _finish_counts(rep, read, losses.of(topic, report.damaged), report.warnings)
        report.topics[topic] = rep
        return rep

    wrench_report = topic_report(wrench_topic, t_w.size)
    wrench_report.frame_ids = frames_w
    wrench_report.note_stamps(t_w)
    wrench_report.non_finite = int((~np.isfinite(v_w)).any(axis=1).sum())

    positions = [(topic_map.markers[name], data) for name, data in marker_data.items()]
    if pose_data is not None:
        positions.append((pose_topic, pose_data))
    for topic, (t_m, v_m, _f, frames_m, _log) in positions:
        rep = topic_report(topic, t_m.size)
        rep.frame_ids = frames_m
        rep.note_stamps(t_m)
        rep.non_finite = int((~np.isfinite(v_m[:, :3])).any(axis=1).sum())
        foreign = [f for f in frames_m if f != world_frame]
        if foreign:
            report.warnings.append(f"{rep.topic}: positions stamped in {foreign}, expected {world_frame}")

    transforms = TransformBuffer()
    for topic in (topic_map.tf_static, topic_map.tf):
        stream = sink.streams.get(topic)
        if topic in report.present:
            rep = topic_report(topic, len(stream.transforms) if stream else 0)
            if stream is not None:
                samples = [s for _, batch in stream.transforms for s in batch]
                rep.frame_ids = sorted({s.parent_frame for s in samples})
                stamps = np.array([s.t_ns for s in samples], dtype=np.int64)
                rep.nonpositive_stamps = int((stamps <= 0).sum())
                if stamps.size:
                    rep.first_stamp_ns, rep.last_stamp_ns = int(stamps.min()), int(stamps.max())
                for _receive_ns, batch in sorted(stream.transforms, key=lambda item: item[0]):
                    usable = [s for s in batch if _usable_transform(s)]
                    rep.non_finite += len(batch) - len(usable)
                    (transforms.add_static if topic == topic_map.tf_static else transforms.add)(usable)

    for rep in report.topics.values():
        for label, count in (
            ("non-finite (or zero-quaternion) values", rep.non_finite),
            ("stamps earlier than the previous one", rep.out_of_order),
            ("stamps equal to the previous one", rep.duplicate_stamps),
            ("stamps at or before time 0", rep.nonpositive_stamps),
        ):
            if count:
                report.warnings.append(f"{rep.topic}: {count} samples with {label} (returned as recorded)")
    if report.chunks_without_crc:
        report.warnings.append(
            f"{report.chunks_without_crc} chunks carry no CRC: damage inside them cannot be detected"
        )
    for line in report.damage:
        report.warnings.append(f"damage: {line}")
    if report.damaged and report.lost_messages is None:
        report.warnings.append(
            "the bag is damaged and neither metadata.yaml, an MCAP summary nor the message indexes of the damaged "
            "chunks give the message counts: the number of lost messages is unknown"
        )

    # Required streams (the robot's handle pose stands in for the hand marker).
    handle_pose = None
    if pose_data is not None and pose_data[0].size:
        handle_pose = MarkerSeries(t_ns=pose_data[0], position_m=np.ascontiguousarray(pose_data[1][:, :3]))
    required = [m for m in REQUIRED_MARKERS if not (handle_pose is not None and m == "hand")]
    for name, topic, count in [("wrench", wrench_topic, t_w.size)] + [
        (m, topic_map.markers[m], marker_data[m][0].size if m in marker_data else 0) for m in required
    ]:
        if topic not in report.present and (name == "wrench" or name not in marker_data):
            if metadata is None and not all(scan.channels_complete for scan in scans) and (losses.unknown or orphans):
                # Without metadata.yaml the topic list comes from the Channel records that survived, and some
                # loss belongs to a channel unknown: the topic may have been lost, not missing.
                raise BagCorruptError(
                    f"required topic {topic} is not among the topics that survive the damage "
                    f"({', '.join(sorted(report.present)) or 'none'}; {_damage_summary(report.damage)})",
                    report.crc_errors,
                    report.lost_messages,
                )
            raise MissingTopicError(topic, report.present)
        if count == 0:
            _refuse_empty_stream(topic, report, sink.streams.get(topic))
    if len(frames_w) > 1:
        raise UnsupportedBagError(f"{wrench_topic} carries several frame ids {frames_w}: one is expected")

    if strict and (report.damaged or report.lost_messages):
        raise BagCorruptError(
            f"{root} is damaged: {report.crc_errors} CRC errors, "
            f"{'truncated, ' if report.truncated else ''}{report.lost_messages} messages lost",
            report.crc_errors,
            report.lost_messages,
        )

    wrench_frame = frames_w[0] if frames_w else world_frame
    rotation = _rotation(transforms, t_w, wrench_frame, world_frame, aliases, report)
    markers = {
        name: MarkerSeries(t_ns=data[0], position_m=np.ascontiguousarray(data[1][:, :3]))
        for name, data in marker_data.items()
        if data[0].size
    }
    report.n_segments = 3 if "wrist" in markers else 2
    if "wrist" in marker_data and "wrist" not in markers:
        report.warnings.append("the wrist marker topic has no messages: the chain is read as 2 segments")
    session = Session(
        wrench=WrenchSeries(
            t_ns=t_w,
            force_n=np.ascontiguousarray(v_w[:, :3]),
            torque_nm=np.ascontiguousarray(v_w[:, 3:]),
            frame_id=wrench_frame,
        ),
        markers=markers,
        rotation_world_from_sensor=rotation,
        handle_pose=handle_pose,
    )
    receive = {"wrench": log_w}
    receive.update({name: data[4] for name, data in marker_data.items() if data[0].size})
    if handle_pose is not None and pose_data is not None:
        receive["handle_pose"] = pose_data[4]
    return BagRead(session, report, receive)


def _damage_summary(damage: list[str]) -> str:
    """The damaged places of a bag in one short phrase: how many, and the first (a person reads one line; the
    full list is in the estimate's bag section and the warnings)."""
    if len(damage) <= 1:
        return "".join(damage)
    return f"{len(damage)} damaged places, the first: {damage[0]}"


def _refuse_empty_stream(topic: str, report: ReadReport, stream: _Stream | None) -> None:
    """Raise the error that says why a required topic returned no message."""
    rep = report.topics.get(topic)
    if report.damaged or (rep is not None and (rep.lost or rep.undecodable)):
        causes = [f"{report.crc_errors} CRC errors"] + (["truncated"] if report.truncated else [])
        if rep is not None and rep.lost:
            causes.append(f"{rep.lost} of the {rep.expected} messages the bag lists are not in its files")
        if rep is not None and rep.undecodable and stream is not None:
            causes.append(f"{rep.undecodable} messages do not decode ({stream.first_error})")
        if report.damage:
            causes.append(_damage_summary(report.damage))
        raise BagCorruptError(
            f"{topic}: no intact message survives ({'; '.join(causes)})",
            report.crc_errors,
            report.lost_messages,
        )
    raise MissingTopicError(topic, report.present, detail="has no messages")


def _usable_transform(sample: TransformSample) -> bool:
    """A transform with a finite, non-zero quaternion (others cannot give a rotation)."""
    q = sample.rotation_xyzw
    return bool(np.isfinite(q).all() and np.any(q != 0.0))


def _check_types(present: Mapping[str, str], expected: Mapping[str, str]) -> None:
    for topic, msgtype in sorted(present.items()):
        want = expected.get(topic)
        if want is not None and msgtype and msgtype != want:
            raise MessageTypeError(topic, want, [msgtype])


def _expected_counts(metadata: BagMetadata | None, scans: list[ScanResult]) -> dict[str, int] | None:
    if metadata is not None and metadata.topics:
        return {name: entry.message_count for name, entry in metadata.topics.items()}
    if scans and all(scan.summary_counts is not None for scan in scans):
        counts: dict[str, int] = {}
        for scan in scans:
            for topic, count in (scan.summary_counts or {}).items():
                counts[topic] = counts.get(topic, 0) + count
        return counts
    return None
