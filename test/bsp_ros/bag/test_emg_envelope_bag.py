"""The EMG envelope stream through a bag: written by the bag writer, read back equal; rosbags' serializer agrees
with the codec byte for byte; a stream whose channels change is read with the change counted, not mended."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from rosbags.typesys import Stores, get_typestore

from bsp_ros.bag import TopicMap, read_session, write_session_bag
from bsp_ros.bag.emg_cdr import EMG_TYPE, decode_envelope, encode_envelope
from bsp_ros.bag.emg_read import collect_envelopes
from bsp_ros.bag.reader.sink import SessionSink, Stream
from bsp_ros.core.simulation import SimulatedSession
from bsp_ros.core.streams import EmgSeries

CHANNELS = ("biceps", "triceps", "deltoid_anterior")


def _emg(simulated: SimulatedSession, rate_hz: float = 80.0, seed: int = 3) -> EmgSeries:
    """Envelopes over the session's span at ``rate_hz``: log-normal noise of a few uV, float32-exact."""
    t_w = simulated.session.wrench.t_ns
    t_ns = np.arange(t_w[0], t_w[-1], round(1e9 / rate_hz), dtype=np.int64)
    rng = np.random.default_rng(seed)
    envelope = (3.0 * np.exp(0.3 * rng.standard_normal((t_ns.size, len(CHANNELS))))).astype(np.float32)
    return EmgSeries(t_ns=t_ns, envelope=envelope.astype(np.float64), channels=CHANNELS)


def test_codec_matches_rosbags_serializer() -> None:
    store = get_typestore(Stores.ROS2_JAZZY)
    types = store.types
    values = np.array([0.5, 2.25, 7.0])
    dim = types["std_msgs/msg/MultiArrayDimension"](label=",".join(CHANNELS), size=3, stride=3)
    layout = types["std_msgs/msg/MultiArrayLayout"](dim=[dim], data_offset=0)
    message = types[EMG_TYPE](layout=layout, data=values.astype(np.float32))
    raw = bytes(store.serialize_cdr(message, EMG_TYPE))
    assert encode_envelope(CHANNELS, values) == raw
    decoded = decode_envelope(raw)
    assert decoded is not None
    assert decoded[0] == CHANNELS
    np.testing.assert_array_equal(decoded[1], values)
    assert decode_envelope(raw[:20]) is None


def test_emg_round_trip(human_session: SimulatedSession, tmp_path: Path) -> None:
    emg = _emg(human_session)
    session = dataclasses.replace(human_session.session, emg=emg)
    bag = write_session_bag(tmp_path / "with_emg", session, human_session.truth.to_dict())
    read = read_session(bag)
    back = read.session.emg
    assert back is not None
    assert back.channels == CHANNELS
    assert back.other_layout == 0
    np.testing.assert_array_equal(back.t_ns, emg.t_ns)
    np.testing.assert_array_equal(back.envelope, emg.envelope)
    assert read.report.topics["/emg/envelope"].read == emg.t_ns.size
    # the other streams as without EMG
    np.testing.assert_array_equal(read.session.wrench.force_n, human_session.session.wrench.force_n)


def test_no_emg_topic_reads_none(human_session: SimulatedSession, tmp_path: Path) -> None:
    bag = write_session_bag(tmp_path / "plain", human_session.session, human_session.truth.to_dict())
    read = read_session(bag)
    assert read.session.emg is None
    assert "/emg/envelope" not in read.report.topics


def test_emg_topic_remapped_and_ignored(human_session: SimulatedSession, tmp_path: Path) -> None:
    emg = _emg(human_session)
    session = dataclasses.replace(human_session.session, emg=emg)
    bag = write_session_bag(tmp_path / "remapped", session, topics=TopicMap(emg="/cell/emg"))
    assert read_session(bag).session.emg is None
    back = read_session(bag, topics=TopicMap(emg="/cell/emg")).session.emg
    assert back is not None and back.t_ns.size == emg.t_ns.size
    assert read_session(bag, topics=TopicMap(emg="")).session.emg is None


def test_changing_channels_are_counted() -> None:
    """A message with other channels than the first's is counted in ``other_layout`` and left out, not merged."""
    stream = Stream(topic="/emg/envelope", msgtype=EMG_TYPE)
    for k in range(6):
        channels = CHANNELS[:2] if k == 3 else CHANNELS
        SessionSink._feed_envelope(stream, encode_envelope(channels, np.full(len(channels), k + 0.5)), 1000 + k)
    SessionSink._feed_envelope(stream, b"\x00\x01\x00\x00\x05", 2000)
    emg = collect_envelopes(stream)
    assert emg is not None
    assert emg.channels == CHANNELS
    assert emg.other_layout == 1
    assert stream.undecodable == 1
    np.testing.assert_array_equal(emg.t_ns, [1000, 1001, 1002, 1004, 1005])
    np.testing.assert_array_equal(emg.envelope[:, 2], [0.5, 1.5, 2.5, 4.5, 5.5])
