"""Play a rosbag2 MCAP bag onto ROS 2 topics (rclpy, serialized), with recorded timing, reporting any damage."""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bsp_ros.bag.errors import UnsupportedBagError
from bsp_ros.bag.mcap_scan import ScanResult
from bsp_ros.bag.topics import TF_TYPE, TRANSFORM_TYPE
from bsp_ros.cell import CellDescription
from bsp_ros.errors import BspError, InputError
from bsp_ros.live.replay.batches import Batch, scan_thread
from bsp_ros.live.replay.clock import CLOCK_QOS, CLOCK_TYPE, clock_bytes, sleep_until
from bsp_ros.live.replay.plan import TopicPlan, bag_files, plan_topics
from bsp_ros.live.replay.report import PlayReport, note_damage
from bsp_ros.live.replay.transform_bridge import TransformBridge
from bsp_ros.live.runtime.qos import QosSpec
from msg_adapters.tf import TransformSample, build_transform_stamped

_LOG = logging.getLogger("bsp_ros.live.replay")
_QUEUE_BATCHES = 4
#: The bridged sensor rotation: reliable and transient-local (a late subscriber gets the latest ones).
BRIDGE_QOS = QosSpec(reliable=True, depth=100, transient_local=True)


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
    cell: CellDescription | None = None,
) -> PlayReport:
    """Publish a bag's messages on ROS 2 topics (rclpy), timed by their receive (log) times.

    Messages are read raw from the MCAP file(s) with CRC checking and published as serialized CDR, byte
    for byte as recorded; a topic whose message package is not installed is skipped, named in the report. Where
    tf2_msgs is not installed, /tf_static and /tf are played as the ``cell``'s sensor rotation on its transform
    topic (geometry_msgs/TransformStamped, :class:`TransformBridge`) unless the bag has that topic. The wrench and
    marker streams go out best effort
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
    cell : the cell description (its frames and transform topic; None: TF topics without tf2_msgs are skipped).

    Returns
    -------
    PlayReport
        Counts per topic, skipped topics and damage found.

    Raises
    ------
    BagNotFoundError, NotABagError, UnsupportedBagError, InputError, RuntimeBackendError
    """
    _check_rates(rate, clock_hz)
    stop = stop or threading.Event()
    files, meta = bag_files(path)
    report = PlayReport(path=str(path))
    plans = _playable_plans(path, files, meta, topics, report)

    from bsp_ros.live.runtime.ros import Client

    client = Client("rosbag2_player", domain_id)
    started = time.monotonic()
    try:
        outputs = _open_outputs(client, plans, cell, report)
        clock_write = _raw_writer(client.publisher(CLOCK_TYPE, "/clock", CLOCK_QOS)) if clock else None
        _wait_for_subscribers(outputs.waited(), wait_subscribers_s, settle_s, stop)
        report.matched = {t: p.get_subscription_count() for t, p in outputs.waited().items()}
        if on_start is not None:
            on_start(report)
        _play_passes(files, outputs.writers, outputs.plan_of, report, rate, loop, clock_write, clock_hz, stop)
        report.interrupted = stop.is_set()
        report.bridge_sent = 0 if outputs.bridge is None else outputs.bridge.converter.sent
        _await_reliable_acks(outputs, report, ack_timeout_s)
        time.sleep(0.05)  # best-effort samples just written leave the socket
    finally:
        report.wall_s = time.monotonic() - started
        client.close()
    return report


def _check_rates(rate: float, clock_hz: float) -> None:
    """InputError unless ``rate`` (time scale) is finite and ``clock_hz`` (Hz) finite and positive."""
    if not np.isfinite(rate):
        raise InputError(f"rate must be finite, got {rate!r}")
    if not (np.isfinite(clock_hz) and clock_hz > 0):
        raise InputError(f"clock rate must be positive, got {clock_hz!r}")


def _playable_plans(
    path: str | Path, files: Sequence[Path], meta: Path | None, topics: Sequence[str] | None, report: PlayReport
) -> list[TopicPlan]:
    """The bag's topics to play (:func:`plan_topics`); the skipped ones go into ``report``.

    Raises
    ------
    UnsupportedBagError
        If every topic is skipped.
    """
    plans = plan_topics(files, meta, topics, report)
    if not plans and report.skipped:
        # Exiting 0 after publishing nothing would read as a successful replay.
        reasons = "; ".join(f"{topic}: {why}" for topic, why in sorted(report.skipped.items()))
        raise UnsupportedBagError(f"{path}: nothing to play, every topic is skipped ({reasons})")
    return plans


def _await_reliable_acks(outputs: _Outputs, report: PlayReport, ack_timeout_s: float) -> None:
    """Wait up to ``ack_timeout_s`` seconds (0.5 s when interrupted) for every reliable publisher that published
    to be acknowledged; ``report.acked`` says whether all were (it stays as it is if none published)."""
    reliable = outputs.reliable_in_use(report)
    if reliable:
        # Interrupted: do not hang on a subscriber that may be dead (DDS notices only after its lease).
        deadline = time.monotonic() + (min(ack_timeout_s, 0.5) if report.interrupted else ack_timeout_s)
        report.acked = all(_wait_for_acks(p, deadline - time.monotonic()) for p in reliable)


@dataclass(frozen=True)
class _Outputs:
    """Where each played topic goes.

    Attributes
    ----------
    writers : topic -> function publishing one serialized message (raw, or through the bridge).
    publishers : topic -> its rclpy publisher, for the topics published as recorded.
    plan_of : topic -> its plan, for every topic played.
    bridge : the TransformStamped bridge of /tf_static and /tf, or None.
    """

    writers: dict[str, Callable[[bytes], None]]
    publishers: dict[str, Any]
    plan_of: dict[str, TopicPlan]
    bridge: _Bridge | None

    def waited(self) -> dict[str, Any]:
        """The publishers whose subscribers playback waits for: every topic's and the bridge's, by topic."""
        return {**self.publishers, **({} if self.bridge is None else {self.bridge.topic: self.bridge.publisher})}

    def reliable_in_use(self, report: PlayReport) -> list[Any]:
        """The reliable publishers that published something (the bridge's if it sent a transform)."""
        reliable = [p for t, p in self.publishers.items() if self.plan_of[t].qos.reliable and report.published[t]]
        reliable += [self.bridge.publisher] if self.bridge is not None and self.bridge.converter.sent else []
        return reliable


def _open_outputs(
    client: Any, plans: Sequence[TopicPlan], cell: CellDescription | None, report: PlayReport
) -> _Outputs:
    """A publisher per planned topic whose type is installed, or the bridge for TF topics without tf2_msgs.

    ``report`` gets each played topic with a count of 0 and its expected count, each skipped one with the
    reason, each bridged one with its transform topic.
    """
    from bsp_ros.live.runtime.ros import has_message, message_class

    writers: dict[str, Callable[[bytes], None]] = {}
    publishers: dict[str, Any] = {}
    plan_of: dict[str, TopicPlan] = {}
    bridge: _Bridge | None = None
    bridged = cell is not None and not has_message(TF_TYPE) and cell.transform_topic not in {p.topic for p in plans}
    for plan in plans:
        if bridged and plan.msgtype == TF_TYPE:
            assert cell is not None
            bridge = bridge or _Bridge.start(client, cell)
            writers[plan.topic] = bridge.converter.writer(static=plan.latched)
            report.bridged[plan.topic] = cell.transform_topic
        else:
            try:
                message_class(plan.msgtype)
            except BspError:
                report.skipped[plan.topic] = f"its type {plan.msgtype or '<none>'} is not installed"
                continue
            publishers[plan.topic] = client.publisher(plan.msgtype, plan.topic, plan.qos)
            writers[plan.topic] = _raw_writer(publishers[plan.topic])
        plan_of[plan.topic] = plan
        report.published[plan.topic] = 0
        report.expected[plan.topic] = plan.expected
    return _Outputs(writers, publishers, plan_of, bridge)


@dataclass(frozen=True)
class _Bridge:
    """The TransformStamped publisher of the cell's sensor rotation and the bridge feeding it."""

    topic: str
    publisher: Any
    converter: TransformBridge

    @classmethod
    def start(cls, client: Any, cell: CellDescription) -> _Bridge:
        """The publisher (reliable, transient-local: a node that starts late still gets the rotation)."""
        from bsp_ros.live.runtime.ros import message_class

        publisher = client.publisher(TRANSFORM_TYPE, cell.transform_topic, BRIDGE_QOS)

        def publish(sample: TransformSample) -> None:
            publisher.publish(build_transform_stamped(message_class, sample))

        return cls(cell.transform_topic, publisher, TransformBridge(cell.world_frame, cell.sensor_frame, publish))


def _raw_writer(publisher: Any) -> Callable[[bytes], None]:
    """A function publishing serialized CDR (with its encapsulation header) as it is on ``publisher``."""
    topic = publisher.topic_name

    def write(data: bytes) -> None:
        try:
            publisher.publish(data)  # rclpy: bytes are published raw, no deserialize/serialize round trip
        except Exception as exc:  # rclpy raises RCLError
            raise BspError(f"publishing on {topic} failed: {exc}") from exc

    return write


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
    batches: queue.Queue[Batch | ScanResult | BaseException | None] = queue.Queue(maxsize=_QUEUE_BATCHES)
    scan_stop = threading.Event()
    thread = scan_thread(files, lambda c: c.topic in writers, batches, scan_stop)
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
                    note_damage(report, item)
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
                    next_clock_ns = sleep_until(
                        target, stop, clock_write, next_clock_ns, clock_period_ns, t_log0, t_wall0, rate
                    )
                    if stop.is_set():
                        return False
                if clock_write is not None and next_clock_ns is not None and log_ns >= next_clock_ns:
                    clock_write(clock_bytes(log_ns))
                    next_clock_ns = log_ns + clock_period_ns
                writers[topic](data)
                report.published[topic] += 1
    finally:
        latched_done |= latched_now
        scan_stop.set()
        thread.join(timeout=5.0)
