"""`session_recorder` records the EMG envelopes: its spool writes each message's bytes as they came, so the stored
session is identified with the stretches they show active left out, as `bsp identify` identifies the cell's own
recording."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from bsp_ros.bag import TopicMap, write_session_bag
from bsp_ros.bag.offline import identify_bag
from bsp_ros.core.simulation import human_arm_cell, simulate_cell
from bsp_ros.core.streams import EmgSeries
from bsp_ros.live.session.control import SessionControl
from bsp_ros.live.session.recording import SessionRecording, topic_types

CHANNELS = ("biceps", "triceps", "deltoid_anterior")
EMG_TOPIC = "/emg/envelope"


def _messages(bag: Path) -> Iterator[tuple[str, int, bytes]]:
    (mcap,) = bag.glob("*.mcap")
    with mcap.open("rb") as stream:
        for _, channel, message in make_reader(stream).iter_messages(log_time_order=True):
            yield channel.topic, message.log_time, message.data


@pytest.fixture(scope="module")
def cell_bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 40 s session whose EMG shows the biceps at four times its floor for 3 s (20-23 s) without a net torque."""
    simulated = simulate_cell(human_arm_cell(duration_s=40.0, seed=11))
    t_w = simulated.session.wrench.t_ns
    t_ns = np.arange(t_w[0], t_w[-1], 10_000_000, dtype=np.int64)  # 100 Hz
    rng = np.random.default_rng(3)
    kernel = np.hanning(15) / np.hanning(15).sum()
    envelope = 2.4 + 0.3 * np.column_stack(
        [np.convolve(rng.standard_normal(t_ns.size), kernel, "same") for _ in CHANNELS]
    )
    t_s = (t_ns - t_ns[0]) * 1e-9
    envelope[(t_s >= 20.0) & (t_s < 23.0), 0] *= 4.0
    session = dataclasses.replace(simulated.session, emg=EmgSeries(t_ns=t_ns, envelope=envelope, channels=CHANNELS))
    return write_session_bag(tmp_path_factory.mktemp("cell") / "emg", session, simulated.truth.to_dict())


def test_the_recorder_records_the_emg_and_its_session_leaves_the_burst_out(cell_bag: Path, tmp_path: Path) -> None:
    topics = TopicMap()
    types = topic_types(topics)
    assert types[EMG_TOPIC] == "std_msgs/msg/Float32MultiArray"
    assert EMG_TOPIC not in topic_types(dataclasses.replace(topics, emg=""))
    control = SessionControl(node_name="session_recorder", end_timeout_s=2.0, max_session_s=1800.0, auto_start=True)
    control.name_subject("P012")
    recording = SessionRecording(control, tmp_path / "live_recordings", topics, with_tf=True)
    sent: list[bytes] = []
    last_ns = 0
    for topic, t_ns, data in _messages(cell_bag):
        if topic in types:
            recording.on_message(topic, t_ns, data)
            last_ns = t_ns
            sent += [data] if topic == EMG_TOPIC else []
    change = recording.tick(last_ns + 2_500_000_000)
    assert change.finished is not None
    _, spool = change.finished
    # The EMG messages that came once the wrench had started the session, byte for byte, in order.
    kept = [data for topic, _, data in _messages(spool.path) if topic == EMG_TOPIC]
    assert len(kept) >= len(sent) - 2 and kept == sent[len(sent) - len(kept) :]

    recorded, reference = identify_bag(spool.path), identify_bag(cell_bag)
    assert recorded["quality"]["valid"], recorded["quality"]["message"]
    (active,) = [f for f in recorded["quality"]["findings"] if f["code"] == "arm_active"]
    assert active["values"]["channels"] == "biceps" and active["values"]["active_s"] == pytest.approx(3.4, abs=0.1)
    for segment, q in reference["segments"].items():
        value = recorded["segments"][segment]["static_moment_kgm"]["value"]
        assert value == pytest.approx(q["static_moment_kgm"]["value"], rel=1e-3), segment
