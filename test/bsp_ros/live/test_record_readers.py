"""A `bsp record` bag over real DDS is read whole, message for message, by rosbags, mcap and bsp_ros.

rosbags pairs each ``metadata.yaml`` topic with the MCAP channel of the same name, type and offered QoS
profiles, and silently reads nothing of a topic whose two lists differ. The recording here has both cases that
can make them differ: a second publisher that joins a topic after its first message, and a topic subscribed
by its given type before any publisher exists.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.highlevel import AnyReader

from bsp_ros.bag.mcap_scan import ChannelInfo, scan_mcap
from bsp_ros.live.runtime.qos import QosSpec
from bsp_ros.live.runtime.ros import Client, has_message, message_class

ROOT = Path(__file__).resolve().parents[3]
PEER = Path(__file__).with_name("play_record_peer.py")
DIAGNOSTICS = ("/diagnostics", "diagnostic_msgs/msg/DiagnosticArray")
ESTIMATE = ("/bsp/estimate_json", "std_msgs/msg/String")
#: Messages per publisher and phase: enough for several MCAP chunks, few enough for a ~10 s test.
PER_PHASE = 60
#: Deep enough that no reliable sample is overwritten before the recorder acknowledges it.
RELIABLE = QosSpec(True, 4 * PER_PHASE)
pytestmark = [
    pytest.mark.dds,
    pytest.mark.skipif(not has_message(DIAGNOSTICS[1]), reason="diagnostic_msgs is not installed"),
]

#: One message as each reader returns it: topic, log (receive) time in ns, serialized CDR.
Record = tuple[str, int, bytes]


def _bsp_record(*args: object) -> subprocess.Popen[str]:
    """``bsp record ARGS`` in its own process (play_record_peer.py loads only `play` and `record`)."""
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    command = [sys.executable, str(PEER), "record", *map(str, args)]
    return subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)


def _wait_lines(proc: subprocess.Popen[str], prefixes: set[str], timeout_s: float = 15.0) -> None:
    """Read ``proc``'s stdout until a line starting with each of ``prefixes`` was seen."""
    assert proc.stdout is not None
    missing = set(prefixes)
    deadline = time.monotonic() + timeout_s
    while missing and time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        missing -= {p for p in missing if line.startswith(p)}
    assert not missing, f"no line starting with {sorted(missing)} (exit {proc.poll()})"


def _diagnostic(cls: Any, status_cls: Any, name: str) -> Any:
    return cls(status=[status_cls(name=name, message="ok", hardware_id="bench")])


class _Publishers:
    """The test's publishers, each in its own rclpy context (a participant of its own, as a node process)."""

    def __init__(self, domain: int) -> None:
        self.domain = domain
        self.clients: list[Client] = []
        self.diag_cls = message_class(DIAGNOSTICS[1])
        self.status_cls = message_class("diagnostic_msgs/msg/DiagnosticStatus")
        self.string_cls = message_class(ESTIMATE[1])
        self.sent: dict[str, list[str]] = {DIAGNOSTICS[0]: [], ESTIMATE[0]: []}

    def publisher(self, name: str, topic: tuple[str, str]) -> tuple[Client, Any]:
        client = Client(name, self.domain)
        self.clients.append(client)
        return client, client.publisher(topic[1], topic[0], RELIABLE)

    def send(self, client: Client, publisher: Any, topic: str, label: str) -> None:
        """Publish PER_PHASE messages labelled ``label`` and the index, at about 500 per second."""
        for k in range(PER_PHASE):
            text = f"{label} {k}"
            if topic == DIAGNOSTICS[0]:
                publisher.publish(_diagnostic(self.diag_cls, self.status_cls, text))
            else:
                publisher.publish(self.string_cls(data=text))
            self.sent[topic].append(text)
            client.spin(0.002)

    def close(self) -> None:
        for client in self.clients:
            client.close()


def _matched(client: Client, publisher: Any) -> bool:
    return client.spin_until(lambda: publisher.get_subscription_count() > 0, 15.0)


def _record_session(out: Path, domain: int, procs: list[subprocess.Popen[str]]) -> dict[str, list[str]]:
    """Record /diagnostics (two publishers, the second joining late) and /bsp/estimate_json (type given, its
    publisher starting after the subscription); returns each topic's labels as published."""
    pubs = _Publishers(domain)
    try:
        first = pubs.publisher("diagnostics_first", DIAGNOSTICS)
        recorder = _bsp_record(DIAGNOSTICS[0], ":".join(ESTIMATE), "--out", out, "--domain", domain)
        procs.append(recorder)
        _wait_lines(recorder, {f"subscribed {DIAGNOSTICS[0]}", f"subscribed {ESTIMATE[0]}"})
        assert _matched(*first), "the recorder's /diagnostics subscription was not discovered"
        pubs.send(*first, DIAGNOSTICS[0], "first")
        first[0].spin(0.3)  # the recorder writes them, opening the topic's channel, before the others join
        second = pubs.publisher("diagnostics_second", DIAGNOSTICS)
        estimate = pubs.publisher("estimate", ESTIMATE)
        assert _matched(*second) and _matched(*estimate), "the late publishers were not discovered"
        for client, publisher, topic, label in (
            (*first, DIAGNOSTICS[0], "first again"),
            (*second, DIAGNOSTICS[0], "second"),
            (*estimate, ESTIMATE[0], "estimate"),
        ):
            pubs.send(client, publisher, topic, label)
        first[0].spin(0.5)
        # Stopped while every publisher is still in the graph, as a recording of running nodes is.
        recorder.send_signal(signal.SIGINT)
        _, err = recorder.communicate(timeout=20)
    finally:
        pubs.close()
    assert recorder.returncode == 0, err
    return pubs.sent


def _with_rosbags(bag: Path) -> tuple[list[Record], dict[str, list[str]], dict[str, int]]:
    """rosbags' AnyReader: the messages, their labels, and the connections' counts (from metadata.yaml)."""
    records: list[Record] = []
    labels: dict[str, list[str]] = {}
    with AnyReader([bag]) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
        assert len(reader.connections) == len(counts), "one connection per topic"
        for connection, timestamp, rawdata in reader.messages():
            records.append((connection.topic, timestamp, bytes(rawdata)))
            labels.setdefault(connection.topic, []).append(_label(reader.deserialize(rawdata, connection.msgtype)))
    return records, labels, counts


def _with_mcap(bag: Path) -> tuple[list[Record], dict[str, list[str]], dict[str, Any]]:
    """The mcap reader with the mcap_ros2 decoder: the messages, their labels, and each channel's QoS."""
    records: list[Record] = []
    labels: dict[str, list[str]] = {}
    (file,) = bag.glob("*.mcap")
    with file.open("rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        for _, channel, message, decoded in reader.iter_decoded_messages(log_time_order=False):
            records.append((channel.topic, message.log_time, bytes(message.data)))
            labels.setdefault(channel.topic, []).append(_label(decoded))
        summary = reader.get_summary()
    assert summary is not None
    topics = [c.topic for c in summary.channels.values()]
    assert len(topics) == len(set(topics)), "one channel per topic"
    qos = {c.topic: yaml.safe_load(c.metadata["offered_qos_profiles"]) for c in summary.channels.values()}
    return records, labels, qos


class _Sink:
    """bsp_ros's scanner sink keeping every message of every channel."""

    def __init__(self) -> None:
        self.records: list[Record] = []

    def wants(self, channel: ChannelInfo) -> bool:
        return True

    def feed(
        self, channel: ChannelInfo, buf: np.ndarray, offsets: np.ndarray, lengths: np.ndarray, log_ns: np.ndarray
    ) -> None:
        for o, n, t in zip(offsets.tolist(), lengths.tolist(), log_ns.tolist(), strict=True):
            self.records.append((channel.topic, int(t), buf[o : o + n].tobytes()))


def _with_bsp_ros(bag: Path) -> list[Record]:
    sink = _Sink()
    (file,) = bag.glob("*.mcap")
    result = scan_mcap(file, sink)
    assert not result.damage, result.damage
    return sink.records


def _label(message: Any) -> str:
    """The label a test publisher put in ``message`` (String or DiagnosticArray)."""
    return str(message.data) if hasattr(message, "data") else str(message.status[0].name)


def test_recorded_bag_reads_whole_with_rosbags_mcap_and_bsp_ros(
    tmp_path: Path, ros_domain: int, procs: list[subprocess.Popen[str]]
) -> None:
    out = tmp_path / "readers"
    sent = _record_session(out, ros_domain, procs)

    meta = yaml.safe_load((out / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    listed = {t["topic_metadata"]["name"]: t for t in meta["topics_with_message_count"]}
    rosbags_records, rosbags_labels, rosbags_counts = _with_rosbags(out)
    mcap_records, mcap_labels, channel_qos = _with_mcap(out)
    bsp_records = _with_bsp_ros(out)

    # Every message, none twice: reliable publishers, matched before they published.
    for topic, labels in sent.items():
        assert sorted(rosbags_labels.get(topic, [])) == sorted(labels), topic
        assert sorted(mcap_labels[topic]) == sorted(labels), topic
    # The same profiles on both sides: metadata.yaml's sequence and the MCAP channel's YAML string.
    assert channel_qos == {name: t["topic_metadata"]["offered_qos_profiles"] for name, t in listed.items()}
    assert channel_qos[DIAGNOSTICS[0]], "the publisher that gave /diagnostics its type is listed"
    expected = {topic: len(labels) for topic, labels in sent.items()}
    assert rosbags_counts == {name: t["message_count"] for name, t in listed.items()} == expected
    assert meta["message_count"] == len(rosbags_records) == sum(expected.values())
    # Message for message: topic, receive time and bytes alike (rosbags merges channels by time, mcap and
    # bsp_ros keep the file's order).
    assert sorted(rosbags_records) == sorted(mcap_records) == sorted(bsp_records)
    for topic in sent:
        assert [r for r in mcap_records if r[0] == topic] == [r for r in bsp_records if r[0] == topic], topic
