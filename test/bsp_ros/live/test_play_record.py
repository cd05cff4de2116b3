"""`bsp play` and `bsp record` over real DDS on loopback, in separate processes: complete, bit-exact, kill-tolerant."""

from __future__ import annotations

import itertools
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from ros_domains import next_domain_id

from bsp_ros.bag import read_session, write_session_bag
from bsp_ros.bag.mcap_scan import ChannelInfo, scan_mcap
from bsp_ros.errors import InputError
from bsp_ros.live.recorder import parse_topic_specs, subscription_qos
from bsp_ros.live.replay import playback_qos
from bsp_ros.live.runtime.ros import has_message

ROOT = Path(__file__).resolve().parents[3]
PEER = Path(__file__).with_name("play_record_peer.py")
TOPICS = ["/ft_sensor/wrench", "/mocap/shoulder", "/mocap/elbow", "/mocap/wrist", "/mocap/hand", "/tf_static"]
#: /tf_static needs tf2_msgs, which the PyPI wheels lack: there play sends its rotation as the cell's TransformStamped
#: (/ft_sensor/transform) and record records that topic in its place.
TF_INSTALLED = has_message("tf2_msgs/msg/TFMessage")
PLAYABLE = TOPICS if TF_INSTALLED else TOPICS[:-1]
TRANSFORM_TOPIC = "/ft_sensor/transform"
pytestmark = pytest.mark.dds


def _domain(k: int) -> int:
    """A fresh ROS domain id (see conftest.py); ``k`` only tells the tests' calls apart."""
    return next_domain_id()


def _bsp(*args: object) -> subprocess.Popen[str]:
    """``bsp ARGS`` (play and record only: the other subcommands' imports would slow every start)."""
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    return subprocess.Popen(
        [sys.executable, str(PEER), *map(str, args)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


def _wait_line(proc: subprocess.Popen[str], prefix: str, timeout: float = 20.0) -> str:
    assert proc.stdout is not None
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        if line.startswith(prefix):
            return line
    raise AssertionError(f"no line starting with {prefix!r} (exit {proc.poll()})")


class _RawSink:
    def __init__(self) -> None:
        self.data: dict[str, list[bytes]] = {}

    def wants(self, channel: ChannelInfo) -> bool:
        return True

    def feed(
        self, channel: ChannelInfo, buf: np.ndarray, offsets: np.ndarray, lengths: np.ndarray, log_ns: np.ndarray
    ) -> None:
        out = self.data.setdefault(channel.topic, [])
        out += [buf[o : o + n].tobytes() for o, n in zip(offsets.tolist(), lengths.tolist(), strict=True)]


def _raw(bag: Path) -> dict[str, list[bytes]]:
    """Topic -> raw CDR payloads in file order (per topic: receive order)."""
    sink = _RawSink()
    for file in sorted(bag.glob("*.mcap")):
        scan_mcap(file, sink)
    return sink.data


@pytest.fixture(scope="module")
def source_bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from bsp_ros.core.simulation import human_arm_cell, simulate_cell

    simulated = simulate_cell(human_arm_cell(duration_s=10))
    return write_session_bag(tmp_path_factory.mktemp("play") / "session", simulated.session)


def test_play_and_record_are_bsp_subcommands() -> None:
    from bsp_ros.cli import play, record

    for module in (play, record):
        assert callable(module.add_parser) and callable(module.run)


def test_qos_choices_and_topic_specs() -> None:
    assert not playback_qos("/ft_sensor/wrench", False).reliable
    assert not playback_qos("/mocap/hand", False).reliable
    tf_static = playback_qos("/tf_static", True, 3)
    assert tf_static.reliable and tf_static.transient_local and tf_static.depth == 3
    assert playback_qos("/bsp/estimate", False).reliable
    assert subscription_qos("/ft_sensor/wrench", [(True, False)]) == (False, False)
    assert subscription_qos("/tf_static", [(True, True)]) == (True, True)
    assert subscription_qos("/tf_static", [(True, True), (True, False)]) == (True, False)
    assert subscription_qos("/other", [(True, False), (False, False)]) == (False, False)
    specs = parse_topic_specs(["/a", "b:std_msgs/msg/String"])
    assert [(s.topic, s.msgtype) for s in specs] == [("/a", None), ("/b", "std_msgs/msg/String")]
    with pytest.raises(InputError):
        parse_topic_specs(["/a:std_msgs/String"])


def test_play_into_recorder_loses_nothing_and_is_bit_identical(
    source_bag: Path, tmp_path: Path, procs: list[subprocess.Popen[str]]
) -> None:
    domain = _domain(0)
    out = tmp_path / "recorded"
    recorder = _bsp("record", *TOPICS, "--out", out, "--domain", domain)
    procs.append(recorder)
    _wait_line(recorder, "recording")
    # Twice real time (600 messages/s). Best-effort streams as fast as possible (--rate 0, ~5000/s) overrun
    # the Python recorder's rclpy executor: Fast DDS then drops samples, as best effort allows.
    player = _bsp("play", source_bag, "--rate", 2, "--domain", domain, "--wait-subscribers", 15)
    procs.append(player)
    played, err = player.communicate(timeout=40)
    assert player.returncode == 0, err
    assert f"playing {len(TOPICS)} topics" in played and "without subscribers" not in played
    if not TF_INSTALLED:  # /tf_static's rotation went out on the transform topic, said once
        assert played.count("tf2_msgs is not installed") == 1 and TRANSFORM_TOPIC in played, played
    time.sleep(0.5)
    recorder.send_signal(signal.SIGINT)
    _, err = recorder.communicate(timeout=20)
    assert recorder.returncode == 0, err

    source, copy = _raw(source_bag), _raw(out)
    source = {t: v for t, v in source.items() if t in PLAYABLE}
    transforms = copy.pop(TRANSFORM_TOPIC, [])
    assert len(transforms) == (0 if TF_INSTALLED else 1)
    assert {t: len(v) for t, v in copy.items()} == {t: len(v) for t, v in source.items()}
    for topic in source:
        assert copy[topic] == source[topic], topic  # every payload, byte for byte, in order
    meta = yaml.safe_load((out / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert meta["version"] == 9 and meta["storage_identifier"] == "mcap" and len(meta["relative_file_paths"]) == 1
    assert meta["message_count"] == sum(len(v) for v in source.values()) + len(transforms)

    original, again = read_session(source_bag), read_session(out)
    assert again.report.clean or not TF_INSTALLED, again.report.warnings
    assert again.report.chunks_read > 1 and again.report.chunks_without_crc == 0
    np.testing.assert_array_equal(again.session.wrench.t_ns, original.session.wrench.t_ns)
    assert again.session.wrench.force_n.tobytes() == original.session.wrench.force_n.tobytes()
    assert again.session.wrench.torque_nm.tobytes() == original.session.wrench.torque_nm.tobytes()
    for name, series in original.session.markers.items():
        assert again.session.markers[name].position_m.tobytes() == series.position_m.tobytes()
    assert again.report.rotation_source == ("tf" if TF_INSTALLED else "topic")
    np.testing.assert_allclose(
        again.session.rotation_world_from_sensor, original.session.rotation_world_from_sensor, atol=1e-12
    )


@pytest.mark.skipif(not TF_INSTALLED, reason="tf2_msgs is not installed")
def test_tf_static_reaches_a_late_subscriber_and_clock_runs(
    source_bag: Path, procs: list[subprocess.Popen[str]]
) -> None:
    from rclpy.serialization import serialize_message

    from bsp_ros.live.runtime.ros import Client

    domain = _domain(1)
    player = _bsp(
        "play", source_bag, "--rate", 5, "--clock", "--domain", domain, "--wait-subscribers", 0,
        "--topics", "/tf_static", "/ft_sensor/wrench",
    )  # fmt: skip
    procs.append(player)
    _wait_line(player, "playing")
    time.sleep(0.5)  # /tf_static went out before anyone listened
    got: list[object] = []
    clock: list[int] = []
    with Client("late_listener", domain) as client:
        client.subscribe("tf2_msgs/msg/TFMessage", "/tf_static", got.append, "tf_static_listener")
        client.subscribe(
            "rosgraph_msgs/msg/Clock",
            "/clock",
            lambda m: clock.append(m.clock.sec * 1_000_000_000 + m.clock.nanosec),
            "sensor_data",
        )
        client.spin_until(lambda: (bool(got) and len(clock) > 5) or player.poll() is not None, 30)
        client.spin(0.3)
    assert len(got) == 1
    assert serialize_message(got[0]) == _raw(source_bag)["/tf_static"][0]
    assert len(clock) > 5 and all(b >= a for a, b in itertools.pairwise(clock))
    player.send_signal(signal.SIGINT)
    stdout, _ = player.communicate(timeout=20)
    assert "interrupted" in stdout


def test_killed_recorder_leaves_a_bag_read_up_to_the_cut(
    source_bag: Path, tmp_path: Path, procs: list[subprocess.Popen[str]]
) -> None:
    domain = _domain(2)
    out = tmp_path / "killed"
    recorder = _bsp("record", *TOPICS, "--out", out, "--domain", domain)
    procs.append(recorder)
    _wait_line(recorder, "recording")
    player = _bsp("play", source_bag, "--rate", 1, "--domain", domain, "--wait-subscribers", 15)
    procs.append(player)
    _wait_line(player, "playing")
    time.sleep(2.5)
    killed_ns = time.time_ns()
    recorder.kill()
    recorder.wait(timeout=10)
    player.send_signal(signal.SIGINT)
    player.communicate(timeout=20)

    assert not (out / "metadata.yaml").exists()
    read = read_session(out)
    report = read.report
    assert report.truncated and report.crc_errors == 0
    lost_s = (killed_ns - int(read.receive_ns["wrench"][-1])) / 1e9
    assert 0.0 <= lost_s < 1.0, f"lost {lost_s:.3f} s of data"
    print(f"killed recorder: {lost_s:.3f} s of data lost, {read.session.wrench.t_ns.size} wrenches kept")
    assert read.session.wrench.t_ns.size >= 150  # ~2.5 s at 100 Hz, less the loss
    source = _raw(source_bag)
    for topic, payloads in _raw(out).items():
        if topic != TRANSFORM_TOPIC:  # the bridged rotation: not in the source bag
            assert payloads == source[topic][: len(payloads)], topic  # an intact prefix


def test_damaged_bag_plays_its_intact_part_and_says_so(
    source_bag: Path, tmp_path: Path, procs: list[subprocess.Popen[str]]
) -> None:
    domain = _domain(3)
    damaged = tmp_path / "damaged"
    shutil.copytree(source_bag, damaged)
    mcap = next(damaged.glob("*.mcap"))
    with mcap.open("r+b") as stream:
        stream.truncate(int(mcap.stat().st_size * 0.6))
    out = tmp_path / "from_damaged"
    recorder = _bsp("record", *TOPICS, "--out", out, "--domain", domain)
    procs.append(recorder)
    _wait_line(recorder, "recording")
    player = _bsp("play", damaged, "--rate", 2, "--domain", domain, "--wait-subscribers", 15)
    procs.append(player)
    played, err = player.communicate(timeout=40)
    assert player.returncode == 1
    assert "truncated" in played and "lost to damage" in played and "damaged" in err
    time.sleep(0.5)
    recorder.send_signal(signal.SIGINT)
    recorder.communicate(timeout=20)

    copy, source = _raw(out), _raw(source_bag)
    wrench = copy["/ft_sensor/wrench"]
    assert 0 < len(wrench) < len(source["/ft_sensor/wrench"])
    assert f"/ft_sensor/wrench: {len(wrench)} published (bag lists {len(source['/ft_sensor/wrench'])})" in played
    for topic, payloads in copy.items():
        if topic != TRANSFORM_TOPIC:  # the bridged rotation: not in the source bag
            assert payloads == source[topic][: len(payloads)], topic


def test_tf_static_without_tf2_msgs_goes_out_as_the_transform_topic_and_clock_runs(
    source_bag: Path, procs: list[subprocess.Popen[str]]
) -> None:
    from bsp_ros.live.runtime.ros import Client

    domain = _domain(4)
    clock: list[int] = []
    # The listener first, and real-time playback (10 s): best-effort /clock samples sent before discovery
    # completes are lost, and at 5x the whole bag could pass in that time.
    with Client("clock_listener", domain) as client:
        client.subscribe(
            "rosgraph_msgs/msg/Clock",
            "/clock",
            lambda m: clock.append(m.clock.sec * 1_000_000_000 + m.clock.nanosec),
            "sensor_data",
        )
        player = _bsp(
            "play", source_bag, "--rate", 1, "--clock", "--domain", domain, "--wait-subscribers", 0,
            "--topics", "/tf_static", "/ft_sensor/wrench",
        )  # fmt: skip
        procs.append(player)
        client.spin_until(lambda: len(clock) > 5 or player.poll() is not None, 30)
    assert len(clock) > 5 and all(b >= a for a, b in itertools.pairwise(clock))
    player.send_signal(signal.SIGINT)
    stdout, stderr = player.communicate(timeout=20)
    if not TF_INSTALLED:
        assert "/tf_static" in stdout + stderr and "tf2_msgs is not installed" in stdout + stderr
        assert "pip install" not in stdout + stderr


@pytest.mark.parametrize("spec", ["/x:no_such_msgs/msg/Nothing", "/foo:geometry_msgs/msg/Nope"])
def test_record_refuses_a_type_that_is_not_installed_as_a_bad_argument(spec: str, tmp_path: Path) -> None:
    recorder = _bsp("record", spec, "--out", tmp_path / "bag", "--domain", _domain(5))
    _, err = recorder.communicate(timeout=30)
    assert recorder.returncode == 2, err  # README: 2 bad argument (6 is for a middleware that cannot start)
    msgtype = spec.partition(":")[2]
    assert msgtype in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "bag").exists()


def test_record_of_a_topic_nobody_publishes_leaves_no_bag_and_says_so(tmp_path: Path) -> None:
    out = tmp_path / "rec1"
    recorder = _bsp("record", "--out", out, "/nonexistent_topic", "--duration", 2, "--domain", _domain(6))
    stdout, err = recorder.communicate(timeout=30)
    assert recorder.returncode == 3, (stdout, err)  # README: 3 the data cannot be used (nothing recorded)
    assert "recording 1 topic into" in stdout
    assert "nothing was recorded" in err and "/nonexistent_topic" in err and "Traceback" not in err
    assert not out.exists()


def test_record_lists_the_publishers_offered_qos_and_spans_every_topic(
    tmp_path: Path, procs: list[subprocess.Popen[str]]
) -> None:
    """A reliable publisher on a sensor topic (the recorder subscribes best effort) is recorded as reliable,
    as rosbag2 records the offered profiles; the duration and files[] span the earliest to the latest
    receive time over all topics."""
    from bsp_ros.live.runtime.qos import QosSpec
    from bsp_ros.live.runtime.ros import Client, message_class

    domain = _domain(7)
    out = tmp_path / "qos"
    wrench_cls = message_class("geometry_msgs/msg/WrenchStamped")
    pose_cls = message_class("geometry_msgs/msg/PoseStamped")
    with Client("qos_publisher", domain) as client:
        reliable = client.publisher("geometry_msgs/msg/WrenchStamped", "/ft_sensor/wrench", QosSpec(True, 10))
        durable = client.publisher("geometry_msgs/msg/PoseStamped", "/mocap/hand", QosSpec(True, 1, True))
        recorder = _bsp("record", "/ft_sensor/wrench", "/mocap/hand", "--out", out, "--domain", domain)
        procs.append(recorder)
        _wait_line(recorder, "recording")
        # Publish only once discovery matched both topics: on a loaded machine it can take seconds, and
        # messages sent before it reach nobody (the recorder would then rightly report nothing recorded).
        matched = client.spin_until(
            lambda: reliable.get_subscription_count() > 0 and durable.get_subscription_count() > 0, 20.0
        )
        assert matched, "the recorder's subscriptions were not discovered in 20 s"
        deadline = time.monotonic() + 20
        sent = 0
        while time.monotonic() < deadline and sent < 300:
            if recorder.poll() is not None:
                break
            reliable.publish(wrench_cls())
            if sent % 3 == 0:
                durable.publish(pose_cls())
            sent += 1
            client.spin(0.01)
        time.sleep(0.5)
        recorder.send_signal(signal.SIGINT)
        _, err = recorder.communicate(timeout=20)
    assert recorder.returncode == 0, err
    meta = yaml.safe_load((out / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    topics = [t["topic_metadata"] for t in meta["topics_with_message_count"]]
    offered = {t["name"]: t["offered_qos_profiles"] for t in topics}
    assert [p["reliability"] for p in offered["/ft_sensor/wrench"]] == ["reliable"]
    assert [p["durability"] for p in offered["/ft_sensor/wrench"]] == ["volatile"]
    assert [(p["reliability"], p["durability"]) for p in offered["/mocap/hand"]] == [("reliable", "transient_local")]
    for profiles in offered.values():
        assert set(profiles[0]) == {
            "history", "depth", "reliability", "durability", "deadline", "lifespan", "liveliness",
            "liveliness_lease_duration", "avoid_ros_namespace_conventions",
        }  # fmt: skip
        assert profiles[0]["deadline"] == {"sec": 9223372036, "nsec": 854775807}  # rclpy's default: infinite
    (file,) = out.glob("*.mcap")
    from mcap.reader import make_reader

    with file.open("rb") as stream:
        reader = make_reader(stream)
        logs = [m.log_time for _, _, m in reader.iter_messages(log_time_order=False)]
        summary = reader.get_summary()
    assert summary is not None
    channel_qos = {c.topic: yaml.safe_load(c.metadata["offered_qos_profiles"]) for c in summary.channels.values()}
    assert channel_qos == offered  # the MCAP channels say the same
    assert len(logs) == meta["message_count"] > 100
    start, duration = meta["starting_time"]["nanoseconds_since_epoch"], meta["duration"]["nanoseconds"]
    assert (start, duration) == (min(logs), max(logs) - min(logs))
    (entry,) = meta["files"]
    assert entry["starting_time"]["nanoseconds_since_epoch"] == start and entry["duration"]["nanoseconds"] == duration
