"""The Cyclone DDS node runtime: cross-process delivery, QoS, ROS graph discovery and parameters."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsParticipant, BuiltinTopicDcpsPublication
from cyclonedds.domain import DomainParticipant
from cyclonedds.qos import Policy, Qos
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic

from bsp_ros.errors import InputError, RuntimeBackendError
from bsp_ros.runtime import dds_types, make_context
from bsp_ros.runtime.dds_backend import DdsContext, resolve_topic
from bsp_ros.runtime.params import parse_param_args, rclpy_cli_args
from bsp_ros.runtime.qos import dds_qos

PEER = Path(__file__).with_name("dds_peer.py")
ROOT = Path(__file__).resolve().parents[3]
pytestmark = pytest.mark.dds


def _domain(k: int) -> int:
    """A domain id unique to this test process and test (Cyclone allows 0..232)."""
    return 10 + (os.getpid() % 50) * 4 + k


def _peer(*args: object) -> subprocess.Popen[str]:
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    return subprocess.Popen(
        [sys.executable, str(PEER), *map(str, args)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        env=env,
    )


def _expect_line(proc: subprocess.Popen[str], want: str) -> None:
    assert proc.stdout is not None
    line = proc.stdout.readline().strip()
    assert line == want, f"peer said {line!r}, expected {want!r}"


@pytest.fixture
def latched_peer() -> Iterator[int]:
    """A peer process holding a transient-local /tf_static message; yields its domain."""
    domain = _domain(1)
    proc = _peer("latch", domain)
    try:
        _expect_line(proc, "PUBLISHED")
        yield domain
    finally:
        assert proc.stdin is not None
        proc.stdin.close()
        proc.wait(timeout=10)


def test_200_wrenches_between_processes_arrive_complete_and_in_order() -> None:
    domain = _domain(0)
    sink = _peer("sub", domain, 200)
    try:
        _expect_line(sink, "READY")
        source = _peer("pub", domain, 200)
        _expect_line(source, "ACKED")
        assert source.wait(timeout=10) == 0
        assert sink.stdout is not None
        got = json.loads(sink.stdout.readline())
    finally:
        sink.kill()
        sink.wait()
    assert got == [float(i) for i in range(200)]


def test_late_subscriber_gets_transient_local_tf_static(latched_peer: int) -> None:
    with DdsContext(latched_peer, args=[]) as ctx:
        node = ctx.create_node("late_listener")
        got: list[object] = []
        node.create_subscription("tf2_msgs/msg/TFMessage", "/tf_static", got.append, "tf_static_listener")
        deadline = time.monotonic() + 10.0
        ctx.spin(until=lambda: bool(got) or time.monotonic() > deadline)
    assert len(got) == 1
    (tf,) = got[0].transforms  # type: ignore[attr-defined]
    assert (tf.header.frame_id, tf.child_frame_id) == ("world", "ft_sensor")
    assert tf.transform.translation.y == -0.2


def _user_data(qos: Qos) -> bytes:
    policy = qos[Policy.Userdata]
    return bytes(policy.data) if policy is not None else b""


def test_ros_graph_discovery_sees_our_node(latched_peer: int) -> None:
    info_cls = dds_types.dds_class("rmw_dds_common/msg/ParticipantEntitiesInfo")
    dp = DomainParticipant(latched_peer)
    info_reader = DataReader(dp, Topic(dp, "ros_discovery_info", info_cls), qos=dds_qos("discovery_info"))
    participants = BuiltinDataReader(dp, BuiltinTopicDcpsParticipant)
    publications = BuiltinDataReader(dp, BuiltinTopicDcpsPublication)
    deadline = time.monotonic() + 10.0
    infos: list[object] = []
    enclaves: dict[bytes, bytes] = {}
    writers: dict[str, bytes] = {}
    while time.monotonic() < deadline:
        infos += [s for s in info_reader.take(N=100) if hasattr(s, "node_entities_info_seq")]
        for p in participants.take(N=100):
            enclaves[p.key.bytes] = _user_data(p.qos)
        for w in publications.take(N=100):
            writers[w.topic_name] = _user_data(w.qos)
            writers["type:" + w.topic_name] = w.type_name.encode()
        ours = [i for i in infos if any(n.node_name == "bsp_probe" for n in i.node_entities_info_seq)]  # type: ignore[attr-defined]
        if ours and "rt/tf_static" in writers and bytes(ours[-1].gid.data) in enclaves:  # type: ignore[attr-defined]
            break
        time.sleep(0.05)
    assert ours, "no ros_discovery_info naming bsp_probe"
    info = ours[-1]
    (node,) = [n for n in info.node_entities_info_seq if n.node_name == "bsp_probe"]  # type: ignore[attr-defined]
    assert node.node_namespace == "/cell"
    assert len(node.writer_gid_seq) == 1 and len(node.reader_gid_seq) == 1
    assert enclaves[bytes(info.gid.data)] == b"enclave=/;"  # type: ignore[attr-defined]
    assert writers["rt/tf_static"] == f"typehash={dds_types.type_hash('tf2_msgs/msg/TFMessage')};".encode()
    assert writers["type:rt/tf_static"] == b"tf2_msgs::msg::dds_::TFMessage_"


def test_topic_names_resolve_like_rcl() -> None:
    assert resolve_topic("/ft_sensor/wrench", "/cell", "n") == "/ft_sensor/wrench"
    assert resolve_topic("wrench", "/cell", "n") == "/cell/wrench"
    assert resolve_topic("wrench", "/", "n") == "/wrench"
    assert resolve_topic("~/state", "/cell", "n") == "/cell/n/state"
    with pytest.raises(RuntimeBackendError, match="bad-name"):
        resolve_topic("/bad-name", "/", "n")


def test_make_context_auto_is_dds_without_rclpy() -> None:
    assert "rclpy" not in sys.modules
    with make_context(domain_id=_domain(2), args=[]) as ctx:
        assert ctx.backend == "dds"
        ticks: list[int] = []
        node = ctx.create_node("ticker")
        node.create_timer(0.02, lambda: ticks.append(node.now_ns()))
        ctx.spin(until=0.3)
        assert 8 <= len(ticks) <= 16 and ticks == sorted(ticks)
    assert "rclpy" not in sys.modules


def test_publish_accepts_rosbags_dds_and_serialized_messages_and_writes_xcdr1() -> None:
    joint_state = "sensor_msgs/msg/JointState"
    with DdsContext(_domain(2), args=[]) as ctx:
        node = ctx.create_node("loopback")
        got: list[object] = []
        pub = node.create_publisher(joint_state, "joints", "sensor_data")
        node.create_subscription(joint_state, "joints", got.append, "sensor_data")
        representation = pub._writer.get_qos()[Policy.DataRepresentation]
        assert representation.use_cdrv0_representation and not representation.use_xcdrv2_representation
        cls = ctx.message_class
        assert cls(joint_state) is dds_types.typestore().types[joint_state]
        header = cls("std_msgs/msg/Header")(stamp=cls("builtin_interfaces/msg/Time")(sec=3, nanosec=4), frame_id="")
        deadline = time.monotonic() + 5.0
        while pub.get_subscription_count() == 0 and time.monotonic() < deadline:
            time.sleep(0.01)
        pub.publish(
            cls(joint_state)(header=header, name=["q1"], position=np.array([-0.5]), velocity=[], effort=np.zeros(1))
        )
        dds_cls = dds_types.dds_class
        dds_header = dds_types.ros_to_dds(header)
        pub.publish(dds_cls(joint_state)(header=dds_header, name=["q2"], position=[1.5], velocity=[], effort=[]))
        store = dds_types.typestore()
        serialized = cls(joint_state)(header=header, name=["q3"], position=np.array([2.5]), velocity=[], effort=[])
        pub.publish(bytes(store.serialize_cdr(dds_types.dds_to_ros(dds_types.ros_to_dds(serialized)), joint_state)))
        with pytest.raises(RuntimeBackendError, match="not plain CDR"):
            pub.publish(b"\xff\xff\0\0garbage")
        with pytest.raises(RuntimeBackendError, match="JointState"):
            pub.publish(cls("std_msgs/msg/String")(data="wrong"))
        with pytest.raises(RuntimeBackendError, match="cannot serialise"):
            pub.publish(cls(joint_state)(header=header, name="q1", position=None, velocity=[], effort=[]))
        ctx.spin(until=lambda: len(got) >= 3 or time.monotonic() > deadline)
    received = [(m.name, m.position.tolist(), m.effort.tolist()) for m in got]  # type: ignore[attr-defined]
    assert received == [(["q1"], [-0.5], [0.0]), (["q2"], [1.5], []), (["q3"], [2.5], [])]
    assert all(m.sample_info.source_timestamp > 0 for m in got)  # type: ignore[attr-defined]


def test_a_sample_that_fails_to_decode_is_dropped_with_a_warning_and_the_next_one_delivered(caplog) -> None:
    # Cyclone itself refuses malformed CDR (a raw write of a truncated body fails), so a decoding failure
    # is forced here: the first sample's decoder raises, as rosbags would on data it cannot read.
    joint_state = "sensor_msgs/msg/JointState"
    with DdsContext(_domain(2), args=[]) as ctx:
        node = ctx.create_node("malformed")
        got: list[object] = []
        pub = node.create_publisher(joint_state, "joints", "estimates")
        sub = node.create_subscription(joint_state, "joints", got.append, "estimates")
        decode, calls = sub._deserialize, []

        def fails_first(data: object, type_name: str) -> object:
            calls.append(type_name)
            if len(calls) == 1:
                raise ValueError("truncated sequence")
            return decode(data, type_name)

        sub._deserialize = fails_first  # type: ignore[method-assign]
        deadline = time.monotonic() + 5.0
        while pub.get_subscription_count() == 0 and time.monotonic() < deadline:
            time.sleep(0.01)
        cls = ctx.message_class
        empty = np.zeros(0)
        for sec in (1, 2):
            header = cls("std_msgs/msg/Header")(
                stamp=cls("builtin_interfaces/msg/Time")(sec=sec, nanosec=0), frame_id=""
            )
            pub.publish(cls(joint_state)(header=header, name=[], position=empty, velocity=empty, effort=empty))
        ctx.spin(until=lambda: len(got) >= 1 or time.monotonic() > deadline)
        ctx.spin(0.2)
    assert [m.header.stamp.sec for m in got] == [2]  # type: ignore[attr-defined]
    assert any(
        "dropped a malformed sensor_msgs/msg/JointState on /joints: truncated sequence" in r.getMessage()
        for r in caplog.records
    )


# --- parameters ---

YAML = """
/**:
  ros__parameters:
    cutoff_hz: 5.0
    frame: world
    nested:
      gain: 2
other_node:
  ros__parameters:
    cutoff_hz: 99.0
filter:
  ros__parameters:
    cutoff_hz: 7.5
"""


@pytest.fixture(scope="module")
def param_ctx() -> Iterator[DdsContext]:
    ctx = DdsContext(_domain(3), args=[])
    yield ctx
    ctx.shutdown()


def _node(ctx: DdsContext, tmp_path: Path, name: str, *extra: str) -> object:
    path = tmp_path / "params.yaml"
    path.write_text(YAML)
    ctx.param_args, _ = parse_param_args(["--params-file", str(path), *extra])
    return ctx.create_node(name)


def test_parameters_from_yaml_and_overrides(param_ctx: DdsContext, tmp_path: Path) -> None:
    node = _node(param_ctx, tmp_path, "filter", "--param", "frame:=ft_base")
    assert node.declare_parameter("cutoff_hz", 1.0, "cutoff", "Hz", lo=0.1, hi=50.0) == 7.5  # type: ignore[attr-defined]
    assert node.declare_parameter("frame", "x") == "ft_base"  # type: ignore[attr-defined]
    assert node.declare_parameter("nested.gain", 1, lo=0, hi=10) == 2  # type: ignore[attr-defined]
    assert node.declare_parameter("absent", 0.25) == 0.25  # type: ignore[attr-defined]
    wild = _node(param_ctx, tmp_path, "someone_else")
    assert wild.declare_parameter("cutoff_hz", 1.0) == 5.0  # type: ignore[attr-defined]


def test_parameter_range_and_type_errors_name_the_value(param_ctx: DdsContext, tmp_path: Path) -> None:
    node = _node(param_ctx, tmp_path, "filter_range", "-p", "cutoff_hz:=500.0", "-p", "gain:=3")
    with pytest.raises(InputError, match=r"cutoff_hz.*500\.0"):
        node.declare_parameter("cutoff_hz", 1.0, lo=0.1, hi=50.0)  # type: ignore[attr-defined]
    with pytest.raises(InputError, match=r"gain.*3.*decimal point"):
        node.declare_parameter("gain", 1.0)  # type: ignore[attr-defined]
    nan_node = _node(param_ctx, tmp_path, "filter_nan", "--param", "x:=.nan")
    with pytest.raises(InputError, match="nan"):
        nan_node.declare_parameter("x", 1.0)  # type: ignore[attr-defined]


def test_param_args_translate_to_ros_args(tmp_path: Path) -> None:
    args, rest = parse_param_args(["bag.mcap", "--params-file", "a.yaml", "--param", "k:=1.5", "-p", "s:=hi"])
    assert rest == ["bag.mcap"]
    assert args.overrides == {"k": 1.5, "s": "hi"}
    assert rclpy_cli_args(args) == ["--ros-args", "--params-file", "a.yaml", "-p", "k:=1.5", "-p", "s:=hi"]
    with pytest.raises(InputError, match="name:=value"):
        parse_param_args(["--param", "k=1"])
