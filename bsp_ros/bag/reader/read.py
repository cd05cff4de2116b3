"""Read a rosbag2 MCAP bag (directory or single ``.mcap``) into a Session, fast, reporting every loss."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np

from bsp_ros.bag.cell_metadata import stated_from_custom_data
from bsp_ros.bag.layout import resolve_bag
from bsp_ros.bag.mcap_scan import ProgressCallback, ScanResult, scan_mcap
from bsp_ros.bag.metadata import BagMetadata
from bsp_ros.bag.reader.counts import Losses, TopicCounter, expected_message_counts
from bsp_ros.bag.reader.refusals import (
    check_types,
    refuse_damage,
    refuse_empty_bag,
    refuse_wrong_channels,
    require_streams,
)
from bsp_ros.bag.reader.rotation import usable_transform, wrench_rotation
from bsp_ros.bag.reader.sink import Collected, SessionSink, Streams, collect_streams
from bsp_ros.bag.report import ReadReport
from bsp_ros.bag.topics import StatedRotation, TopicMap
from bsp_ros.core.streams import MarkerSeries, Session, WrenchSeries
from msg_adapters.rotation_track import TransformBuffer


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


def read_session(
    path: str | Path,
    *,
    topics: TopicMap | None = None,
    world_frame: str | None = None,
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
    world_frame : name of the ``world`` frame (default: ``topics.world_frame``, ``world``).
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
    world_frame = world_frame or topic_map.world_frame
    aliases = dict(frame_aliases or {})
    root = Path(path)
    report = ReadReport(path=str(root))
    files, metadata = _resolve_files(root, report)
    report.files = [str(f) for f in files]
    report.bytes_total = sum(f.stat().st_size for f in files)
    expected_types = topic_map.expected_types()
    if metadata is not None:
        report.present.update({name: entry.msgtype for name, entry in metadata.topics.items()})
        check_types(report.present, expected_types)

    sink = SessionSink(topic_map)
    scans = _scan_files(files, sink, report, progress)
    refuse_wrong_channels(sink, report.present, expected_types)
    losses = Losses.of_scans(scans)
    counter = TopicCounter(report, sink.streams, expected_types, expected_message_counts(metadata, scans), losses)
    refuse_empty_bag(root, report, scans, counter.expected, losses)

    streams = collect_streams(sink, topic_map, report.present)
    _count_streams(streams, topic_map, world_frame, counter)
    transforms = _read_transforms(sink, topic_map, counter, (topic_map.tf_static, topic_map.tf))
    topic_transforms = _read_transforms(sink, topic_map, counter, (topic_map.transform,))
    stated = topic_map.stated or _stated_in_metadata(metadata, report)
    _warn_of_anomalies(report)

    # Required streams (the robot's handle pose stands in for the hand marker).
    handle_pose = _handle_pose(streams.pose)
    may_be_lost = _topics_may_be_lost(metadata, scans, losses)
    require_streams(streams, topic_map, report, sink.streams, handle_pose is not None, may_be_lost)
    if strict:
        refuse_damage(root, report)

    rotations = _Rotations(transforms, topic_transforms, stated)
    session = _session(streams, handle_pose, rotations, world_frame, aliases, report)
    return BagRead(session, report, _receive_times(streams, handle_pose))


def _resolve_files(path: Path, report: ReadReport) -> tuple[list[Path], BagMetadata | None]:
    """The bag's MCAP files and metadata (:func:`bsp_ros.bag.layout.resolve_bag`), noting its findings."""
    layout = resolve_bag(path)
    report.warnings.extend(layout.warnings)
    report.damage.extend(layout.damage)
    return layout.files, layout.metadata


def _scan_files(
    files: Sequence[Path], sink: SessionSink, report: ReadReport, progress: ProgressCallback | None
) -> list[ScanResult]:
    """Scan every file into ``sink``, noting the topics present, the chunks read and the damage in ``report``."""
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
    return scans


def _count_streams(streams: Streams, topic_map: TopicMap, world_frame: str, counter: TopicCounter) -> None:
    """Report the wrench and position topics: counts, frames, stamps, non-finite values."""
    t_w, v_w, _, frames_w, _ = streams.wrench
    wrench_report = counter.count(topic_map.wrench, t_w.size)
    wrench_report.frame_ids = frames_w
    wrench_report.note_stamps(t_w)
    wrench_report.non_finite = int((~np.isfinite(v_w)).any(axis=1).sum())

    positions = [(topic_map.markers[name], data) for name, data in streams.markers.items()]
    if streams.pose is not None:
        positions.append((topic_map.handle_pose, streams.pose))
    for topic, (t_m, v_m, _f, frames_m, _log) in positions:
        rep = counter.count(topic, t_m.size)
        rep.frame_ids = frames_m
        rep.note_stamps(t_m)
        rep.non_finite = int((~np.isfinite(v_m[:, :3])).any(axis=1).sum())
        foreign = [f for f in frames_m if f != world_frame]
        if foreign:
            counter.report.warnings.append(f"{rep.topic}: positions stamped in {foreign}, expected {world_frame}")
    if topic_map.emg and (topic_map.emg in counter.report.present or topic_map.emg in counter.streams):
        emg = streams.emg
        rep = counter.count(topic_map.emg, 0 if emg is None else emg.t_ns.size + emg.other_layout)
        if emg is not None:
            rep.frame_ids = list(emg.channels)
            rep.note_stamps(emg.t_ns)


def _read_transforms(
    sink: SessionSink, topic_map: TopicMap, counter: TopicCounter, topics: tuple[str, ...]
) -> TransformBuffer:
    """Report transform ``topics`` (/tf_static and /tf, or the TransformStamped topic) and buffer their usable
    transforms, in receive order (/tf_static's as fixed)."""
    transforms = TransformBuffer()
    for topic in topics:
        if not topic:
            continue
        stream = sink.streams.get(topic)
        if topic in counter.report.present:
            rep = counter.count(topic, len(stream.transforms) if stream else 0)
            if stream is not None:
                samples = [s for _, batch in stream.transforms for s in batch]
                rep.frame_ids = sorted({s.parent_frame for s in samples})
                stamps = np.array([s.t_ns for s in samples], dtype=np.int64)
                rep.nonpositive_stamps = int((stamps <= 0).sum())
                if stamps.size:
                    rep.first_stamp_ns, rep.last_stamp_ns = int(stamps.min()), int(stamps.max())
                for _receive_ns, batch in sorted(stream.transforms, key=lambda item: item[0]):
                    usable = [s for s in batch if usable_transform(s)]
                    rep.non_finite += len(batch) - len(usable)
                    (transforms.add_static if topic == topic_map.tf_static else transforms.add)(usable)
    return transforms


def _warn_of_anomalies(report: ReadReport) -> None:
    """Warn of the questionable samples returned, the chunks without CRC, and each damaged place."""
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


def _handle_pose(pose: Collected | None) -> MarkerSeries | None:
    """The robot's handle pose as a marker (None without messages)."""
    if pose is not None and pose[0].size:
        return MarkerSeries(t_ns=pose[0], position_m=np.ascontiguousarray(pose[1][:, :3]))
    return None


def _topics_may_be_lost(metadata: BagMetadata | None, scans: list[ScanResult], losses: Losses) -> bool:
    """Without metadata.yaml the topic list comes from the Channel records that survived, and some loss belongs
    to a channel unknown: a topic may have been lost, not missing."""
    orphans = sum(scan.orphans for scan in scans)
    return bool(metadata is None and not all(scan.channels_complete for scan in scans) and (losses.unknown or orphans))


class _Rotations(NamedTuple):
    """What the wrench's rotation may come from: TF, the TransformStamped topic, a cell's stated mounting."""

    tf: TransformBuffer
    topic: TransformBuffer
    stated: StatedRotation | None


def _stated_in_metadata(metadata: BagMetadata | None, report: ReadReport) -> StatedRotation | None:
    """The sensor mounting `bsp record` wrote into ``metadata.yaml`` from its cell file (None: none, or unusable,
    with a warning)."""
    if metadata is None:
        return None
    stated, problem = stated_from_custom_data(metadata.custom)
    if problem:
        report.warnings.append(problem)
    return stated


def _session(
    streams: Streams,
    handle_pose: MarkerSeries | None,
    rotations: _Rotations,
    world_frame: str,
    frame_aliases: Mapping[str, str],
    report: ReadReport,
) -> Session:
    """The Session of the collected streams, the wrench rotated into ``world_frame`` (warnings to ``report``)."""
    t_w, v_w, _, frames_w, _ = streams.wrench
    wrench_frame = frames_w[0] if frames_w else world_frame
    rotation = wrench_rotation(
        rotations.tf, t_w, wrench_frame, world_frame, frame_aliases, report, rotations.topic, rotations.stated
    )
    markers = {
        name: MarkerSeries(t_ns=data[0], position_m=np.ascontiguousarray(data[1][:, :3]))
        for name, data in streams.markers.items()
        if data[0].size
    }
    report.n_segments = 3 if "wrist" in markers else 2
    if "wrist" in streams.markers and "wrist" not in markers:
        report.warnings.append("the wrist marker topic has no messages: the chain is read as 2 segments")
    return Session(
        wrench=WrenchSeries(
            t_ns=t_w,
            force_n=np.ascontiguousarray(v_w[:, :3]),
            torque_nm=np.ascontiguousarray(v_w[:, 3:]),
            frame_id=wrench_frame,
        ),
        markers=markers,
        rotation_world_from_sensor=rotation,
        handle_pose=handle_pose,
        emg=streams.emg,
    )


def _receive_times(streams: Streams, handle_pose: MarkerSeries | None) -> dict[str, np.ndarray]:
    """Stream name -> receive (log) times of the streams the session holds."""
    receive = {"wrench": streams.wrench[4]}
    receive.update({name: data[4] for name, data in streams.markers.items() if data[0].size})
    if handle_pose is not None and streams.pose is not None:
        receive["handle_pose"] = streams.pose[4]
    if streams.emg is not None:
        receive["emg"] = streams.emg.t_ns
    return receive
