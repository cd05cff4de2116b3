"""Play a rosbag2 MCAP bag onto ROS 2 topics (rclpy, serialized), with recorded timing, reporting any damage."""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from bsp_ros.bag.errors import NotABagError, UnsupportedBagError
from bsp_ros.bag.layout import resolve_bag
from bsp_ros.bag.mcap_scan import ChannelInfo, ScanResult, scan_mcap
from bsp_ros.bag.metadata import METADATA_FILE, read_metadata
from bsp_ros.errors import BspError, InputError
from bsp_ros.live.runtime.qos import QosSpec
from bsp_ros.live.sensor_topics import SENSOR_TOPIC_PREFIXES, is_sensor_topic

__all__ = [
    "SENSOR_TOPIC_PREFIXES",
    "PlayReport",
    "TopicPlan",
    "bag_files",
    "play_bag",
    "playback_qos",
]

_LOG = logging.getLogger("bsp_ros.live.replay")

#: Writer history of reliable volatile topics: deep, so a fast replay does not overwrite unacknowledged samples.
RELIABLE_DEPTH = 1000
_LATCHED_DEPTH_MAX = 1000
_CLOCK_TYPE = "rosgraph_msgs/msg/Clock"
_CLOCK_QOS = QosSpec(reliable=False, depth=1)  # rclcpp::ClockQoS
_QUEUE_BATCHES = 4
_SLEEP_SLICE_S = 0.05


@dataclass(frozen=True)
class TopicPlan:
    """How one bag topic is published.

    Attributes
    ----------
    topic, msgtype : name and ROS message type.
    qos : writer QoS.
    latched : published ahead of the timeline (transient-local), not again when looping.
    expected : messages the bag lists for it (metadata.yaml or the MCAP summary), None if unknown.
    """

    topic: str
    msgtype: str
    qos: QosSpec
    latched: bool
    expected: int | None


@dataclass
class PlayReport:
    """What a playback did.

    Attributes
    ----------
    path : the bag played.
    published : topic -> messages published (over all loops).
    expected : topic -> messages the bag lists per pass (None if unknown).
    skipped : topic -> why it was not played (unknown type, not CDR, not selected).
    matched : topic -> matched subscriptions when playback started.
    loops : complete passes over the bag.
    crc_errors, truncated : damage found in the (first) pass.
    lost_in_bad_chunks : topic -> messages in chunks that failed their CRC.
    damage : one line per damaged place.
    first_pass : topic -> messages published by the first complete pass (empty if none completed).
    acked : every reliable writer's samples were acknowledged at the end (None: nothing to wait for).
    interrupted : playback was stopped before the end.
    wall_s : playback time, s.
    """

    path: str
    published: dict[str, int] = field(default_factory=dict)
    expected: dict[str, int | None] = field(default_factory=dict)
    skipped: dict[str, str] = field(default_factory=dict)
    matched: dict[str, int] = field(default_factory=dict)
    loops: int = 0
    first_pass: dict[str, int] = field(default_factory=dict)
    crc_errors: int = 0
    truncated: bool = False
    lost_in_bad_chunks: dict[str, int] = field(default_factory=dict)
    damage: list[str] = field(default_factory=list)
    acked: bool | None = None
    interrupted: bool = False
    wall_s: float = 0.0

    @property
    def damaged(self) -> bool:
        """True if part of the bag could not be read."""
        return bool(self.crc_errors or self.truncated or self.damage)

    def lost(self, topic: str) -> int | None:
        """Messages of ``topic`` the bag lists but a pass could not play (None if unknown)."""
        expected = self.expected.get(topic)
        if expected is not None and self.first_pass:
            return max(0, expected - self.first_pass.get(topic, 0))
        if self.damaged and topic in self.lost_in_bad_chunks:
            return self.lost_in_bad_chunks[topic]
        return None

    def summary_lines(self) -> list[str]:
        """Human-readable summary: one line per topic, then damage."""
        lines = []
        for topic in sorted(set(self.published) | set(self.expected)):
            if topic in self.skipped:
                continue
            count = self.published.get(topic, 0)
            expected = self.expected.get(topic)
            text = f"{topic}: {count} published"
            if expected is not None:
                text += f" (bag lists {expected}{' per pass' if self.loops > 1 else ''})"
            lost = self.lost(topic)
            if lost:
                text += f", {lost} lost to damage"
            lines.append(text)
        for topic, why in sorted(self.skipped.items()):
            lines.append(f"{topic}: skipped ({why})")
        if self.damaged:
            lines.append(
                f"bag damaged: {self.crc_errors} chunks failed their CRC"
                + (", file truncated" if self.truncated else "")
                + "; the intact part was played"
            )
            lines += [f"  {line}" for line in self.damage]
        if self.acked is False:
            lines.append("not every reliable subscriber acknowledged all messages before the timeout")
        return lines


def playback_qos(topic: str, latched: bool, latched_count: int = 1) -> QosSpec:
    """The writer QoS a ROS 2 user expects for a replayed topic.

    Parameters
    ----------
    topic : topic name.
    latched : the topic was recorded transient-local (``/tf_static`` always is).
    latched_count : messages of a latched topic (its history depth, so late joiners get all of them).

    Returns
    -------
    QosSpec
        ``sensor_data`` (best effort, depth 5) for the wrench and marker streams; reliable transient-local
        for latched topics; reliable volatile (depth :data:`RELIABLE_DEPTH`) for everything else.
    """
    if latched:
        return QosSpec(reliable=True, depth=min(max(1, latched_count), _LATCHED_DEPTH_MAX), transient_local=True)
    if is_sensor_topic(topic):
        return QosSpec(reliable=False, depth=5)
    return QosSpec(reliable=True, depth=RELIABLE_DEPTH)


def bag_files(path: str | Path) -> tuple[list[Path], Path | None]:
    """The MCAP files of a bag and its ``metadata.yaml`` (None if absent).

    Parameters
    ----------
    path : bag directory, its ``metadata.yaml`` or an ``.mcap`` file.

    Returns
    -------
    (files, metadata_path)

    Raises
    ------
    BagError subclasses
        As :func:`bsp_ros.bag.layout.resolve_bag` (other storage or file compression: unsupported).
    """
    layout = resolve_bag(path)
    if not layout.files:
        raise NotABagError(f"{path}: {METADATA_FILE} lists no file")
    return layout.files, layout.metadata_path


def _transient_local(durability: object) -> bool:
    """A recorded durability policy: a name (metadata version 9) or rmw's enum value (older rosbag2 writes
    ``durability: 1``, RMW_QOS_POLICY_DURABILITY_TRANSIENT_LOCAL)."""
    if isinstance(durability, int) and not isinstance(durability, bool):
        return durability == 1
    return str(durability or "").lower().startswith("transient_local")


def _latched_from_metadata(meta: Path) -> set[str]:
    """Topics whose offered QoS in ``metadata.yaml`` is transient-local."""
    try:
        info = yaml.safe_load(meta.read_text("utf-8"))["rosbag2_bagfile_information"]
        latched = set()
        for entry in info.get("topics_with_message_count") or []:
            topic = entry["topic_metadata"]
            profiles = topic.get("offered_qos_profiles") or []
            if isinstance(profiles, str):  # rosbag2 before version 9 stores a YAML string
                profiles = yaml.safe_load(profiles) or []
            if profiles and all(_transient_local(p.get("durability")) for p in profiles):
                latched.add(str(topic["name"]))
        return latched
    except (yaml.YAMLError, KeyError, TypeError, AttributeError):
        return set()


class _ChannelSink:
    """Collects channels only (a pre-pass over a bag without metadata)."""

    def wants(self, channel: ChannelInfo) -> bool:
        return False

    def feed(self, *args: Any) -> None:  # pragma: no cover - never fed
        return


_Batch = list[tuple[int, str, bytes]]  # (log_ns, topic, raw CDR), in log-time order


class _BatchSink:
    """Turns the scanner's per-channel feeds into log-time ordered batches of raw messages."""

    def __init__(self, wanted: Callable[[ChannelInfo], bool], out: Callable[[_Batch], None]) -> None:
        self._wanted = wanted
        self._out = out
        self._buf: np.ndarray | None = None
        self._parts: list[tuple[np.ndarray, np.ndarray, list[str], list[bytes]]] = []

    def wants(self, channel: ChannelInfo) -> bool:
        return self._wanted(channel)

    def feed(
        self, channel: ChannelInfo, buf: np.ndarray, offsets: np.ndarray, lengths: np.ndarray, log_ns: np.ndarray
    ) -> None:
        if self._buf is not None and buf is not self._buf:
            self.flush()
        self._buf = buf
        data = [buf[o : o + n].tobytes() for o, n in zip(offsets.tolist(), lengths.tolist(), strict=True)]
        self._parts.append((log_ns, offsets, [channel.topic] * len(data), data))

    def flush(self) -> None:
        """Emit what was fed since the last flush, sorted by log time (ties: file order)."""
        if not self._parts:
            return
        log = np.concatenate([p[0] for p in self._parts])
        where = np.concatenate([p[1] for p in self._parts])
        topics = [t for p in self._parts for t in p[2]]
        data = [d for p in self._parts for d in p[3]]
        self._parts.clear()
        self._buf = None
        order = np.lexsort((where, log))
        self._out([(int(log[i]), topics[i], data[i]) for i in order.tolist()])


def _scan_thread(
    files: Sequence[Path],
    wanted: Callable[[ChannelInfo], bool],
    batches: queue.Queue[_Batch | ScanResult | BaseException | None],
    stop: threading.Event,
) -> threading.Thread:
    """Start a thread that scans ``files`` and puts batches, then each file's ScanResult, then None."""

    def put(item: _Batch | ScanResult | BaseException | None) -> None:
        while not stop.is_set():
            try:
                batches.put(item, timeout=0.1)
                return
            except queue.Full:
                continue
        raise _StoppedError

    def work() -> None:
        try:
            for file in files:
                sink = _BatchSink(wanted, put)
                result = scan_mcap(file, sink)
                sink.flush()
                put(result)
            put(None)
        except _StoppedError:
            return
        except BaseException as error:  # handed to the playing thread
            try:
                put(error)
            except _StoppedError:
                return

    thread = threading.Thread(target=work, name="bsp_ros-play-scan", daemon=True)
    thread.start()
    return thread


class _StoppedError(Exception):
    """The playback was stopped while the scanner waited."""


def _raw_writer(publisher: Any) -> Callable[[bytes], None]:
    """A function publishing serialized CDR (with its encapsulation header) as it is on ``publisher``."""
    topic = publisher.topic_name

    def write(data: bytes) -> None:
        try:
            publisher.publish(data)  # rclpy: bytes are published raw, no deserialize/serialize round trip
        except Exception as exc:  # rclpy raises RCLError
            raise BspError(f"publishing on {topic} failed: {exc}") from exc

    return write


_clock_store: Any = None


def _clock_bytes(t_ns: int) -> bytes:
    global _clock_store
    if _clock_store is None:
        from rosbags.typesys import Stores, get_typestore

        _clock_store = get_typestore(Stores.ROS2_JAZZY)
    store = _clock_store
    time_cls = store.types["builtin_interfaces/msg/Time"]
    msg = store.types[_CLOCK_TYPE](clock=time_cls(sec=t_ns // 1_000_000_000, nanosec=t_ns % 1_000_000_000))
    return bytes(store.serialize_cdr(msg, _CLOCK_TYPE))


def _plan(
    files: Sequence[Path], meta: Path | None, topics: Sequence[str] | None, report: PlayReport
) -> list[TopicPlan]:
    """Topics, types, QoS and expected counts of a bag (from metadata.yaml, else a channel pre-pass)."""
    types: dict[str, str] = {}
    encodings: dict[str, str] = {}
    expected: dict[str, int | None] = {}
    latched = _latched_from_metadata(meta) if meta is not None else set()
    if meta is not None:
        metadata = read_metadata(meta)
        for name, entry in metadata.topics.items():
            types[name] = entry.msgtype
            encodings[name] = entry.serialization_format
            expected[name] = entry.message_count
    else:
        counts: dict[str, int] | None = {}
        for file in files:
            scan = scan_mcap(file, _ChannelSink())
            for channel in scan.channels.values():
                types.setdefault(channel.topic, channel.msgtype)
                encodings.setdefault(channel.topic, channel.encoding)
            if counts is not None and scan.summary_counts is not None:
                for name, count in scan.summary_counts.items():
                    counts[name] = counts.get(name, 0) + count
            else:
                counts = None
        for name in types:
            expected[name] = None if counts is None else counts.get(name, 0)
    if "/tf_static" in types:
        latched.add("/tf_static")
    if topics:
        unknown = [t for t in topics if t not in types]
        if unknown:
            raise InputError(f"topics {unknown} are not in the bag; it has {sorted(types)}")
    plans = []
    for name, msgtype in types.items():
        if topics and name not in topics:
            continue
        if encodings.get(name, "cdr") != "cdr":
            report.skipped[name] = f"encoded as {encodings[name]!r}, not cdr"
            continue
        listed = expected.get(name)
        is_latched = name in latched
        qos = playback_qos(name, is_latched, listed or 1)
        plans.append(TopicPlan(name, msgtype, qos, is_latched, listed))
    return plans


def play_bag(
    path: str | Path,
    *,
    rate: float = 1.0,
    loop: bool = False,
    clock: bool = False,
    clock_hz: float = 40.0,
    topics: Sequence[str] | None = None,
    domain_id: int | None = None,
    wait_subscribers_s: float = 2.0,
    settle_s: float = 0.2,
    ack_timeout_s: float = 5.0,
    stop: threading.Event | None = None,
    on_start: Callable[[PlayReport], None] | None = None,
) -> PlayReport:
    """Publish a bag's messages on ROS 2 topics (rclpy), timed by their receive (log) times.

    Messages are read raw from the MCAP file(s) with CRC checking and published as serialized CDR, byte
    for byte as recorded; a topic whose message package is not installed (e.g. ``tf2_msgs`` outside a
    cell) is skipped with a warning naming its type. The wrench and marker streams go out best effort
    (``sensor_data``), latched (transient-local) topics such as ``/tf_static`` reliable transient-local
    and ahead of the timeline, everything else reliable. A damaged bag plays its intact part; the report
    says what was lost.

    Parameters
    ----------
    path : bag directory, its ``metadata.yaml`` or an ``.mcap`` file.
    rate : time scale (2 = twice as fast); 0 (or less) publishes as fast as possible.
    loop : replay forever (the stamps and ``/clock`` jump back at each pass) until ``stop`` is set.
    clock : publish ``rosgraph_msgs/msg/Clock`` on ``/clock`` with the bag's log time.
    clock_hz : ``/clock`` rate in bag time, Hz.
    topics : play only these topics (default: all).
    domain_id : ROS domain id (``ROS_DOMAIN_ID`` or 0 when omitted).
    wait_subscribers_s : wait up to this long for every topic to have a matched subscriber before playing.
    settle_s : pause after the subscribers matched, s (lets the subscribers' side of discovery finish).
    ack_timeout_s : wait up to this long at the end for reliable subscribers to acknowledge everything
        (at most 0.5 s when stopped early).
    stop : set it (e.g. from a signal handler) to stop the playback early.
    on_start : called once the publishers exist and playback begins (with the report so far).

    Returns
    -------
    PlayReport
        Counts per topic, skipped topics and damage found.

    Raises
    ------
    BagNotFoundError, NotABagError, UnsupportedBagError, InputError, RuntimeBackendError
    """
    if not np.isfinite(rate):
        raise InputError(f"rate must be finite, got {rate!r}")
    if not (np.isfinite(clock_hz) and clock_hz > 0):
        raise InputError(f"clock rate must be positive, got {clock_hz!r}")
    stop = stop or threading.Event()
    files, meta = bag_files(path)
    report = PlayReport(path=str(path))
    plans = _plan(files, meta, topics, report)
    if not plans and report.skipped:
        # Exiting 0 after publishing nothing would read as a successful replay.
        reasons = "; ".join(f"{topic}: {why}" for topic, why in sorted(report.skipped.items()))
        raise UnsupportedBagError(f"{path}: nothing to play, every topic is skipped ({reasons})")

    from bsp_ros.live.runtime.ros import Client, message_class

    client = Client("rosbag2_player", domain_id)
    started = time.monotonic()
    try:
        writers: dict[str, Callable[[bytes], None]] = {}
        publishers: dict[str, Any] = {}
        plan_of: dict[str, TopicPlan] = {}
        for plan in plans:
            try:
                message_class(plan.msgtype)
            except BspError as error:
                report.skipped[plan.topic] = f"type {plan.msgtype or '<none>'} not installed: {error}"
                _LOG.warning("skipping %s: %s", plan.topic, report.skipped[plan.topic])
                continue
            pub = client.publisher(plan.msgtype, plan.topic, plan.qos)
            publishers[plan.topic] = pub
            writers[plan.topic] = _raw_writer(pub)
            plan_of[plan.topic] = plan
            report.published[plan.topic] = 0
            report.expected[plan.topic] = plan.expected
        clock_write = _raw_writer(client.publisher(_CLOCK_TYPE, "/clock", _CLOCK_QOS)) if clock else None

        _wait_for_subscribers(publishers, wait_subscribers_s, settle_s, stop)
        report.matched = {t: p.get_subscription_count() for t, p in publishers.items()}
        if on_start is not None:
            on_start(report)
        _play_passes(files, writers, plan_of, report, rate, loop, clock_write, clock_hz, stop)
        report.interrupted = stop.is_set()
        reliable = [p for t, p in publishers.items() if plan_of[t].qos.reliable and report.published[t]]
        if reliable:
            # Interrupted: do not hang on a subscriber that may be dead (DDS notices only after its lease).
            deadline = time.monotonic() + (min(ack_timeout_s, 0.5) if report.interrupted else ack_timeout_s)
            report.acked = all(_wait_for_acks(p, deadline - time.monotonic()) for p in reliable)
        time.sleep(0.05)  # best-effort samples just written leave the socket
    finally:
        report.wall_s = time.monotonic() - started
        client.close()
    return report


def _wait_for_acks(publisher: Any, timeout_s: float) -> bool:
    from rclpy.duration import Duration

    return bool(publisher.wait_for_all_acked(Duration(nanoseconds=max(0, int(timeout_s * 1e9)))))


def _wait_for_subscribers(publishers: dict[str, Any], timeout_s: float, settle_s: float, stop: threading.Event) -> None:
    if timeout_s <= 0 or not publishers:
        return
    deadline = time.monotonic() + timeout_s
    while not stop.is_set() and time.monotonic() < deadline:
        if all(p.get_subscription_count() > 0 for p in publishers.values()):
            stop.wait(settle_s)
            return
        stop.wait(0.02)
    if any(p.get_subscription_count() > 0 for p in publishers.values()):
        stop.wait(settle_s)


def _play_passes(
    files: Sequence[Path],
    writers: dict[str, Callable[[bytes], None]],
    plans: dict[str, TopicPlan],
    report: PlayReport,
    rate: float,
    loop: bool,
    clock_write: Callable[[bytes], None] | None,
    clock_hz: float,
    stop: threading.Event,
) -> None:
    """Play the bag once, or until ``stop`` when looping."""
    latched_done: set[str] = set()
    first = True
    while not stop.is_set():
        finished = _play_once(
            files, writers, plans, report, rate, clock_write, clock_hz, stop, latched_done, record_damage=first
        )
        if not finished:
            return
        report.loops += 1
        if first:
            report.first_pass = dict(report.published)
        first = False
        if not loop:
            return


def _play_once(
    files: Sequence[Path],
    writers: dict[str, Callable[[bytes], None]],
    plans: dict[str, TopicPlan],
    report: PlayReport,
    rate: float,
    clock_write: Callable[[bytes], None] | None,
    clock_hz: float,
    stop: threading.Event,
    latched_done: set[str],
    record_damage: bool,
) -> bool:
    """One pass over the bag; returns False if stopped before the end."""
    batches: queue.Queue[_Batch | ScanResult | BaseException | None] = queue.Queue(maxsize=_QUEUE_BATCHES)
    scan_stop = threading.Event()
    thread = _scan_thread(files, lambda c: c.topic in writers, batches, scan_stop)
    fast = rate <= 0
    clock_period_ns = int(1e9 / clock_hz)
    t_log0: int | None = None
    t_wall0 = 0.0
    next_clock_ns: int | None = None
    latched_now = {t for t, p in plans.items() if p.latched and t not in latched_done}
    try:
        while True:
            item = batches.get()
            if item is None:
                return True
            if isinstance(item, BaseException):
                raise item
            if isinstance(item, ScanResult):
                if record_damage:
                    _note_damage(report, item)
                continue
            # Latched topics go out first, without waiting for their time (and once over all loops).
            for _, topic, data in item:
                if topic in latched_now:
                    writers[topic](data)
                    report.published[topic] += 1
            for log_ns, topic, data in item:
                if stop.is_set():
                    return False
                if topic in latched_now or topic in latched_done:
                    continue
                if t_log0 is None:
                    t_log0, t_wall0 = log_ns, time.monotonic()
                    next_clock_ns = log_ns
                if not fast:
                    target = t_wall0 + (log_ns - t_log0) / 1e9 / rate
                    next_clock_ns = _sleep_until(
                        target, stop, clock_write, next_clock_ns, clock_period_ns, t_log0, t_wall0, rate
                    )
                    if stop.is_set():
                        return False
                if clock_write is not None and next_clock_ns is not None and log_ns >= next_clock_ns:
                    clock_write(_clock_bytes(log_ns))
                    next_clock_ns = log_ns + clock_period_ns
                writers[topic](data)
                report.published[topic] += 1
    finally:
        latched_done |= latched_now
        scan_stop.set()
        thread.join(timeout=5.0)


def _sleep_until(
    target: float,
    stop: threading.Event,
    clock_write: Callable[[bytes], None] | None,
    next_clock_ns: int | None,
    clock_period_ns: int,
    t_log0: int,
    t_wall0: float,
    rate: float,
) -> int | None:
    """Sleep until the monotonic time ``target``, publishing ``/clock`` ticks meanwhile; returns the next tick."""
    while not stop.is_set():
        now = time.monotonic()
        wake = target
        if clock_write is not None and next_clock_ns is not None:
            tick_at = t_wall0 + (next_clock_ns - t_log0) / 1e9 / rate
            if tick_at <= now and tick_at < target:
                clock_write(_clock_bytes(next_clock_ns))
                next_clock_ns += clock_period_ns
                continue
            wake = min(target, tick_at)
        if target <= now:
            return next_clock_ns
        delay = max(0.0, wake - now)
        if delay > _SLEEP_SLICE_S:
            stop.wait(_SLEEP_SLICE_S)
        else:
            time.sleep(delay)
    return next_clock_ns


def _note_damage(report: PlayReport, scan: ScanResult) -> None:
    report.crc_errors += scan.crc_errors
    report.truncated = report.truncated or scan.truncated
    report.damage.extend(scan.damage)
    for topic, count in scan.lost_in_bad_chunks.items():
        report.lost_in_bad_chunks[topic] = report.lost_in_bad_chunks.get(topic, 0) + count
    if scan.orphans:
        report.damage.append(f"{scan.orphans} messages on channels whose definition was lost (not played)")
