"""`bsp play` publishes a bag's EMG envelopes and `bsp record` records them, over real DDS on loopback in separate
processes: every message byte for byte, in order, at the played timing."""

from __future__ import annotations

import dataclasses
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from ros_domains import next_domain_id

from bsp_ros.bag import write_session_bag
from bsp_ros.bag.emg_cdr import decode_envelope
from bsp_ros.core.simulation import human_arm_cell, simulate_cell
from bsp_ros.core.streams import EmgSeries

ROOT = Path(__file__).resolve().parents[3]
PEER = Path(__file__).with_name("play_record_peer.py")
CHANNELS = ("biceps", "triceps")
TOPICS = ("/ft_sensor/wrench", "/emg/envelope")
pytestmark = pytest.mark.dds


def _bsp(*args: object) -> subprocess.Popen[str]:
    """``bsp ARGS`` (play or record) in its own process."""
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    command = [sys.executable, str(PEER), *map(str, args)]
    return subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)


def _messages(bag: Path, topic: str) -> list[tuple[int, bytes]]:
    """``topic``'s log times (ns) and payloads, in log time order."""
    (mcap,) = bag.glob("*.mcap")
    with mcap.open("rb") as stream:
        messages = make_reader(stream).iter_messages(log_time_order=True)
        return [(m.log_time, m.data) for _, c, m in messages if c.topic == topic]


def _wait_line(proc: subprocess.Popen[str], prefix: str, timeout_s: float = 20.0) -> None:
    assert proc.stdout is not None
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line or line.startswith(prefix):
            break
    assert line.startswith(prefix), f"no line starting with {prefix!r} (exit {proc.poll()})"


@pytest.fixture
def source_bag(tmp_path: Path) -> Path:
    """8 s of wrench (100 Hz) and two channels of 100 Hz envelopes, a burst of the biceps at 4-5 s."""
    simulated = simulate_cell(human_arm_cell(duration_s=8.0, seed=5))
    t_w = simulated.session.wrench.t_ns
    t_ns = np.arange(t_w[0], t_w[-1], 10_000_000, dtype=np.int64)
    envelope = 2.0 + 0.1 * np.random.default_rng(4).standard_normal((t_ns.size, len(CHANNELS)))
    envelope[(t_ns - t_ns[0] >= 4_000_000_000) & (t_ns - t_ns[0] < 5_000_000_000), 0] *= 4.0
    session = dataclasses.replace(simulated.session, emg=EmgSeries(t_ns=t_ns, envelope=envelope, channels=CHANNELS))
    return write_session_bag(tmp_path / "source", session)


def test_play_publishes_the_emg_and_record_records_it(
    source_bag: Path, tmp_path: Path, procs: list[subprocess.Popen[str]]
) -> None:
    domain = next_domain_id()
    out = tmp_path / "recorded"
    recorder = _bsp("record", *TOPICS, "--out", out, "--domain", domain)
    procs.append(recorder)
    _wait_line(recorder, "recording")
    player = _bsp("play", source_bag, "--rate", 2, "--topics", *TOPICS, "--domain", domain, "--wait-subscribers", 15)
    procs.append(player)
    played, err = player.communicate(timeout=40)
    assert player.returncode == 0, err
    assert f"playing {len(TOPICS)} topics" in played and "without subscribers" not in played, played
    time.sleep(0.5)
    recorder.send_signal(signal.SIGINT)
    _, err = recorder.communicate(timeout=20)
    assert recorder.returncode == 0, err

    source, copy = _messages(source_bag, TOPICS[1]), _messages(out, TOPICS[1])
    assert [data for _, data in copy] == [data for _, data in source]  # every message, byte for byte, in order
    decoded = decode_envelope(copy[0][1])
    assert decoded is not None and decoded[0] == CHANNELS
    # Played at twice real time: received 5 ms apart (the recorded 10 ms halved), within the transport's jitter.
    assert np.median(np.diff([t for t, _ in copy])) == pytest.approx(5_000_000, rel=0.2)
