"""Record ROS 2 topics (rclpy, serialized) into a rosbag2 MCAP bag: small CRC-checked chunks, flushed often."""

from __future__ import annotations

import logging
import os
import re
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from bsp_ros import __version__
from bsp_ros.bag.errors import BagWriteError
from bsp_ros.bag.mcap_writer import started_mcap_writer
from bsp_ros.bag.metadata import METADATA_FILE, TopicRecord, build_metadata, channel_metadata, dump_metadata
from bsp_ros.errors import DataError, InputError, RuntimeBackendError
from bsp_ros.live.sensor_topics import is_sensor_topic

__all__ = [
    "RecordReport",
    "TopicSpec",
    "offered_profile",
    "parse_topic_specs",
    "record",
    "subscription_qos",
    "transform_topic_for_tf",
]

_LOG = logging.getLogger("bsp_ros.live.recorder")

DEFAULT_CHUNK_BYTES = 48 * 1024
DEFAULT_FLUSH_S = 0.25
_TAKE_N = 256
_POLL_S = 0.1
_TOPIC_RE = re.compile(r"^(/[A-Za-z_][A-Za-z0-9_]*)+$")


@dataclass(frozen=True)
class TopicSpec:
    """A topic to record: name and (optionally) its ROS message type."""

    topic: str
    msgtype: str | None = None


def parse_topic_specs(specs: Sequence[str]) -> list[TopicSpec]:
    """Parse ``TOPIC`` or ``TOPIC:TYPE`` arguments (``/ft_sensor/wrench:geometry_msgs/msg/WrenchStamped``).

    Raises
    ------
    InputError
        On an invalid topic or type name, or a topic given twice.
    """
    out: list[TopicSpec] = []
    for spec in specs:
        topic, _, msgtype = spec.partition(":")
        topic = topic if topic.startswith("/") else "/" + topic
        if not _TOPIC_RE.match(topic):
            raise InputError(f"invalid topic {spec!r}: ROS names are /-separated tokens of letters, digits and _")
        if msgtype and (msgtype.count("/") != 2 or not all(msgtype.split("/"))):
            raise InputError(f"invalid message type in {spec!r}: write pkg/msg/Type")
        if any(t.topic == topic for t in out):
            raise InputError(f"topic {topic} given twice")
        out.append(TopicSpec(topic, msgtype or None))
    if not out:
        raise InputError("give at least one topic to record")
    return out


def transform_topic_for_tf(
    specs: Sequence[TopicSpec], transform_topic: str, tf_installed: bool
) -> tuple[list[TopicSpec], str]:
    """Where tf2_msgs is not installed, /tf_static and /tf (which cannot be subscribed) give way to the cell's
    TransformStamped topic of the sensor frame: the topics to record, and a note saying so ('' if nothing changed).

    Parameters
    ----------
    specs : the topics asked for.
    transform_topic : the cell's TransformStamped topic ('' none).
    tf_installed : tf2_msgs/msg/TFMessage can be imported.
    """
    tf_topics = [s.topic for s in specs if s.topic in ("/tf_static", "/tf")]
    if tf_installed or not tf_topics:
        return list(specs), ""
    kept = [s for s in specs if s.topic not in tf_topics]
    if not transform_topic:
        return kept, f"{', '.join(tf_topics)}: tf2_msgs is not installed and the cell names no transform topic"
    if transform_topic not in {s.topic for s in kept}:
        kept.append(TopicSpec(transform_topic, "geometry_msgs/msg/TransformStamped"))
    return kept, (
        f"{', '.join(tf_topics)}: tf2_msgs is not installed; the sensor's rotation is recorded from {transform_topic} "
        "(geometry_msgs/TransformStamped) instead"
    )


def subscription_qos(topic: str, offered: Sequence[tuple[bool, bool]]) -> tuple[bool, bool]:
    """``(reliable, transient_local)`` of the subscription for a topic, as rosbag2 adapts it to publishers.

    Parameters
    ----------
    topic : topic name.
    offered : ``(reliable, transient_local)`` of each publisher discovered (may be empty).

    Returns
    -------
    tuple of bool
        Best effort for sensor streams or if any publisher is best effort, else reliable; transient-local
        only if every publisher is (``/tf_static`` with no publisher yet: transient-local).
    """
    if offered:
        reliable = all(r for r, _ in offered) and not is_sensor_topic(topic)
        durable = all(d for _, d in offered)
    else:
        reliable = not is_sensor_topic(topic)
        durable = topic == "/tf_static"
    return reliable, durable


def _duration(value: Any) -> dict[str, int]:
    """An rclpy Duration as rosbag2 writes it: ``{sec, nsec}`` (RMW_DURATION_INFINITE: 9223372036 s 854775807 ns)."""
    ns = int(value.nanoseconds)
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}


def offered_profile(qos: Any) -> dict[str, Any]:
    """A publisher's QoS (rclpy ``QoSProfile`` from the graph) as rosbag2 (metadata version 9) records it in
    ``offered_qos_profiles``: policies as lower-case names (the graph reports ``history: unknown``, depth 0)."""
    return {
        "history": qos.history.name.lower(),
        "depth": int(qos.depth),
        "reliability": qos.reliability.name.lower(),
        "durability": qos.durability.name.lower(),
        "deadline": _duration(qos.deadline),
        "lifespan": _duration(qos.lifespan),
        "liveliness": qos.liveliness.name.lower(),
        "liveliness_lease_duration": _duration(qos.liveliness_lease_duration),
        "avoid_ros_namespace_conventions": bool(qos.avoid_ros_namespace_conventions),
    }


@dataclass
class _Publisher:
    """A publisher found in the ROS graph: its type, its offered QoS as rosbag2 records it, and the two
    policies the subscription adapts to."""

    msgtype: str
    profile: dict[str, Any]
    reliable: bool
    transient_local: bool


@dataclass(kw_only=True)
class RecordReport:
    """What a recording wrote.

    Attributes
    ----------
    path : the bag directory.
    counts : topic -> messages written.
    types : topic -> message type of the topics subscribed.
    missing : topics never subscribed (no publisher with a type appeared, and none was given).
    unsubscribed : topic -> why it could not be subscribed (its type not installed, or no definition to store).
    warnings : human-readable findings.
    start_ns, end_ns : first and last receive time (0 if nothing was received).
    wall_s : recording time, s.
    """

    path: str
    counts: dict[str, int] = field(default_factory=dict)
    types: dict[str, str] = field(default_factory=dict)
    missing: list[str] = field(default_factory=list)
    unsubscribed: dict[str, str] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    start_ns: int = 0
    end_ns: int = 0
    wall_s: float = 0.0

    def summary_lines(self) -> list[str]:
        """One line per topic, then the warnings."""
        lines = [f"{t} [{self.types[t]}]: {self.counts.get(t, 0)} messages" for t in self.types]
        lines += [f"{t}: not recorded (no publisher found)" for t in self.missing]
        return lines + [f"warning: {w}" for w in self.warnings]


@dataclass(kw_only=True)
class _Sub:
    """A subscribed topic: its publishers so far, its MCAP channel once opened, and what it received.

    Attributes
    ----------
    topic, msgtype : topic name and message type.
    subscription : the rclpy raw subscription.
    offered : publisher gid -> its offered QoS as rosbag2 records it, every publisher seen until the channel
        is opened.
    record : the topic as written (count 0), fixed when the channel is opened; its profiles go both into the
        MCAP channel and into ``metadata.yaml``.
    channel_id : the MCAP channel, once opened.
    inbox : ``(receive time in ns, raw CDR)`` not yet written.
    count : messages written.
    """

    topic: str
    msgtype: str
    subscription: Any
    offered: dict[bytes, dict[str, Any]]
    record: TopicRecord | None = None
    channel_id: int | None = None
    inbox: list[tuple[int, bytes]] = field(default_factory=list)
    count: int = 0


class _Recorder:
    """The raw rclpy subscriptions and the MCAP writer of one recording (all used from one thread)."""

    def __init__(
        self, out: Path, domain_id: int | None, chunk_bytes: int, custom_data: Mapping[str, str] | None = None
    ) -> None:
        from rosbags.typesys import Stores, get_typestore

        from bsp_ros.live.runtime.ros import Client

        self.out = out
        self.mcap_name = f"{out.name}_0.mcap"
        self.typestore = get_typestore(Stores.ROS2_JAZZY)
        self.client = Client("rosbag2_recorder", domain_id)
        self.subs: dict[str, _Sub] = {}
        self.schemas: dict[str, int] = {}
        # Buffered (the mcap writer would wrap a raw file anyway); :meth:`flush` pushes everything to the OS.
        self.stream = (out / self.mcap_name).open("xb")
        self.writer = started_mcap_writer(self.stream, chunk_bytes, "recorder")
        self.start_ns = 0
        self.end_ns = 0
        self.unflushed = 0
        self.custom_data = dict(custom_data or {})

    def discovered(self, topics: Sequence[str]) -> dict[str, dict[bytes, _Publisher]]:
        """ROS topic -> {publisher gid: publisher} of ``topics`` (rclpy ``get_publishers_info_by_topic``)."""
        from rclpy.qos import DurabilityPolicy, ReliabilityPolicy

        found: dict[str, dict[bytes, _Publisher]] = {}
        for topic in topics:
            for info in self.client.node.get_publishers_info_by_topic(topic):
                qos = info.qos_profile
                found.setdefault(topic, {})[bytes(info.endpoint_gid)] = _Publisher(
                    info.topic_type,
                    offered_profile(qos),
                    qos.reliability == ReliabilityPolicy.RELIABLE,
                    qos.durability == DurabilityPolicy.TRANSIENT_LOCAL,
                )
        return found

    def note_publishers(self, sub: _Sub) -> None:
        """Add the publishers of ``sub``'s type now in the graph to its offered profiles (late joiners too)."""
        for gid, publisher in self.discovered([sub.topic]).get(sub.topic, {}).items():
            if publisher.msgtype == sub.msgtype:
                sub.offered.setdefault(gid, publisher.profile)

    def open_channel(self, sub: _Sub) -> int:
        """Register ``sub``'s MCAP channel (once) with the profiles of every publisher known now.

        Opened at the first message rather than at subscription: a topic subscribed by its given type before
        any publisher appeared would otherwise carry no profile. The profiles are then fixed, as rosbag2 fixes
        them: ``metadata.yaml`` must list exactly the channel's, or rosbags reads none of its messages.
        """
        if sub.channel_id is None:
            self.note_publishers(sub)
            qos = tuple(sub.offered.values())
            sub.record = TopicRecord(sub.topic, sub.msgtype, self.typestore.hash_rihs01(sub.msgtype), qos, 0)
            sub.channel_id = self.writer.register_channel(
                sub.topic, "cdr", self.schemas[sub.msgtype], channel_metadata(sub.record)
            )
        return sub.channel_id

    def subscribe(
        self, topic: str, msgtype: str, reliable: bool, durable: bool, offered: dict[bytes, dict[str, Any]]
    ) -> _Sub:
        """Create the raw subscription of a topic and register its schema (its channel opens with its first
        message: :meth:`open_channel`)."""
        from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

        from bsp_ros.live.runtime.ros import message_class

        cls = message_class(msgtype)  # raises, naming the type and its package, when it is not installed
        if msgtype not in self.schemas:
            try:
                msgdef, _ = self.typestore.generate_msgdef(msgtype, ros_version=2)
            except Exception as exc:  # rosbags: a type outside its Jazzy store
                raise InputError(f"{topic}: no message definition of {msgtype} to store in the bag: {exc}") from exc
            self.schemas[msgtype] = self.writer.register_schema(msgtype, "ros2msg", msgdef.encode("utf-8"))
        sub = _Sub(topic=topic, msgtype=msgtype, subscription=None, offered=dict(offered))
        qos = QoSProfile(
            history=HistoryPolicy.KEEP_ALL,
            reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
            durability=DurabilityPolicy.TRANSIENT_LOCAL if durable else DurabilityPolicy.VOLATILE,
        )

        def on_message(data: bytes) -> None:
            sub.inbox.append((time.time_ns(), data))

        sub.subscription = self.client.node.create_subscription(cls, topic, on_message, qos, raw=True)
        self.subs[topic] = sub
        return sub

    def spin(self, seconds: float) -> None:
        """Receive for ``seconds`` (raw CDR goes to each topic's inbox)."""
        self.client.spin(seconds)

    def take_all(self) -> int:
        """Write every message received so far; returns how many."""
        total = 0
        for sub in self.subs.values():
            inbox, sub.inbox = sub.inbox, []
            if inbox:
                self._write(sub, inbox)
            total += len(inbox)
        self.unflushed += total
        return total

    def _write(self, sub: _Sub, inbox: list[tuple[int, bytes]]) -> None:
        """Write ``inbox`` (receive time in ns, raw CDR) to ``sub``'s channel, opening it first if need be."""
        channel_id = self.open_channel(sub)
        for now, data in inbox:
            # rclpy hands raw messages without their source timestamp: publish time = receive time.
            self.writer.add_message(channel_id, log_time=now, data=data, publish_time=now, sequence=sub.count)
            sub.count += 1
        # The recording spans every topic: earliest and latest receive time over all of them.
        first = min(now for now, _ in inbox)
        self.start_ns = min(self.start_ns, first) if self.start_ns else first
        self.end_ns = max(self.end_ns, max(now for now, _ in inbox))

    def flush(self) -> None:
        """Close the open chunk and hand everything written so far to the OS (a kill cannot lose it)."""
        if self.unflushed:
            self.writer.flush()
            self.unflushed = 0

    def finish(self) -> list[TopicRecord]:
        """Write the summary, footer and the rosbag2 metadata record; returns the topics, in subscription order.

        A topic that received nothing gets its channel now, so that the MCAP lists every topic
        ``metadata.yaml`` lists.
        """
        records = [self._final_record(s) for s in self.subs.values()]
        meta = build_metadata(self.mcap_name, records, self.start_ns, self.end_ns, self._custom())
        self.writer.add_metadata(
            "rosbag2",
            {"serialized_metadata": dump_metadata(meta["rosbag2_bagfile_information"]), "ROS_DISTRO": "jazzy"},
        )
        self.writer.finish()
        self.stream.flush()
        os.fsync(self.stream.fileno())
        self.stream.close()
        return records

    def _final_record(self, sub: _Sub) -> TopicRecord:
        """``sub`` as written: its channel's record with the count of messages written."""
        self.open_channel(sub)
        assert sub.record is not None  # set by open_channel
        return replace(sub.record, message_count=sub.count)

    def _custom(self) -> dict[str, str]:
        return {"writer": f"bsp_ros {__version__} recorder", **self.custom_data}

    def close(self) -> None:
        """Leave the ROS graph (the file is closed by :meth:`finish`, or left as is after a failure)."""
        if not self.stream.closed:
            self.stream.close()
        self.client.close()


def record(
    topics: Sequence[str | TopicSpec],
    out_dir: str | Path,
    *,
    domain_id: int | None = None,
    duration_s: float | None = None,
    chunk_bytes: int = DEFAULT_CHUNK_BYTES,
    flush_interval_s: float = DEFAULT_FLUSH_S,
    stop: threading.Event | None = None,
    on_subscribe: Callable[[str, str], None] | None = None,
    custom_data: Mapping[str, str] | None = None,
) -> RecordReport:
    """Record ROS 2 topics into a new rosbag2 bag (metadata version 9, one ``.mcap``).

    Types come from ``TOPIC:TYPE`` or from the publishers in the ROS graph; a topic is subscribed (raw:
    serialized CDR) as soon as its type is known, and refused with a warning naming the type if its message
    package is not installed (a type given on the command line that is not installed is an error at once).
    QoS follows the publishers (rosbag2's adaptation); sensor streams are subscribed best effort. Payloads
    are stored exactly as received (serialized CDR), log time = publish time = receive time (ns, wall
    clock; rclpy's raw subscriptions give no source timestamp). Chunks are small, CRC-checked and flushed
    at least every ``flush_interval_s``: a killed recorder leaves an ``.mcap`` that
    :func:`bsp_ros.bag.read_session` reads up to the cut.
    ``metadata.yaml`` is written at the end. Each topic has one MCAP channel; it and ``metadata.yaml`` list
    the same offered QoS profiles: those of the publishers known when the topic's first message arrived (a
    publisher that joins later is not listed, as with rosbag2), so that rosbags pairs them and reads the bag.

    Parameters
    ----------
    topics : ``"/topic"``, ``"/topic:pkg/msg/Type"`` or :class:`TopicSpec`.
    out_dir : bag directory to create (must not exist; never name it after a person).
    domain_id : ROS domain id (``ROS_DOMAIN_ID`` or 0 when omitted).
    duration_s : stop after this long (default: until ``stop`` is set).
    chunk_bytes : MCAP chunk size, bytes (at least 4096).
    flush_interval_s : longest time a received message stays in memory, s.
    stop : set it (e.g. from a SIGINT/SIGTERM handler) to finish the recording.
    on_subscribe : called with ``(topic, type)`` when a topic is subscribed.
    custom_data : more ``custom_data`` pairs for ``metadata.yaml`` (the cell's stated sensor mounting).

    Returns
    -------
    RecordReport
    """
    specs, out = _checked_request(topics, out_dir, duration_s, chunk_bytes, flush_interval_s)
    stop = stop or threading.Event()
    out.mkdir(parents=True)
    report = RecordReport(path=str(out))
    started = time.monotonic()
    deadline = None if duration_s is None else started + duration_s
    rec = _Recorder(out, domain_id, chunk_bytes, custom_data)
    try:
        pending = {s.topic: s for s in specs}
        loop = _Loop(stop=stop, deadline=deadline, flush_interval_s=flush_interval_s, on_subscribe=on_subscribe)
        _receive_until_stopped(rec, pending, report, loop)
        rec.spin(0.05)  # what arrived meanwhile
        rec.take_all()
        _finish_bag(rec, out, pending, report)
    finally:
        report.wall_s = time.monotonic() - started
        rec.close()
    for topic in report.missing:
        report.warnings.append(f"{topic}: no publisher with a known type appeared; not recorded")
    if not any(report.counts.values()):
        _remove_empty_bag(out, rec.mcap_name)
        heard = ", ".join(f"{t} [{m}]" for t, m in report.types.items()) or "none"
        raise DataError(
            f"nothing was recorded in {report.wall_s:.1f} s: no message arrived (topics subscribed: {heard}; "
            f"no publisher found: {', '.join(report.missing) or 'none'}); no bag was left at {out}"
            + "".join(f"; {topic}: cannot subscribe ({why})" for topic, why in report.unsubscribed.items())
        )
    return report


def _checked_request(
    topics: Sequence[str | TopicSpec],
    out_dir: str | Path,
    duration_s: float | None,
    chunk_bytes: int,
    flush_interval_s: float,
) -> tuple[list[TopicSpec], Path]:
    """:func:`record`'s arguments checked, before anything is created: the topics to record and the bag directory.

    Raises
    ------
    InputError
        On a bad or repeated topic, a duration (s) that is not positive, ``chunk_bytes`` below 4096, a flush
        interval (s) that is not positive, or a given type that is not installed.
    BagWriteError
        If ``out_dir`` exists.
    RuntimeBackendError
        If rclpy is missing.
    """
    specs = [t if isinstance(t, TopicSpec) else parse_topic_specs([t])[0] for t in topics]
    if len({s.topic for s in specs}) != len(specs):
        raise InputError("a topic is given twice")
    if duration_s is not None and not (duration_s > 0):
        raise InputError(f"duration must be positive, got {duration_s!r}")
    if chunk_bytes < 4096 or not (flush_interval_s > 0):
        raise InputError("chunk_bytes must be >= 4096 and flush_interval_s > 0")
    out = Path(out_dir)
    if out.exists():
        raise BagWriteError(f"{out} exists already: refusing to overwrite a bag")
    from bsp_ros.live.runtime.ros import message_class, require_rclpy

    require_rclpy()  # no middleware: 6; past this, a type that cannot be loaded is a bad argument
    for spec in specs:
        if spec.msgtype is not None:
            try:
                message_class(spec.msgtype)  # a type not installed fails now, naming it and its package
            except RuntimeBackendError as error:
                raise InputError(f"{spec.topic}:{spec.msgtype}: {error}") from None
    return specs, out


@dataclass(frozen=True, kw_only=True)
class _Loop:
    """When :func:`_receive_until_stopped` ends and how often it flushes.

    Attributes
    ----------
    stop : set to end the recording.
    deadline : ``time.monotonic()`` at which it ends, s (None: when ``stop`` is set).
    flush_interval_s : longest time a received message stays in memory, s.
    on_subscribe : called with ``(topic, type)`` when a topic is subscribed.
    """

    stop: threading.Event
    deadline: float | None
    flush_interval_s: float
    on_subscribe: Callable[[str, str], None] | None


def _receive_until_stopped(rec: _Recorder, pending: dict[str, TopicSpec], report: RecordReport, loop: _Loop) -> None:
    """Subscribe the ``pending`` topics as their publishers appear, and write what arrives until ``loop`` ends.

    The graph is searched every ``_POLL_S`` seconds while a topic is pending (subscribed topics leave
    ``pending``); what was written is flushed every ``loop.flush_interval_s`` seconds.
    """
    last_flush = time.monotonic()
    last_discovery = 0.0
    while not loop.stop.is_set():
        now = time.monotonic()
        if loop.deadline is not None and now >= loop.deadline:
            break
        if pending and now - last_discovery >= _POLL_S:
            last_discovery = now
            _subscribe_pending(rec, pending, report, loop.on_subscribe)
        if rec.subs:
            rec.spin(min(_POLL_S, loop.flush_interval_s))
        else:
            loop.stop.wait(_POLL_S / 2)
        rec.take_all()
        if time.monotonic() - last_flush >= loop.flush_interval_s:
            rec.flush()
            last_flush = time.monotonic()


def _finish_bag(rec: _Recorder, out: Path, pending: Mapping[str, TopicSpec], report: RecordReport) -> None:
    """Close the MCAP file, write ``metadata.yaml`` (atomically) and fill ``report``'s counts, types, missing
    topics and time span (ns)."""
    records = rec.finish()
    report.counts = {r.name: r.message_count for r in records}
    report.types = {r.name: r.msgtype for r in records}
    report.missing = sorted(pending)
    report.start_ns, report.end_ns = rec.start_ns, rec.end_ns
    meta = build_metadata(rec.mcap_name, records, rec.start_ns, rec.end_ns, rec._custom())
    tmp = out / (METADATA_FILE + ".tmp")
    tmp.write_text(dump_metadata(meta), "utf-8")
    os.replace(tmp, out / METADATA_FILE)


def _remove_empty_bag(out: Path, mcap_name: str) -> None:
    """Delete the bag directory this recording created, holding no message (only its own two files)."""
    for name in (mcap_name, METADATA_FILE, METADATA_FILE + ".tmp"):
        (out / name).unlink(missing_ok=True)
    try:
        out.rmdir()
    except OSError:  # something else was put there meanwhile: leave it
        _LOG.warning("%s is not empty; left in place", out)


def _subscribe_pending(
    rec: _Recorder,
    pending: dict[str, TopicSpec],
    report: RecordReport,
    on_subscribe: Callable[[str, str], None] | None,
) -> None:
    found = rec.discovered(list(pending))
    for topic, spec in list(pending.items()):
        publishers = found.get(topic, {})
        types = {p.msgtype for p in publishers.values()}
        msgtype = spec.msgtype
        if msgtype is None:
            if not types:
                continue
            if len(types) > 1:
                report.warnings.append(f"{topic}: publishers disagree on the type {sorted(types)}; using the first")
            msgtype = sorted(types)[0]
        elif types and msgtype not in types:
            report.warnings.append(f"{topic}: given as {msgtype} but published as {sorted(types)}")
        from bsp_ros.errors import BspError

        try:
            matching = {gid: p for gid, p in publishers.items() if p.msgtype == msgtype}
            reliable, durable = subscription_qos(topic, [(p.reliable, p.transient_local) for p in matching.values()])
            rec.subscribe(topic, msgtype, reliable, durable, {gid: p.profile for gid, p in matching.items()})
        except BspError as error:
            report.unsubscribed[topic] = str(error)
            report.warnings.append(f"{topic}: cannot subscribe ({error})")
            _LOG.warning("%s: cannot subscribe (%s)", topic, error)
            del pending[topic]
            continue
        del pending[topic]
        if on_subscribe is not None:
            on_subscribe(topic, msgtype)
